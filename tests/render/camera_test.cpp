// Cameras: named views, fitting a sphere, turntables and projection, against hand-derived values.
#include <gtest/gtest.h>

#include <cmath>

#include "lodkit/error.h"
#include "lodkit/render.h"

namespace lod {
namespace {

constexpr double pi = 3.14159265358979323846;

double distance(const float3& a, const float3& b) {
  return std::sqrt(double(a.x - b.x) * (a.x - b.x) + double(a.y - b.y) * (a.y - b.y) + double(a.z - b.z) * (a.z - b.z));
}

TEST(Camera, NamedViews) {
  EXPECT_EQ(view_direction("front"), (float3{0, 0, 1}));
  EXPECT_EQ(view_direction("back"), (float3{0, 0, -1}));
  EXPECT_EQ(view_direction("left"), (float3{-1, 0, 0}));
  EXPECT_EQ(view_direction("right"), (float3{1, 0, 0}));
  EXPECT_EQ(view_direction("top"), (float3{0, 1, 0}));
  EXPECT_EQ(view_direction("bottom"), (float3{0, -1, 0}));
  EXPECT_EQ(view_direction("iso"), (float3{1, 1, 1}));
  EXPECT_EQ(view_direction("iso-back-left-below"), (float3{-1, -1, -1}));
  EXPECT_EQ(view_direction("1,2,-3"), (float3{1, 2, -3}));
  EXPECT_EQ(view_names().size(), 15u);
  for (const char* bad : {"", "sideways", "0,0,0", "1,2", "1,2,3,4", "nan,0,1"}) {
    try {
      view_direction(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const Error& e) {
      EXPECT_EQ(e.category(), ErrorCategory::usage);
    }
  }
}

// A unit sphere with a 90 degree field of view on a square image: the eye is 1 / sin(45 deg) away.
TEST(Camera, FitTouchesTheSphere) {
  const BoundingSphere sphere{{1, 2, 3}, 1};
  const RenderCamera c = fit_camera(sphere, {0, 0, 2}, 1.0, pi / 2);
  EXPECT_NEAR(distance(c.eye, sphere.center), std::sqrt(2.0), 1e-5);
  EXPECT_NEAR(c.eye.z - 3, std::sqrt(2.0), 1e-5);
  EXPECT_EQ(c.target, sphere.center);
  EXPECT_LE(c.near, std::sqrt(2.0) - 1);
  EXPECT_GE(c.far, std::sqrt(2.0) + 1);
  // A wide image: the vertical field is the narrower one, so the same distance.
  EXPECT_NEAR(distance(fit_camera(sphere, {0, 0, 1}, 2.0, pi / 2).eye, sphere.center), std::sqrt(2.0), 1e-5);
  // A tall image (aspect 1/2): the horizontal half-angle is atan(tan(45 deg) / 2).
  EXPECT_NEAR(distance(fit_camera(sphere, {0, 0, 1}, 0.5, pi / 2).eye, sphere.center), 1 / std::sin(std::atan(0.5)), 1e-4);
  // The sphere's silhouette touches the top and bottom of the image: a point on the sphere at
  // angle asin(r/d) from the axis projects onto the border.
  const RenderCamera square = fit_camera(sphere, {0, 0, 1}, 1.0, pi / 2);
  const double d = std::sqrt(2.0), tangent_z = 1 / d;  // the tangent circle's plane, from the centre
  const float3 tangent{1, float(2 + std::sqrt(1 - tangent_z * tangent_z)), float(3 + tangent_z)};
  EXPECT_NEAR(project(square, 100, 100, tangent).y, 0.0, 1e-3);
  // Orthographic: the diameter across the smaller side.
  EXPECT_NEAR(fit_camera(sphere, {1, 0, 0}, 2.0, pi / 2, true).ortho_height, 2.0, 1e-6);
  EXPECT_NEAR(fit_camera(sphere, {1, 0, 0}, 0.5, pi / 2, true).ortho_height, 4.0, 1e-6);
}

TEST(Camera, TopViewKeepsTheFrontDown) {
  const RenderCamera c = fit_camera({{0, 0, 0}, 1}, view_direction("top"), 1.0);
  // From above, a point in front (+z) is in the lower half of the image, one on the right (+x) on the right.
  EXPECT_GT(project(c, 100, 100, {0, 0, 0.5f}).y, 50);
  EXPECT_GT(project(c, 100, 100, {0.5f, 0, 0}).x, 50);
}

TEST(Camera, ProjectCentreAndDepth) {
  RenderCamera c;
  c.eye = {0, 0, 5};
  c.fov = pi / 2;
  const float3 centre = project(c, 200, 100, {0, 0, 0});
  EXPECT_NEAR(centre.x, 100, 1e-4);
  EXPECT_NEAR(centre.y, 50, 1e-4);
  EXPECT_NEAR(centre.z, 5, 1e-5);
  // tan(45 deg) = 1: at depth 5, y = 5 is the top edge; x = 5 is half-way to the right edge on a 2:1 image.
  EXPECT_NEAR(project(c, 200, 100, {0, 5, 0}).y, 0, 1e-3);
  EXPECT_NEAR(project(c, 200, 100, {5, 0, 0}).x, 150, 1e-3);
}

TEST(Camera, Turntable) {
  const BoundingSphere sphere{{0, 1, 0}, 2};
  const RenderCamera first = turntable_camera(sphere, 0, 4, 1.0, 0.0);
  const RenderCamera front = fit_camera(sphere, {0, 0, 1}, 1.0);
  EXPECT_EQ(first.eye, front.eye);
  const RenderCamera quarter = turntable_camera(sphere, 1, 4, 1.0, 0.0);
  EXPECT_NEAR(quarter.eye.x, distance(front.eye, sphere.center), 1e-4);
  EXPECT_NEAR(quarter.eye.z, 0, 1e-4);
  // 30 degrees up: the eye's height over the centre is sin(30 deg) of the distance.
  const RenderCamera raised = turntable_camera(sphere, 3, 8, 1.0, pi / 6);
  EXPECT_NEAR(raised.eye.y - 1, 0.5 * distance(raised.eye, sphere.center), 1e-4);
  EXPECT_THROW(turntable_camera(sphere, 4, 4, 1.0), Error);
  EXPECT_THROW(turntable_camera(sphere, 0, 0, 1.0), Error);
}

TEST(Camera, SphereDirectionsAreUnitAndSpread) {
  const std::vector<float3> d = sphere_directions(64);
  ASSERT_EQ(d.size(), 64u);
  double sx = 0, sy = 0, sz = 0, closest = 4;
  for (size_t i = 0; i < d.size(); ++i) {
    EXPECT_NEAR(distance(d[i], {0, 0, 0}), 1.0, 1e-5);
    sx += d[i].x, sy += d[i].y, sz += d[i].z;
    for (size_t j = 0; j < i; ++j) closest = std::min(closest, distance(d[i], d[j]));
  }
  EXPECT_LT(std::sqrt(sx * sx + sy * sy + sz * sz) / 64, 0.05);  // balanced
  EXPECT_GT(closest, 0.2);  // no two nearly equal (an even spread of 64 is ~0.44 apart)
}

}  // namespace
}  // namespace lod
