// The renderer on Mesa's llvmpipe (or any GL 4.5 driver): coverage, depth, shading, wireframe and
// heat-map colours against values derived by hand, and determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/measure.h"
#include "lodkit/render.h"
#include "lodkit/runtime.h"
#include "render/render_support.h"

namespace lod {
namespace {

using test::add_rectangle;
using test::srgb_byte;

constexpr double pi = 3.14159265358979323846;

RenderCamera front_ortho(double height, float distance = 5) {
  RenderCamera c;
  c.eye = {0, 0, distance};
  c.ortho_height = height;
  c.near = 1;
  c.far = 20;
  return c;
}

void expect_rgb(const Image& image, uint32_t x, uint32_t y, int r, int g, int b, int tolerance = 0) {
  const uint8_t* p = image.pixel(x, y);
  EXPECT_NEAR(p[0], r, tolerance) << "red at (" << x << ", " << y << ")";
  EXPECT_NEAR(p[1], g, tolerance) << "green at (" << x << ", " << y << ")";
  EXPECT_NEAR(p[2], b, tolerance) << "blue at (" << x << ", " << y << ")";
}

TEST(Render, ContextIsOpenGL45Core) {
  RenderContext gl;
  EXPECT_FALSE(gl.renderer().empty());
  EXPECT_NE(gl.version().find("4."), std::string::npos) << gl.version();
  EXPECT_GE(gl.max_samples(), 1u);
}

// A unit cube seen head-on in orthographic projection: 4 units over 200 rows is 50 pixels per unit,
// so the cube [-0.5, 0.5]^3 covers columns [125, 175) and rows [75, 125) of a 300x200 image.
TEST(Render, OrthographicCubeCoversTheExpectedSquare) {
  Mesh cube = shapes::cube();
  for (float3& p : cube.positions) p = {p.x / 2, p.y / 2, p.z / 2};
  RenderContext gl;
  for (uint32_t samples : {1u, 4u}) {
    const Image image = render(gl, cube, front_ortho(4), {.width = 300, .height = 200, .samples = samples});
    ASSERT_EQ(image.rgba.size(), 300u * 200 * 4);
    uint64_t wrong = 0;
    for (uint32_t y = 0; y < 200; ++y)
      for (uint32_t x = 0; x < 300; ++x) {
        const bool inside = x >= 126 && x <= 173 && y >= 76 && y <= 123;
        const bool outside = x <= 123 || x >= 176 || y <= 73 || y >= 126;  // one pixel of slack at each edge
        const bool background = image.pixel(x, y)[0] == 255;
        if ((inside && (background || !image.covered(x, y))) || (outside && (!background || image.covered(x, y)))) ++wrong;
      }
    EXPECT_EQ(wrong, 0u) << samples << " samples";
    // The front face (z = 0.5) is 4.5 from the eye; facing the headlight it shows the albedo exactly.
    EXPECT_NEAR(image.depth[100 * 300 + 150], 4.5f, 1e-4f);
    expect_rgb(image, 150, 100, srgb_byte(0.6), srgb_byte(0.6), srgb_byte(0.6), 1);
  }
  // Exact coverage without MSAA: 50 x 50 pixel centres.
  const Image image = render(gl, cube, front_ortho(4), {.width = 300, .height = 200, .samples = 1});
  uint64_t covered = 0;
  for (uint32_t y = 0; y < 200; ++y)
    for (uint32_t x = 0; x < 300; ++x) covered += image.covered(x, y);
  EXPECT_NEAR(double(covered), 2500.0, 2 * 50 + 2 * 50);
}

// The perspective camera follows the runtime's screen-space error: a length e at depth d spans
// e * H / (2 d tan(fov / 2)) pixels.
TEST(Render, PerspectiveSizeMatchesScreenSpaceError) {
  Mesh square;
  add_rectangle(square, -0.5f, -0.5f, 0.5f, 0.5f, 0);
  RenderCamera camera;
  camera.eye = {0, 0, 10};
  camera.fov = 40 * pi / 180;
  camera.near = 1;
  camera.far = 50;
  RenderContext gl;
  const Image image = render(gl, square, camera, {.width = 400, .height = 400, .samples = 1});
  uint32_t columns = 0, rows = 0;
  for (uint32_t x = 0; x < 400; ++x) columns += image.covered(x, 200);
  for (uint32_t y = 0; y < 400; ++y) rows += image.covered(200, y);
  const double expected = screen_space_error(1.0, 10.0, 400.0, camera.fov);  // 54.95 pixels
  EXPECT_NEAR(expected, 400 / (2 * 10 * std::tan(20 * pi / 180)), 1e-9);
  EXPECT_NEAR(columns, expected, 1.0);
  EXPECT_NEAR(rows, expected, 1.0);
  EXPECT_NEAR(image.depth[200 * 400 + 200], 10.0f, 1e-3f);
}

// A near red rectangle hides a far blue one, whichever is drawn first, in both projections.
TEST(Render, NearTriangleHidesFarOne) {
  const float4 red{1, 0, 0, 1}, blue{0, 0, 1, 1};
  RenderContext gl;
  for (bool near_first : {true, false}) {
    Mesh mesh;
    if (near_first) add_rectangle(mesh, -1, -1, 1, 1, 0, red);
    add_rectangle(mesh, -0.5f, -1, 1.5f, 1, -1, blue);
    if (!near_first) add_rectangle(mesh, -1, -1, 1, 1, 0, red);

    // Orthographic, 50 pixels per unit: red over columns [50, 150), blue over [75, 175).
    const Image ortho = render(gl, mesh, front_ortho(4), {.width = 200, .height = 200, .samples = 1});
    expect_rgb(ortho, 100, 100, 255, 0, 0);
    expect_rgb(ortho, 60, 100, 255, 0, 0);
    expect_rgb(ortho, 160, 100, 0, 0, 255);
    EXPECT_NEAR(ortho.depth[100 * 200 + 100], 5.0f, 1e-4f);
    EXPECT_NEAR(ortho.depth[100 * 200 + 160], 6.0f, 1e-4f);

    // Perspective from z = 5 with a 60 degree field: x = 100 + 173.2 x / (5 - z), so red covers
    // columns [65.4, 134.6] and blue [85.6, 143.3].
    RenderCamera camera;
    camera.eye = {0, 0, 5};
    camera.fov = 60 * pi / 180;
    camera.near = 0.5;
    camera.far = 20;
    const Image perspective = render(gl, mesh, camera, {.width = 200, .height = 200, .samples = 1});
    expect_rgb(perspective, 100, 100, 255, 0, 0);
    expect_rgb(perspective, 70, 100, 255, 0, 0);
    expect_rgb(perspective, 139, 100, 0, 0, 255);
    EXPECT_NEAR(perspective.depth[100 * 200 + 100], 5.0f, 1e-3f);
    EXPECT_NEAR(perspective.depth[100 * 200 + 139], 6.0f, 1e-3f);
  }
}

// Reversed float depth separates surfaces 1e-4 apart at distance 5 with a 1e5 far/near ratio.
TEST(Render, DepthIsPreciseOverAWideRange) {
  RenderContext gl;
  RenderCamera camera;
  camera.eye = {0, 0, 5};
  camera.near = 0.01;
  camera.far = 1000;
  for (bool near_first : {true, false}) {
    Mesh mesh;
    if (near_first) add_rectangle(mesh, -1, -1, 1, 1, 0, {1, 0, 0, 1});
    add_rectangle(mesh, -1, -1, 1, 1, -1e-4f, {0, 0, 1, 1});
    if (!near_first) add_rectangle(mesh, -1, -1, 1, 1, 0, {1, 0, 0, 1});
    const Image image = render(gl, mesh, camera, {.width = 64, .height = 64, .samples = 1});
    for (uint32_t y = 28; y < 36; ++y)
      for (uint32_t x = 28; x < 36; ++x) ASSERT_EQ(image.pixel(x, y)[0], 255) << near_first << " at " << x << "," << y;
  }
}

// Heat-map mode shows lod::heat_color exactly on faces turned to the camera.
TEST(Render, HeatmapColoursReadBack) {
  Mesh mesh;
  add_rectangle(mesh, -2, -1, -0.7f, 1, 0, heat_color(0));     // blue
  add_rectangle(mesh, -0.6f, -1, 0.6f, 1, 0, heat_color(0.5f));  // green
  add_rectangle(mesh, 0.7f, -1, 2, 1, 0, heat_color(1));        // red
  RenderContext gl;
  RenderOptions options{.width = 200, .height = 100, .heatmap = true};
  // 50 pixels per unit, x = 100 + 50 x.
  const Image image = render(gl, mesh, front_ortho(2), options);
  expect_rgb(image, 30, 50, 0, 0, 255);
  expect_rgb(image, 100, 50, 0, 255, 0);
  expect_rgb(image, 170, 50, 255, 0, 0);
  expect_rgb(image, 67, 50, 255, 255, 255);  // the gap between blue and green, x = -0.65
}

TEST(Render, HeatmapNeedsVertexColours) {
  RenderContext gl;
  try {
    render(gl, shapes::cube(), front_ortho(4), {.width = 32, .height = 32, .heatmap = true});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.category(), ErrorCategory::bad_input);
    EXPECT_NE(std::string(e.what()).find("no vertex colours"), std::string::npos) << e.what();
  }
}

// Lambert with a headlight: a face at 60 degrees to the view gets ambient + (1 - ambient) cos 60.
TEST(Render, LambertShadingFlatAndSmooth) {
  const double angle = 60 * pi / 180;
  Mesh tilted;
  const float c = float(std::cos(angle)), s = float(std::sin(angle));
  tilted.positions = {{-1, -c, -s}, {1, -c, -s}, {1, c, s}, {-1, c, s}};
  tilted.normals.assign(4, {0, -s, c});
  tilted.indices = {0, 1, 2, 0, 2, 3};
  const double expected = 0.6 * (0.2 + 0.8 * 0.5);
  RenderContext gl;
  for (Shading shading : {Shading::smooth, Shading::flat}) {
    const Image image = render(gl, tilted, front_ortho(4), {.width = 64, .height = 64, .shading = shading});
    expect_rgb(image, 32, 32, srgb_byte(expected), srgb_byte(expected), srgb_byte(expected), 1);
  }
  // Without normals they are computed (the plane's), with the same result.
  tilted.normals.clear();
  const Image image = render(gl, tilted, front_ortho(4), {.width = 64, .height = 64});
  expect_rgb(image, 32, 32, srgb_byte(expected), srgb_byte(expected), srgb_byte(expected), 1);
}

TEST(Render, ComputedNormalsMatchTheSphere) {
  Mesh with = shapes::icosphere(4);
  Mesh without = with;
  without.normals.clear();
  RenderContext gl;
  RenderCamera camera = front_ortho(2.5);
  const Image a = render(gl, with, camera, {.width = 128, .height = 128});
  const Image b = render(gl, without, camera, {.width = 128, .height = 128});
  double sum = 0;
  int worst = 0;
  for (size_t i = 0; i < a.rgba.size(); ++i) {
    const int d = std::abs(int(a.rgba[i]) - int(b.rgba[i]));
    sum += d;
    worst = std::max(worst, d);
  }
  EXPECT_LT(sum / double(a.rgba.size()), 1.0);
  EXPECT_LT(worst, 16);
}

// Wireframe: the edges of a triangle are dark, its inside keeps the shading.
TEST(Render, WireframeDrawsTheEdges) {
  Mesh triangle;
  triangle.positions = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
  triangle.indices = {0, 1, 2};
  RenderContext gl;
  // 50 pixels per unit: the bottom edge is row 150, the centroid (0, -1/3) near row 117.
  const RenderOptions plain{.width = 200, .height = 200, .samples = 1};
  RenderOptions wire = plain;
  wire.wireframe = true;
  const Image a = render(gl, triangle, front_ortho(4), plain);
  const Image b = render(gl, triangle, front_ortho(4), wire);
  const int albedo = srgb_byte(0.6);
  expect_rgb(a, 100, 149, albedo, albedo, albedo, 1);
  expect_rgb(b, 100, 117, albedo, albedo, albedo, 1);
  EXPECT_LT(b.pixel(100, 149)[0], 60);
  // The slanted edge from (1, -1) to (0, 1): its midpoint (0.5, 0) is at pixel (125, 100).
  EXPECT_LT(b.pixel(124, 100)[0], 100);
  EXPECT_EQ(b.pixel(110, 100)[0], a.pixel(110, 100)[0]);
}

// The same input gives the same bytes: twice in one context, and in a fresh context.
TEST(Render, DeterministicBytes) {
  Mesh mesh = shapes::torus(1.0f, 0.35f, 48, 24);
  mesh.colors.clear();
  for (const float3& p : mesh.positions) mesh.colors.push_back(heat_color(0.5f + 0.5f * p.x));
  const RenderCamera camera = fit_camera(bounding_sphere(mesh), view_direction("iso"), 4.0 / 3.0);
  const RenderOptions options{.width = 320, .height = 240, .samples = 4, .wireframe = true};
  std::string first;
  {
    RenderContext gl;
    const Image a = render(gl, mesh, camera, options);
    const Image b = render(gl, mesh, camera, options);
    EXPECT_TRUE(a.rgba == b.rgba);
    EXPECT_TRUE(a.depth == b.depth);
    first = encode_png(a);
    EXPECT_EQ(first, encode_png(b));
  }
  RenderContext gl;
  EXPECT_EQ(encode_png(render(gl, mesh, camera, options)), first);
}

// Contexts alive at once each draw their own meshes, and one outlives the other.
TEST(Render, TwoContextsAtOnce) {
  Mesh red, blue;
  add_rectangle(red, -1, -1, 1, 1, 0, {1, 0, 0, 1});
  add_rectangle(blue, -1, -1, 1, 1, 0, {0, 0, 1, 1});
  auto first = std::make_unique<RenderContext>();
  const GpuMesh red_mesh(*first, red);
  {
    RenderContext second;
    const GpuMesh blue_mesh(second, blue);
    const RenderOptions options{.width = 16, .height = 16};
    expect_rgb(render(*first, red_mesh, front_ortho(4), options), 8, 8, 255, 0, 0);
    expect_rgb(render(second, blue_mesh, front_ortho(4), options), 8, 8, 0, 0, 255);
    expect_rgb(render(*first, red_mesh, front_ortho(4), options), 8, 8, 255, 0, 0);
  }
  expect_rgb(render(*first, red_mesh, front_ortho(4), {.width = 16, .height = 16}), 8, 8, 255, 0, 0);
  RenderContext third;
  expect_rgb(render(third, blue, front_ortho(4), {.width = 16, .height = 16}), 8, 8, 0, 0, 255);
  expect_rgb(render(*first, red_mesh, front_ortho(4), {.width = 16, .height = 16}), 8, 8, 255, 0, 0);
}

TEST(Render, RejectsBadSizesAndCameras) {
  RenderContext gl;
  const Mesh cube = shapes::cube();
  auto category = [&](const RenderCamera& camera, const RenderOptions& options) {
    try {
      render(gl, cube, camera, options);
    } catch (const Error& e) {
      return e.category();
    }
    return ErrorCategory::internal;
  };
  EXPECT_EQ(category(front_ortho(4), {.width = 0, .height = 10}), ErrorCategory::usage);
  EXPECT_EQ(category(front_ortho(4), {.width = 1u << 30, .height = 10}), ErrorCategory::usage);
  RenderCamera same = front_ortho(4);
  same.target = same.eye;
  EXPECT_EQ(category(same, {.width = 8, .height = 8}), ErrorCategory::usage);
  RenderCamera parallel = front_ortho(4);
  parallel.up = {0, 0, 1};
  EXPECT_EQ(category(parallel, {.width = 8, .height = 8}), ErrorCategory::usage);
  Mesh broken = cube;
  broken.indices[0] = 1000;
  EXPECT_THROW(render(gl, broken, front_ortho(4), {.width = 8, .height = 8}), Error);
}

}  // namespace
}  // namespace lod
