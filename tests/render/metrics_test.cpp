// Image metrics on hand-built images (exact values) and on rendered spheres (values from geometry).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/render.h"

namespace lod {
namespace {

constexpr float inf = std::numeric_limits<float>::infinity();

// A w x h image with the rectangle [x0, x1) x [y0, y1) covered at depth `depth`.
Image block(uint32_t w, uint32_t h, uint32_t x0, uint32_t y0, uint32_t x1, uint32_t y1, float depth) {
  Image image;
  image.width = w;
  image.height = h;
  image.rgba.assign(size_t(w) * h * 4, 255);
  image.depth.assign(size_t(w) * h, inf);
  for (uint32_t y = y0; y < y1; ++y)
    for (uint32_t x = x0; x < x1; ++x) image.depth[size_t(y) * w + x] = depth;
  return image;
}

TEST(ImageMetrics, ShiftedSquare) {
  // A 10x10 square and the same moved 3 pixels right and 1 nearer.
  const Image a = block(40, 30, 10, 10, 20, 20, 5.0f), b = block(40, 30, 13, 10, 23, 20, 4.0f);
  const ImageDifference d = compare_images(a, b);
  EXPECT_EQ(d.covered_a, 100u);
  EXPECT_EQ(d.covered_b, 100u);
  EXPECT_EQ(d.covered_both, 70u);
  EXPECT_EQ(d.covered_one, 60u);
  EXPECT_DOUBLE_EQ(d.coverage_difference, 60.0 / 130.0);
  EXPECT_DOUBLE_EQ(d.max_depth_difference, 1.0);
  EXPECT_DOUBLE_EQ(d.mean_depth_difference, 1.0);
  EXPECT_DOUBLE_EQ(d.silhouette_displacement_px, 3.0);
}

TEST(ImageMetrics, DiagonalDisplacementIsEuclidean) {
  // Moved 3 right and 4 down: the far corner is 5 pixels from the other outline's corner.
  const Image a = block(50, 50, 10, 10, 30, 30, 1.0f), b = block(50, 50, 13, 14, 33, 34, 1.0f);
  EXPECT_DOUBLE_EQ(compare_images(a, b).silhouette_displacement_px, 5.0);
}

TEST(ImageMetrics, GrownSquare) {
  // One pixel added all round: every outline pixel is within sqrt(2) (corners) of the other's.
  const Image a = block(30, 30, 10, 10, 20, 20, 2.0f), b = block(30, 30, 9, 9, 21, 21, 2.5f);
  const ImageDifference d = compare_images(a, b);
  EXPECT_EQ(d.covered_one, 144u - 100u);
  EXPECT_NEAR(d.silhouette_displacement_px, std::sqrt(2.0), 1e-12);
  EXPECT_DOUBLE_EQ(d.mean_depth_difference, 0.5);
}

TEST(ImageMetrics, EmptyImages) {
  const Image empty = block(8, 8, 0, 0, 0, 0, 1.0f), some = block(8, 8, 2, 2, 4, 4, 1.0f);
  EXPECT_EQ(compare_images(empty, empty).silhouette_displacement_px, 0.0);
  EXPECT_EQ(compare_images(empty, empty).coverage_difference, 0.0);
  EXPECT_TRUE(std::isinf(compare_images(empty, some).silhouette_displacement_px));
  EXPECT_EQ(compare_images(empty, some).coverage_difference, 1.0);
  EXPECT_THROW(compare_images(empty, block(8, 9, 0, 0, 0, 0, 1.0f)), Error);
  Image no_depth = some;
  no_depth.depth.clear();
  EXPECT_THROW(compare_images(no_depth, some), Error);
}

TEST(ImageMetrics, IdenticalMeshesDoNotDiffer) {
  const Mesh torus = shapes::torus();
  RenderContext gl;
  const ViewsDifference d = compare_views(gl, torus, torus, {.views = 4, .width = 96, .height = 96});
  ASSERT_EQ(d.views.size(), 4u);
  ASSERT_EQ(d.cameras.size(), 4u);
  EXPECT_EQ(d.max_coverage_difference, 0.0);
  EXPECT_EQ(d.max_depth_difference, 0.0);
  EXPECT_EQ(d.max_silhouette_displacement_px, 0.0);
  for (const ImageDifference& v : d.views) EXPECT_GT(v.covered_both, 1000u);
}

// A unit sphere against the same sphere scaled by 0.95, orthographic: the outline moves by
// 0.05 * (pixels per unit) everywhere, and the annulus is 1 - 0.95^2 of the larger disc.
TEST(ImageMetrics, ScaledSphere) {
  const Mesh a = shapes::icosphere(5);
  Mesh b = a;
  for (float3& p : b.positions) p = {p.x * 0.95f, p.y * 0.95f, p.z * 0.95f};
  RenderContext gl;
  const uint32_t size = 400;
  const ViewsDifference d = compare_views(gl, a, b, {.views = 3, .width = size, .height = size, .orthographic = true});
  // fit_camera shows the bounding sphere's diameter (radius 1, rounded up in float) across the image.
  const double pixels_per_unit = size / 2.0;
  EXPECT_NEAR(d.max_silhouette_displacement_px, 0.05 * pixels_per_unit, 1.5);
  const double annulus = 1 - 0.95 * 0.95;
  for (const ImageDifference& v : d.views) {
    EXPECT_NEAR(v.coverage_difference, annulus, 0.01);
    EXPECT_NEAR(v.silhouette_displacement_px, 0.05 * pixels_per_unit, 1.5);
  }
  // The nearest points are 0.05 apart; towards b's outline the gap grows.
  EXPECT_GE(d.max_depth_difference, 0.05 - 1e-3);
  EXPECT_GT(d.mean_depth_difference, 0.05 - 1e-3);
}

}  // namespace
}  // namespace lod
