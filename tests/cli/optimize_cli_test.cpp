// lodkit optimize and lodkit analyze from the command line: the written file is the library's result,
// the reports agree with it, a Möbius strip is a warning, bad options are usage errors.
#include <gtest/gtest.h>

#include <array>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>

#include "core/shapes.h"
#include "lodkit/io.h"
#include "lodkit/optimize.h"
#include "optimize/optimize_test_support.h"
#include "test_support.h"

namespace lod {
namespace {

TEST(CliOptimize, WeldsOrientsAndWritesTheLibraryResult) {
  test::TempDir dir;
  const Mesh torus = shapes::torus(1.0f, 0.3f, 24, 12);
  Mesh broken = torus;
  for (size_t t = 0; t < broken.triangle_count(); t += 2) std::swap(broken.indices[3 * t + 1], broken.indices[3 * t + 2]);
  broken = test::triangle_soup(broken);
  write_mesh(broken, dir / "soup.ply");
  const test::RunResult r = test::run_cli(
      {"optimize", (dir / "soup.ply").string(), "-o", (dir / "out.ply").string(), "--weld", "--orient", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const Mesh out = read_mesh(dir / "out.ply");
  EXPECT_EQ(j["output_triangles"], out.triangle_count());
  EXPECT_EQ(j["output_vertices"], out.vertex_count());
  EXPECT_EQ(out.vertex_count(), torus.vertex_count());  // the soup welds back (seam copies keep their UVs)
  EXPECT_EQ(j["orient"]["flipped_triangles"], torus.triangle_count() / 2);
  EXPECT_EQ(j["orient"]["non_orientable_components"], 0);
  EXPECT_LT(j["acmr_after"].get<double>(), j["acmr_before"].get<double>());
  EXPECT_EQ(test::position_triangles(out), test::position_triangles(torus));
  // The same call through the library gives the same mesh (the PLY round trip is exact).
  const OptimizeResult lib = optimize(read_mesh(dir / "soup.ply"), {.weld = true, .orient = true});
  EXPECT_EQ(lib.mesh.indices, out.indices);
  EXPECT_EQ(lib.mesh.positions, out.positions);
}

// Two unit squares side by side as a triangle soup (12 vertices, one normal), with a morph target
// that opens a crease between them: a copy moves down on the left square, up on the right. A weld
// joins copies whose targets agree (4 vertices per square), never a left copy with a right one at
// the shared edge, even by position alone, so each vertex keeps its own offset.
TEST(CliOptimize, WeldKeepsVerticesWhoseMorphTargetsDiffer) {
  test::TempDir dir;
  Mesh squares;
  for (const float x0 : {0.0f, 1.0f})
    for (const auto& tri : {std::array<float3, 3>{{{x0, 0, 0}, {x0 + 1, 0, 0}, {x0 + 1, 1, 0}}},
                            std::array<float3, 3>{{{x0, 0, 0}, {x0 + 1, 1, 0}, {x0, 1, 0}}}})
      for (const float3& p : tri) {
        squares.indices.push_back(uint32_t(squares.positions.size()));
        squares.positions.push_back(p);
        squares.normals.push_back({0, 0, 1});
      }
  // Which square a vertex belongs to, from the triangles that use it (centroid left or right of x = 1).
  const auto offsets_by_square = [](const Mesh& m) {
    std::vector<float3> expected(m.vertex_count());
    for (size_t t = 0; t < m.triangle_count(); ++t) {
      float x = 0;
      for (int c = 0; c < 3; ++c) x += m.positions[m.indices[3 * t + c]].x;
      for (int c = 0; c < 3; ++c) expected[m.indices[3 * t + c]] = {0, 0, x < 3 ? -0.5f : 0.5f};
    }
    return expected;
  };
  Scene scene = scene_from_mesh(squares);
  scene.primitives[0].targets.push_back({.positions = offsets_by_square(squares)});
  write_scene(scene, dir / "in.glb");
  for (const char* how : {"--weld", "--weld-positions", "--weld=0.01"}) {
    SCOPED_TRACE(how);
    const test::RunResult r = test::run_cli({"optimize", (dir / "in.glb").string(), "-o", (dir / "out.glb").string(), how, "--force"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Mesh out = read_scene(dir / "out.glb").primitives[0].mesh;
    EXPECT_EQ(out.vertex_count(), 8u);  // 6 without the target: the shared edge's two positions
    EXPECT_EQ(out.triangle_count(), 4u);
    EXPECT_EQ(test::glb_morph_positions(dir / "out.glb"), offsets_by_square(out));
  }
  test::expect_valid_gltf({dir / "out.glb"});
}

// A flag whose value may be left out, written just before the input file, leaves the file to be
// the input (CLI11 alone would take its name as the value): the same file as with the flag after it.
TEST(CliOptimize, OptionalValueFlagsBeforeTheInputLeaveItTheInput) {
  test::TempDir dir;
  write_mesh(test::triangle_soup(shapes::icosphere(2)), dir / "soup.ply");
  const std::string in = (dir / "soup.ply").string();
  for (const char* flag : {"--weld", "--overdraw"}) {
    SCOPED_TRACE(flag);
    const test::RunResult after = test::run_cli({"optimize", in, flag, "-o", (dir / "after.ply").string(), "--json"});
    ASSERT_EQ(after.exit_code, 0) << after.err;
    const test::RunResult before = test::run_cli({"optimize", flag, in, "-o", (dir / "before.ply").string(), "--json"});
    ASSERT_EQ(before.exit_code, 0) << before.err;
    EXPECT_EQ(test::read_bytes(dir / "before.ply"), test::read_bytes(dir / "after.ply"));
    const auto j = nlohmann::json::parse(before.out);
    if (std::string(flag) == "--weld") EXPECT_EQ(j["output_vertices"], shapes::icosphere(2).vertex_count());
    else EXPECT_EQ(j["overdraw"]["threshold"], 1.05);
  }
  // A word that is no number, with the input given too, is an error, not a second input.
  EXPECT_EQ(test::run_cli({"optimize", "--weld", "x", in, "-o", (dir / "o.ply").string()}).exit_code, 1);
  EXPECT_EQ(test::run_cli({"optimize", "--weld", "-o", (dir / "o.ply").string()}).exit_code, 1);  // no input
}

TEST(CliOptimize, StripIndicesDecodeToTheWrittenMesh) {
  test::TempDir dir;
  write_mesh(shapes::icosphere(3), dir / "sphere.ply");
  for (const bool restart : {false, true}) {
    std::vector<std::string> args = {"optimize", (dir / "sphere.ply").string(), "-o", (dir / "out.ply").string(),
                                     "--strips=best", "--strip-indices", (dir / "strip.u32").string(), "--json", "--force"};
    if (restart) args.push_back("--restart");
    const test::RunResult r = test::run_cli(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    std::ifstream in(dir / "strip.u32", std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_EQ(bytes.size() % 4, 0u);
    std::vector<uint32_t> strip(bytes.size() / 4);
    for (size_t k = 0; k < strip.size(); ++k)
      for (int b = 0; b < 4; ++b) strip[k] |= uint32_t(uint8_t(bytes[4 * k + size_t(b)])) << (8 * b);
    EXPECT_EQ(j["strips"]["indices"], strip.size());
    EXPECT_EQ(j["strips"]["restart"], restart);
    const Mesh out = read_mesh(dir / "out.ply");
    EXPECT_EQ(test::index_triangles(unstripify(strip, restart)), test::index_triangles(out.indices));
    EXPECT_NEAR(j["strips"]["indices_per_triangle"].get<double>(), double(strip.size()) / double(out.triangle_count()), 1e-12);
  }
}

TEST(CliOptimize, MoebiusStripIsAWarning) {
  test::TempDir dir;
  write_mesh(test::moebius_strip(20), dir / "moebius.obj");
  const test::RunResult r =
      test::run_cli({"optimize", (dir / "moebius.obj").string(), "-o", (dir / "out.obj").string(), "--orient", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: 1 non-orientable"), std::string::npos) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["orient"]["non_orientable_components"], 1);
}

TEST(CliOptimize, BadOptionsAreUsageErrors) {
  test::TempDir dir;
  write_mesh(shapes::icosphere(1), dir / "s.ply");
  const std::string in = (dir / "s.ply").string(), out = (dir / "o.ply").string();
  for (const std::vector<std::string>& extra :
       {std::vector<std::string>{"--strips=fast"}, {"--weld=-1"}, {"--cache", "2"}, {"--strip-indices", "x.u32"}}) {
    std::vector<std::string> args = {"optimize", in, "-o", out};
    args.insert(args.end(), extra.begin(), extra.end());
    EXPECT_EQ(test::run_cli(args).exit_code, 1) << extra[0];
  }
}

TEST(CliAnalyze, ReportsTheLibraryAnalyzers) {
  test::TempDir dir;
  Mesh grid = shapes::grid(12, 12);
  grid.indices = test::shuffled_triangles(grid.indices, 5);
  write_mesh(grid, dir / "grid.ply");
  const Mesh m = read_mesh(dir / "grid.ply");
  const test::RunResult r = test::run_cli({"analyze", (dir / "grid.ply").string(), "--cache", "12", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["triangles"], m.triangle_count());
  ASSERT_EQ(j["cache"].size(), 2u);
  const VertexCacheStats fifo = analyze_vertex_cache(m.indices, m.vertex_count(), {.cache_size = 12});
  EXPECT_EQ(j["cache"][0]["policy"], "fifo");
  EXPECT_EQ(j["cache"][0]["misses"], fifo.misses);
  EXPECT_DOUBLE_EQ(j["cache"][0]["acmr"].get<double>(), fifo.acmr);
  EXPECT_LT(j["cache"][0]["optimized_acmr"].get<double>(), fifo.acmr);
  const VertexCacheStats lru = analyze_vertex_cache(m.indices, m.vertex_count(), {.cache_size = 12, .policy = CachePolicy::lru});
  EXPECT_EQ(j["cache"][1]["misses"], lru.misses);
  ASSERT_EQ(j["strips"].size(), 4u);
  for (const auto& s : j["strips"]) EXPECT_GE(s["indices_per_triangle"].get<double>(), 1.0);
  // The table names its rows.
  const test::RunResult table = test::run_cli({"analyze", (dir / "grid.ply").string()});
  ASSERT_EQ(table.exit_code, 0) << table.err;
  for (const char* row : {"FIFO 16", "LRU 16", "overfetch", "best restart", "sgi degenerate"})
    EXPECT_NE(table.out.find(row), std::string::npos) << row;
  EXPECT_EQ(test::run_cli({"analyze", (dir / "grid.ply").string(), "--cache", "99"}).exit_code, 1);
}

}  // namespace
}  // namespace lod
