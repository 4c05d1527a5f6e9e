// The engine on messy meshes: seeded random corruptions of small shapes and fans (duplicate,
// reversed, degenerate and fin triangles, pinched positions, seams, stray vertices, extreme scales) under
// random options. Whatever the input, simplify must not crash or throw, its output must validate,
// the record must replay to the output and undo to the input, and the thread count must not matter.
// The ASan/UBSan preset runs this too, which is where a stray read would show.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <string>

#include "core/shapes.h"
#include "lodkit/simplify.h"

namespace lod {
namespace {

// Draws from the raw generator only (std:: distributions are not the same on every library), so
// a seed names the same case everywhere.
struct Draw {
  std::mt19937 gen;
  explicit Draw(uint32_t seed) : gen(seed) {}
  uint32_t below(uint32_t n) { return n ? uint32_t(gen() % n) : 0; }
  bool chance(uint32_t percent) { return below(100) < percent; }
  float unit() { return float(gen() >> 8) * 0x1p-24f; }  // [0, 1)
};

uint32_t add_vertex(Mesh& m, const float3& p, Draw& d) {
  const uint32_t v = uint32_t(m.vertex_count());
  m.positions.push_back(p);
  if (!m.normals.empty()) m.normals.push_back({0, 0, 1});
  if (!m.tangents.empty()) m.tangents.push_back({1, 0, 0, 1});
  for (auto& uvs : m.uvs)
    if (!uvs.empty()) uvs.push_back({d.unit(), d.unit()});
  if (!m.colors.empty()) m.colors.push_back({d.unit(), d.unit(), d.unit(), 1});
  return v;
}

void add_triangle(Mesh& m, uint32_t a, uint32_t b, uint32_t c) {
  m.indices.insert(m.indices.end(), {a, b, c});
  if (!m.materials.empty()) m.materials.push_back(0);
}

Mesh messy_mesh(Draw& d) {
  Mesh m;
  switch (d.below(6)) {
    case 0: m = shapes::icosphere(1 + d.below(2)); break;
    case 1: m = shapes::torus(1.0f, 0.3f, 8 + d.below(12), 6 + d.below(6)); break;
    case 2: m = shapes::grid(2 + d.below(8), 2 + d.below(8)); break;
    case 3: m = shapes::cylinder(6 + d.below(10)); break;
    case 4: {  // a fan: one position with hundreds of faces, inside a disc or on its border
      const uint32_t n = 100 + d.below(900);
      const bool closed = d.chance(50);
      m.positions.push_back({0, 0, 0});
      for (uint32_t i = 0; i < n; ++i) {
        const float a = float(i) * (closed ? 6.2831853f : 3.1415926f) / float(closed ? n : n - 1);
        m.positions.push_back({std::cos(a), std::sin(a), 0.1f * d.unit()});
      }
      for (uint32_t i = 0; i + (closed ? 0 : 1) < n; ++i) m.indices.insert(m.indices.end(), {0, 1 + i, 1 + (i + 1) % n});
      break;
    }
    default: {  // a soup: random triangles over random points, any orientation or overlap
      const uint32_t points = 3 + d.below(60), triangles = 1 + d.below(120);
      for (uint32_t i = 0; i < points; ++i) m.positions.push_back({d.unit(), d.unit(), d.unit()});
      for (uint32_t i = 0; i < triangles; ++i) m.indices.insert(m.indices.end(), {d.below(points), d.below(points), d.below(points)});
    }
  }
  // Attribute streams (some meshes keep the shape's own normals).
  if (d.chance(50)) m.normals.assign(m.vertex_count(), {0, 0, 1});
  if (d.chance(50)) {
    m.uvs[0].resize(m.vertex_count());
    for (float2& uv : m.uvs[0]) uv = {d.unit(), d.unit()};
  }
  if (d.chance(30)) {
    m.colors.resize(m.vertex_count());
    for (float4& c : m.colors) c = {d.unit(), d.unit(), d.unit(), 1};
  }
  if (d.chance(30)) {
    m.materials.resize(m.triangle_count());
    for (uint32_t& id : m.materials) id = d.below(3);
  }
  const uint32_t edits = d.below(12);
  for (uint32_t e = 0; e < edits && m.triangle_count() > 0; ++e) {
    const uint32_t t = d.below(uint32_t(m.triangle_count()));
    const uint32_t a = m.indices[3 * t], b = m.indices[3 * t + 1], c = m.indices[3 * t + 2];
    switch (d.below(8)) {
      case 0: add_triangle(m, a, b, c); break;  // duplicate
      case 1: std::swap(m.indices[3 * t + 1], m.indices[3 * t + 2]); break;  // reversed winding
      case 2: add_triangle(m, a, a, b); break;  // repeated corner
      case 3: {  // collinear: a corner on the middle of an edge
        const float3 p = m.positions[a], q = m.positions[b];
        add_triangle(m, a, b, add_vertex(m, {(p.x + q.x) / 2, (p.y + q.y) / 2, (p.z + q.z) / 2}, d));
        break;
      }
      case 4:  // a fin: a third face on edge a-b
        add_triangle(m, b, a, add_vertex(m, {d.unit() * 2 - 1, d.unit() * 2 - 1, d.unit() * 2 - 1}, d));
        break;
      case 5: {  // pinch: another vertex moved onto a's position (same position id, another wedge)
        const uint32_t v = d.below(uint32_t(m.vertex_count()));
        m.positions[v] = m.positions[a];
        break;
      }
      case 6: {  // seam: the corner gets a copy of its vertex with other attributes
        const uint32_t copy = add_vertex(m, m.positions[a], d);
        m.indices[3 * t] = copy;
        break;
      }
      default: add_vertex(m, {d.unit(), d.unit(), d.unit()}, d); break;  // unused vertex
    }
  }
  if (d.chance(5)) {  // a second copy of everything on top of the first: every face doubled
    const uint32_t n = uint32_t(m.vertex_count());
    const size_t corners = m.indices.size();
    for (uint32_t v = 0; v < n; ++v) add_vertex(m, m.positions[v], d);
    for (size_t i = 0; i < corners; i += 3) add_triangle(m, m.indices[i] + n, m.indices[i + 1] + n, m.indices[i + 2] + n);
  }
  if (d.chance(3))  // every position the same: nothing but degenerate faces
    for (float3& p : m.positions) p = {0.5f, 0.5f, 0.5f};
  if (d.chance(3)) m.indices.clear(), m.materials.clear();  // no triangles at all
  if (d.chance(20)) {  // extreme scales
    const float s = d.chance(50) ? 1e-6f : 1e6f;
    for (float3& p : m.positions) p = {p.x * s, p.y * s, p.z * s};
  }
  return m;
}

SimplifyOptions random_options(Draw& d, const Mesh& m) {
  SimplifyOptions o;
  const float ratios[] = {0.0f, 0.01f, 0.3f, 0.9f};
  o.target_ratio = ratios[d.below(4)];
  o.metric = Metric(d.below(5));
  o.keep_vertices = d.chance(20);
  o.lock_border = d.chance(20);
  o.normal_weight = d.chance(50) ? d.unit() * 2 : 0;
  o.uv_weight = d.chance(50) ? d.unit() * 2 : 0;
  o.color_weight = d.chance(30) ? d.unit() : 0;
  o.min_normal_dot = d.unit() * 2 - 1;
  o.max_aspect_ratio = d.chance(20) ? 2 + d.unit() * 20 : 0;
  o.distance_guard = d.chance(70) ? 6 : 0;
  o.fit_iterations = d.below(4);
  if (d.chance(20)) o.max_relative_error = d.unit() * 0.05f;
  if (d.chance(20)) {
    float3 lo, hi;
    bounding_box(m, lo, hi);
    o.aggregate_distance = (hi.x - lo.x + hi.y - lo.y + hi.z - lo.z) * d.unit() * 0.2f;
  }
  if (d.chance(20)) {
    o.locked.resize(m.vertex_count());
    for (uint8_t& l : o.locked) l = d.chance(10);
  }
  if (d.chance(20)) {
    o.importance.resize(m.vertex_count());
    for (float& w : o.importance) w = d.unit() * 4;
  }
  return o;
}

TEST(SimplifyRobustness, MessyMeshesUnderRandomOptions) {
  constexpr uint32_t cases = 1000;
  uint32_t collapsed = 0;
  for (uint32_t seed = 1; seed <= cases; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Draw d(seed);
    const Mesh mesh = messy_mesh(d);
    ASSERT_NO_THROW(validate(mesh));
    SimplifyOptions options = random_options(d, mesh);
    const bool prune = d.chance(15);
    options.prune = prune;
    options.threads = 1;
    SimplifyResult r;
    ASSERT_NO_THROW(r = simplify(mesh, options));
    ASSERT_NO_THROW(validate(r.mesh, "simplified"));
    EXPECT_EQ(r.output_triangles, r.mesh.triangle_count());
    EXPECT_LE(r.output_triangles, mesh.triangle_count());
    EXPECT_EQ(r.record.collapses.size(), r.collapses);
    collapsed += r.collapses > 0;
    // Replay describes the mesh before pruning (SimplifyOptions::prune).
    if (!prune) {
      EXPECT_EQ(replay(mesh, r.record, r.record.collapses.size()), r.mesh);
    }
    EXPECT_EQ(replay_and_undo(mesh, r.record), mesh);
    options.threads = 2;
    EXPECT_EQ(simplify(mesh, options).mesh, r.mesh);
  }
  // The cases must mostly do something, or the checks above test nothing.
  EXPECT_GT(collapsed, cases / 2);
}

}  // namespace
}  // namespace lod
