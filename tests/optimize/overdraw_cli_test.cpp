// The overdraw options of the command line: lodkit optimize --overdraw[=T] (after the cache order,
// the written mesh is the library's result, the report gives the overdraw before and after) and the
// overdraw rows of lodkit analyze. (Here rather than in tests/cli: they check the overdraw pass.)
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "lodkit/io.h"
#include "lodkit/optimize.h"
#include "optimize_test_support.h"
#include "test_support.h"

namespace lod {
namespace {

TEST(CliOptimizeOverdraw, WritesTheLibraryResultAndReportsOverdraw) {
  test::TempDir dir;
  write_mesh(test::nested_spheres(), dir / "nested.ply");
  const Mesh input = read_mesh(dir / "nested.ply");
  for (const std::string threshold : {"", "1.2"}) {
    const std::string option = threshold.empty() ? "--overdraw" : "--overdraw=" + threshold;
    const test::RunResult r = test::run_cli({"optimize", (dir / "nested.ply").string(), "-o", (dir / "out.ply").string(), option, "--json"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    const float t = threshold.empty() ? 1.05f : 1.2f;
    EXPECT_FLOAT_EQ(j["overdraw"]["threshold"].get<float>(), t) << option;
    const Mesh out = read_mesh(dir / "out.ply");
    const OptimizeResult lib = optimize(input, {.overdraw = true, .overdraw_threshold = t});
    EXPECT_EQ(lib.mesh.indices, out.indices) << option;
    EXPECT_EQ(lib.mesh.positions, out.positions) << option;
    EXPECT_EQ(test::position_triangles(out), test::position_triangles(input));
    EXPECT_DOUBLE_EQ(j["overdraw"]["before"].get<double>(), analyze_overdraw(input.indices, input.positions).overdraw);
    EXPECT_DOUBLE_EQ(j["overdraw"]["after"].get<double>(), analyze_overdraw(out.indices, out.positions).overdraw);
    EXPECT_LT(j["overdraw"]["after"].get<double>(), j["overdraw"]["before"].get<double>());
  }
  // The table has an overdraw row.
  const test::RunResult table = test::run_cli({"optimize", (dir / "nested.ply").string(), "-o", (dir / "out.obj").string(), "--overdraw"});
  ASSERT_EQ(table.exit_code, 0) << table.err;
  EXPECT_NE(table.out.find("\noverdraw "), std::string::npos) << table.out;
  EXPECT_NE(table.out.find("(threshold 1.05)"), std::string::npos) << table.out;
  // Bad thresholds and --strips are usage errors.
  for (const std::vector<std::string>& extra : {std::vector<std::string>{"--overdraw=0.9"}, {"--overdraw", "--strips=best"}}) {
    std::vector<std::string> args = {"optimize", (dir / "nested.ply").string(), "-o", (dir / "bad.ply").string()};
    args.insert(args.end(), extra.begin(), extra.end());
    EXPECT_EQ(test::run_cli(args).exit_code, 1) << extra[0];
  }
}

TEST(CliAnalyzeOverdraw, ReportsOverdrawAsIsInCacheOrderAndAfterThePass) {
  test::TempDir dir;
  write_mesh(test::nested_spheres(), dir / "nested.ply");
  const Mesh m = read_mesh(dir / "nested.ply");
  const test::RunResult r = test::run_cli({"analyze", (dir / "nested.ply").string(), "--cache", "32", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out)["overdraw"];
  const std::vector<uint32_t> cache_order = optimize_vertex_cache(m.indices, m.vertex_count(), {.cache_size = 32});
  const std::vector<uint32_t> overdraw_order = optimize_overdraw(cache_order, m.positions, {.cache_size = 32, .threshold = 1.05f});
  EXPECT_DOUBLE_EQ(j["as_is"].get<double>(), analyze_overdraw(m.indices, m.positions).overdraw);
  EXPECT_DOUBLE_EQ(j["cache_order"].get<double>(), analyze_overdraw(cache_order, m.positions).overdraw);
  EXPECT_DOUBLE_EQ(j["overdraw_order"].get<double>(), analyze_overdraw(overdraw_order, m.positions).overdraw);
  EXPECT_DOUBLE_EQ(j["overdraw_order_acmr"].get<double>(), analyze_vertex_cache(overdraw_order, m.vertex_count(), {.cache_size = 32}).acmr);
  EXPECT_FLOAT_EQ(j["threshold"].get<float>(), 1.05f);
  // At the default 16 entries the pass finds clusters within the threshold and draws the outer
  // sphere first (at 32 here it keeps the cache order).
  const test::RunResult r16 = test::run_cli({"analyze", (dir / "nested.ply").string(), "--json"});
  ASSERT_EQ(r16.exit_code, 0) << r16.err;
  const auto j16 = nlohmann::json::parse(r16.out)["overdraw"];
  EXPECT_LT(j16["overdraw_order"].get<double>(), j16["as_is"].get<double>() - 0.05);
  const test::RunResult table = test::run_cli({"analyze", (dir / "nested.ply").string()});
  ASSERT_EQ(table.exit_code, 0) << table.err;
  for (const char* row : {"\noverdraw ", "\nas is ", "\ncache order ", "\noverdraw 1.05 "})
    EXPECT_NE(table.out.find(row), std::string::npos) << row;
}

}  // namespace
}  // namespace lod
