// Overdraw order and the overdraw analyzer: hand-derived counts on stacked squares, the order's
// exactness and miss bound, and nested spheres drawn inside-out.
#include <gtest/gtest.h>

#include <algorithm>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/optimize.h"
#include "optimize_test_support.h"

namespace lod {
namespace {

// Two unit squares facing +z, at z = 0 and z = 1, over the same x-y square; `near_first` puts the
// z = 1 square (nearer to a camera on +z) first.
void stacked_squares(bool near_first, std::vector<float3>& positions, std::vector<uint32_t>& indices) {
  positions.clear();
  indices.clear();
  for (const float z : near_first ? std::array<float, 2>{1, 0} : std::array<float, 2>{0, 1}) {
    const uint32_t b = uint32_t(positions.size());
    positions.insert(positions.end(), {{0, 0, z}, {1, 0, z}, {1, 1, z}, {0, 1, z}});
    indices.insert(indices.end(), {b, b + 1, b + 2, b, b + 2, b + 3});  // counter-clockwise seen from +z
  }
}

TEST(AnalyzeOverdraw, StackedSquaresByHand) {
  // Axis views only: from +z both squares face the camera and cover the same pixels; from -z both
  // are back faces; from the four side views they are edge-on. Far square first: every covered pixel
  // is shaded twice (the near one passes the depth test everywhere), near first: once.
  std::vector<float3> p;
  std::vector<uint32_t> idx;
  const OverdrawOptions axes{.resolution = 128, .diagonal_views = false};
  stacked_squares(false, p, idx);
  const OverdrawStats far_first = analyze_overdraw(idx, p, axes);
  stacked_squares(true, p, idx);
  const OverdrawStats near_first = analyze_overdraw(idx, p, axes);
  EXPECT_EQ(far_first.pixels_covered, near_first.pixels_covered);
  EXPECT_EQ(far_first.pixels_shaded, 2 * far_first.pixels_covered);
  EXPECT_EQ(near_first.pixels_shaded, near_first.pixels_covered);
  EXPECT_DOUBLE_EQ(far_first.overdraw, 2.0);
  EXPECT_DOUBLE_EQ(near_first.overdraw, 1.0);
  // The bounding sphere (radius sqrt(3)/2) spans the 128 pixels, so a unit square is 128 / sqrt(3) =
  // 73.9 pixels wide: between 73 and 75 pixel centres per side (the two triangles share the diagonal
  // without double counting, or the near-first count would exceed the covered pixels).
  EXPECT_GE(near_first.pixels_covered, 73u * 73u);
  EXPECT_LE(near_first.pixels_covered, 75u * 75u);
  // One square alone is framed by its own bounding sphere (radius sqrt(2)/2): 128 / sqrt(2) = 90.5
  // pixels wide, shaded once.
  const OverdrawStats one = analyze_overdraw(std::vector<uint32_t>(idx.begin(), idx.begin() + 6), p, axes);
  EXPECT_GE(one.pixels_covered, 90u * 90u);
  EXPECT_LE(one.pixels_covered, 91u * 91u);
  EXPECT_EQ(one.pixels_shaded, one.pixels_covered);
}

TEST(AnalyzeOverdraw, ConvexMeshIsShadedOnceFromEveryView) {
  // A closed convex mesh with back faces culled: the front faces never overlap, whatever the order.
  const Mesh sphere = shapes::icosphere(3);
  const OverdrawStats s = analyze_overdraw(test::shuffled_triangles(sphere.indices, 7), sphere.positions);
  EXPECT_GT(s.pixels_covered, 0u);
  EXPECT_EQ(s.pixels_shaded, s.pixels_covered);
  EXPECT_THROW(analyze_overdraw(std::vector<uint32_t>{0, 1}, sphere.positions), Error);
  EXPECT_THROW(analyze_overdraw(sphere.indices, sphere.positions, {.resolution = 0}), Error);
}

TEST(OverdrawOrder, KeepsTrianglesAndStaysWithinTheMissBound) {
  const Mesh torus = shapes::torus(1.0f, 0.4f, 48, 24), grid = shapes::grid(30, 30), nested = test::nested_spheres();
  for (const Mesh* m : {&torus, &grid, &nested})
    for (const float threshold : {1.0f, 1.05f, 1.5f})
      for (const uint32_t size : {16u, 32u}) {
        const std::vector<uint32_t> in = optimize_vertex_cache(m->indices, m->vertex_count(), {.cache_size = size});
        const std::vector<uint32_t> out = optimize_overdraw(in, m->positions, {.cache_size = size, .threshold = threshold});
        // Corner order kept exactly: each output triple is an input triple.
        EXPECT_EQ(test::exact_triangles(out), test::exact_triangles(in));
        const uint64_t before = analyze_vertex_cache(in, m->vertex_count(), {.cache_size = size}).misses;
        const uint64_t after = analyze_vertex_cache(out, m->vertex_count(), {.cache_size = size}).misses;
        EXPECT_LE(double(after), double(before) * threshold) << "threshold " << threshold << " cache " << size;
      }
  EXPECT_THROW(optimize_overdraw(torus.indices, torus.positions, {.threshold = 0.9f}), Error);
  EXPECT_THROW(optimize_overdraw(torus.indices, std::span<const float3>(torus.positions).first(3)), Error);
}

TEST(OverdrawOrder, OuterSphereDrawnBeforeTheOneItHides) {
  // Inner sphere first: from every view its front half is shaded, then the outer sphere covers it
  // all again (overdraw about 1 + 0.5^2). The outer sphere's clusters lie out twice as far along their
  // normals, so they go first and the inner sphere fails the depth test almost everywhere.
  const Mesh m = test::nested_spheres();
  const OverdrawStats before = analyze_overdraw(m.indices, m.positions);
  EXPECT_GT(before.overdraw, 1.2);
  const std::vector<uint32_t> out = optimize_overdraw(m.indices, m.positions, {.threshold = 1.05f});
  const OverdrawStats after = analyze_overdraw(out, m.positions);
  EXPECT_EQ(after.pixels_covered, before.pixels_covered);
  EXPECT_LT(after.overdraw, 1.05);
  // The same output for the same input.
  EXPECT_EQ(optimize_overdraw(m.indices, m.positions, {.threshold = 1.05f}), out);
}

TEST(OverdrawOrder, PermutationGivesTheIndexBuffer) {
  // overdraw_order is optimize_overdraw's order as a permutation of the input triangles.
  const Mesh nested = test::nested_spheres(), torus = shapes::torus(1.0f, 0.4f, 48, 24);
  for (const Mesh* m : {&nested, &torus}) {
    const std::vector<uint32_t> order = overdraw_order(m->indices, m->positions);
    std::vector<uint32_t> sorted = order, identity(order.size());
    std::sort(sorted.begin(), sorted.end());
    for (uint32_t t = 0; t < identity.size(); ++t) identity[t] = t;
    ASSERT_EQ(sorted, identity);
    std::vector<uint32_t> applied;
    for (const uint32_t t : order) applied.insert(applied.end(), {m->indices[3 * t], m->indices[3 * t + 1], m->indices[3 * t + 2]});
    EXPECT_EQ(applied, optimize_overdraw(m->indices, m->positions));
  }
  EXPECT_NE(overdraw_order(nested.indices, nested.positions)[0], 0u);  // the outer sphere goes first
}

}  // namespace
}  // namespace lod
