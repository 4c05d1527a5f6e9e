// lodkit lod: the glTF it writes passes the Khronos validator, uses MSFT_lod with one node per level
// in the scene's order, and its reported levels are the library's chain.
#include <gtest/gtest.h>

#include <cstring>
#include <nlohmann/json.hpp>

#include "core/shapes.h"
#include "lodkit/io.h"
#include "lodkit/lod.h"
#include "test_support.h"

namespace lod {
namespace {

// The JSON chunk of a .glb (little-endian header, then the first chunk).
nlohmann::json glb_json(const std::filesystem::path& path) {
  const FileBytes bytes = read_file_bytes(path);
  uint32_t length = 0;
  std::memcpy(&length, bytes.data() + 12, 4);
  return nlohmann::json::parse(std::string(reinterpret_cast<const char*>(bytes.data()) + 20, length));
}

TEST(CliLod, WritesAValidMsftLodChain) {
  test::TempDir dir;
  const Mesh torus = shapes::torus(1.0f, 0.3f, 48, 24);
  write_mesh(torus, dir / "torus.ply");
  const test::RunResult r = test::run_cli({"lod", (dir / "torus.ply").string(), "-o", (dir / "chain.glb").string(),
                                           "--ratios", "1,0.5,0.2,0.05", "--json", "--lpm", (dir / "t.lpm").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto report = nlohmann::json::parse(r.out);
  ASSERT_EQ(report["levels"].size(), 4u);

  const nlohmann::json doc = glb_json(dir / "chain.glb");
  EXPECT_NE(std::find(doc["extensionsUsed"].begin(), doc["extensionsUsed"].end(), "MSFT_lod"), doc["extensionsUsed"].end());
  const auto& root = doc["nodes"][0];
  EXPECT_EQ(root["extensions"]["MSFT_lod"]["ids"], nlohmann::json({1, 2, 3}));
  const auto& coverage = root["extras"]["MSFT_screencoverage"];
  ASSERT_EQ(coverage.size(), 4u);
  for (size_t i = 1; i < 4; ++i) EXPECT_LT(coverage[i].get<double>(), coverage[i - 1].get<double>());

  // Each level's node carries its error; the meshes are the library's chain, level by level.
  const LodChain chain = build_lod_chain(read_mesh(dir / "torus.ply"), {.ratios = {1.0f, 0.5f, 0.2f, 0.05f}});
  const Scene scene = read_scene(dir / "chain.glb");
  ASSERT_EQ(scene.primitives.size(), 4u);
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(scene.primitives[i].mesh.indices, chain.levels[i].mesh.indices) << "level " << i;
    EXPECT_EQ(scene.primitives[i].mesh.positions, chain.levels[i].mesh.positions) << "level " << i;
    EXPECT_FLOAT_EQ(doc["nodes"][i]["extras"]["lodkit"]["error"].get<float>(), chain.levels[i].error);
    EXPECT_EQ(report["levels"][i]["triangles"], chain.levels[i].mesh.triangle_count());
  }
  // The progressive mesh reaches the coarsest level's size.
  ProgressiveMesh pm = read_progressive_mesh(dir / "t.lpm");
  pm.set_collapses(pm.collapse_count());
  EXPECT_LE(pm.mesh().triangle_count(), chain.levels[3].mesh.triangle_count());

  if (!test::validator_available()) GTEST_SKIP() << "gltf-validator not installed (scripts/setup.sh installs it)";
  const test::ValidatorRun v = test::run_validator({dir / "chain.glb"});
  EXPECT_EQ(v.status, 0) << v.output;
  EXPECT_NE(v.output.find(": 0 errors"), std::string::npos) << v.output;
}

TEST(CliLod, RefusesNonGltfOutputAndBadLists) {
  test::TempDir dir;
  write_mesh(shapes::icosphere(2), dir / "s.ply");
  EXPECT_EQ(test::run_cli({"lod", (dir / "s.ply").string(), "-o", (dir / "o.ply").string()}).exit_code, 1);
  EXPECT_EQ(test::run_cli({"lod", (dir / "s.ply").string(), "-o", (dir / "o.glb").string(), "--ratios", "1,x"}).exit_code, 1);
  EXPECT_EQ(test::run_cli({"lod", (dir / "s.ply").string(), "-o", (dir / "o.glb").string(), "--ratios", "0.5,0.7"}).exit_code, 1);
  EXPECT_EQ(test::run_cli({"lod", (dir / "missing.ply").string(), "-o", (dir / "o.glb").string()}).exit_code, 2);
}

}  // namespace
}  // namespace lod
