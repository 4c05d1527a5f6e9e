// Orientation repair: consistent winding per part, closed parts outward, Möbius strips reported.
#include <gtest/gtest.h>

#include <random>

#include "core/shapes.h"
#include "lodkit/optimize.h"
#include "optimize_test_support.h"

namespace lod {
namespace {

Mesh flip_some(Mesh m, double fraction, uint32_t seed, size_t* flipped = nullptr) {
  std::mt19937 rng(seed);
  std::bernoulli_distribution coin(fraction);
  size_t n = 0;
  for (size_t t = 0; t < m.triangle_count(); ++t)
    if (coin(rng)) std::swap(m.indices[3 * t + 1], m.indices[3 * t + 2]), ++n;
  if (flipped) *flipped = n;
  return m;
}

TEST(Orient, TorusWithHalfItsFacesFlippedIsRepairedOutward) {
  const Mesh torus = shapes::torus(1.0f, 0.3f, 24, 12);  // outward, counter-clockwise
  ASSERT_GT(test::signed_volume6(torus), 0);
  for (const uint32_t seed : {1u, 2u, 3u}) {
    size_t flipped = 0;
    const Mesh broken = flip_some(torus, 0.5, seed, &flipped);
    ASSERT_GT(test::repeated_directed_edges(broken), 0u);
    const OrientResult r = orient(broken);
    EXPECT_EQ(r.components, 1u);
    EXPECT_EQ(r.closed_components, 1u);
    EXPECT_EQ(r.non_orientable_components, 0u);
    EXPECT_EQ(test::repeated_directed_edges(r.mesh), 0u);
    EXPECT_GT(test::signed_volume6(r.mesh), 0);
    // Exactly the flipped triangles were turned back: the result is the torus, winding and all.
    EXPECT_EQ(r.flipped_triangles, flipped);
    EXPECT_EQ(r.mesh.indices, torus.indices);
  }
}

TEST(Orient, InsideOutSphereIsTurnedOutward) {
  const Mesh sphere = shapes::icosphere(2);
  Mesh inside_out = sphere;
  for (size_t t = 0; t < inside_out.triangle_count(); ++t) std::swap(inside_out.indices[3 * t + 1], inside_out.indices[3 * t + 2]);
  ASSERT_LT(test::signed_volume6(inside_out), 0);
  const OrientResult r = orient(inside_out);
  EXPECT_EQ(r.turned_outward, 1u);
  EXPECT_EQ(r.flipped_triangles, sphere.triangle_count());
  EXPECT_EQ(r.mesh.indices, sphere.indices);
  // Told not to turn parts outward, a consistent part is left alone.
  const OrientResult kept = orient(inside_out, {.outward = false});
  EXPECT_EQ(kept.flipped_triangles, 0u);
  EXPECT_EQ(kept.mesh.indices, inside_out.indices);
}

TEST(Orient, SeamsDoNotCutTheWalk) {
  // The cube's faces share no vertex index (hard edges), only positions.
  const Mesh cube = shapes::cube();
  size_t flipped = 0;
  const Mesh broken = flip_some(cube, 0.5, 11, &flipped);
  ASSERT_GT(flipped, 0u);
  const OrientResult r = orient(broken);
  EXPECT_EQ(r.components, 1u);
  EXPECT_EQ(r.mesh.indices, cube.indices);
}

TEST(Orient, OpenPartKeepsItsMajorityWinding) {
  // A grid with 30% of its faces flipped: the larger area decides, so the 70% stay as they were.
  const Mesh grid = shapes::grid(10, 10);
  const Mesh broken = flip_some(grid, 0.3, 5);
  const OrientResult r = orient(broken);
  EXPECT_EQ(r.components, 1u);
  EXPECT_EQ(r.closed_components, 0u);
  EXPECT_EQ(r.mesh.indices, grid.indices);
}

TEST(Orient, EachPartOnItsOwn) {
  // Two spheres, one inside out and one half flipped: both end outward.
  Mesh two = shapes::icosphere(1);
  const size_t n = two.vertex_count();
  const Mesh other = flip_some(shapes::icosphere(1), 0.5, 9);
  for (size_t t = 0; t < two.triangle_count(); ++t) std::swap(two.indices[3 * t + 1], two.indices[3 * t + 2]);
  for (const float3& p : other.positions) two.positions.push_back({p.x + 3, p.y, p.z});
  for (const uint32_t i : other.indices) two.indices.push_back(uint32_t(n) + i);
  const OrientResult r = orient(two);
  EXPECT_EQ(r.components, 2u);
  EXPECT_EQ(r.closed_components, 2u);
  EXPECT_EQ(test::repeated_directed_edges(r.mesh), 0u);
  // Each sphere's own signed volume is positive.
  Mesh first = r.mesh, second = r.mesh;
  first.indices.assign(r.mesh.indices.begin(), r.mesh.indices.begin() + long(other.indices.size()));
  second.indices.assign(r.mesh.indices.begin() + long(other.indices.size()), r.mesh.indices.end());
  EXPECT_GT(test::signed_volume6(first), 0);
  EXPECT_GT(test::signed_volume6(second), 0);
}

TEST(Orient, MoebiusStripIsReportedNotRepaired) {
  const Mesh strip = test::moebius_strip(24);
  OrientResult r;
  ASSERT_NO_THROW(r = orient(strip));
  EXPECT_EQ(r.components, 1u);
  EXPECT_EQ(r.non_orientable_components, 1u);
  EXPECT_EQ(r.closed_components, 0u);
  // The triangles are all still there (some reversed): the same set up to winding.
  Mesh unwound = r.mesh, original = strip;
  for (Mesh* m : {&unwound, &original})
    for (size_t t = 0; t < m->triangle_count(); ++t) {
      uint32_t* c = &m->indices[3 * t];
      std::sort(c, c + 3);
    }
  EXPECT_EQ(test::index_triangles(unwound.indices), test::index_triangles(original.indices));
  // An orientable band (the same strip without the half twist) is not reported.
  Mesh band = strip;
  const uint32_t s = 24;
  band.indices[6 * (s - 1) + 2] = 0, band.indices[6 * (s - 1) + 3] = 0, band.indices[6 * (s - 1) + 5] = 1;
  EXPECT_EQ(orient(band).non_orientable_components, 0u);
}

TEST(Orient, DegenerateAndNonManifoldInputDoNotBreakIt) {
  const Mesh fin = shapes::fin();  // three triangles on one edge
  const OrientResult r = orient(fin);
  EXPECT_EQ(r.non_manifold_edges, 1u);
  EXPECT_EQ(r.components, 3u);
  Mesh degenerate;
  degenerate.positions = {{0, 0, 0}, {1, 0, 0}};
  degenerate.indices = {0, 1, 1};
  EXPECT_EQ(orient(degenerate).components, 0u);
}

}  // namespace
}  // namespace lod
