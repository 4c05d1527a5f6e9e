// Meshes in the forms lod::surface_form detects, and independent checks that a result has the form:
// shared by the library's tests (form_test.cpp) and the CLI's (simplify_cli_test.cpp).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <tuple>

#include "core/shapes.h"
#include "lodkit/mesh.h"
#include "optimize/optimize_test_support.h"

namespace lod::test {

// Triangle t's unit normal from its corners, in double.
inline std::array<double, 3> face_normal(const Mesh& m, size_t t) {
  const float3 &a = m.positions[m.indices[3 * t]], &b = m.positions[m.indices[3 * t + 1]], &c = m.positions[m.indices[3 * t + 2]];
  const double ux = double(b.x) - a.x, uy = double(b.y) - a.y, uz = double(b.z) - a.z;
  const double vx = double(c.x) - a.x, vy = double(c.y) - a.y, vz = double(c.z) - a.z;
  const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx, l = std::sqrt(nx * nx + ny * ny + nz * nz);
  return {nx / l, ny / l, nz / l};
}

// Gives a mesh's corners their face normals: a soup, each triangle's three vertices its own.
inline Mesh flat_shaded(const Mesh& smooth) {
  Mesh plain = smooth;
  plain.normals.clear();
  Mesh flat = triangle_soup(plain);
  for (size_t t = 0; t < flat.triangle_count(); ++t) {
    const auto n = face_normal(flat, t);
    for (int k = 0; k < 3; ++k) flat.normals.push_back({float(n[0]), float(n[1]), float(n[2])});
  }
  return flat;
}

// "" when every triangle's corners hold its own face normal (within 1e-5), else the first that does not.
inline std::string faceted_problem(const Mesh& m) {
  if (m.normals.size() != m.vertex_count()) return "not one normal per vertex";
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    const auto n = face_normal(m, t);
    for (int k = 0; k < 3; ++k) {
      const float3& c = m.normals[m.indices[3 * t + k]];
      if (std::abs(c.x - n[0]) > 1e-5 || std::abs(c.y - n[1]) > 1e-5 || std::abs(c.z - n[2]) > 1e-5)
        return "triangle " + std::to_string(t) + " corner " + std::to_string(k) + " is not faceted";
    }
  }
  return "";
}

// A wavy 40x40 sheet with normals (0, 0, 1), and the same sheet double-sided by duplication: backs
// on copies of its vertices, winding reversed, normals negated.
struct TwoSided {
  Mesh sheet, two;
};
// `one` double-sided by duplication: backs on copies of its vertices (after them), winding
// reversed, normals negated.
inline Mesh double_sided(const Mesh& one) {
  Mesh two = one;
  const uint32_t n = uint32_t(one.vertex_count());
  for (uint32_t v = 0; v < n; ++v) {
    append_vertex(two, one, v);
    if (!two.normals.empty()) two.normals.back() = {-one.normals[v].x, -one.normals[v].y, -one.normals[v].z};
  }
  for (size_t t = 0; t < one.triangle_count(); ++t)
    two.indices.insert(two.indices.end(), {n + one.indices[3 * t], n + one.indices[3 * t + 2], n + one.indices[3 * t + 1]});
  return two;
}
inline TwoSided double_sided_sheet() {
  TwoSided s;
  s.sheet = shapes::grid(40, 40);
  for (float3& p : s.sheet.positions) p.z = 0.1f * std::sin(6 * p.x) * std::cos(5 * p.y);
  s.sheet.normals.assign(s.sheet.vertex_count(), {0, 0, 1});  // (one way to make the twins differ)
  s.two = double_sided(s.sheet);
  return s;
}

// "" when every triangle has a twin: the same three positions, reversed, with the opposite normals
// (each twin counted once).
inline std::string double_sided_problem(const Mesh& m) {
  if (m.normals.size() != m.vertex_count()) return "not one normal per vertex";
  using Corner = std::tuple<float, float, float, float, float, float>;  // position, normal
  std::map<std::array<Corner, 3>, int> count;
  const auto corner = [&](uint32_t v, float s) {
    const float3 &p = m.positions[v], &q = m.normals[v];
    return Corner{p.x, p.y, p.z, s * q.x, s * q.y, s * q.z};
  };
  const auto key = [](std::array<Corner, 3> c) {
    std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
    return c;
  };
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    const uint32_t a = m.indices[3 * t], b = m.indices[3 * t + 1], c = m.indices[3 * t + 2];
    ++count[key({corner(a, 1), corner(b, 1), corner(c, 1)})];
    --count[key({corner(a, -1), corner(c, -1), corner(b, -1)})];
  }
  for (const auto& [k, c] : count)
    if (c != 0) return "a triangle without its reversed twin";
  return "";
}

}  // namespace lod::test
