// Shared by the CLI tests that carry a morph target through lodkit simplify and lodkit lod: an offset
// that is an invertible linear function of the position, so an interpolated offset names the input
// point it stands for, and a check of those points on a torus(1, 0.3, 40, 20).
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/shapes.h"
#include "lodkit/io.h"
#include "lodkit/mesh.h"

namespace lod::test {

inline float3 morph_offset(const float3& p) { return {0.5f * p.z, 0.25f * p.x, -0.4f * p.y}; }
inline float3 morph_offset_inverse(const float3& o) { return {4.0f * o.y, -2.5f * o.z, 2.0f * o.x}; }

// A scene of torus(1, 0.3, 40, 20) whose one primitive has one morph target: morph_offset of each
// position.
inline Scene morphing_torus() {
  Scene scene = scene_from_mesh(shapes::torus(1.0f, 0.3f, 40, 20));
  MorphTarget target;
  for (const float3& p : scene.primitives[0].mesh.positions) target.positions.push_back(morph_offset(p));
  scene.primitives[0].targets.push_back(target);
  return scene;
}

// Per vertex of a simplified torus(1, 0.3, 40, 20), the input point its morph offset stands for
// (morph_offset_inverse of it): checks that it lies on the input torus, about as near the vertex as
// the torus is. Returns how many are off the vertex (the vertex moved off the input surface).
inline size_t expect_points_on_torus(const Mesh& moved, const std::vector<float3>& offsets, const std::string& label) {
  EXPECT_EQ(offsets.size(), moved.vertex_count()) << label;
  size_t off_input = 0;
  for (size_t v = 0; v < moved.vertex_count() && v < offsets.size(); ++v) {
    const float3 p = moved.positions[v], q = morph_offset_inverse(offsets[v]);
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
