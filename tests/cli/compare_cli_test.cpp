// lodkit compare from the command line: the report is the library's result, the heat map reads back
// with the hottest colour at the maximum, and bad input or a heat map over an input is refused.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "core/shapes.h"
#include "lodkit/io.h"
#include "lodkit/measure.h"
#include "test_support.h"

namespace lod {
namespace {

TEST(CliCompare, JsonIsTheLibraryResultAndTheHeatmapReadsBack) {
  test::TempDir dir;
  write_mesh(shapes::icosphere(3), dir / "a.ply");
  write_mesh(shapes::torus(0.8f, 0.3f, 12, 8), dir / "b.obj");
  const test::RunResult r = test::run_cli({"compare", (dir / "a.ply").string(), (dir / "b.obj").string(), "--samples",
                                           "20000", "--seed", "5", "--json", "--heatmap", (dir / "heat.ply").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);

  const Mesh a = read_mesh(dir / "a.ply"), b = read_mesh(dir / "b.obj");
  const Deviation d = compare(a, b, {.samples = 20'000, .seed = 5});
  EXPECT_EQ(j["a_to_b"]["hausdorff"].get<double>(), d.a_to_b.max);
  EXPECT_EQ(j["a_to_b"]["mean"].get<double>(), d.a_to_b.mean);
  EXPECT_EQ(j["a_to_b"]["rms"].get<double>(), d.a_to_b.rms);
  EXPECT_EQ(j["b_to_a"]["hausdorff"].get<double>(), d.b_to_a.max);
  EXPECT_EQ(j["symmetric"]["hausdorff"].get<double>(), d.hausdorff);
  EXPECT_EQ(j["symmetric"]["rms"].get<double>(), d.rms);
  EXPECT_EQ(j["symmetric"]["relative_hausdorff"].get<double>(), d.relative_hausdorff);
  EXPECT_EQ(j["diagonal"].get<double>(), d.diagonal);
  EXPECT_EQ(j["a_to_b"]["samples"]["total"].get<uint64_t>(), d.a_to_b.samples());
  EXPECT_EQ(j["a_to_b"]["samples"]["vertex"].get<uint64_t>(), a.vertex_count());
  EXPECT_EQ(j["a_triangles"].get<uint64_t>(), a.triangle_count());
  EXPECT_TRUE(j["a_to_b"]["attributes"].contains("normal_angle_degrees"));
  EXPECT_EQ(j["heatmap"]["scale"].get<double>(), d.a_to_b.max);
  EXPECT_EQ(j["heatmap"]["ramp"].size(), 5u);

  // The heat map is a with colours on the ramp; the vertex nearest the maximum is the hottest.
  const Mesh heat = read_mesh(dir / "heat.ply");
  ASSERT_EQ(heat.positions, a.positions);
  ASSERT_EQ(heat.indices, a.indices);
  ASSERT_EQ(heat.colors.size(), a.vertex_count());
  const auto& p = j["a_to_b"]["max_point"];
  const float3 at{p[0].get<float>(), p[1].get<float>(), p[2].get<float>()};
  size_t nearest = 0;
  float nearest_distance = 1e30f;
  for (size_t v = 0; v < heat.positions.size(); ++v) {
    const float dx = heat.positions[v].x - at.x, dy = heat.positions[v].y - at.y, dz = heat.positions[v].z - at.z;
    if (dx * dx + dy * dy + dz * dz < nearest_distance) nearest_distance = dx * dx + dy * dy + dz * dz, nearest = v;
  }
  EXPECT_EQ(heat.colors[nearest], (float4{1, 0, 0, 1}));
  for (size_t v = 0; v < heat.colors.size(); ++v) EXPECT_EQ(heat.colors[v], heat_color(d.vertex_error[v] / float(d.a_to_b.max)));

  // glTF: the same colours through COLOR_0.
  const test::RunResult g = test::run_cli({"compare", (dir / "a.ply").string(), (dir / "b.obj").string(), "--samples",
                                           "20000", "--seed", "5", "--heatmap", (dir / "heat.glb").string()});
  ASSERT_EQ(g.exit_code, 0) << g.err;
  EXPECT_EQ(read_mesh(dir / "heat.glb").colors, heat.colors);
  // The table: three rows with the same numbers.
  EXPECT_NE(g.out.find("a -> b"), std::string::npos) << g.out;
  EXPECT_NE(g.out.find("b -> a"), std::string::npos);
  EXPECT_NE(g.out.find("symmetric"), std::string::npos);
  EXPECT_NE(g.out.find("Hausdorff%"), std::string::npos);
}

// The acceptance case: the bunny against itself simplified to 1%, heat maps in PLY and glTF.
TEST(CliCompare, BunnyHeatmapIsHottestAtTheMaximum) {
  const auto corpus = test::corpus_dir();
  if (corpus.empty()) GTEST_SKIP() << "corpus absent (scripts/fetch-corpus.sh)";
  test::TempDir dir;
  const std::string bunny = (corpus / "bunny00.off").string();
  ASSERT_EQ(test::run_cli({"simplify", bunny, "-o", (dir / "lod.ply").string(), "--ratio", "0.01"}).exit_code, 0);
  const test::RunResult r = test::run_cli({"compare", bunny, (dir / "lod.ply").string(), "--samples", "200000",
                                           "--json", "--heatmap", (dir / "heat.ply").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(test::run_cli({"compare", bunny, (dir / "lod.ply").string(), "--samples", "200000", "--heatmap",
                           (dir / "heat.gltf").string()})
                .exit_code,
            0);
  const Mesh a = read_mesh(bunny), ply = read_mesh(dir / "heat.ply"), gltf = read_mesh(dir / "heat.gltf");
  ASSERT_EQ(ply.colors.size(), a.vertex_count());
  EXPECT_EQ(gltf.colors, ply.colors);
  const auto& p = j["a_to_b"]["max_point"];
  const float x = p[0].get<float>(), y = p[1].get<float>(), z = p[2].get<float>();
  size_t nearest = 0;
  float best = 1e30f;
  for (size_t v = 0; v < a.vertex_count(); ++v) {
    const float dx = a.positions[v].x - x, dy = a.positions[v].y - y, dz = a.positions[v].z - z;
    if (dx * dx + dy * dy + dz * dz < best) best = dx * dx + dy * dy + dz * dz, nearest = v;
  }
  EXPECT_EQ(ply.colors[nearest], (float4{1, 0, 0, 1}));
  // Most of the bunny is close to its LOD: cool colours dominate.
  size_t hot = 0;
  for (const float4& c : ply.colors) hot += c.x > 0.5f;
  EXPECT_LT(hot, a.vertex_count() / 4);
}

TEST(CliCompare, RefineReportsABound) {
  test::TempDir dir;
  write_mesh(shapes::icosphere(2), dir / "a.off");
  write_mesh(shapes::icosphere(1), dir / "b.off");
  const test::RunResult r =
      test::run_cli({"compare", (dir / "a.off").string(), (dir / "b.off").string(), "--refine", "--json", "--threads", "2"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_GE(j["symmetric"]["hausdorff_bound"].get<double>(), j["symmetric"]["hausdorff"].get<double>());
  EXPECT_GE(j["a_to_b"]["hausdorff_bound"].get<double>(), j["a_to_b"]["hausdorff"].get<double>());
}

TEST(CliCompare, BadInputAndHeatmapOverAnInputAreRefused) {
  test::TempDir dir;
  write_mesh(shapes::icosphere(1), dir / "a.ply");
  const std::string a = (dir / "a.ply").string();
  test::write_text(dir / "bad.obj", "v 0 0 0\nf 1 2 3\n");
  test::RunResult r = test::run_cli({"compare", a, (dir / "bad.obj").string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("bad.obj"), std::string::npos) << r.err;
  r = test::run_cli({"compare", a, (dir / "missing.ply").string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  // A mesh with points but no triangles.
  test::write_text(dir / "points.obj", "v 0 0 0\nv 1 0 0\n");
  r = test::run_cli({"compare", (dir / "points.obj").string(), a});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("no triangles"), std::string::npos) << r.err;

  const Mesh before = read_mesh(a);
  r = test::run_cli({"compare", a, a, "--heatmap", a});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(read_mesh(a), before);
  r = test::run_cli({"compare", a, a, "--heatmap", (dir / "heat.stl").string()});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  r = test::run_cli({"compare", a});
  EXPECT_EQ(r.exit_code, 1) << r.err;
}

}  // namespace
}  // namespace lod
