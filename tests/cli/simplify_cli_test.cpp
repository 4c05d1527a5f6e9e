// lodkit simplify from the command line: the report matches the written file and the library, and
// a missing target is a usage error.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "core/shapes.h"
#include "lodkit/io.h"
#include "lodkit/simplify.h"
#include "test_support.h"

namespace lod {
namespace {

TEST(CliSimplify, WritesTheLibraryResultAndReportsIt) {
  test::TempDir dir;
  const Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);
  write_mesh(torus, dir / "torus.ply");
  const test::RunResult r =
      test::run_cli({"simplify", (dir / "torus.ply").string(), "-o", (dir / "out.ply").string(), "--ratio", "0.1",
                     "--metric", "cqem", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const Mesh out = read_mesh(dir / "out.ply");
  EXPECT_EQ(j["output_triangles"], out.triangle_count());
  EXPECT_LE(out.triangle_count(), torus.triangle_count() / 10);
  // The same call through the library gives the same mesh (the PLY round trip is exact).
  const SimplifyResult lib = simplify(read_mesh(dir / "torus.ply"), {.target_ratio = 0.1f, .metric = Metric::constrained_qem});
  EXPECT_EQ(lib.mesh.indices, out.indices);
  EXPECT_EQ(lib.mesh.positions, out.positions);
}

TEST(CliSimplify, NeedsATarget) {
  test::TempDir dir;
  write_mesh(shapes::icosphere(1), dir / "s.ply");
  const test::RunResult r = test::run_cli({"simplify", (dir / "s.ply").string(), "-o", (dir / "o.ply").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("target"), std::string::npos) << r.err;
  const test::RunResult bad = test::run_cli(
      {"simplify", (dir / "s.ply").string(), "-o", (dir / "o.ply").string(), "--ratio", "0.5", "--metric", "nope"});
  EXPECT_EQ(bad.exit_code, 1);
}

}  // namespace
}  // namespace lod
