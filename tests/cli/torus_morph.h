// A check shared by the CLI tests that carry a morph target through lodkit simplify and lodkit lod:
// on a torus(1, 0.3, 40, 20) whose target offsets are an invertible linear function of the position.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "lodkit/mesh.h"

namespace lod::test {

// Per vertex of a simplified torus(1, 0.3, 40, 20), the input point its morph offset stands for
// (`inverse` of it): checks that it lies on the input torus, about as near the vertex as the torus
// is. Returns how many are off the vertex (the vertex moved off the input surface).
template <class Inverse>
inline size_t expect_points_on_torus(const Mesh& moved, const std::vector<float3>& offsets, Inverse inverse, const std::string& label) {
  EXPECT_EQ(offsets.size(), moved.vertex_count()) << label;
  size_t off_input = 0;
  for (size_t v = 0; v < moved.vertex_count() && v < offsets.size(); ++v) {
    const float3 p = moved.positions[v], q = inverse(offsets[v]);
    // On the polygonal torus: within the sag of its chords around the ring and the tube
    // (1.3 (1 - cos(pi / 40)) + 0.3 (1 - cos(pi / 20)) < 0.0078) of the round one.
    const double ring = std::hypot(double(q.x), double(q.y)) - 1.0;
    EXPECT_LT(std::fabs(std::hypot(ring, double(q.z)) - 0.3), 0.0078) << label << " vertex " << v;
    // And about as near the vertex as the torus is (the vertex's distance to the round torus, plus the sag).
    const double d = std::hypot(double(p.x) - q.x, double(p.y) - q.y, double(p.z) - q.z);
    const double off = std::fabs(std::hypot(std::hypot(double(p.x), double(p.y)) - 1.0, double(p.z)) - 0.3);
    EXPECT_LT(d, off + 0.0078) << label << " vertex " << v;
    off_input += d > 1e-4;
  }
  return off_input;
}

}  // namespace lod::test
