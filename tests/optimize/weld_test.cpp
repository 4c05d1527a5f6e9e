// Weld: exact and tolerant, attributes kept apart unless told, remap table consistent with the mesh.
#include <gtest/gtest.h>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/optimize.h"
#include "optimize_test_support.h"

namespace lod {
namespace {

TEST(Weld, IcosphereSoupGetsBackItsUniqueVertices) {
  const Mesh sphere = shapes::icosphere(3);
  const Mesh soup = test::triangle_soup(sphere);
  ASSERT_EQ(soup.vertex_count(), 3 * sphere.triangle_count());
  const WeldResult r = weld(soup);
  // 10 * 4^3 + 2 vertices, every one shared by the soup's copies (their normals are copies too).
  EXPECT_EQ(r.output_vertices, 10u * 64u + 2u);
  EXPECT_EQ(r.mesh.vertex_count(), sphere.vertex_count());
  EXPECT_EQ(r.degenerate_triangles, 0u);
  EXPECT_EQ(test::position_triangles(r.mesh), test::position_triangles(sphere));
  // The remap sends every soup vertex to an output vertex with the same streams.
  ASSERT_EQ(r.remap.size(), soup.vertex_count());
  for (size_t v = 0; v < soup.vertex_count(); ++v) {
    ASSERT_LT(r.remap[v], r.mesh.vertex_count());
    EXPECT_EQ(r.mesh.positions[r.remap[v]], soup.positions[v]);
    EXPECT_EQ(r.mesh.normals[r.remap[v]], soup.normals[v]);
  }
  // Kept vertices come in order of first appearance.
  uint32_t next = 0;
  for (size_t v = 0; v < soup.vertex_count(); ++v)
    if (r.remap[v] == next) ++next;
    else EXPECT_LT(r.remap[v], next);
}

TEST(Weld, PositionsOnlyOrBitwiseAcrossAttributes) {
  const Mesh cube = shapes::cube();  // 24 vertices: 8 corners x 3 faces with their own normals
  EXPECT_EQ(weld(cube).output_vertices, 24u);                              // hard normals and UV seams kept
  EXPECT_EQ(weld(cube, {.ignore_attributes = true}).output_vertices, 8u);  // told to drop them
  const WeldResult positions_only = weld(cube, {.ignore_attributes = true});
  EXPECT_EQ(test::position_triangles(positions_only.mesh), test::position_triangles(cube));
}

TEST(Weld, ExactWeldFoldsNegativeZero) {
  Mesh m;
  m.positions = {{0.0f, 1, 2}, {-0.0f, 1, 2}, {1, 0, 0}, {0, 1, 0}};
  m.indices = {0, 2, 3, 1, 3, 2};
  const WeldResult r = weld(m);
  EXPECT_EQ(r.output_vertices, 3u);
  EXPECT_EQ(r.remap[0], r.remap[1]);
}

TEST(Weld, TolerantWeldMergesWithinEpsilonOnly) {
  // A grid soup with every copy of a vertex nudged by up to 0.4 * eps: all copies of one vertex lie
  // within 0.8 * eps of each other, while distinct grid vertices are 1/8 apart, far beyond eps.
  const Mesh grid = shapes::grid(8, 8);
  Mesh soup = test::triangle_soup(grid);
  const float eps = 1e-3f;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-0.4f * eps / 1.7320508f, 0.4f * eps / 1.7320508f);
  for (float3& p : soup.positions) p = {p.x + jitter(rng), p.y + jitter(rng), p.z + jitter(rng)};
  soup.normals.clear();
  soup.uvs[0].clear();
  EXPECT_EQ(weld(soup).output_vertices, soup.vertex_count());  // exact: nothing is bitwise equal
  const WeldResult r = weld(soup, {.position_tolerance = eps});
  EXPECT_EQ(r.output_vertices, grid.vertex_count());
  EXPECT_EQ(r.degenerate_triangles, 0u);
  for (size_t v = 0; v < soup.vertex_count(); ++v) {
    const float3 &a = soup.positions[v], &b = r.mesh.positions[r.remap[v]];
    EXPECT_LE(std::hypot(a.x - b.x, a.y - b.y, a.z - b.z), eps);
  }
  // A tolerance far below the nudges welds nothing.
  EXPECT_EQ(weld(soup, {.position_tolerance = 1e-9f}).output_vertices, soup.vertex_count());
}

TEST(Weld, TolerantAttributesKeepSeamsUnlessRaised) {
  // Two copies of one position whose UVs differ by 0.5 (a seam) and normals by 1e-4 (noise).
  Mesh m;
  m.positions = {{0, 0, 0}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.normals = {{0, 0, 1}, {0, 1e-4f, 1}, {0, 0, 1}, {0, 0, 1}};
  m.uvs[0] = {{0, 0}, {0.5f, 0}, {1, 0}, {0, 1}};
  m.indices = {0, 2, 3, 1, 3, 2};
  EXPECT_EQ(weld(m, {.position_tolerance = 1e-6f, .normal_tolerance = 1e-3f}).output_vertices, 4u);
  EXPECT_EQ(weld(m, {.position_tolerance = 1e-6f, .normal_tolerance = 1e-3f, .uv_tolerance = 0.5f}).output_vertices, 3u);
  EXPECT_EQ(weld(m, {.position_tolerance = 1e-6f, .uv_tolerance = 0.5f}).output_vertices, 4u);  // normals bitwise
  EXPECT_EQ(weld(m, {.position_tolerance = 1e-6f, .ignore_attributes = true}).output_vertices, 3u);
}

TEST(Weld, DegenerateTrianglesCountedAndRemovedOnRequest) {
  // A sliver whose two close corners weld into one.
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1e-5f, 0}, {0, 1, 0}};
  m.indices = {0, 1, 2, 0, 1, 3};
  m.materials = {4, 5};
  const WeldResult kept = weld(m, {.position_tolerance = 1e-4f});
  EXPECT_EQ(kept.degenerate_triangles, 1u);
  EXPECT_EQ(kept.mesh.triangle_count(), 2u);
  const WeldResult removed = weld(m, {.position_tolerance = 1e-4f, .remove_degenerate = true});
  EXPECT_EQ(removed.degenerate_triangles, 1u);
  ASSERT_EQ(removed.mesh.triangle_count(), 1u);
  EXPECT_EQ(removed.mesh.materials, std::vector<uint32_t>{5});
}

// Vertex classes (streams the Mesh does not hold, such as morph targets) keep copies apart even
// when welding by position alone, exactly or within a tolerance; one class for all changes nothing.
TEST(Weld, VertexClassesStayApart) {
  const Mesh cube = shapes::cube();  // 24 vertices: 4 per face, each corner on 3 faces
  std::vector<uint32_t> by_face(cube.vertex_count()), one(cube.vertex_count(), 7);
  for (uint32_t v = 0; v < cube.vertex_count(); ++v) by_face[v] = v / 4;
  for (const float tolerance : {0.0f, 1e-3f}) {
    EXPECT_EQ(weld(cube, {.position_tolerance = tolerance, .ignore_attributes = true, .vertex_classes = one}).output_vertices, 8u);
    const WeldResult apart = weld(cube, {.position_tolerance = tolerance, .ignore_attributes = true, .vertex_classes = by_face});
    EXPECT_EQ(apart.output_vertices, 24u) << tolerance;
  }
  try {
    weld(cube, {.vertex_classes = std::span<const uint32_t>(one).first(23)});
    FAIL() << "expected a usage error";
  } catch (const Error& e) {
    EXPECT_EQ(e.category(), ErrorCategory::usage);
  }
}

TEST(Weld, RejectsNegativeTolerance) {
  try {
    weld(shapes::cube(), {.position_tolerance = -1});
    FAIL() << "expected a usage error";
  } catch (const Error& e) {
    EXPECT_EQ(e.category(), ErrorCategory::usage);
  }
}

}  // namespace
}  // namespace lod
