// lodkit render end to end: single images, heat maps from lodkit compare, contact sheets of a
// lodkit lod chain, turntables, determinism across processes, and the missing-driver path.
#include <gtest/gtest.h>
#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/shapes.h"
#include "io/lod_chain_scene.h"
#include "lodkit/io.h"
#include "lodkit/render.h"
#include "render/render_support.h"
#include "lodkit/skin.h"
#include "skin/fixtures.h"
#include "test_support.h"

namespace lod {
namespace {

using test::run_cli;

TEST(RenderCli, WritesThePictureAtTheRequestedSize) {
  test::TempDir dir;
  write_mesh(shapes::torus(), dir / "torus.ply");
  const auto r = run_cli({"render", (dir / "torus.ply").string(), "-o", (dir / "t.png").string(), "--size", "320x200",
                          "--view", "front", "--wire", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["triangles"], shapes::torus().triangle_count());
  EXPECT_EQ(j["width"], 320);
  const Image image = read_png(dir / "t.png");
  EXPECT_EQ(image.width, 320u);
  EXPECT_EQ(image.height, 200u);
  // The torus (around +z, seen from the front) leaves its hole and the corners white, its ring drawn.
  EXPECT_EQ(image.pixel(160, 100)[0], 255);
  EXPECT_EQ(image.pixel(2, 2)[0], 255);
  uint32_t drawn = 0;
  for (size_t i = 0; i < image.rgba.size(); i += 4) drawn += image.rgba[i] < 250;
  EXPECT_GT(drawn, 320u * 200 / 10);
}

// Two processes, the same bytes.
TEST(RenderCli, Deterministic) {
  test::TempDir dir;
  write_mesh(shapes::icosphere(3), dir / "sphere.obj");
  for (const char* name : {"a.png", "b.png"}) {
    const auto r = run_cli({"render", (dir / "sphere.obj").string(), "-o", (dir / name).string(), "--size", "256x192",
                            "--wire", "--flat"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  const std::string a = test::read_bytes(dir / "a.png"), b = test::read_bytes(dir / "b.png");
  EXPECT_GT(a.size(), 1000u);
  EXPECT_EQ(a, b);
}

// lodkit compare --heatmap colours A by its distance to B; lodkit render --heatmap shows them. Here
// the left part of A lies on B (distance 0: blue) and the right part 0.1 from it (the maximum: red).
TEST(RenderCli, HeatmapFromCompareReadsBackAtTheExpectedPixels) {
  test::TempDir dir;
  Mesh a, b;
  test::add_rectangle(a, -1, -0.5f, -0.1f, 0.5f, 0);
  test::add_rectangle(a, 0.1f, -0.5f, 1, 0.5f, 0);
  test::add_rectangle(b, -1, -0.5f, -0.1f, 0.5f, 0);
  test::add_rectangle(b, 0.1f, -0.5f, 1, 0.5f, -0.1f);
  write_mesh(a, dir / "a.ply");
  write_mesh(b, dir / "b.ply");
  auto r = run_cli({"compare", (dir / "a.ply").string(), (dir / "b.ply").string(), "--heatmap", (dir / "heat.ply").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli({"render", (dir / "heat.ply").string(), "-o", (dir / "heat.png").string(), "--heatmap", "--view", "front",
               "--ortho", "--size", "400x400"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Image image = read_png(dir / "heat.png");
  // The rectangles fill x in [-1, 1] around the image centre: x = 0.55 is at a quarter of the width
  // from either side whatever the scale, inside each rectangle (they cover |x| >= 0.1).
  const uint8_t* left = image.pixel(100, 200);
  const uint8_t* right = image.pixel(300, 200);
  EXPECT_EQ(int(left[0]), 0);
  EXPECT_EQ(int(left[1]), 0);
  EXPECT_EQ(int(left[2]), 255);
  EXPECT_EQ(int(right[0]), 255);
  EXPECT_EQ(int(right[1]), 0);
  EXPECT_EQ(int(right[2]), 0);
  // Without colours --heatmap is bad input.
  r = run_cli({"render", (dir / "b.ply").string(), "-o", (dir / "x.png").string(), "--heatmap"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
}

// A chain written the way lodkit lod writes one (MSFT_lod on the first node, lodkit.error and
// relative_error in each node's extras), built by hand so the labels' numbers are known.
TEST(RenderCli, ContactSheetOfALodChain) {
  test::TempDir dir;
  const Scene chain = test::lod_chain_scene({shapes::icosphere(3), shapes::icosphere(2), shapes::icosphere(1)},
                                            {R"({"lodkit":{"error":0,"relative_error":0}})",
                                             R"({"lodkit":{"error":0.0125,"relative_error":0.0036}})",
                                             R"({"lodkit":{"error":0.05,"relative_error":0.0144}})"});
  write_scene(chain, dir / "chain.glb");
  auto r = run_cli({"render", (dir / "chain.glb").string(), "--sheet", "-o", (dir / "sheet.png").string(), "--size",
                    "600x300", "--columns", "3", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["panels"].size(), 3u);
  const char* labels[3] = {"LOD0: 1,280 triangles, error 0 (0%)", "LOD1: 320 triangles, error 0.0125 (0.36%)",
                           "LOD2: 80 triangles, error 0.05 (1.4%)"};
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(j["panels"][i]["label"], labels[i]);
  const Image sheet = read_png(dir / "sheet.png");
  ASSERT_EQ(sheet.width, 600u);
  ASSERT_EQ(sheet.height, 300u);
  const SheetLayout layout = sheet_layout(3, {.width = 600, .height = 300, .columns = 3});
  for (uint32_t k = 0; k < 3; ++k) {
    // The sphere is drawn in the middle of each panel; its label under it.
    const uint8_t* centre = sheet.pixel(k * 200 + 100, layout.panel_height / 2);
    EXPECT_LT(centre[0], 250) << "panel " << k;
    uint32_t dark = 0;
    for (uint32_t y = layout.panel_height; y < 300; ++y)
      for (uint32_t x = k * 200; x < k * 200 + 200; ++x) dark += sheet.pixel(x, y)[0] < 100;
    EXPECT_GT(dark, 20u) << "label " << k;
  }
  // Not a chain: clean errors.
  write_mesh(shapes::icosphere(1), dir / "sphere.ply");
  r = run_cli({"render", (dir / "sphere.ply").string(), "--sheet", "-o", (dir / "x.png").string()});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  write_mesh(shapes::cube(), dir / "cube.glb");
  r = run_cli({"render", (dir / "cube.glb").string(), "--sheet", "-o", (dir / "x.png").string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("MSFT_lod"), std::string::npos) << r.err;
}

// A file with two chains: a sphere's, and a cube's (then an icosahedron's) drawn by 5 instances
// under a node named "crates". --chain picks by index or by name (the instanced node's, or its LOD0's); an instanced
// level is drawn once, its instance count in the label; an unknown chain is a usage error that
// lists them.
TEST(RenderCli, SheetPicksOneOfSeveralChains) {
  test::TempDir dir;
  Scene scene = test::lod_chain_scene({shapes::icosphere(2), shapes::icosphere(1)}, {"", ""});
  Node crates;
  crates.name = "crates";
  crates.translation = {10, 0, 0};
  scene.nodes.push_back(crates);
  scene.roots.push_back(2);
  for (uint32_t i = 0; i < 2; ++i) {
    Primitive prim;
    prim.mesh = i == 0 ? shapes::cube() : shapes::icosphere(0);
    prim.gltf_mesh = 2 + i;
    scene.primitives.push_back(prim);
    Node level;
    level.name = fmt::format("crates_LOD{}", i);
    level.mesh = int32_t(2 + i);
    for (int k = 0; k < 5; ++k) level.gpu_instances.push_back({.translation = {float(3 * k), 0, 0}});
    if (i == 0) level.parent = 2, level.lod_ids = {4};
    scene.nodes.push_back(level);
  }
  scene.nodes[2].children = {3};
  write_scene(scene, dir / "two.glb");
  const auto panels = [&](const std::string& chain) {
    const test::RunResult r = run_cli({"render", (dir / "two.glb").string(), "--sheet", "-o", (dir / "s.png").string(),
                                       "--size", "200x100", "--json", "--chain", chain});
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out.empty() ? "{}" : r.out)["panels"];
  };
  EXPECT_EQ(panels("0")[1]["triangles"], shapes::icosphere(1).triangle_count());
  for (const char* name : {"1", "crates", "crates_LOD0"}) {
    const nlohmann::json p = panels(name);
    ASSERT_EQ(p.size(), 2u) << name;
    EXPECT_EQ(p[0]["triangles"], shapes::cube().triangle_count()) << name;  // one instance
    EXPECT_EQ(p[1]["label"], "LOD1: 20 triangles x 5 instances") << name;
  }
  const test::RunResult bad = run_cli({"render", (dir / "two.glb").string(), "--sheet", "-o", (dir / "s.png").string(), "--chain", "barrels"});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("2 chains: 0 (''"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("1 ('crates_LOD0', 'crates')"), std::string::npos) << bad.err;
}

// A skinned chain posed mid-animation: both panels draw the same skinned mesh (LOD1 is a copy of
// LOD0, so no simplifier runs under this suite's leak checker), so the two halves match pixel for
// pixel, and the posed character covers other pixels than the one in its bind pose. LOD1's copy is
// in two primitives (materials, fixtures::halves_by_x), each posed.
TEST(RenderCli, SkinnedSheetIsPosedByTheClip) {
  test::TempDir dir;
  Scene scene = fixtures::humanoid_scene();
  const std::vector<SkinnedPrimitive> skinned = skinned_primitives(scene);
  ASSERT_EQ(skinned.size(), 1u);
  Primitive copy = scene.primitives[skinned[0].primitive];
  copy.gltf_mesh = 1;
  for (const Primitive& p : scene.primitives) copy.gltf_mesh = std::max(copy.gltf_mesh, p.gltf_mesh + 1);
  const std::array<Mesh, 2> halves = fixtures::halves_by_x(copy.mesh);
  for (uint32_t h = 0; h < 2; ++h) {
    copy.mesh = halves[h], copy.gltf_primitive = h;
    scene.primitives.push_back(copy);
  }
  Node lod1;
  lod1.name = "LOD1";
  lod1.mesh = int32_t(copy.gltf_mesh);
  lod1.skin = int32_t(skinned[0].skin);
  scene.nodes.push_back(lod1);
  scene.nodes[skinned[0].node].lod_ids = {int32_t(scene.nodes.size() - 1)};
  write_scene(scene, dir / "chain.glb");

  auto render = [&](const std::vector<std::string>& extra, const std::string& name) {
    std::vector<std::string> args = {"render", (dir / "chain.glb").string(), "--sheet", "--size", "400x240",
                                     "--view", "left", "-o", (dir / name).string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return read_png(dir / name);
  };
  const Image posed = render({"--clip", "walk", "--time", "0.3"}, "posed.png");
  const Image rest = render({}, "rest.png");
  const Image by_index = render({"--clip", "0", "--time", "0.3"}, "index.png");
  ASSERT_EQ(posed.width, 400u);
  const uint32_t panel_height = sheet_layout(2, {.width = 400, .height = 240}).panel_height;
  uint32_t differ_halves = 0, differ_rest = 0;
  for (uint32_t y = 0; y < panel_height; ++y)
    for (uint32_t x = 4; x < 196; ++x) {  // inside the panels (a rule separates them)
      differ_halves += std::memcmp(posed.pixel(x, y), posed.pixel(x + 200, y), 3) != 0;
      differ_rest += std::memcmp(posed.pixel(x, y), rest.pixel(x, y), 3) != 0;
    }
  EXPECT_EQ(differ_halves, 0u);
  EXPECT_GT(differ_rest, 500u);  // the walk swings the legs and arms
  EXPECT_EQ(posed.rgba, by_index.rgba);
  // --clip needs a sheet and an animation that exists.
  EXPECT_EQ(run_cli({"render", (dir / "chain.glb").string(), "--clip", "walk", "-o", (dir / "x.png").string()}).exit_code, 1);
  EXPECT_EQ(run_cli({"render", (dir / "chain.glb").string(), "--sheet", "--clip", "dance", "-o", (dir / "x.png").string()})
                .exit_code,
            1);
}

// Frame 0 of a level turntable is the front view.
TEST(RenderCli, TurntableFrames) {
  test::TempDir dir;
  write_mesh(shapes::torus(1.0f, 0.3f), dir / "torus.ply");
  auto r = run_cli({"render", (dir / "torus.ply").string(), "--turntable", "4", "--elevation", "0", "-o",
                    (dir / "frames").string(), "--size", "160x120"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* name : {"frame-000.png", "frame-001.png", "frame-002.png", "frame-003.png"})
    EXPECT_TRUE(std::filesystem::exists(dir / "frames" / name)) << name;
  EXPECT_FALSE(std::filesystem::exists(dir / "frames" / "frame-004.png"));
  r = run_cli({"render", (dir / "torus.ply").string(), "--view", "front", "-o", (dir / "front.png").string(), "--size",
               "160x120"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(test::read_bytes(dir / "frames" / "frame-000.png"), test::read_bytes(dir / "front.png"));
  EXPECT_NE(test::read_bytes(dir / "frames" / "frame-000.png"), test::read_bytes(dir / "frames" / "frame-001.png"));
}

TEST(RenderCli, UsageAndInputErrors) {
  test::TempDir dir;
  write_mesh(shapes::cube(), dir / "cube.ply");
  const std::string in = (dir / "cube.ply").string(), out = (dir / "o.png").string();
  EXPECT_EQ(run_cli({"render", in, "-o", (dir / "o.jpg").string()}).exit_code, 1);
  EXPECT_EQ(run_cli({"render", in, "-o", out, "--size", "12"}).exit_code, 1);
  EXPECT_EQ(run_cli({"render", in, "-o", out, "--size", "0x10"}).exit_code, 1);
  EXPECT_EQ(run_cli({"render", in, "-o", out, "--view", "sideways"}).exit_code, 1);
  EXPECT_EQ(run_cli({"render", in, "-o", out, "--fov", "180"}).exit_code, 1);
  EXPECT_EQ(run_cli({"render", in, "-o", out, "--sheet", "--turntable", "3"}).exit_code, 1);
  EXPECT_EQ(run_cli({"render", (dir / "missing.ply").string(), "-o", out}).exit_code, 2);
  test::write_text(dir / "bad.obj", "v 0 0 0\nf 1 2 3\n");
  const auto r = run_cli({"render", (dir / "bad.obj").string(), "-o", out});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bad.obj"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out));
}

// With glvnd's EGL vendor list pointing nowhere there is no driver: one clear line, exit code 2.
TEST(RenderCli, MissingDriverIsACleanError) {
  test::TempDir dir;
  write_mesh(shapes::cube(), dir / "cube.ply");
  const char* old = std::getenv("__EGL_VENDOR_LIBRARY_FILENAMES");
  const std::string saved = old ? old : "";
  setenv("__EGL_VENDOR_LIBRARY_FILENAMES", "/nonexistent/egl_vendor.json", 1);
  const auto r = run_cli({"render", (dir / "cube.ply").string(), "-o", (dir / "x.png").string()});
  if (old)
    setenv("__EGL_VENDOR_LIBRARY_FILENAMES", saved.c_str(), 1);
  else
    unsetenv("__EGL_VENDOR_LIBRARY_FILENAMES");
  EXPECT_EQ(r.signal, 0);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("lodkit: error: OpenGL: no EGL driver", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
}

}  // namespace
}  // namespace lod
