// Helpers for the optimize tests: triangle sets compared independently of order, and small shapes.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <random>
#include <tuple>
#include <vector>

#include "core/shapes.h"
#include "lodkit/mesh.h"
#include "lodkit/optimize.h"

namespace lod::test {

// A position as its three float bit patterns (+0.0 and -0.0 folded), so comparisons are exact.
using PositionKey = std::array<uint32_t, 3>;
inline PositionKey position_key(const float3& p) {
  auto bits = [](float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return u == 0x80000000u ? 0u : u;
  };
  return {bits(p.x), bits(p.y), bits(p.z)};
}
using TriangleKey = std::array<PositionKey, 3>;

// Every triangle as its three positions, rotated so the smallest comes first (a rotation keeps the
// winding, a reflection would not), then sorted: equal multisets mean the same triangles with the
// same windings, in any order and over any vertex numbering.
inline std::vector<TriangleKey> position_triangles(const std::vector<float3>& positions, const std::vector<uint32_t>& indices) {
  std::vector<TriangleKey> out;
  for (size_t k = 0; k + 2 < indices.size(); k += 3) {
    TriangleKey t = {position_key(positions[indices[k]]), position_key(positions[indices[k + 1]]),
                     position_key(positions[indices[k + 2]])};
    while (t[1] < t[0] || t[2] < t[0]) t = {t[1], t[2], t[0]};
    out.push_back(t);
  }
  std::sort(out.begin(), out.end());
  return out;
}
inline std::vector<TriangleKey> position_triangles(const Mesh& m) { return position_triangles(m.positions, m.indices); }

// The same over indices (rotation-normalised, sorted).
inline std::vector<std::array<uint32_t, 3>> index_triangles(const std::vector<uint32_t>& indices) {
  std::vector<std::array<uint32_t, 3>> out;
  for (size_t k = 0; k + 2 < indices.size(); k += 3) {
    std::array<uint32_t, 3> t = {indices[k], indices[k + 1], indices[k + 2]};
    while (t[1] < t[0] || t[2] < t[0]) t = {t[1], t[2], t[0]};
    out.push_back(t);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The same without the rotation: each triangle's corners exactly as listed, sorted.
inline std::vector<std::array<uint32_t, 3>> exact_triangles(const std::vector<uint32_t>& indices) {
  std::vector<std::array<uint32_t, 3>> out;
  for (size_t k = 0; k + 2 < indices.size(); k += 3) out.push_back({indices[k], indices[k + 1], indices[k + 2]});
  std::sort(out.begin(), out.end());
  return out;
}

// Every triangle gets its own three vertices (a "triangle soup"), all streams copied.
inline Mesh triangle_soup(const Mesh& m) {
  Mesh out;
  for (size_t c = 0; c < m.indices.size(); ++c) {
    append_vertex(out, m, m.indices[c]);
    out.indices.push_back(uint32_t(c));
  }
  out.materials = m.materials;
  out.groups = m.groups;
  return out;
}

// A Möbius strip: `segments` quads around a circle of radius 1, width 2 * half_width, the strip's
// cross-section turning half a revolution on the way round. Locally every quad is wound the same way,
// but the last quad joins the first upside down, so no consistent winding exists.
inline Mesh moebius_strip(uint32_t segments = 24, float half_width = 0.3f) {
  Mesh m;
  const double pi = std::acos(-1.0);
  for (uint32_t i = 0; i < segments; ++i) {
    const double a = 2 * pi * i / segments;
    const double dx = std::cos(a / 2) * std::cos(a), dy = std::cos(a / 2) * std::sin(a), dz = std::sin(a / 2);
    for (const double s : {1.0, -1.0})
      m.positions.push_back({float(std::cos(a) + s * half_width * dx), float(std::sin(a) + s * half_width * dy), float(s * half_width * dz)});
  }
  for (uint32_t i = 0; i < segments; ++i) {
    const uint32_t top = 2 * i, bottom = 2 * i + 1;
    // Past the last segment the cross-section has turned over: top meets the first bottom.
    const uint32_t next_top = i + 1 < segments ? 2 * (i + 1) : 1, next_bottom = i + 1 < segments ? 2 * (i + 1) + 1 : 0;
    m.indices.insert(m.indices.end(), {top, bottom, next_top, next_top, bottom, next_bottom});
  }
  return m;
}

// Six times the signed volume enclosed by the triangles (positive when they face outward).
inline double signed_volume6(const Mesh& m) {
  double v = 0;
  for (size_t k = 0; k + 2 < m.indices.size(); k += 3) {
    const float3 &p = m.positions[m.indices[k]], &q = m.positions[m.indices[k + 1]], &r = m.positions[m.indices[k + 2]];
    v += double(p.x) * (double(q.y) * r.z - double(q.z) * r.y) - double(p.y) * (double(q.x) * r.z - double(q.z) * r.x) +
         double(p.z) * (double(q.x) * r.y - double(q.y) * r.x);
  }
  return v;
}

// Directed edges (by position) used more than once: zero when every edge between two triangles is
// traversed once each way, i.e. the winding is consistent.
inline size_t repeated_directed_edges(const Mesh& m) {
  std::map<std::pair<PositionKey, PositionKey>, int> count;
  for (size_t k = 0; k + 2 < m.indices.size(); k += 3)
    for (size_t e = 0; e < 3; ++e)
      ++count[{position_key(m.positions[m.indices[k + e]]), position_key(m.positions[m.indices[k + (e + 1) % 3]])}];
  size_t repeated = 0;
  for (const auto& [edge, n] : count) repeated += n > 1;
  return repeated;
}

// Triangles in a random order (seeded), each keeping its corners.
inline std::vector<uint32_t> shuffled_triangles(const std::vector<uint32_t>& indices, uint32_t seed) {
  std::vector<uint32_t> order(indices.size() / 3);
  for (uint32_t t = 0; t < order.size(); ++t) order[t] = t;
  std::mt19937 rng(seed);
  std::shuffle(order.begin(), order.end(), rng);
  std::vector<uint32_t> out;
  for (const uint32_t t : order) out.insert(out.end(), {indices[3 * t], indices[3 * t + 1], indices[3 * t + 2]});
  return out;
}

// Two icospheres (subdivision 3) about the origin, radius 0.5 inside radius 1, each in its own
// vertex-cache order, the inner one first: drawn in that order, the inner sphere is shaded and then
// covered again from every view.
inline Mesh nested_spheres() {
  const Mesh inner = shapes::icosphere(3), outer = shapes::icosphere(3);
  Mesh m;
  for (const Mesh* s : {&inner, &outer}) {
    const float scale = s == &inner ? 0.5f : 1.0f;
    const uint32_t base = uint32_t(m.positions.size());
    for (const float3& p : s->positions) m.positions.push_back({p.x * scale, p.y * scale, p.z * scale});
    for (const uint32_t i : optimize_vertex_cache(s->indices, s->vertex_count())) m.indices.push_back(base + i);
  }
  return m;
}

}  // namespace lod::test
