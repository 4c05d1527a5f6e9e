// lodkit lod: the glTF it writes passes the Khronos validator, uses MSFT_lod with one node per level
// in the scene's order, and its reported levels are the library's chain.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <tuple>
#include <nlohmann/json.hpp>

#include "core/shapes.h"
#include "lodkit/io.h"
#include "lodkit/lod.h"
#include "lodkit/measure.h"
#include "lodkit/skin.h"
#include "skin/fixtures.h"
#include "optimize/optimize_test_support.h"
#include "cli/torus_morph.h"
#include "test_support.h"

namespace lod {
namespace {

using test::glb_json;

// The mesh of glTF mesh `mesh` in a scene read back (a level's), or null.
const Mesh* gltf_mesh(const Scene& scene, size_t mesh) {
  for (const Primitive& p : scene.primitives)
    if (p.gltf_mesh == mesh) return &p.mesh;
  return nullptr;
}

// The weights channels of clip `animation` that drive node `n`.
size_t weight_channels(const nlohmann::json& doc, size_t animation, size_t n) {
  size_t count = 0;
  for (const auto& channel : doc["animations"][animation]["channels"])
    count += channel["target"]["path"] == "weights" && channel["target"]["node"] == n;
  return count;
}

// The nodes of a lodkit lod file that draw a level (extras "lodkit"), in order.
std::vector<size_t> level_nodes(const nlohmann::json& doc) {
  std::vector<size_t> out;
  for (size_t n = 0; n < doc["nodes"].size(); ++n)
    if (doc["nodes"][n].contains("extras") && doc["nodes"][n]["extras"].contains("lodkit")) out.push_back(n);
  return out;
}

// A glTF document's node structure, whatever the order of its nodes: the default scene's roots, each
// with its name, whether it draws a mesh and whether it is instanced, its MSFT_lod levels and its
// children, so described; and how many nodes there are. (What lod on its own output must give as
// lod once gives it.)
nlohmann::json node_structure(const nlohmann::json& doc) {
  const std::function<nlohmann::json(size_t)> describe = [&](size_t n) {
    const nlohmann::json& node = doc["nodes"][n];
    const nlohmann::json extensions = node.value("extensions", nlohmann::json::object());
    nlohmann::json levels = nlohmann::json::array(), children = levels;
    if (extensions.contains("MSFT_lod"))
      for (const size_t id : extensions["MSFT_lod"]["ids"]) levels.push_back(describe(id));
    for (const size_t child : node.value("children", std::vector<size_t>{})) children.push_back(describe(child));
    return nlohmann::json{node.value("name", ""), node.contains("mesh"), extensions.contains("EXT_mesh_gpu_instancing"), levels,
                          children};
  };
  nlohmann::json roots = nlohmann::json::array();
  for (const size_t root : doc["scenes"][doc.value("scene", 0)]["nodes"]) roots.push_back(describe(root));
  return {{"nodes", doc["nodes"].size()}, {"roots", roots}};
}

// --errors limits what the table reports: each level's certified bound (and so its measured error)
// is within its fraction of the diagonal, read back from the file written.
TEST(CliLod, ErrorsLimitTheMeasuredDistance) {
  test::TempDir dir;
  write_mesh(shapes::torus(1.0f, 0.3f, 48, 24), dir / "torus.ply");
  const test::RunResult r = test::run_cli(
      {"lod", (dir / "torus.ply").string(), "-o", (dir / "chain.glb").string(), "--errors", "0,0.004,0.02", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto report = nlohmann::json::parse(r.out);
  ASSERT_EQ(report["levels"].size(), 3u);
  const double diagonal = report["diagonal"].get<double>();
  const Mesh input = read_mesh(dir / "torus.ply");
  const Scene scene = read_scene(dir / "chain.glb");
  ASSERT_EQ(scene.primitives.size(), 3u);
  for (size_t i = 1; i < 3; ++i) {
    const double limit = (i == 1 ? 0.004 : 0.02) * diagonal;
    EXPECT_LE(report["levels"][i]["error_bound"].get<double>(), limit) << "level " << i;
    const Deviation d = compare(input, scene.primitives[i].mesh, {.samples = 100'000, .seed = 3, .refine = true});
    EXPECT_LE(d.hausdorff, limit) << "level " << i;
  }
  // A skinned character's chain too (measured in the bind pose), through the multi-pose simplifier,
  // whose search once asked it to collapse nothing and crashed.
  write_scene(fixtures::humanoid_scene(), dir / "humanoid.glb");
  const test::RunResult s = test::run_cli(
      {"lod", (dir / "humanoid.glb").string(), "-o", (dir / "h.glb").string(), "--errors", "0,0.005,0.02", "--json"});
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const auto chain = nlohmann::json::parse(s.out)["skinned"]["chains"][0];
  ASSERT_EQ(chain["levels"].size(), 3u);
  for (size_t i = 1; i < 3; ++i) {
    EXPECT_LE(chain["levels"][i]["error_bound"].get<double>(), (i == 1 ? 0.005 : 0.02) * chain["diagonal"].get<double>());
    EXPECT_LT(chain["levels"][i]["triangles"].get<uint64_t>(), chain["levels"][i - 1]["triangles"].get<uint64_t>());
  }
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

  test::expect_valid_gltf({dir / "chain.glb"});
}

// A viewer's reading of the chain (tests/gltf-loader/babylon_lod.mjs): Babylon.js loads MSFT_lod
// progressively, the coarsest level (the last id) first, each finer one replacing it, up to
// maxLODsToLoad levels. Stopped after k, it draws the k-th coarsest level, its triangles exactly;
// loading them all ends on level 0. three.js (three_load.mjs) draws level 0.
TEST(CliLod, BabylonLoadsTheChainCoarsestFirst) {
  const std::filesystem::path tools = std::filesystem::path(LODKIT_SOURCE_DIR) / "tests/gltf-loader";
  if (!std::filesystem::exists(tools / "node_modules/@babylonjs/loaders") || std::system("command -v node >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "Babylon.js is not installed in tests/gltf-loader (scripts/setup.sh)";
  test::TempDir dir;
  write_mesh(shapes::torus(1.0f, 0.3f, 48, 24), dir / "torus.ply");
  const test::RunResult r = test::run_cli({"lod", (dir / "torus.ply").string(), "-o", (dir / "chain.glb").string(), "--ratios",
                                           "1,0.5,0.2,0.05", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json levels = nlohmann::json::parse(r.out)["levels"];
  ASSERT_EQ(levels.size(), 4u);
  for (size_t k = 1; k <= 4; ++k) {
    SCOPED_TRACE(k);
    const test::RunResult b = test::run_program({"node", (tools / "babylon_lod.mjs").string(), (dir / "chain.glb").string(), std::to_string(k)});
    ASSERT_EQ(b.exit_code, 0) << b.err;
    const std::string last = b.out.substr(b.out.find_last_of('\n', b.out.size() - 2) + 1);  // (Babylon logs a banner first)
    const nlohmann::json seen = nlohmann::json::parse(last);
    std::vector<std::string> order;
    for (size_t i = 0; i < k; ++i) order.push_back("LOD" + std::to_string(3 - i));
    EXPECT_EQ(seen["loaded"], order);
    ASSERT_EQ(seen["drawn"].size(), 1u);
    EXPECT_EQ(seen["drawn"][0]["indices"], 3 * levels[4 - k]["triangles"].get<size_t>());
  }
  // three.js does not read MSFT_lod: it draws the scene, where level 0 alone is.
  const test::RunResult t = test::run_program({"node", (tools / "three_load.mjs").string(), (dir / "chain.glb").string()});
  ASSERT_EQ(t.exit_code, 0) << t.err;
  const nlohmann::json three = nlohmann::json::parse(t.out)["drawn"];
  ASSERT_EQ(three.size(), 1u);
  EXPECT_EQ(three[0]["indices"], 3 * levels[0]["triangles"].get<size_t>());
}

// lodkit simplify on a chain: the levels it changes lose the facts lodkit lod wrote about them
// (their triangles and errors, and the geomorph whose morph target goes with the old vertices),
// the chain itself (MSFT_lod) stays; a run that changes nothing keeps them all.
TEST(CliLod, SimplifyingAChainDropsItsStaleFacts) {
  test::TempDir dir;
  write_mesh(shapes::torus(1.0f, 0.3f, 32, 16), dir / "torus.ply");
  ASSERT_EQ(test::run_cli({"lod", (dir / "torus.ply").string(), "-o", (dir / "m.glb").string(), "--ratios", "1,0.4,0.1",
                           "--morph"}).exit_code, 0);
  const nlohmann::json before = glb_json(dir / "m.glb");
  ASSERT_TRUE(before["nodes"][0]["extras"].contains("lodkit"));
  ASSERT_TRUE(before["nodes"][0]["extras"].contains("LODKIT_geomorph"));

  test::RunResult r = test::run_cli({"simplify", (dir / "m.glb").string(), "-o", (dir / "same.glb").string(), "--ratio", "1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json same = glb_json(dir / "same.glb");
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(same["nodes"][i]["extras"], before["nodes"][i]["extras"]) << i;

  r = test::run_cli({"simplify", (dir / "m.glb").string(), "-o", (dir / "half.glb").string(), "--ratio", "0.5"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json half = glb_json(dir / "half.glb");
  ASSERT_EQ(half["nodes"].size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const nlohmann::json extras = half["nodes"][i].value("extras", nlohmann::json::object());
    EXPECT_FALSE(extras.contains("lodkit")) << i;
    EXPECT_FALSE(extras.contains("LODKIT_geomorph")) << i;
    EXPECT_FALSE(half["meshes"][i]["primitives"][0].contains("targets")) << i;
  }
  EXPECT_EQ(half["nodes"][0]["extensions"]["MSFT_lod"]["ids"], before["nodes"][0]["extensions"]["MSFT_lod"]["ids"]);
  EXPECT_EQ(half["nodes"][0]["extras"]["MSFT_screencoverage"], before["nodes"][0]["extras"]["MSFT_screencoverage"]);
  EXPECT_FALSE(half["nodes"][1].contains("extras"));  // nothing left: no empty object either

  test::expect_valid_gltf({dir / "half.glb"});
}

// A triangle soup is welded before the chain is built (else no level could lose a triangle): each
// level halves the triangles, and level 0 draws the soup's triangles over shared vertices.
TEST(CliLod, TriangleSoupIsWeldedFirst) {
  test::TempDir dir;
  Mesh torus = shapes::torus(1.0f, 0.3f, 32, 16);
  torus.normals.clear();
  write_mesh(test::triangle_soup(torus), dir / "soup.ply");
  const test::RunResult r = test::run_cli({"lod", (dir / "soup.ply").string(), "-o", (dir / "chain.glb").string(), "--ratios", "1,0.5,0.25"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Scene chain = read_scene(dir / "chain.glb");
  ASSERT_EQ(chain.primitives.size(), 3u);
  EXPECT_EQ(chain.primitives[0].mesh.triangle_count(), torus.triangle_count());
  EXPECT_EQ(chain.primitives[0].mesh.vertex_count(), torus.vertex_count());
  EXPECT_LE(chain.primitives[1].mesh.triangle_count(), torus.triangle_count() / 2);
  EXPECT_LE(chain.primitives[2].mesh.triangle_count(), torus.triangle_count() / 4);
}

// A chain made from a chain: the new one replaces the old, built from the old first level alone
// (the others are not in the scene). The old chain's nodes go (lod::erase_nodes): its first level,
// which lodkit made, and its coarser levels, which nothing draws any more. What is left is the new
// chain, as lod on the torus itself would write it.
TEST(CliLod, ChainingAChainReplacesTheOldChain) {
  test::TempDir dir;
  write_mesh(shapes::torus(1.0f, 0.3f, 32, 16), dir / "torus.ply");
  ASSERT_EQ(test::run_cli({"lod", (dir / "torus.ply").string(), "-o", (dir / "old.glb").string(), "--ratios", "1,0.4,0.1",
                           "--morph"}).exit_code, 0);
  ASSERT_EQ(glb_json(dir / "old.glb")["nodes"].size(), 3u);
  const test::RunResult r =
      test::run_cli({"lod", (dir / "old.glb").string(), "-o", (dir / "new.glb").string(), "--ratios", "1,0.25"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json doc = glb_json(dir / "new.glb");
  ASSERT_EQ(doc["nodes"].size(), 2u);
  EXPECT_EQ(doc["scenes"][doc.value("scene", 0)]["nodes"], nlohmann::json::array({0}));
  EXPECT_EQ(doc["nodes"][0]["extensions"]["MSFT_lod"]["ids"], nlohmann::json::array({1}));
  EXPECT_EQ(doc["nodes"][0]["extras"]["lodkit"]["triangles"].get<uint64_t>(), 32u * 16u * 2u);
  EXPECT_FALSE(doc["nodes"][0]["extras"].contains("LODKIT_geomorph"));  // (no --morph this time)
  EXPECT_FALSE(doc["nodes"][1].contains("extensions"));
  EXPECT_EQ(doc["meshes"].size(), 2u);
  EXPECT_EQ(std::count(doc["extensionsUsed"].begin(), doc["extensionsUsed"].end(), "MSFT_lod"), 1);
  test::expect_valid_gltf({dir / "new.glb"});
  // The same ratios on the torus itself: the same nodes.
  ASSERT_EQ(test::run_cli({"lod", (dir / "torus.ply").string(), "-o", (dir / "once.glb").string(), "--ratios", "1,0.25"}).exit_code, 0);
  const nlohmann::json once = glb_json(dir / "once.glb");
  EXPECT_EQ(node_structure(doc), node_structure(once));
}

// Materials: each level is one glTF mesh with a primitive per material. From OBJ the materials keep
// their names; from a static glTF the chain is written into the source document, so its materials
// (a textured one here), textures, images and other content (a camera) stay as they were.
TEST(CliLod, LevelsKeepTheInputMaterials) {
  test::TempDir dir;
  Mesh torus = shapes::torus(1.0f, 0.3f, 48, 24);
  for (size_t t = 0; t < torus.triangle_count(); ++t) torus.materials.push_back(t < torus.triangle_count() / 2 ? 0 : 1);
  torus.material_names = {"red", "blue"};
  write_mesh(torus, dir / "torus.obj");
  write_scene(scene_from_mesh(torus), dir / "plain.gltf");
  nlohmann::json in;
  {
    std::ifstream file(dir / "plain.gltf");
    in = nlohmann::json::parse(file);
  }
  in["images"] = {{{"uri", "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg=="}}};
  in["samplers"] = {nlohmann::json::object()};
  in["textures"] = {{{"source", 0}, {"sampler", 0}}};
  in["materials"][0]["pbrMetallicRoughness"] = {{"baseColorTexture", {{"index", 0}}}, {"metallicFactor", 0.25}};
  in["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", 1.0}, {"znear", 0.1}}}}};  // no zfar: infinite
  in["nodes"].push_back({{"name", "camera"}, {"camera", 0}, {"translation", {0, 0, 5}}});
  in["scenes"][0]["nodes"].push_back(in["nodes"].size() - 1);
  {
    std::ofstream file(dir / "textured.gltf");
    file << in.dump();
  }
  {
    // Without a scene, the output gets one: viewers would show nothing of the chain otherwise.
    nlohmann::json bare = in;
    bare.erase("scenes"), bare.erase("scene");
    std::ofstream file(dir / "sceneless.gltf");
    file << bare.dump();
  }

  for (const char* input : {"torus.obj", "textured.gltf", "sceneless.gltf"}) {
    SCOPED_TRACE(input);
    const bool gltf = std::string(input) != "torus.obj";
    const test::RunResult r = test::run_cli({"lod", (dir / input).string(), "-o", (dir / "chain.glb").string(),
                                             "--ratios", "1,0.5,0.2", "--force"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json doc = glb_json(dir / "chain.glb");
    ASSERT_EQ(doc["materials"].size(), 2u);
    EXPECT_EQ(doc["materials"][0]["name"], "red");
    EXPECT_EQ(doc["materials"][1]["name"], "blue");
    // The chain's nodes come after the source's; the first is a root and lists the others.
    const size_t first = gltf ? in["nodes"].size() : 0;
    ASSERT_EQ(doc["nodes"].size(), first + 3);
    EXPECT_EQ(doc["nodes"][first]["extensions"]["MSFT_lod"]["ids"], nlohmann::json::array({first + 1, first + 2}));
    ASSERT_TRUE(doc.contains("scenes"));
    const auto& roots = doc["scenes"][doc.value("scene", 0)]["nodes"];
    EXPECT_NE(std::find(roots.begin(), roots.end(), first), roots.end());
    if (gltf) {
      EXPECT_NE(std::find(roots.begin(), roots.end(), 1), roots.end());  // the source's camera node
    }
    uint64_t previous = 0;
    for (size_t i = 0; i < 3; ++i) {
      const auto& mesh = doc["meshes"][doc["nodes"][first + i]["mesh"].get<size_t>()];
      ASSERT_EQ(mesh["primitives"].size(), 2u) << i;
      uint64_t triangles = 0;
      for (size_t k = 0; k < 2; ++k) {
        EXPECT_EQ(mesh["primitives"][k]["material"], k);
        EXPECT_TRUE(mesh["primitives"][k]["attributes"].contains("TEXCOORD_0"));
        triangles += doc["accessors"][mesh["primitives"][k]["indices"].get<size_t>()]["count"].get<uint64_t>() / 3;
      }
      EXPECT_EQ(triangles, doc["nodes"][first + i]["extras"]["lodkit"]["triangles"].get<uint64_t>());
      if (i > 0) {
        EXPECT_LT(triangles, previous);
      }
      previous = triangles;
    }
    if (gltf) {
      EXPECT_EQ(doc["materials"], in["materials"]);
      EXPECT_EQ(doc["textures"], in["textures"]);
      ASSERT_EQ(doc["images"].size(), 1u);  // the data: URI image, now in the .glb's BIN chunk
      EXPECT_EQ(doc["images"][0]["mimeType"], "image/png");
      EXPECT_EQ(doc["cameras"], in["cameras"]);  // zfar still absent
      EXPECT_EQ(doc["nodes"][1]["name"], "camera");
      EXPECT_FALSE(doc["nodes"][0].contains("mesh"));  // the source's node, its mesh now the chain's
    }
    test::expect_valid_gltf({dir / "chain.glb"});
  }
}

// --morph: level i's morph target 0 at weight 1 lands exactly on level i + 1 (its proper triangles),
// also after lodkit optimize has renumbered the vertices, and on one vertex buffer (each level's
// geomorph over all of it, level i's indices drawing only its share).
TEST(CliLod, GeomorphsAreMorphTargets) {
  test::TempDir dir;
  write_mesh(shapes::torus(1.0f, 0.3f, 32, 16), dir / "torus.ply");
  const test::RunResult r = test::run_cli({"lod", (dir / "torus.ply").string(), "-o", (dir / "m.glb").string(),
                                           "--ratios", "1,0.4,0.1", "--morph"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // lodkit optimize renumbers each level's vertices (for another cache than lod's): the morph targets
  // must follow them.
  const test::RunResult o = test::run_cli(
      {"optimize", (dir / "m.glb").string(), "-o", (dir / "opt.glb").string(), "--lru", "--cache", "8"});
  ASSERT_EQ(o.exit_code, 0) << o.err;
  const test::RunResult shared = test::run_cli({"lod", (dir / "torus.ply").string(), "-o", (dir / "ms.glb").string(),
                                                "--ratios", "1,0.4,0.1", "--morph", "--shared-vertices"});
  ASSERT_EQ(shared.exit_code, 0) << shared.err;
  {
    const nlohmann::json doc = glb_json(dir / "ms.glb");
    for (size_t i = 0; i < 3; ++i)
      EXPECT_EQ(doc["meshes"][i]["primitives"][0]["attributes"]["POSITION"], doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"]);
  }
  for (const char* name : {"m.glb", "opt.glb", "ms.glb"}) {
    SCOPED_TRACE(name);
    const nlohmann::json doc = glb_json(dir / name);
    const Scene scene = read_scene(dir / name);
    if (std::string(name) == "opt.glb") {  // really renumbered (else this case would prove nothing)
      for (size_t i = 0; i < 2; ++i)
        EXPECT_NE(scene.primitives[i].mesh.positions, read_scene(dir / "m.glb").primitives[i].mesh.positions) << i;
    }
    const auto proper = [](const Mesh& m) {
      std::vector<std::array<float3, 3>> out;
      for (size_t t = 0; t < m.triangle_count(); ++t) {
        std::array<float3, 3> tri = {m.positions[m.indices[3 * t]], m.positions[m.indices[3 * t + 1]], m.positions[m.indices[3 * t + 2]]};
        // Corners that should coincide may differ by rounding (P + (P_target - P) in float).
        const auto same = [](const float3& a, const float3& b) {
          return std::fabs(a.x - b.x) < 1e-6f && std::fabs(a.y - b.y) < 1e-6f && std::fabs(a.z - b.z) < 1e-6f;
        };
        if (same(tri[0], tri[1]) || same(tri[1], tri[2]) || same(tri[2], tri[0])) continue;
        const auto less = [](const float3& a, const float3& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); };
        std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end(), less), tri.end());
        out.push_back(tri);
      }
      std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
        return std::tie(a[0].x, a[0].y, a[0].z, a[1].x, a[1].y, a[1].z, a[2].x, a[2].y, a[2].z) <
               std::tie(b[0].x, b[0].y, b[0].z, b[1].x, b[1].y, b[1].z, b[2].x, b[2].y, b[2].z);
      });
      return out;
    };
    for (size_t i = 0; i < 2; ++i) {
      EXPECT_EQ(doc["nodes"][i]["extras"]["LODKIT_geomorph"]["to_node"], i + 1);
      const std::vector<float3> offsets = test::glb_morph_positions(dir / name, i);
      Mesh moved = scene.primitives[i].mesh;
      ASSERT_EQ(offsets.size(), moved.vertex_count());
      for (size_t v = 0; v < moved.vertex_count(); ++v) {
        const float3& d = offsets[v];
        moved.positions[v] = {moved.positions[v].x + d.x, moved.positions[v].y + d.y, moved.positions[v].z + d.z};
      }
      // P + (P_target - P) in float may differ from P_target by an ulp: compare after the same rounding
      // the viewer would do, i.e. allow the coarser level's triangles to match within 1e-6.
      const auto a = proper(moved), b = proper(scene.primitives[i + 1].mesh);
      ASSERT_EQ(a.size(), b.size()) << "level " << i;
      // Each morphed triangle matches one coarser triangle (same winding) within rounding.
      const auto near = [](const float3& p, const float3& q) {
        return std::fabs(p.x - q.x) < 1e-6f && std::fabs(p.y - q.y) < 1e-6f && std::fabs(p.z - q.z) < 1e-6f;
      };
      std::vector<bool> used(b.size(), false);
      for (const auto& t : a) {
        bool found = false;
        for (size_t k = 0; k < b.size() && !found; ++k)
          for (int rot = 0; rot < 3 && !found && !used[k]; ++rot)
            if (near(t[0], b[k][rot]) && near(t[1], b[k][(rot + 1) % 3]) && near(t[2], b[k][(rot + 2) % 3]))
              used[k] = found = true;
        ASSERT_TRUE(found) << "level " << i << ": a morphed triangle is not in the next level";
      }
    }
  }
  test::expect_valid_gltf({dir / "m.glb", dir / "opt.glb", dir / "ms.glb"});
}

// --shared-vertices: every level's primitive reads the same vertex accessors, and level i's indices
// stay within its prefix of them.
TEST(CliLod, SharedVerticesWriteOneVertexBuffer) {
  test::TempDir dir;
  write_mesh(shapes::torus(1.0f, 0.3f, 32, 16), dir / "torus.ply");
  const test::RunResult r = test::run_cli({"lod", (dir / "torus.ply").string(), "-o", (dir / "s.glb").string(),
                                           "--ratios", "1,0.4,0.1", "--shared-vertices"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json doc = glb_json(dir / "s.glb");
  const Scene scene = read_scene(dir / "s.glb");
  ASSERT_EQ(scene.primitives.size(), 3u);
  const auto position = doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"];
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(doc["meshes"][i]["primitives"][0]["attributes"]["POSITION"], position) << "level " << i;
    const uint32_t prefix = doc["nodes"][i]["extras"]["lodkit"]["vertex_prefix"].get<uint32_t>();
    for (const uint32_t v : scene.primitives[i].mesh.indices) ASSERT_LT(v, prefix) << "level " << i;
    if (i) {
      EXPECT_LT(scene.primitives[i].mesh.triangle_count(), scene.primitives[i - 1].mesh.triangle_count());
    }
  }
  test::expect_valid_gltf({dir / "s.glb"});
}

TEST(CliLod, RefusesNonGltfOutputAndBadLists) {
  test::TempDir dir;
  write_mesh(shapes::icosphere(2), dir / "s.ply");
  EXPECT_EQ(test::run_cli({"lod", (dir / "s.ply").string(), "-o", (dir / "o.ply").string()}).exit_code, 1);
  EXPECT_EQ(test::run_cli({"lod", (dir / "s.ply").string(), "-o", (dir / "o.glb").string(), "--ratios", "1,x"}).exit_code, 1);
  EXPECT_EQ(test::run_cli({"lod", (dir / "s.ply").string(), "-o", (dir / "o.glb").string(), "--ratios", "0.5,0.7"}).exit_code, 1);
  EXPECT_EQ(test::run_cli({"lod", (dir / "missing.ply").string(), "-o", (dir / "o.glb").string()}).exit_code, 2);
  // --levels, --ratios and --errors each set the levels: together, or --levels 0, they are refused
  // (the one ignored used to pass silently, and --levels 0 gave the default 4).
  for (const std::vector<std::string>& extra :
       {std::vector<std::string>{"--levels", "0"}, {"--levels", "3", "--ratios", "1,0.5"}, {"--levels", "2", "--errors", "0,0.01"}}) {
    std::vector<std::string> args = {"lod", (dir / "s.ply").string(), "-o", (dir / "o.glb").string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const test::RunResult r = test::run_cli(args);
    EXPECT_EQ(r.exit_code, 1) << extra[1] << ": " << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "o.glb"));
}

}  // namespace
}  // namespace lod

namespace lod {
namespace {

// A skinned character: the skinned node gets MSFT_lod levels drawn by new nodes with the same skin;
// the skeleton, the skin and both clips are written back unchanged; every level's influences are
// valid; the file passes the validator.
TEST(CliLod, SkinnedCharacterKeepsItsSkeletonAndClips) {
  test::TempDir dir;
  const Scene input = fixtures::humanoid_scene();
  write_scene(input, dir / "humanoid.glb");
  const Scene written = read_scene(dir / "humanoid.glb");
  const test::RunResult r = test::run_cli({"lod", (dir / "humanoid.glb").string(), "-o", (dir / "lod.glb").string(),
                                           "--ratios", "1,0.4,0.1", "--poses", "8", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto report = nlohmann::json::parse(r.out);
  EXPECT_EQ(report["skinned"]["mode"], "multipose");
  ASSERT_EQ(report["skinned"]["chains"].size(), 1u);
  ASSERT_EQ(report["levels"].size(), 3u);

  const Scene out = read_scene(dir / "lod.glb");
  ASSERT_EQ(out.skins.size(), written.skins.size());
  EXPECT_EQ(out.skins[0].joints, written.skins[0].joints);
  EXPECT_EQ(out.skins[0].inverse_bind_matrices, written.skins[0].inverse_bind_matrices);
  ASSERT_EQ(out.animations.size(), written.animations.size());
  for (size_t a = 0; a < out.animations.size(); ++a) {
    EXPECT_EQ(out.animations[a].name, written.animations[a].name);
    ASSERT_EQ(out.animations[a].channels.size(), written.animations[a].channels.size());
    for (size_t c = 0; c < out.animations[a].channels.size(); ++c) {
      EXPECT_EQ(out.animations[a].channels[c].node, written.animations[a].channels[c].node);
      EXPECT_EQ(out.animations[a].channels[c].times, written.animations[a].channels[c].times);
      EXPECT_EQ(out.animations[a].channels[c].values, written.animations[a].channels[c].values);
    }
  }
  // The skinned node lists two new nodes, each drawing a level with the same skin.
  const std::vector<SkinnedPrimitive> skinned = skinned_primitives(written);
  ASSERT_EQ(skinned.size(), 1u);
  const std::vector<int32_t>& ids = out.nodes[skinned[0].node].lod_ids;
  ASSERT_EQ(ids.size(), 2u);
  uint64_t previous = out.primitives[skinned[0].primitive].mesh.triangle_count();
  EXPECT_EQ(previous, input.primitives[skinned[0].primitive].mesh.triangle_count());
  for (const int32_t id : ids) {
    const Node& node = out.nodes[size_t(id)];
    EXPECT_EQ(node.skin, int32_t(skinned[0].skin));
    const auto it = std::find_if(out.primitives.begin(), out.primitives.end(),
                                 [&](const Primitive& p) { return int32_t(p.gltf_mesh) == node.mesh; });
    ASSERT_NE(it, out.primitives.end());
    const Mesh& m = it->mesh;
    EXPECT_LT(m.triangle_count(), previous);
    previous = m.triangle_count();
    ASSERT_EQ(m.weights.size(), m.vertex_count());
    for (size_t v = 0; v < m.vertex_count(); ++v) {
      const float4& w = m.weights[v];
      EXPECT_NEAR(double(w.x) + w.y + w.z + w.w, 1.0, 1e-6);
      for (size_t k = 0; k < 4; ++k) EXPECT_LT(m.joints[v][k], out.skins[0].joints.size());
    }
  }
  test::expect_valid_gltf({dir / "lod.glb"});
}

// --lpm on a skinned character: the progressive mesh animates with the input's skeleton. Multi-pose:
// its input is the character with normalised weights and its record carries the chosen influences;
// at every size the influences are valid, and the coarsest mesh, posed by the clips, stays as near
// the posed input as the chain's coarsest level. Subset: every vertex is an input vertex with its
// own influences. Houle's record is in a pose, not in bind space: refused.
TEST(CliLod, SkinnedProgressiveMesh) {
  test::TempDir dir;
  write_scene(fixtures::humanoid_scene(), dir / "humanoid.glb");
  const Scene input = read_scene(dir / "humanoid.glb");
  const std::vector<SkinnedPrimitive> skinned = skinned_primitives(input);
  ASSERT_EQ(skinned.size(), 1u);
  const Mesh& rest = input.primitives[skinned[0].primitive].mesh;
  const size_t joints = input.skins[skinned[0].skin].joints.size();
  const std::vector<std::vector<mat4>> poses = sample_poses(input, skinned[0].skin, 5);
  const auto posed = [](const Mesh& m, const std::vector<mat4>& pose) {
    SkinnedVertices v;
    skin_vertices(m, pose, v);
    Mesh out = m;
    out.positions = v.positions;
    return out;
  };
  const auto expect_valid = [&](const Mesh& m) {
    ASSERT_EQ(m.weights.size(), m.vertex_count());
    for (size_t v = 0; v < m.vertex_count(); ++v) {
      const float4& w = m.weights[v];
      ASSERT_NEAR(double(w.x) + w.y + w.z + w.w, 1.0, 1e-6);
      for (size_t k = 0; k < 4; ++k) ASSERT_LT(m.joints[v][k], joints);
    }
  };

  for (const char* mode : {"multipose", "subset"}) {
    SCOPED_TRACE(mode);
    const test::RunResult r = test::run_cli({"lod", (dir / "humanoid.glb").string(), "-o", (dir / "lod.glb").string(),
                                             "--ratios", "1,0.3,0.1", "--skin-mode", mode, "--poses", "8", "--lpm",
                                             (dir / "h.lpm").string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    ProgressiveMesh pm = read_progressive_mesh(dir / "h.lpm");
    const bool multipose = std::string(mode) == "multipose";
    Mesh expected_input = rest;
    if (multipose) normalize_influences(expected_input);
    EXPECT_EQ(test::mesh_difference(pm.input(), expected_input), "");
    EXPECT_EQ(pm.record().influences.size(), multipose ? pm.collapse_count() : 0u);
    ASSERT_GT(pm.collapse_count(), 0u);

    const Scene out = read_scene(dir / "lod.glb");
    const std::vector<int32_t>& ids = out.nodes[skinned[0].node].lod_ids;
    ASSERT_EQ(ids.size(), 2u);
    const Mesh* coarsest = gltf_mesh(out, size_t(out.nodes[size_t(ids[1])].mesh));
    ASSERT_NE(coarsest, nullptr);

    // Subset: input vertices by position, with their own influences.
    std::map<std::tuple<float, float, float>, std::pair<ushort4, float4>> at;
    for (size_t v = 0; v < rest.vertex_count(); ++v)
      at[{rest.positions[v].x, rest.positions[v].y, rest.positions[v].z}] = {rest.joints[v], rest.weights[v]};
    for (const size_t k : {pm.collapse_count() / 2, pm.collapse_count()}) {
      pm.set_collapses(k);
      const Mesh m = pm.mesh();
      expect_valid(m);
      if (!multipose)
        for (size_t v = 0; v < m.vertex_count(); ++v) {
          const auto it = at.find({m.positions[v].x, m.positions[v].y, m.positions[v].z});
          ASSERT_NE(it, at.end());
          ASSERT_EQ(it->second.first, m.joints[v]);
          ASSERT_EQ(it->second.second, m.weights[v]);
        }
    }
    const Mesh last = pm.mesh();
    EXPECT_LE(last.triangle_count(), coarsest->triangle_count());
    double pm_worst = 0, level_worst = 0;
    for (const std::vector<mat4>& pose : poses) {
      const Mesh reference = posed(rest, pose);
      pm_worst = std::max(pm_worst, compare(reference, posed(last, pose), {.samples = 20'000}).hausdorff);
      level_worst = std::max(level_worst, compare(reference, posed(*coarsest, pose), {.samples = 20'000}).hausdorff);
    }
    EXPECT_LE(pm_worst, 1.25 * level_worst) << "progressive " << pm_worst << ", chain " << level_worst;
  }

  const test::RunResult houle = test::run_cli({"lod", (dir / "humanoid.glb").string(), "-o", (dir / "h.glb").string(),
                                               "--skin-mode", "houle", "--lpm", (dir / "houle.lpm").string()});
  EXPECT_EQ(houle.exit_code, 1);
  EXPECT_NE(houle.err.find("houle"), std::string::npos) << houle.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "houle.lpm"));
  EXPECT_FALSE(std::filesystem::exists(dir / "h.glb"));
}

// A skinned character's blend shape (each vertex's offset a linear, invertible function of its
// position), driven by a clip. Level 0 replaces the source primitive with its vertices reordered for
// the vertex cache, and the morph target follows them exactly. The coarser levels, and level 0 when
// it is simplified too, get it interpolated on the input: inverted, each offset names a point of the
// input's surface next to the vertex. Each level's node takes the clip that drives the weight.
// The humanoid with that blend shape on its body and a clip driving it.
Scene humanoid_with_blend_shape() {
  Scene input = fixtures::humanoid_scene();
  const std::vector<SkinnedPrimitive> skinned = skinned_primitives(input);
  Primitive& body = input.primitives[skinned.at(0).primitive];
  MorphTarget blend;
  for (const float3& p : body.mesh.positions) blend.positions.push_back(test::morph_offset(p));
  body.targets.push_back(blend);
  AnimationChannel smile{.node = int32_t(skinned[0].node), .path = AnimationPath::weights, .times = {0, 1, 2},
                         .values = {0, 1, 0}, .components = 1};
  input.animations[0].channels.push_back(smile);
  return input;
}

TEST(CliLod, SkinnedLevelsKeepTheirMorphTargets) {
  test::TempDir dir;
  const Scene input = humanoid_with_blend_shape();
  const std::vector<SkinnedPrimitive> skinned = skinned_primitives(input);
  ASSERT_EQ(skinned.size(), 1u);
  write_scene(input, dir / "humanoid.glb");
  const Mesh& rest = input.primitives[skinned[0].primitive].mesh;
  float3 lo, hi;
  bounding_box(rest, lo, hi);
  const double diagonal = std::hypot(double(hi.x) - lo.x, double(hi.y) - lo.y, double(hi.z) - lo.z);
  // The distance from q to the input surface, brute force.
  const auto to_input = [&](const float3& q) {
    double best = INFINITY;
    for (size_t t = 0; t < rest.triangle_count(); ++t)
      best = std::min(best, test::triangle_distance(q, rest.positions[rest.indices[3 * t]], rest.positions[rest.indices[3 * t + 1]],
                                                    rest.positions[rest.indices[3 * t + 2]]));
    return best;
  };

  for (const char* ratios : {"1,0.4", "0.5,0.2"}) {
    const test::RunResult r = test::run_cli({"lod", (dir / "humanoid.glb").string(), "-o", (dir / "lod.glb").string(),
                                             "--ratios", ratios, "--poses", "4"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Scene out = read_scene(dir / "lod.glb");
    const nlohmann::json doc = glb_json(dir / "lod.glb");
    const uint32_t node = skinned[0].node;
    ASSERT_EQ(out.nodes[node].lod_ids.size(), 1u) << ratios;
    const uint32_t lod_node = uint32_t(out.nodes[node].lod_ids[0]);
    for (const uint32_t n : {node, lod_node}) {
      const size_t mesh = size_t(out.nodes[n].mesh);
      ASSERT_EQ(doc["meshes"][mesh]["primitives"][0]["targets"].size(), 1u) << ratios << " node " << n;
      const Mesh* level = gltf_mesh(out, mesh);
      ASSERT_NE(level, nullptr);
      const std::vector<float3> offsets = test::glb_morph_positions(dir / "lod.glb", mesh);
      ASSERT_EQ(offsets.size(), level->vertex_count());
      const bool exact = n == node && std::string(ratios) == "1,0.4";
      for (size_t v = 0; v < level->vertex_count(); ++v) {
        const float3 p = level->positions[v], q = test::morph_offset_inverse(offsets[v]);
        if (exact) {
          ASSERT_EQ(offsets[v], test::morph_offset(p)) << "vertex " << v;
          continue;
        }
        ASSERT_LT(to_input(q), 1e-4 * diagonal) << ratios << " node " << n << " vertex " << v;
        ASSERT_LT(std::hypot(double(p.x) - q.x, double(p.y) - q.y, double(p.z) - q.z), 0.02 * diagonal)
            << ratios << " node " << n << " vertex " << v;
      }
      // The clip drives the level's weight through the same sampler as the skinned node's.
      int sampler = -1, copies = 0;
      for (const auto& channel : doc["animations"][0]["channels"])
        if (channel["target"]["path"] == "weights") {
          if (channel["target"]["node"] == node) sampler = channel["sampler"];
          if (channel["target"]["node"] == n) ++copies;
        }
      EXPECT_GE(sampler, 0);
      EXPECT_EQ(copies, 1) << ratios << " node " << n;
    }
    test::expect_valid_gltf({dir / "lod.glb"});
  }
}

// The morphing torus drawn by one node that scales it by 2 and moves it by `torus_move`, its weight driven
// by one clip.
constexpr float3 torus_move = {1, 2, 3};
Scene one_morphing_node() {
  Scene input = test::morphing_torus();
  input.nodes[0].translation = torus_move, input.nodes[0].scale = {2, 2, 2};
  Animation clip;
  clip.channels.push_back({.node = 0, .path = AnimationPath::weights, .times = {0, 1}, .values = {0, 1}, .components = 1});
  input.animations.push_back(clip);
  return input;
}

// A static glTF whose one node draws a morphing torus (scaled by 2 and moved): every level of the
// chain keeps the morph target, in world space (the levels are flattened), interpolated where the
// vertices moved, and the clip that drives the node's weight drives each level's; with geomorphs too.
// A level of the morphing torus (scaled by 2, centred on `centre`) and its morph target `target`
// in a .glb, taken back to the torus's own space and checked by expect_points_on_torus: how many
// vertices moved off the input.
size_t torus_offsets_moved(const std::filesystem::path& file, size_t mesh, const Mesh& level, size_t target = 0,
                           const float3& centre = torus_move) {
  Mesh local = level;
  for (float3& p : local.positions) p = {(p.x - centre.x) / 2, (p.y - centre.y) / 2, (p.z - centre.z) / 2};
  std::vector<float3> offsets = test::glb_morph_positions(file, mesh, 0, target);
  for (float3& d : offsets) d = {d.x / 2, d.y / 2, d.z / 2};
  return test::expect_points_on_torus(local, offsets, file.filename().string() + " mesh " + std::to_string(mesh));
}

TEST(CliLod, StaticLevelsKeepOneNodesMorphTargets) {
  test::TempDir dir;
  Scene input = one_morphing_node();
  ASSERT_EQ(input.nodes.size(), 1u);
  write_scene(input, dir / "one.glb");

  const test::RunResult r = test::run_cli({"lod", (dir / "one.glb").string(), "-o", (dir / "lod.glb").string(),
                                           "--ratios", "1,0.5,0.2", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json report = nlohmann::json::parse(r.out);
  EXPECT_EQ(report["morph_targets"], 1);
  EXPECT_FALSE(report["morph_targets_dropped"].get<bool>());
  const Scene out = read_scene(dir / "lod.glb");
  const nlohmann::json doc = glb_json(dir / "lod.glb");
  const std::vector<size_t> levels = level_nodes(doc);
  for (const size_t n : levels) {
    const nlohmann::json& node = doc["nodes"][n];
    const size_t mesh = node["mesh"];
    ASSERT_EQ(doc["meshes"][mesh]["primitives"].size(), 1u);
    ASSERT_EQ(doc["meshes"][mesh]["primitives"][0]["targets"].size(), 1u) << "node " << n;
    const Mesh* level = gltf_mesh(out, mesh);
    ASSERT_NE(level, nullptr);
    const size_t moved = torus_offsets_moved(dir / "lod.glb", mesh, *level);
    if (level->triangle_count() < 1600) {
      EXPECT_GT(moved, level->vertex_count() / 10) << "node " << n;
    }
    EXPECT_EQ(weight_channels(doc, 0, n), 1u) << "node " << n;  // the clip drives the level's weight too
  }
  EXPECT_EQ(levels.size(), 3u);
  test::expect_valid_gltf({dir / "lod.glb"});
  // With geomorphs: level 0 has the input's target, then its geomorph (target 1), which moves each
  // vertex onto one of level 1's; the clip drives target 0 and holds the geomorph at 0.
  const test::RunResult geomorphs = test::run_cli({"lod", (dir / "one.glb").string(), "-o", (dir / "geomorph.glb").string(),
                                                   "--ratios", "1,0.5", "--morph", "--json"});
  ASSERT_EQ(geomorphs.exit_code, 0) << geomorphs.err;
  EXPECT_FALSE(nlohmann::json::parse(geomorphs.out)["morph_targets_dropped"].get<bool>());
  test::expect_valid_gltf({dir / "geomorph.glb"});
  {
    const Scene morphed = read_scene(dir / "geomorph.glb");
    const nlohmann::json gdoc = glb_json(dir / "geomorph.glb");
    const std::vector<size_t> morph_levels = level_nodes(gdoc);
    ASSERT_EQ(morph_levels.size(), 2u);
    const nlohmann::json& fine = gdoc["nodes"][morph_levels[0]];
    ASSERT_EQ(fine["extras"]["LODKIT_geomorph"]["target"], 1);
    const size_t fine_mesh = fine["mesh"], coarse_mesh = gdoc["nodes"][morph_levels[1]]["mesh"];
    ASSERT_EQ(gdoc["meshes"][fine_mesh]["primitives"][0]["targets"].size(), 2u);
    ASSERT_EQ(gdoc["meshes"][coarse_mesh]["primitives"][0]["targets"].size(), 1u);
    const Mesh *fine_level = gltf_mesh(morphed, fine_mesh), *coarse_level = gltf_mesh(morphed, coarse_mesh);
    ASSERT_TRUE(fine_level && coarse_level);
    torus_offsets_moved(dir / "geomorph.glb", fine_mesh, *fine_level);
    const std::vector<float3> geomorph = test::glb_morph_positions(dir / "geomorph.glb", fine_mesh, 0, 1);
    ASSERT_EQ(geomorph.size(), fine_level->vertex_count());
    for (size_t v = 0; v < geomorph.size(); ++v) {
      const float3& p = fine_level->positions[v];
      const float3 to = {p.x + geomorph[v].x, p.y + geomorph[v].y, p.z + geomorph[v].z};
      double nearest = 1e30;
      for (const float3& q : coarse_level->positions)
        nearest = std::min(nearest, std::hypot(double(q.x) - to.x, double(q.y) - to.y, double(q.z) - to.z));
      ASSERT_LT(nearest, 1e-5) << "vertex " << v;
    }
    // Level 0's weights channel: two weights per key, the clip's then 0.
    size_t channels = 0;
    for (const auto& channel : gdoc["animations"][0]["channels"]) {
      if (channel["target"]["path"] != "weights" || channel["target"]["node"] != morph_levels[0]) continue;
      ++channels;
      const nlohmann::json& sampler = gdoc["animations"][0]["samplers"][channel["sampler"].get<size_t>()];
      const std::vector<float> weights = test::glb_floats(dir / "geomorph.glb", sampler["output"]);
      EXPECT_EQ(weights, (std::vector<float>{0, 0, 1, 0}));
    }
    EXPECT_EQ(channels, 1u);
  }
  // lod on that chain: the nodes lod once wrote, each level's weights driven by the clip as before:
  // with geomorphs, level 0's again the clip's then 0; without, the clip's alone (the earlier first
  // level, which holds the weights and clip, is the new one).
  for (const bool morph : {true, false}) {
    SCOPED_TRACE(morph);
    std::vector<std::string> args = {"lod", (dir / "geomorph.glb").string(), "-o", (dir / "relod.glb").string(), "--ratios",
                                     "1,0.5"};
    if (morph) args.push_back("--morph");
    ASSERT_EQ(test::run_cli(args).exit_code, 0);
    test::expect_valid_gltf({dir / "relod.glb"});
    const nlohmann::json rdoc = glb_json(dir / "relod.glb");
    EXPECT_EQ(node_structure(rdoc), node_structure(glb_json(dir / "geomorph.glb")));
    const std::vector<size_t> relod_levels = level_nodes(rdoc);
    ASSERT_EQ(relod_levels.size(), 2u);
    for (size_t i = 0; i < 2; ++i) {
      const size_t n = relod_levels[i];
      ASSERT_EQ(weight_channels(rdoc, 0, n), 1u) << n;
      for (const auto& channel : rdoc["animations"][0]["channels"]) {
        if (channel["target"]["path"] != "weights" || channel["target"]["node"] != n) continue;
        const nlohmann::json& sampler = rdoc["animations"][0]["samplers"][channel["sampler"].get<size_t>()];
        const std::vector<float> weights = i == 0 && morph ? std::vector<float>{0, 0, 1, 0} : std::vector<float>{0, 1};
        EXPECT_EQ(test::glb_floats(dir / "relod.glb", sampler["output"]), weights) << n;
      }
    }
  }
  // lodkit simplify on that chain: each level it changes loses its geomorph (stale: it moved the
  // old vertices), but keeps the input's blend shape, carried to its new vertices, and the clip then
  // drives one weight per key. Level 0 was the input torus, so its new vertices' offsets name points
  // on the morphed torus as above (level 1's, blends of blends, lie further inside its chords).
  const test::RunResult simplified =
      test::run_cli({"simplify", (dir / "geomorph.glb").string(), "-o", (dir / "again.glb").string(), "--ratio", "0.5"});
  ASSERT_EQ(simplified.exit_code, 0) << simplified.err;
  test::expect_valid_gltf({dir / "again.glb"});
  const Scene again = read_scene(dir / "again.glb");
  const nlohmann::json adoc = glb_json(dir / "again.glb");
  const std::vector<size_t> again_levels = level_nodes(glb_json(dir / "geomorph.glb"));  // (the same nodes)
  ASSERT_EQ(again_levels.size(), 2u);
  for (const size_t n : again_levels) {
    const nlohmann::json& node = adoc["nodes"][n];
    EXPECT_FALSE(node.value("extras", nlohmann::json::object()).contains("LODKIT_geomorph")) << n;
    const size_t mesh = node["mesh"];
    ASSERT_EQ(adoc["meshes"][mesh]["primitives"][0]["targets"].size(), 1u) << "node " << n;
    const Mesh* level = gltf_mesh(again, mesh);
    ASSERT_NE(level, nullptr);
    if (n == again_levels[0]) {
      EXPECT_GT(torus_offsets_moved(dir / "again.glb", mesh, *level), 0u);
    }
    if (node.contains("weights")) {
      EXPECT_EQ(node["weights"].size(), 1u) << n;
    }
    for (const auto& channel : adoc["animations"][0]["channels"]) {
      if (channel["target"]["path"] != "weights" || channel["target"]["node"] != n) continue;
      const nlohmann::json& sampler = adoc["animations"][0]["samplers"][channel["sampler"].get<size_t>()];
      EXPECT_EQ(test::glb_floats(dir / "again.glb", sampler["output"]), (std::vector<float>{0, 1})) << n;
    }
  }
}

// `from` with the weights and weights channel of `nodes` (which draw one mesh, driven alike) made
// the mesh's: the first node's channel a KHR_animation_pointer "/meshes/M/weights", the others'
// channels gone. The same animation, as the nodes have no weights of their own.
void weights_to_mesh_pointer(const std::filesystem::path& from, const std::filesystem::path& to, const std::vector<size_t>& nodes) {
  test::Glb glb = test::read_glb(from);
  nlohmann::json& doc = glb.doc;
  const size_t mesh = doc["nodes"][nodes[0]]["mesh"];
  if (doc["nodes"][nodes[0]].contains("weights")) doc["meshes"][mesh]["weights"] = doc["nodes"][nodes[0]]["weights"];
  for (const size_t n : nodes) {
    ASSERT_EQ(doc["nodes"][n]["mesh"], mesh);
    doc["nodes"][n].erase("weights");
  }
  nlohmann::json& channels = doc["animations"][0]["channels"];
  const auto drives = [&](const nlohmann::json& channel, size_t n) {
    return channel["target"]["path"] == "weights" && channel["target"]["node"] == n;
  };
  for (size_t k = 1; k < nodes.size(); ++k)
    channels.erase(std::remove_if(channels.begin(), channels.end(), [&](const nlohmann::json& c) { return drives(c, nodes[k]); }),
                   channels.end());
  size_t pointers = 0;
  for (nlohmann::json& channel : channels)
    if (drives(channel, nodes[0])) {
      channel["target"] = {{"path", "pointer"},
                           {"extensions", {{"KHR_animation_pointer", {{"pointer", "/meshes/" + std::to_string(mesh) + "/weights"}}}}}};
      ++pointers;
    }
  ASSERT_EQ(pointers, 1u);
  doc["extensionsUsed"].push_back("KHR_animation_pointer");
  test::write_bytes(to, test::glb_bytes(glb));
  test::expect_valid_gltf({to});
}

// A mesh's weights animated through KHR_animation_pointer drive the levels as the nodes' channels
// do: a static chain with geomorphs of one node, and one of two nodes drawing the mesh (whose
// levels take both nodes' weights in turn, merged), come out byte for byte as from the nodes'
// channels (the source mesh goes, its pointer with it); a level's pointer loses the weight of a
// geomorph lodkit simplify drops; a skinned character's levels each take a core channel with the
// clip's keys (the source mesh stays, and its pointer).
TEST(CliLod, LevelsFollowAMeshWeightsPointer) {
  test::TempDir dir;
  Scene two = one_morphing_node();
  two.nodes.push_back(two.nodes[0]);
  two.nodes[1].translation = {5, 0, 0};
  two.roots.push_back(1);
  two.animations[0].channels.push_back(two.animations[0].channels[0]);
  two.animations[0].channels[1].node = 1;
  const std::vector<std::pair<Scene, std::vector<size_t>>> inputs = {{one_morphing_node(), {0}}, {two, {0, 1}}};
  for (const auto& [scene, nodes] : inputs) {
    SCOPED_TRACE(nodes.size());
    write_scene(scene, dir / "node.glb");
    weights_to_mesh_pointer(dir / "node.glb", dir / "pointer.glb", nodes);
    for (const char* name : {"node", "pointer"})
      ASSERT_EQ(test::run_cli({"lod", (dir / (std::string(name) + ".glb")).string(), "-o", (dir / (std::string(name) + "-lod.glb")).string(),
                               "--ratios", "1,0.5,0.2", "--morph"}).exit_code, 0) << name;
    const test::Glb from_node = test::read_glb(dir / "node-lod.glb"), from_pointer = test::read_glb(dir / "pointer-lod.glb");
    EXPECT_EQ(from_pointer.doc, from_node.doc);
    EXPECT_TRUE(from_pointer.bin == from_node.bin);
    EXPECT_EQ(weight_channels(from_pointer.doc, 0, level_nodes(from_pointer.doc)[0]), 1u);
  }
  // The one node's chain with level 0's weights made its mesh's: lodkit simplify drops that level's
  // geomorph (as in StaticLevelsKeepOneNodesMorphTargets), so the mesh's weights (when it has any)
  // and each of the pointer's keys lose their second weight.
  write_scene(one_morphing_node(), dir / "node.glb");
  ASSERT_EQ(test::run_cli({"lod", (dir / "node.glb").string(), "-o", (dir / "geomorph.glb").string(), "--ratios", "1,0.5", "--morph"}).exit_code, 0);
  const size_t fine = level_nodes(glb_json(dir / "geomorph.glb"))[0];
  weights_to_mesh_pointer(dir / "geomorph.glb", dir / "geomorph-pointer.glb", {fine});
  ASSERT_EQ(test::run_cli({"simplify", (dir / "geomorph-pointer.glb").string(), "-o", (dir / "again.glb").string(), "--ratio", "0.5"}).exit_code, 0);
  test::expect_valid_gltf({dir / "again.glb"});
  {
    const nlohmann::json doc = glb_json(dir / "again.glb");
    const size_t mesh = doc["nodes"][fine]["mesh"];
    EXPECT_EQ(doc["meshes"][mesh].value("weights", nlohmann::json::array({0.0})), nlohmann::json::array({0.0}));
    size_t pointers = 0;
    for (const auto& channel : doc["animations"][0]["channels"])
      if (channel["target"]["path"] == "pointer") {
        EXPECT_EQ(channel["target"]["extensions"]["KHR_animation_pointer"]["pointer"], "/meshes/" + std::to_string(mesh) + "/weights");
        const nlohmann::json& sampler = doc["animations"][0]["samplers"][channel["sampler"].get<size_t>()];
        EXPECT_EQ(test::glb_floats(dir / "again.glb", sampler["output"]), (std::vector<float>{0, 1}));
        ++pointers;
      }
    EXPECT_EQ(pointers, 1u);
  }

  const Scene humanoid = humanoid_with_blend_shape();
  const uint32_t skinned = skinned_primitives(humanoid).at(0).node;
  write_scene(humanoid, dir / "humanoid.glb");
  weights_to_mesh_pointer(dir / "humanoid.glb", dir / "humanoid-pointer.glb", {skinned});
  ASSERT_EQ(test::run_cli({"lod", (dir / "humanoid-pointer.glb").string(), "-o", (dir / "skinned-lod.glb").string(),
                           "--ratios", "1,0.4", "--poses", "4"}).exit_code, 0);
  test::expect_valid_gltf({dir / "skinned-lod.glb"});
  const nlohmann::json doc = glb_json(dir / "skinned-lod.glb");
  const nlohmann::json& lod_ids = doc["nodes"][skinned]["extensions"]["MSFT_lod"]["ids"];
  ASSERT_EQ(lod_ids.size(), 1u);
  const size_t level = lod_ids[0];
  size_t pointers = 0, channels = 0;
  for (const auto& channel : doc["animations"][0]["channels"]) {
    if (channel["target"]["path"] == "pointer") {
      EXPECT_EQ(channel["target"]["extensions"]["KHR_animation_pointer"]["pointer"],
                "/meshes/" + std::to_string(doc["nodes"][skinned]["mesh"].get<size_t>()) + "/weights");
      ++pointers;
    }
    if (channel["target"]["path"] != "weights" || channel["target"]["node"] != level) continue;
    ++channels;
    const nlohmann::json& sampler = doc["animations"][0]["samplers"][channel["sampler"].get<size_t>()];
    EXPECT_EQ(test::glb_floats(dir / "skinned-lod.glb", sampler["input"]), (std::vector<float>{0, 1, 2}));
    EXPECT_EQ(test::glb_floats(dir / "skinned-lod.glb", sampler["output"]), (std::vector<float>{0, 1, 0}));
  }
  EXPECT_EQ(pointers, 1u);
  EXPECT_EQ(channels, 1u);
}

// The morphing torus drawn by two nodes (the second moved to x = 5): every level has both nodes'
// targets in turn, each zero on the other's vertices and on the torus where it moves, and one
// weights channel per clip, keyed at the union of the two nodes' keys: node 0's curve (0 at 0 s, 1
// at 1 s), node 1's (1 at 0.5 s, 0 at 2 s), both linear and held outside their keys. With a step
// curve against a linear one no channel holds both exactly: the targets are dropped and said so,
// the weights' channels go, a clip left empty goes, and a translation's channel (of a third node,
// which draws nothing) stays.
TEST(CliLod, StaticLevelsMergeSeveralNodesMorphTargets) {
  test::TempDir dir;
  Scene input = one_morphing_node();
  Node second = input.nodes[0];
  second.translation = {5, 0, 0};
  Node marker;  // (moved by the clip, it draws nothing: a moving mesh would get a chain of its own)
  marker.name = "marker";
  input.nodes.insert(input.nodes.end(), {second, marker});
  input.roots.insert(input.roots.end(), {1, 2});
  const Animation weights_only = input.animations[0];
  input.animations[0].channels.push_back(
      {.node = 2, .path = AnimationPath::translation, .times = {0, 1}, .values = {5, 0, 0, 6, 0, 0}, .components = 3});
  input.animations[0].channels.push_back({.node = 1, .path = AnimationPath::weights, .times = {0.5f, 2}, .values = {1, 0}, .components = 1});
  input.animations.push_back(weights_only);
  write_scene(input, dir / "two.glb");
  const test::RunResult two = test::run_cli({"lod", (dir / "two.glb").string(), "-o", (dir / "lod2.glb").string(),
                                             "--ratios", "1,0.5", "--json"});
  ASSERT_EQ(two.exit_code, 0) << two.err;
  EXPECT_EQ(nlohmann::json::parse(two.out)["morph_targets"], 2);
  test::expect_valid_gltf({dir / "lod2.glb"});
  const Scene out = read_scene(dir / "lod2.glb");
  const nlohmann::json doc = glb_json(dir / "lod2.glb");
  const std::array<float3, 2> centres = {torus_move, float3{5, 0, 0}};
  const std::vector<size_t> levels = level_nodes(doc);
  for (const size_t n : levels) {
    const nlohmann::json& node = doc["nodes"][n];
    const size_t mesh = node["mesh"];
    ASSERT_EQ(doc["meshes"][mesh]["primitives"][0]["targets"].size(), 2u) << "node " << n;
    const Mesh* level = gltf_mesh(out, mesh);
    ASSERT_NE(level, nullptr);
    for (size_t k = 0; k < 2; ++k) {
      const std::vector<float3> offsets = test::glb_morph_positions(dir / "lod2.glb", mesh, 0, k);
      ASSERT_EQ(offsets.size(), level->vertex_count());
      // Node k's instance in its torus's own space; the other instance does not move.
      Mesh local;
      std::vector<float3> local_offsets;
      for (size_t v = 0; v < level->vertex_count(); ++v) {
        const float3& p = level->positions[v];
        const auto distance = [&](const float3& c) { return std::hypot(p.x - c.x, p.y - c.y, p.z - c.z); };
        const size_t instance = distance(centres[0]) < distance(centres[1]) ? 0 : 1;
        if (instance != k) {
          ASSERT_EQ(offsets[v], (float3{0, 0, 0})) << "node " << n << " target " << k << " vertex " << v;
          continue;
        }
        local.positions.push_back({(p.x - centres[k].x) / 2, (p.y - centres[k].y) / 2, (p.z - centres[k].z) / 2});
        local_offsets.push_back({offsets[v].x / 2, offsets[v].y / 2, offsets[v].z / 2});
      }
      ASSERT_GT(local.positions.size(), 0u);
      test::expect_points_on_torus(local, local_offsets, "node " + std::to_string(n) + " target " + std::to_string(k));
    }
    // One weights channel per clip: times {0, 0.5, 1, 2}; node 0's weight 0, 0.5, 1, 1 and node
    // 1's 1, 1, 1 - 0.5 / 1.5, 0 (first clip); node 0's curve and node 1 at rest, 0 (second).
    const std::array<std::vector<float>, 2> expected_times = {std::vector<float>{0, 0.5f, 1, 2}, std::vector<float>{0, 1}};
    const std::array<std::vector<float>, 2> expected_weights = {std::vector<float>{0, 1, 0.5f, 1, 1, 1 - 0.5f / 1.5f, 1, 0},
                                                                std::vector<float>{0, 0, 1, 0}};
    for (size_t a = 0; a < 2; ++a) {
      size_t channels = 0;
      for (const auto& channel : doc["animations"][a]["channels"]) {
        if (channel["target"]["path"] != "weights" || channel["target"]["node"] != n) continue;
        ++channels;
        const nlohmann::json& sampler = doc["animations"][a]["samplers"][channel["sampler"].get<size_t>()];
        EXPECT_EQ(sampler.value("interpolation", "LINEAR"), "LINEAR");
        EXPECT_EQ(test::glb_floats(dir / "lod2.glb", sampler["input"]), expected_times[a]) << "clip " << a;
        const std::vector<float> weights = test::glb_floats(dir / "lod2.glb", sampler["output"]);
        ASSERT_EQ(weights.size(), expected_weights[a].size()) << "clip " << a;
        for (size_t i = 0; i < weights.size(); ++i) EXPECT_NEAR(weights[i], expected_weights[a][i], 1e-6) << "clip " << a << " " << i;
      }
      EXPECT_EQ(channels, 1u) << "node " << n << " clip " << a;
    }
  }
  EXPECT_EQ(levels.size(), 2u);
  // The levels take the same two nodes' weights: one merged sampler per clip serves them all.
  for (size_t a = 0; a < 2; ++a) {
    std::set<size_t> samplers;
    for (const auto& channel : doc["animations"][a]["channels"])
      if (channel["target"]["path"] == "weights") samplers.insert(channel["sampler"].get<size_t>());
    EXPECT_EQ(samplers.size(), 1u) << "clip " << a;
  }

  // Node 1's curve as a step: no one channel can follow both.
  input.animations[0].channels.back().interpolation = Interpolation::step;
  write_scene(input, dir / "mixed.glb");
  const test::RunResult mixed = test::run_cli({"lod", (dir / "mixed.glb").string(), "-o", (dir / "lod3.glb").string(),
                                               "--ratios", "1,0.5"});
  ASSERT_EQ(mixed.exit_code, 0) << mixed.err;
  EXPECT_NE(mixed.out.find("morph targets dropped: clip"), std::string::npos) << mixed.out;
  EXPECT_EQ(nlohmann::json::parse(test::run_cli({"info", "--json", (dir / "lod3.glb").string()}).out)["gltf"]["morph_targets"], 0);
  // The weights' channels go with their samplers, and the clip left empty (invalid glTF); the
  // translation's stays, its sampler renumbered.
  const nlohmann::json doc3 = glb_json(dir / "lod3.glb");
  ASSERT_EQ(doc3["animations"].size(), 1u);
  ASSERT_EQ(doc3["animations"][0]["channels"].size(), 1u);
  EXPECT_EQ(doc3["animations"][0]["channels"][0]["target"]["path"], "translation");
  EXPECT_EQ(doc3["animations"][0]["channels"][0]["sampler"], 0);
  EXPECT_EQ(doc3["animations"][0]["samplers"].size(), 1u);
  test::expect_valid_gltf({dir / "lod3.glb"});
}

// With one vertex buffer (subset placement), every level takes the buffer's morph target, which is
// the input's own at each of its vertices: exact, one accessor for all levels, and the clip drives
// every level's weight.
TEST(CliLod, SharedVerticesKeepOneNodesMorphTargets) {
  test::TempDir dir;
  write_scene(one_morphing_node(), dir / "one.glb");
  const test::RunResult r = test::run_cli({"lod", (dir / "one.glb").string(), "-o", (dir / "lod.glb").string(),
                                           "--ratios", "1,0.5,0.2", "--shared-vertices", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json report = nlohmann::json::parse(r.out);
  EXPECT_EQ(report["morph_targets"], 1);
  EXPECT_FALSE(report["morph_targets_dropped"].get<bool>());
  test::expect_valid_gltf({dir / "lod.glb"});
  const Scene out = read_scene(dir / "lod.glb");
  const nlohmann::json doc = glb_json(dir / "lod.glb");
  std::set<size_t> positions, targets;
  const std::vector<size_t> levels = level_nodes(doc);
  for (const size_t n : levels) {
    const nlohmann::json& node = doc["nodes"][n];
    const size_t mesh = node["mesh"];
    const nlohmann::json& prim = doc["meshes"][mesh]["primitives"][0];
    ASSERT_EQ(prim["targets"].size(), 1u) << "node " << n;
    positions.insert(prim["attributes"]["POSITION"].get<size_t>());
    targets.insert(prim["targets"][0]["POSITION"].get<size_t>());
    const Mesh* level = gltf_mesh(out, mesh);
    ASSERT_NE(level, nullptr);
    // Every offset names its own vertex: none moved off the input.
    EXPECT_EQ(torus_offsets_moved(dir / "lod.glb", mesh, *level), 0u) << "node " << n;
    EXPECT_EQ(weight_channels(doc, 0, n), 1u) << "node " << n;
  }
  EXPECT_EQ(levels.size(), 3u);
  EXPECT_EQ(positions.size(), 1u);
  EXPECT_EQ(targets.size(), 1u);
  // Compressed and quantized, likewise: one target accessor (in grid steps) for all levels.
  ASSERT_EQ(test::run_cli({"lod", (dir / "one.glb").string(), "-o", (dir / "packed.glb").string(), "--ratios", "1,0.5,0.2",
                           "--shared-vertices", "-c", "-q"}).exit_code, 0);
  test::expect_valid_gltf({dir / "packed.glb"});
  const nlohmann::json packed = glb_json(dir / "packed.glb");
  targets.clear();
  for (const nlohmann::json& mesh : packed["meshes"])
    for (const nlohmann::json& prim : mesh["primitives"])
      if (prim.contains("targets")) targets.insert(prim["targets"][0]["POSITION"].get<size_t>());
  ASSERT_EQ(targets.size(), 1u);
  EXPECT_EQ(packed["accessors"][*targets.begin()]["componentType"], 5122);  // shorts
  // With geomorphs as well: the blend shape once for all levels, then each level's own geomorph.
  ASSERT_EQ(test::run_cli({"lod", (dir / "one.glb").string(), "-o", (dir / "morph.glb").string(), "--ratios", "1,0.5,0.2",
                           "--shared-vertices", "--morph"}).exit_code, 0);
  test::expect_valid_gltf({dir / "morph.glb"});
  const nlohmann::json morph = glb_json(dir / "morph.glb");
  std::set<size_t> blends, geomorphs;
  std::vector<size_t> counts;
  for (const size_t n : level_nodes(morph)) {
    const nlohmann::json& node = morph["nodes"][n];
    const nlohmann::json& prim = morph["meshes"][node["mesh"].get<size_t>()]["primitives"][0];
    counts.push_back(prim["targets"].size());
    blends.insert(prim["targets"][0]["POSITION"].get<size_t>());
    if (prim["targets"].size() == 2) {
      EXPECT_EQ(node["extras"]["LODKIT_geomorph"]["target"], 1);
      geomorphs.insert(prim["targets"][1]["POSITION"].get<size_t>());
    }
  }
  EXPECT_EQ(counts, (std::vector<size_t>{2, 2, 1}));
  EXPECT_EQ(blends.size(), 1u);
  EXPECT_EQ(geomorphs.size(), 2u);
}

// --shared-vertices on a skinned character, in each skin mode: the skinned node and its levels draw
// one vertex buffer (positions, joints, weights) and one blend-shape accessor, whose offsets are
// exact at every vertex (subset placement moves none); each level's indices stay within its prefix.
TEST(CliLod, SkinnedSharedVerticesWriteOneBufferWithItsBlendShapes) {
  test::TempDir dir;
  const Scene input = humanoid_with_blend_shape();
  const std::vector<SkinnedPrimitive> skinned = skinned_primitives(input);
  write_scene(input, dir / "humanoid.glb");
  for (const char* mode : {"houle", "subset", "multipose"}) {
    SCOPED_TRACE(mode);
    const test::RunResult r = test::run_cli({"lod", (dir / "humanoid.glb").string(), "-o", (dir / "lod.glb").string(),
                                             "--ratios", "0.5,0.2", "--poses", "4", "--skin-mode", mode, "--shared-vertices"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    test::expect_valid_gltf({dir / "lod.glb"});
    const Scene out = read_scene(dir / "lod.glb");
    const nlohmann::json doc = glb_json(dir / "lod.glb");
    const uint32_t node = skinned[0].node;
    ASSERT_EQ(out.nodes[node].lod_ids.size(), 1u);
    std::set<std::string> accessors;  // attribute name and accessor, over both levels
    uint64_t previous = ~uint64_t(0);
    for (const uint32_t n : {node, uint32_t(out.nodes[node].lod_ids[0])}) {
      const size_t mesh = size_t(out.nodes[n].mesh);
      const nlohmann::json& prim = doc["meshes"][mesh]["primitives"][0];
      for (const char* name : {"POSITION", "JOINTS_0", "WEIGHTS_0"})
        accessors.insert(std::string(name) + std::to_string(prim["attributes"][name].get<int>()));
      ASSERT_EQ(prim["targets"].size(), 1u);
      accessors.insert("target" + std::to_string(prim["targets"][0]["POSITION"].get<int>()));
      const Mesh* level = gltf_mesh(out, mesh);
      ASSERT_NE(level, nullptr);
      EXPECT_LT(level->triangle_count(), previous);
      previous = level->triangle_count();
      const uint32_t prefix = doc["nodes"][n]["extras"]["lodkit"]["vertex_prefix"];
      for (const uint32_t v : level->indices) ASSERT_LT(v, prefix);
      const std::vector<float3> offsets = test::glb_morph_positions(dir / "lod.glb", mesh);
      ASSERT_EQ(offsets.size(), level->vertex_count());
      for (size_t v = 0; v < offsets.size(); ++v) ASSERT_EQ(offsets[v], test::morph_offset(level->positions[v])) << "vertex " << v;
    }
    EXPECT_EQ(accessors.size(), 4u);  // each of the four once
  }
}

// How many of `mesh`'s positions have no position of `reference` within `tolerance` (a grid of
// cells that size, each point checked against its own and the neighbouring cells).
size_t points_off(const Mesh& mesh, const Mesh& reference, double tolerance) {
  const auto cell = [&](const float3& p) {
    return std::array<int64_t, 3>{int64_t(std::floor(p.x / tolerance)), int64_t(std::floor(p.y / tolerance)),
                                  int64_t(std::floor(p.z / tolerance))};
  };
  std::map<std::array<int64_t, 3>, std::vector<float3>> cells;
  for (const float3& p : reference.positions) cells[cell(p)].push_back(p);
  size_t off = 0;
  for (const float3& p : mesh.positions) {
    const std::array<int64_t, 3> c = cell(p);
    bool near = false;
    for (int64_t dx = -1; dx <= 1 && !near; ++dx)
      for (int64_t dy = -1; dy <= 1 && !near; ++dy)
        for (int64_t dz = -1; dz <= 1 && !near; ++dz) {
          const auto it = cells.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == cells.end()) continue;
          for (const float3& q : it->second) near = near || std::hypot(p.x - q.x, p.y - q.y, p.z - q.z) <= tolerance;
        }
    off += !near;
  }
  return off;
}

// A forest: a morphing torus drawn 30 times by one instanced node (EXT_mesh_gpu_instancing, its
// weight driven by a clip), beside a sphere drawn by a plain node. The torus gets a chain of its
// own, in its own space (one torus's triangles per level, not 30), whose level nodes draw the 30
// instances under the old node and keep the morph target and clip; the sphere gets the static
// chain. Level 0 of both draws the input in place. Compressed and quantized too.
TEST(CliLod, InstancedMeshesGetTheirOwnChain) {
  test::TempDir dir;
  Scene input = one_morphing_node();
  const Mesh sphere = shapes::icosphere(3);
  Primitive ball;
  ball.mesh = sphere, ball.gltf_mesh = 1;
  input.primitives.push_back(ball);
  Node plain;
  plain.name = "ball", plain.mesh = 1, plain.translation = {0, 0, -10};
  input.nodes.push_back(plain);
  input.roots.push_back(1);
  input.nodes[0].name = "trees";
  for (int k = 0; k < 30; ++k)
    input.nodes[0].gpu_instances.push_back({.translation = {float(k % 6) * 8, float(k / 6) * 8, 0},
                                            .rotation = {0, 0, std::sin(0.05f * k), std::cos(0.05f * k)},
                                            .scale = {1, 1, 1 + 0.01f * k}});
  write_scene(input, dir / "forest.glb");
  const Scene read = read_scene(dir / "forest.glb");
  ASSERT_EQ(read.nodes[0].gpu_instances.size(), 30u);
  const size_t torus_triangles = input.primitives[0].mesh.triangle_count();

  for (const bool packed : {false, true}) {
    SCOPED_TRACE(packed ? "-c -q" : "plain");
    std::vector<std::string> args = {"lod", (dir / "forest.glb").string(), "-o", (dir / "lod.glb").string(), "--ratios", "1,0.3", "--json"};
    if (packed) args.insert(args.end(), {"-c", "-q"});
    const test::RunResult r = test::run_cli(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    test::expect_valid_gltf({dir / "lod.glb"});
    const nlohmann::json report = nlohmann::json::parse(r.out);
    EXPECT_EQ(report["levels"][0]["triangles"], sphere.triangle_count());  // the static chain: the sphere alone
    ASSERT_EQ(report["instanced"].size(), 1u);
    EXPECT_EQ(report["instanced"][0]["node"], "trees");
    EXPECT_EQ(report["instanced"][0]["instances"], 30);
    EXPECT_EQ(report["instanced"][0]["levels"][0]["triangles"], torus_triangles);
    EXPECT_LT(report["instanced"][0]["levels"][1]["triangles"].get<size_t>(), torus_triangles);

    const Scene out = read_scene(dir / "lod.glb");
    const nlohmann::json doc = glb_json(dir / "lod.glb");
    EXPECT_FALSE(doc["nodes"][0].contains("mesh"));
    ASSERT_EQ(doc["nodes"][0]["children"].size(), 1u);
    const size_t lod0 = doc["nodes"][0]["children"][0];
    ASSERT_EQ(out.nodes[lod0].lod_ids.size(), 1u);
    for (const size_t n : {lod0, size_t(out.nodes[lod0].lod_ids[0])}) {
      ASSERT_EQ(out.nodes[n].gpu_instances.size(), 30u) << n;
      for (size_t k = 0; k < 30 && !packed; ++k) {  // (quantized, they take the grid: see flatten below)
        EXPECT_NEAR(out.nodes[n].gpu_instances[k].translation.x, read.nodes[0].gpu_instances[k].translation.x, 1e-3) << k;
        EXPECT_NEAR(out.nodes[n].gpu_instances[k].scale.z, read.nodes[0].gpu_instances[k].scale.z, 1e-3) << k;
      }
      const nlohmann::json& prim = doc["meshes"][doc["nodes"][n]["mesh"].get<size_t>()]["primitives"][0];
      EXPECT_EQ(prim["targets"].size(), 1u) << n;
      EXPECT_EQ(weight_channels(doc, 0, n), 1u) << n;
    }
    // Level 0 everywhere draws the input: the same points, in world space (within the grid's step when quantized).
    const Mesh before = flatten(read);
    Scene first = out;
    for (Node& node : first.nodes) node.lod_ids.clear();
    const Mesh after = flatten(first);
    EXPECT_EQ(after.triangle_count(), before.triangle_count());
    float3 lo, hi;
    bounding_box(before, lo, hi);
    const double tolerance = packed ? 1e-3 * std::hypot(hi.x - lo.x, hi.y - lo.y, hi.z - lo.z) : 1e-4;
    EXPECT_EQ(points_off(after, before, tolerance), 0u);
  }
}

// One torus drawn by two instanced nodes (3 and 2 instances) and a plain node, beside a sphere: the
// torus gets one chain, whose levels (the same glTF meshes) each of the three nodes draws under
// it, with its own instances (none for the plain one); the sphere gets the static chain. Level 0
// draws the input in place.
TEST(CliLod, AMeshDrawnByManyNodesGetsOneChain) {
  test::TempDir dir;
  Scene input = one_morphing_node();
  input.animations.clear();
  Primitive ball;
  ball.mesh = shapes::icosphere(2), ball.gltf_mesh = 1;
  input.primitives.push_back(ball);
  input.nodes[0].name = "a";
  for (int k = 0; k < 3; ++k) input.nodes[0].gpu_instances.push_back({.translation = {float(6 * k), 0, 0}});
  Node b = input.nodes[0], c = input.nodes[0], d;
  b.name = "b", b.translation = {0, 10, 0}, b.gpu_instances.resize(2);
  c.name = "c", c.translation = {0, -10, 0}, c.gpu_instances.clear();
  d.name = "ball", d.mesh = 1, d.translation = {0, 0, -10};
  input.nodes.insert(input.nodes.end(), {b, c, d});
  input.roots = {0, 1, 2, 3};
  write_scene(input, dir / "many.glb");
  const test::RunResult r = test::run_cli({"lod", (dir / "many.glb").string(), "-o", (dir / "lod.glb").string(), "--ratios", "1,0.25", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  test::expect_valid_gltf({dir / "lod.glb"});
  const nlohmann::json report = nlohmann::json::parse(r.out);
  ASSERT_EQ(report["instanced"].size(), 1u);
  EXPECT_EQ(report["instanced"][0]["node"], "a, b, c");
  EXPECT_EQ(report["instanced"][0]["instances"], 6);
  EXPECT_EQ(report["instanced"][0]["levels"][0]["triangles"], input.primitives[0].mesh.triangle_count());
  EXPECT_EQ(report["levels"][0]["triangles"], ball.mesh.triangle_count());
  const Scene out = read_scene(dir / "lod.glb");
  std::set<std::vector<int32_t>> level_meshes;  // per node: its levels' glTF meshes
  for (size_t n = 0; n < 3; ++n) {
    ASSERT_EQ(out.nodes[n].children.size(), 1u) << n;
    EXPECT_EQ(out.nodes[n].mesh, -1) << n;
    const Node& lod0 = out.nodes[size_t(out.nodes[n].children[0])];
    ASSERT_EQ(lod0.lod_ids.size(), 1u) << n;
    EXPECT_EQ(lod0.gpu_instances.size(), input.nodes[n].gpu_instances.size()) << n;
    EXPECT_EQ(out.nodes[size_t(lod0.lod_ids[0])].gpu_instances.size(), input.nodes[n].gpu_instances.size()) << n;
    level_meshes.insert({lod0.mesh, out.nodes[size_t(lod0.lod_ids[0])].mesh});
  }
  EXPECT_EQ(level_meshes.size(), 1u);
  // lodkit info lists the four chains: the sphere's, then the torus's under a, b and c.
  const nlohmann::json info = nlohmann::json::parse(test::run_cli({"info", "--json", (dir / "lod.glb").string()}).out);
  const nlohmann::json& chains = info["gltf"]["lod_chains"];
  ASSERT_EQ(chains.size(), 4u);
  EXPECT_EQ(chains[0]["triangles"][0], ball.mesh.triangle_count());
  const std::array<const char*, 3> names = {"a_LOD0", "b_LOD0", "c_LOD0"};
  const std::array<size_t, 3> instances = {3, 2, 1};
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(chains[k + 1]["node"], names[k]);
    EXPECT_EQ(chains[k + 1]["instances"], instances[k]);
    EXPECT_EQ(chains[k + 1]["triangles"], chains[1]["triangles"]);
    EXPECT_EQ(chains[k + 1]["triangles"][0], input.primitives[0].mesh.triangle_count());
  }
  const Mesh before = flatten(read_scene(dir / "many.glb")), after = flatten(out);
  EXPECT_EQ(after.triangle_count(), before.triangle_count());
  EXPECT_EQ(points_off(after, before, 1e-4), 0u);
  // lod on its own output: the earlier coarser levels and the sphere's chain go, and the nodes lod
  // once wrote stay. The torus morphs, and its first levels' weights drive it now (those of a, b
  // and c went with their meshes): each is the new first level. Level 0 still draws the input.
  const auto lod_again = [&](const char* from, const char* to) {
    const test::RunResult again =
        test::run_cli({"lod", (dir / from).string(), "-o", (dir / to).string(), "--ratios", "1,0.25", "--json"});
    EXPECT_EQ(again.exit_code, 0) << again.err;
    test::expect_valid_gltf({dir / to});
    const Mesh twice = flatten(read_scene(dir / to));
    EXPECT_EQ(twice.triangle_count(), before.triangle_count());
    EXPECT_EQ(points_off(twice, before, 1e-4), 0u);
    return nlohmann::json::parse(again.out);
  };
  EXPECT_EQ(lod_again("lod.glb", "again.glb")["instanced"][0]["node"], "a, b, c");
  const nlohmann::json once = glb_json(dir / "lod.glb"), twice = glb_json(dir / "again.glb");
  EXPECT_EQ(node_structure(twice), node_structure(once));
  std::vector<std::string> empty;  // nodes that draw nothing and have no children
  for (const nlohmann::json& node : twice["nodes"])
    if (!node.contains("mesh") && !node.contains("children")) empty.push_back(node["name"]);
  EXPECT_EQ(empty, std::vector<std::string>{"ball"});
  // Without morph targets, the new levels go below a, b and c in place of the old (which go).
  input.primitives[0].targets.clear();
  write_scene(input, dir / "still.glb");
  ASSERT_EQ(test::run_cli({"lod", (dir / "still.glb").string(), "-o", (dir / "still-lod.glb").string(), "--ratios", "1,0.25"}).exit_code, 0);
  EXPECT_EQ(lod_again("still-lod.glb", "still-again.glb")["instanced"][0]["node"], "a, b, c");
  EXPECT_EQ(node_structure(glb_json(dir / "still-again.glb")), node_structure(glb_json(dir / "still-lod.glb")));
}

// `scene` (its nodes' transforms) as clip 0 poses it at `time`, flattened (coarser levels left out).
Mesh posed(Scene scene, float time) {
  Pose pose = rest_pose(scene);
  sample_animation(scene, 0, time, pose);
  for (size_t n = 0; n < scene.nodes.size(); ++n) {
    Node& node = scene.nodes[n];
    node.lod_ids.clear();
    if (!node.has_matrix) node.translation = pose.translation[n], node.rotation = pose.rotation[n], node.scale = pose.scale[n];
  }
  return flatten(scene);
}

// Level 0 of `out` draws `in`'s points where `in` has them, as clip 0 poses both at each of `times`.
void expect_posed_alike(const Scene& in, const Scene& out, std::initializer_list<float> times) {
  for (const float time : times) {
    SCOPED_TRACE(time);
    const Mesh before = posed(in, time), after = posed(out, time);
    EXPECT_EQ(after.triangle_count(), before.triangle_count());
    EXPECT_EQ(points_off(after, before, 1e-4), 0u);
  }
}

// `lodkit lod DIR/IN -o DIR/OUT --json` with `options`: its report, after checking that it
// succeeded and wrote valid glTF.
nlohmann::json lod_report(const std::filesystem::path& dir, const char* in, const char* out, std::vector<std::string> options) {
  std::vector<std::string> args = {"lod", (dir / in).string(), "-o", (dir / out).string(), "--json"};
  args.insert(args.end(), options.begin(), options.end());
  const test::RunResult r = test::run_cli(args);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  test::expect_valid_gltf({dir / out});
  return nlohmann::json::parse(r.out);
}

// Appends a glTF mesh per given mesh, one primitive each, numbered on from the scene's primitives.
void add_meshes(Scene& scene, std::initializer_list<const Mesh*> meshes) {
  for (const Mesh* m : meshes) {
    Primitive p;
    p.mesh = *m, p.gltf_mesh = uint32_t(scene.primitives.size());
    scene.primitives.push_back(std::move(p));
  }
}

// A torus spun by a clip ("spinner"), a sphere on an arm below it ("arm", moved by its parent's
// motion only), a blade below the arm that a second channel also turns ("blade") and a static
// sphere ("base"). The torus and the arm's sphere move together: one chain for the pair (a rigid
// group) in the spinner's space, under it; the blade moves on its own: a chain of its own under
// its node; the base gets the static chain. The clip still moves them all (level 0 draws the input
// as the clip poses it, at any time); baked into the static chain at rest, they would stand still.
TEST(CliLod, AnimatedNodesKeepTheirMotion) {
  test::TempDir dir;
  Scene input;
  const Mesh torus = shapes::torus(1.0f, 0.3f, 32, 16), ball = shapes::icosphere(2), base = shapes::icosphere(1),
             blade = shapes::torus(0.4f, 0.05f, 24, 8);
  add_meshes(input, {&torus, &ball, &base, &blade});
  Node spinner, arm, stand, fan;
  spinner.name = "spinner", spinner.mesh = 0, spinner.translation = {0, 0, 2}, spinner.children = {1};
  arm.name = "arm", arm.mesh = 1, arm.translation = {3, 0, 0}, arm.scale = {0.5f, 0.5f, 0.5f}, arm.children = {3};
  stand.name = "base", stand.mesh = 2, stand.translation = {0, 0, -3};
  fan.name = "blade", fan.mesh = 3, fan.translation = {0, 2, 0};
  input.nodes = {spinner, arm, stand, fan};
  input.roots = {0, 2};
  Animation spin;
  spin.name = "spin";
  // A quarter turn per second, keyed every quarter second (linear slerp between close keys): the
  // spinner about z, the blade about x.
  AnimationChannel turn{.node = 0, .path = AnimationPath::rotation, .times = {}, .values = {}, .components = 4}, roll = turn;
  roll.node = 3;
  for (int k = 0; k <= 8; ++k) {
    const float angle = float(M_PI) / 8 * float(k) / 2;
    turn.times.push_back(float(k) / 4), roll.times.push_back(float(k) / 4);
    turn.values.insert(turn.values.end(), {0, 0, std::sin(angle / 2), std::cos(angle / 2)});
    roll.values.insert(roll.values.end(), {std::sin(angle / 2), 0, 0, std::cos(angle / 2)});
  }
  spin.channels = {turn, roll};
  input.animations.push_back(spin);
  write_scene(input, dir / "spin.glb");

  const test::RunResult r = test::run_cli({"lod", (dir / "spin.glb").string(), "-o", (dir / "lod.glb").string(), "--ratios", "1,0.3", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  test::expect_valid_gltf({dir / "lod.glb"});
  const nlohmann::json report = nlohmann::json::parse(r.out);
  EXPECT_EQ(report["levels"][0]["triangles"], base.triangle_count());  // the static chain: the base alone
  EXPECT_FALSE(report.contains("instanced"));
  ASSERT_EQ(report["animated"].size(), 2u);
  EXPECT_EQ(report["animated"][0]["node"], "spinner");
  EXPECT_EQ(report["animated"][0]["group_nodes"], 2);
  EXPECT_EQ(report["animated"][0]["levels"][0]["triangles"], torus.triangle_count() + ball.triangle_count());
  EXPECT_LT(report["animated"][0]["levels"][1]["triangles"].get<size_t>(), torus.triangle_count());
  EXPECT_EQ(report["animated"][1]["node"], "blade");
  EXPECT_FALSE(report["animated"][1].contains("group_nodes"));
  EXPECT_EQ(report["animated"][1]["levels"][0]["triangles"], blade.triangle_count());

  const Scene in = read_scene(dir / "spin.glb"), out = read_scene(dir / "lod.glb");
  for (const size_t n : {0, 1, 3}) EXPECT_EQ(out.nodes[n].mesh, -1) << n;
  for (const size_t n : {0, 3}) {
    ASSERT_FALSE(out.nodes[n].children.empty()) << n;
    const Node& lod0 = out.nodes[size_t(out.nodes[n].children.back())];
    EXPECT_EQ(lod0.name, input.nodes[n].name + "_LOD0");
    EXPECT_EQ(lod0.lod_ids.size(), 1u) << n;
  }
  EXPECT_EQ(out.nodes[1].children, input.nodes[1].children);  // the arm's sphere is the spinner's chain's
  expect_posed_alike(in, out, {0.0f, 0.6f, 2.0f});
  // The moving meshes have moved: posed at 2 s, the input's arm and blade are not where they stand at rest.
  EXPECT_GT(points_off(posed(in, 2.0f), posed(in, 0.0f), 1e-2), (ball.vertex_count() + blade.vertex_count()) / 2);
  // lod on its own output: the nodes lod once wrote, and the same motion.
  ASSERT_EQ(test::run_cli({"lod", (dir / "lod.glb").string(), "-o", (dir / "again.glb").string(), "--ratios", "1,0.3"}).exit_code, 0);
  test::expect_valid_gltf({dir / "again.glb"});
  EXPECT_EQ(node_structure(glb_json(dir / "again.glb")), node_structure(glb_json(dir / "lod.glb")));
  expect_posed_alike(in, read_scene(dir / "again.glb"), {0.0f, 0.6f, 2.0f});
}

// A turntable: a clip spins the root, and 12 static parts below it (three meshes, one of them drawn
// by ten nodes) move with it. One chain for the lot (a rigid group), not one per mesh, in the
// root's space: the chain the same parts get at rest (no clip, the root at the origin) in the static
// chain, level for level. The clip still moves every level-0 point with the root.
TEST(CliLod, ARigidGroupGetsOneChain) {
  test::TempDir dir;
  Scene input;
  const Mesh plate = shapes::icosphere(3), post = shapes::torus(0.2f, 0.05f, 16, 8), top = shapes::icosphere(2);
  add_meshes(input, {&plate, &post, &top});
  Node table;
  table.name = "table";
  input.nodes.push_back(table);
  const auto add = [&](int32_t mesh, float3 at, float size) {
    Node n;
    n.mesh = mesh, n.translation = at, n.scale = {size, size, size}, n.parent = 0;
    input.nodes[0].children.push_back(int32_t(input.nodes.size()));
    input.nodes.push_back(n);
  };
  add(0, {0, 0, 0}, 2.0f);
  for (int k = 0; k < 10; ++k) add(1, {2.5f * std::cos(0.6f * float(k)), 2.5f * std::sin(0.6f * float(k)), 0.5f}, 1.0f);
  add(2, {0, 0, 2.5f}, 0.5f);
  input.roots = {0};
  write_scene(input, dir / "still.glb");
  input.nodes[0].translation = {1, 2, 3};
  Animation spin;
  spin.name = "spin";
  AnimationChannel turn{.node = 0, .path = AnimationPath::rotation, .times = {0, 1, 2}, .values = {}, .components = 4};
  for (const float angle : {0.0f, 1.0f, 2.0f}) turn.values.insert(turn.values.end(), {0, 0, std::sin(angle / 2), std::cos(angle / 2)});
  spin.channels.push_back(turn);
  input.animations.push_back(spin);
  write_scene(input, dir / "spin.glb");

  const auto lod = [&](const char* in, const char* out) { return lod_report(dir.path, in, out, {"--ratios", "1,0.1,0.01"}); };
  const nlohmann::json still = lod("still.glb", "still-lod.glb"), report = lod("spin.glb", "spin-lod.glb");
  ASSERT_EQ(report["animated"].size(), 1u);
  const nlohmann::json& group = report["animated"][0];
  EXPECT_EQ(group["node"], "table");
  EXPECT_EQ(group["group_nodes"], 12);
  EXPECT_EQ(group["levels"][0]["triangles"], plate.triangle_count() + 10 * post.triangle_count() + top.triangle_count());
  EXPECT_FALSE(still.contains("animated"));
  EXPECT_EQ(group["levels"], still["levels"]);
  EXPECT_LT(group["levels"][2]["triangles"].get<size_t>(), group["levels"][1]["triangles"].get<size_t>());

  const Scene in = read_scene(dir / "spin.glb"), out = read_scene(dir / "spin-lod.glb");
  for (size_t n = 1; n < in.nodes.size(); ++n) {
    EXPECT_EQ(out.nodes[n].mesh, -1) << n;
    EXPECT_TRUE(out.nodes[n].children.empty()) << n;
  }
  ASSERT_EQ(out.nodes[0].children.size(), 13u);
  EXPECT_EQ(out.nodes[size_t(out.nodes[0].children.back())].name, "table_LOD0");
  // No static chain: nothing for a progressive mesh (.lpm) of the input.
  const test::RunResult lpm = test::run_cli({"lod", (dir / "spin.glb").string(), "-o", (dir / "o.glb").string(), "--lpm",
                                             (dir / "o.lpm").string()});
  EXPECT_EQ(lpm.exit_code, 1);  // (a usage error)
  EXPECT_NE(lpm.err.find("with chains of its own"), std::string::npos) << lpm.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "o.glb"));
  expect_posed_alike(in, out, {0.0f, 0.7f, 2.0f});
}

// Two morphing tori (two meshes, their weights driven by the clip) below a carrier that the clip
// also moves: a rigid group, whose levels carry both nodes' targets and their weights merged into
// one channel per level, as the static chain of the same file without the carrier's motion does:
// the same levels, targets and weight keys, the group's under the carrier.
TEST(CliLod, ARigidGroupMergesItsNodesMorphTargets) {
  test::TempDir dir;
  Scene input = one_morphing_node();
  Node second = input.nodes[0], carrier;
  input.primitives.push_back(input.primitives[0]);  // (a mesh of its own: one drawn twice keeps its own chain)
  input.primitives.back().gltf_mesh = 1;
  second.mesh = 1, second.translation = {5, 0, 0};
  carrier.name = "carrier", carrier.children = {0, 1};
  input.nodes.insert(input.nodes.end(), {second, carrier});
  input.nodes[0].parent = input.nodes[1].parent = 2;
  input.roots = {2};
  input.animations[0].channels.push_back({.node = 1, .path = AnimationPath::weights, .times = {0.5f, 2}, .values = {1, 0}, .components = 1});
  write_scene(input, dir / "still.glb");
  input.animations[0].channels.push_back(
      {.node = 2, .path = AnimationPath::translation, .times = {0, 1}, .values = {0, 0, 0, 0, 3, 0}, .components = 3});
  write_scene(input, dir / "carried.glb");
  const auto lod = [&](const char* in, const char* out) { return lod_report(dir.path, in, out, {"--ratios", "1,0.5"}); };
  const nlohmann::json still = lod("still.glb", "still-lod.glb"), carried = lod("carried.glb", "carried-lod.glb");
  EXPECT_EQ(still["morph_targets"], 2);
  EXPECT_EQ(carried["morph_targets"], 2);
  ASSERT_EQ(carried["animated"].size(), 1u);
  EXPECT_EQ(carried["animated"][0]["node"], "carrier");
  EXPECT_EQ(carried["animated"][0]["group_nodes"], 2);
  EXPECT_EQ(carried["animated"][0]["levels"], still["levels"]);

  const nlohmann::json a = glb_json(dir / "still-lod.glb"), b = glb_json(dir / "carried-lod.glb");
  const std::vector<size_t> la = level_nodes(a), lb = level_nodes(b);
  ASSERT_EQ(la.size(), 2u);
  ASSERT_EQ(lb.size(), 2u);
  EXPECT_EQ(b["nodes"][2]["children"].back(), lb[0]);
  // The weights channel of clip 0 driving node n of `doc`: its sampler's keys and values.
  const auto weight_keys = [&](const std::filesystem::path& file, const nlohmann::json& doc, size_t n) {
    std::vector<std::vector<float>> keys;
    for (const auto& channel : doc["animations"][0]["channels"])
      if (channel["target"]["path"] == "weights" && channel["target"]["node"] == n) {
        const nlohmann::json& sampler = doc["animations"][0]["samplers"][channel["sampler"].get<size_t>()];
        keys.push_back(test::glb_floats(file, sampler["input"]));
        keys.push_back(test::glb_floats(file, sampler["output"]));
      }
    return keys;
  };
  for (size_t i = 0; i < 2; ++i) {
    SCOPED_TRACE(i);
    const size_t ma = a["nodes"][la[i]]["mesh"], mb = b["nodes"][lb[i]]["mesh"];
    for (size_t k = 0; k < 2; ++k) {
      const std::vector<float3> ta = test::glb_morph_positions(dir / "still-lod.glb", ma, 0, k),
                                tb = test::glb_morph_positions(dir / "carried-lod.glb", mb, 0, k);
      ASSERT_FALSE(ta.empty()) << k;
      EXPECT_TRUE(ta == tb) << k;
    }
    const std::vector<std::vector<float>> ka = weight_keys(dir / "still-lod.glb", a, la[i]), kb = weight_keys(dir / "carried-lod.glb", b, lb[i]);
    ASSERT_EQ(ka.size(), 2u);  // one channel
    EXPECT_EQ(ka, kb);
    EXPECT_EQ(ka[1].size(), 2 * ka[0].size());  // two weights a key: both nodes'
  }
  // lod on its own output: the nodes lod once wrote, each level's weights driven as before (its
  // first level the earlier one, which holds them).
  lod("carried-lod.glb", "again.glb");
  const nlohmann::json c = glb_json(dir / "again.glb");
  EXPECT_EQ(node_structure(c), node_structure(b));
  const std::vector<size_t> lc = level_nodes(c);
  ASSERT_EQ(lc.size(), 2u);
  for (size_t i = 0; i < 2; ++i)
    EXPECT_EQ(weight_keys(dir / "again.glb", c, lc[i]), weight_keys(dir / "carried-lod.glb", b, lb[i])) << i;
}

// KHR_node_visibility: a torus its node hides ("hidden"), and a lamp and a bulb below a node a clip
// switches off after a second (a KHR_animation_pointer, step keys; the node carries no extension
// of its own), beside a shown sphere. In the static chain the hidden torus would show, and the
// switch would turn nothing off: the torus gets a chain of its own under its node, the lamp and
// bulb a rigid group's under the switch, and the static chain is the sphere's alone. Level 0 draws
// what the input does (flatten() leaves the hidden torus out of both), and, every node shown, every
// input point where it was.
TEST(CliLod, VisibilitySwitchesKeepTheirMeshesBelowThem) {
  test::TempDir dir;
  Scene input;
  const Mesh sphere = shapes::icosphere(2), torus = shapes::torus(1.0f, 0.3f, 32, 16), lamp = shapes::icosphere(1),
             bulb = shapes::torus(0.3f, 0.1f, 16, 8);
  add_meshes(input, {&sphere, &torus, &lamp, &bulb});
  Node shown, hidden, blinker, lamp_node, bulb_node;
  shown.name = "shown", shown.mesh = 0;
  hidden.name = "hidden", hidden.mesh = 1, hidden.translation = {4, 0, 0};
  blinker.name = "blinker", blinker.translation = {0, 4, 0}, blinker.children = {3, 4};
  lamp_node.name = "lamp", lamp_node.mesh = 2, lamp_node.parent = 2;
  bulb_node.name = "bulb", bulb_node.mesh = 3, bulb_node.parent = 2, bulb_node.translation = {0, 1.5f, 0};
  input.nodes = {shown, hidden, blinker, lamp_node, bulb_node};
  input.roots = {0, 1, 2};
  write_scene(input, dir / "plain.glb");
  test::Glb glb = test::read_glb(dir / "plain.glb");
  nlohmann::json& doc = glb.doc;
  doc["nodes"][1]["extensions"] = {{"KHR_node_visibility", {{"visible", false}}}};
  // Keys at 0 and 1 s (floats), then on (1) and off (0) as unsigned bytes.
  const size_t at = glb.bin.size(), views = doc["bufferViews"].size(), accessors = doc["accessors"].size();
  const std::array<float, 2> times = {0, 1};
  const auto* time_bytes = reinterpret_cast<const uint8_t*>(times.data());
  glb.bin.insert(glb.bin.end(), time_bytes, time_bytes + sizeof(times));
  glb.bin.insert(glb.bin.end(), {1, 0, 0, 0});
  doc["buffers"][0]["byteLength"] = glb.bin.size();
  doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", at}, {"byteLength", 8}});
  doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", at + 8}, {"byteLength", 2}});
  doc["accessors"].push_back({{"bufferView", views}, {"componentType", 5126}, {"count", 2}, {"type", "SCALAR"}, {"min", {0}}, {"max", {1}}});
  doc["accessors"].push_back({{"bufferView", views + 1}, {"componentType", 5121}, {"count", 2}, {"type", "SCALAR"}});
  const nlohmann::json target = {{"path", "pointer"},
                                 {"extensions", {{"KHR_animation_pointer", {{"pointer", "/nodes/2/extensions/KHR_node_visibility/visible"}}}}}};
  doc["animations"] = {{{"name", "blink"},
                        {"samplers", {{{"input", accessors}, {"output", accessors + 1}, {"interpolation", "STEP"}}}},
                        {"channels", {{{"sampler", 0}, {"target", target}}}}}};
  doc["extensionsUsed"] = {"KHR_node_visibility", "KHR_animation_pointer"};
  test::write_bytes(dir / "switch.glb", test::glb_bytes(glb));
  test::expect_valid_gltf({dir / "switch.glb"});
  {
    // The switch alone, no node with the extension: written again, the document still declares it.
    test::Glb blink = glb;
    blink.doc["nodes"][1].erase("extensions");
    test::write_bytes(dir / "blink.glb", test::glb_bytes(blink));
    write_scene(read_scene(dir / "blink.glb"), dir / "blink-again.glb");
    test::expect_valid_gltf({dir / "blink-again.glb"});
    const nlohmann::json used = test::glb_json(dir / "blink-again.glb")["extensionsUsed"];
    EXPECT_EQ(std::count(used.begin(), used.end(), "KHR_node_visibility"), 1);
  }
  Scene in = read_scene(dir / "switch.glb");
  EXPECT_FALSE(in.nodes[0].has_visibility);
  EXPECT_TRUE(in.nodes[1].has_visibility);
  EXPECT_TRUE(in.nodes[2].has_visibility);
  EXPECT_FALSE(in.nodes[3].has_visibility);
  for (size_t n = 0; n < in.nodes.size(); ++n) EXPECT_EQ(in.nodes[n].visible, n != 1) << n;
  EXPECT_EQ(flatten(in).triangle_count(), sphere.triangle_count() + lamp.triangle_count() + bulb.triangle_count());

  const test::RunResult r = test::run_cli({"lod", (dir / "switch.glb").string(), "-o", (dir / "lod.glb").string(), "--ratios", "1,0.3", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  test::expect_valid_gltf({dir / "lod.glb"});
  const nlohmann::json report = nlohmann::json::parse(r.out);
  EXPECT_EQ(report["levels"][0]["triangles"], sphere.triangle_count());
  EXPECT_FALSE(report.contains("animated"));
  ASSERT_EQ(report["visibility"].size(), 2u);
  EXPECT_EQ(report["visibility"][0]["node"], "hidden");
  EXPECT_EQ(report["visibility"][0]["levels"][0]["triangles"], torus.triangle_count());
  EXPECT_EQ(report["visibility"][1]["node"], "blinker");
  EXPECT_EQ(report["visibility"][1]["group_nodes"], 2);
  EXPECT_EQ(report["visibility"][1]["levels"][0]["triangles"], lamp.triangle_count() + bulb.triangle_count());

  const nlohmann::json out = glb_json(dir / "lod.glb");
  EXPECT_EQ(out["nodes"][1]["extensions"]["KHR_node_visibility"], doc["nodes"][1]["extensions"]["KHR_node_visibility"]);
  EXPECT_EQ(out["animations"][0]["channels"][0]["target"], target);
  for (const size_t n : {1, 2, 3, 4}) EXPECT_FALSE(out["nodes"][n].contains("mesh")) << n;
  for (const auto& [n, name] : {std::pair{1, "hidden_LOD0"}, std::pair{2, "blinker_LOD0"}}) {
    ASSERT_TRUE(out["nodes"][n].contains("children")) << n;
    EXPECT_EQ(out["nodes"][out["nodes"][n]["children"].back().get<size_t>()]["name"], name);
  }
  Scene first = read_scene(dir / "lod.glb");
  for (Node& node : first.nodes) node.lod_ids.clear();
  for (const bool all_shown : {false, true}) {
    SCOPED_TRACE(all_shown);
    if (all_shown)
      for (Scene* scene : {&in, &first})
        for (Node& node : scene->nodes) node.visible = true;
    const Mesh before = flatten(in), after = flatten(first);
    EXPECT_EQ(after.triangle_count(), before.triangle_count());
    EXPECT_EQ(points_off(after, before, 1e-4), 0u);
  }
  EXPECT_EQ(flatten(in).triangle_count(), sphere.triangle_count() + torus.triangle_count() + lamp.triangle_count() + bulb.triangle_count());
}

// A textured sphere (UVs: its x, y) beside a plain torus (no UVs): the static chain keeps each
// material's streams. (Flattened as they are, the sphere's UVs would be dropped: the torus has none.)
// Level 0 has the sphere's UVs exactly; the coarser levels near the sphere's x, y. With one vertex
// buffer, the materials share it, UVs included (the torus's are 0). A node no root reaches draws a
// plain mesh of the textured material: it is not drawn, so the material keeps its UVs.
TEST(CliLod, EachMaterialKeepsItsOwnStreams) {
  test::TempDir dir;
  Mesh sphere = shapes::icosphere(3);
  Mesh torus = shapes::torus(1.0f, 0.3f, 32, 16);
  Mesh spare = shapes::icosphere(1);
  torus.uvs[0].clear(), spare.uvs[0].clear();
  for (const float3& p : sphere.positions) sphere.uvs[0].push_back({p.x, p.y});
  ASSERT_TRUE(sphere.uvs[1].empty());
  Scene input;
  add_meshes(input, {&sphere, &torus, &spare});
  input.material_names = {"textured", "plain"};
  input.primitives[0].material = 0, input.primitives[1].material = 1, input.primitives[2].material = 0;
  Node a, b, c;
  a.name = "sphere", a.mesh = 0;
  b.name = "torus", b.mesh = 1, b.translation = {3, 0, 0};
  c.name = "unreached", c.mesh = 2;
  input.nodes = {a, b, c};
  input.roots = {0, 1};
  write_scene(input, dir / "mixed.glb");
  for (const bool shared : {false, true}) {
    SCOPED_TRACE(shared);
    std::vector<std::string> options = {"--ratios", "1,0.5,0.2"};
    if (shared) options.push_back("--shared-vertices");
    const nlohmann::json report = lod_report(dir.path, "mixed.glb", "lod.glb", options);
    const Scene out = read_scene(dir / "lod.glb");
    size_t first = out.nodes.size();  // the chain's LOD0 node
    for (size_t n = 0; n < out.nodes.size(); ++n)
      if (!out.nodes[n].lod_ids.empty()) first = std::min(first, n);
    ASSERT_LT(first, out.nodes.size());
    ASSERT_EQ(out.nodes[first].lod_ids.size(), 2u);
    std::vector<int32_t> meshes = {out.nodes[first].mesh};
    for (const int32_t id : out.nodes[first].lod_ids) meshes.push_back(out.nodes[size_t(id)].mesh);
    for (size_t i = 0; i < meshes.size(); ++i) {
      SCOPED_TRACE(i);
      size_t seen = 0;
      for (const Primitive& prim : out.primitives) {
        if (int32_t(prim.gltf_mesh) != meshes[i]) continue;
        ++seen;
        const Mesh& m = prim.mesh;
        EXPECT_FALSE(m.normals.empty());
        if (prim.material == 1) {
          EXPECT_EQ(m.uvs[0].empty(), !shared);
          continue;
        }
        ASSERT_EQ(m.uvs[0].size(), m.vertex_count());
        std::set<uint32_t> used(m.indices.begin(), m.indices.end());
        for (const uint32_t v : used) {
          const float tolerance = i == 0 || shared ? 0.0f : 0.05f;
          ASSERT_NEAR(m.uvs[0][v].x, m.positions[v].x, tolerance) << v;
          ASSERT_NEAR(m.uvs[0][v].y, m.positions[v].y, tolerance) << v;
        }
      }
      EXPECT_EQ(seen, 2u);
    }
  }
}

// A skinned character's props get chains too: a rock on the ground (the static chain) and a ball in
// its right hand (a node below the wrist joint, which the walk moves: a chain of its own, under
// it). The character's chain is the one it gets alone; posed by the walk, level 0 draws the input's
// props where they are.
TEST(CliLod, SkinnedCharactersPropsGetChainsToo) {
  test::TempDir dir;
  const Scene humanoid = fixtures::humanoid_scene();
  Scene input = humanoid;
  const Mesh rock = shapes::icosphere(2), ball = shapes::torus(0.08f, 0.03f, 24, 12);
  const uint32_t meshes = uint32_t(input.primitives.size());
  for (const Mesh* m : {&rock, &ball}) {
    Primitive p;
    p.mesh = *m, p.gltf_mesh = meshes + uint32_t(m == &ball);
    input.primitives.push_back(std::move(p));
  }
  int32_t wrist = -1;
  for (size_t n = 0; n < input.nodes.size(); ++n)
    if (input.nodes[n].name == "wrist_r") wrist = int32_t(n);
  ASSERT_GE(wrist, 0);
  Node stone, held;
  stone.name = "rock", stone.mesh = int32_t(meshes), stone.translation = {1.5f, 0, 0}, stone.scale = {0.3f, 0.3f, 0.3f};
  held.name = "ball", held.mesh = int32_t(meshes + 1), held.translation = {0, -0.1f, 0};
  input.nodes.insert(input.nodes.end(), {stone, held});
  input.roots.push_back(int32_t(input.nodes.size() - 2));
  input.nodes[size_t(wrist)].children.push_back(int32_t(input.nodes.size() - 1));
  write_scene(humanoid, dir / "alone.glb");
  write_scene(input, dir / "props.glb");

  const auto lod = [&](const char* in, const char* out) { return lod_report(dir.path, in, out, {"--ratios", "1,0.4", "--poses", "4"}); };
  const nlohmann::json alone = lod("alone.glb", "alone-lod.glb"), report = lod("props.glb", "props-lod.glb");
  EXPECT_FALSE(alone.contains("static"));
  ASSERT_EQ(report["skinned"]["chains"].size(), 1u);
  EXPECT_EQ(report["skinned"]["chains"], alone["skinned"]["chains"]);
  EXPECT_EQ(report["static"]["levels"][0]["triangles"], rock.triangle_count());
  EXPECT_LT(report["static"]["levels"][1]["triangles"].get<size_t>(), rock.triangle_count());
  ASSERT_EQ(report["animated"].size(), 1u);
  EXPECT_EQ(report["animated"][0]["node"], "ball");
  EXPECT_EQ(report["animated"][0]["levels"][0]["triangles"], ball.triangle_count());

  const Scene in = read_scene(dir / "props.glb"), out = read_scene(dir / "props-lod.glb");
  const size_t ball_node = input.nodes.size() - 1;
  EXPECT_EQ(out.nodes[ball_node].mesh, -1);
  ASSERT_EQ(out.nodes[ball_node].children.size(), 1u);
  EXPECT_EQ(out.nodes[size_t(out.nodes[ball_node].children[0])].name, "ball_LOD0");
  expect_posed_alike(in, out, {0.0f, 0.3f, 0.7f});

  // --morph: the props' chains get geomorphs (a morph target on each level but the last, named in
  // its node's extras); the character's chain stays as it was (it morphs at run time, a glTF morph
  // target could not move its joint weights). Level 0 still draws the input in every pose.
  const nlohmann::json morphed = lod_report(dir.path, "props.glb", "props-morph.glb", {"--ratios", "1,0.4", "--poses", "4", "--morph"});
  EXPECT_EQ(morphed["skinned"]["chains"], alone["skinned"]["chains"]);
  EXPECT_EQ(morphed["static"]["geomorphs"], true);
  EXPECT_EQ(morphed["animated"][0]["geomorphs"], true);
  EXPECT_FALSE(morphed["skinned"]["chains"][0].contains("geomorphs"));
  const nlohmann::json doc = test::glb_json(dir / "props-morph.glb");
  std::vector<std::string> morphing;
  for (const nlohmann::json& node : doc["nodes"]) {
    if (!node.contains("extras") || !node["extras"].contains("LODKIT_geomorph")) continue;
    morphing.push_back(node.value("name", ""));
    EXPECT_FALSE(node.contains("skin")) << morphing.back();
    EXPECT_EQ(doc["meshes"][node["mesh"].get<size_t>()]["primitives"][0]["targets"].size(), 1u) << morphing.back();
  }
  std::sort(morphing.begin(), morphing.end());
  EXPECT_EQ(morphing, (std::vector<std::string>{"LOD0", "ball_LOD0"}));
  expect_posed_alike(in, read_scene(dir / "props-morph.glb"), {0.0f, 0.3f, 0.7f});

  // The rock as glTF mesh 0, before the character's: its triangles leave the document (the static
  // chain has them), and the character's levels still share level 0's vertex buffer.
  Scene rock_first = input;
  const auto swapped = [](int32_t mesh) { return mesh == 0 ? 1 : mesh == 1 ? 0 : mesh; };
  for (Primitive& p : rock_first.primitives) p.gltf_mesh = uint32_t(swapped(int32_t(p.gltf_mesh)));
  for (Node& n : rock_first.nodes) n.mesh = swapped(n.mesh);
  std::rotate(rock_first.primitives.begin(), rock_first.primitives.begin() + 1, rock_first.primitives.begin() + 2);  // (the writer numbers meshes by first appearance)
  write_scene(rock_first, dir / "rock-first.glb");
  ASSERT_EQ(read_scene(dir / "rock-first.glb").primitives[0].mesh.triangle_count(), rock.triangle_count());
  const nlohmann::json shared = lod_report(dir.path, "rock-first.glb", "rock-first-lod.glb", {"--ratios", "1,0.4", "--poses", "4", "--shared-vertices"});
  ASSERT_EQ(shared["skinned"]["chains"].size(), 1u);
  EXPECT_EQ(shared["static"]["levels"][0]["triangles"], rock.triangle_count());
  expect_posed_alike(read_scene(dir / "rock-first.glb"), read_scene(dir / "rock-first-lod.glb"), {0.0f, 0.7f});

  // lod on its own output: the character's earlier levels (skinned nodes in its MSFT_lod) are not
  // characters of their own, and give way to the new levels; the rock's and ball's earlier levels
  // go into new chains of the same sizes. As many meshes as the first output, each drawn once, and
  // level 0 still draws the input in every pose. The character alone (no props' chain, that takes
  // every other mesh) too.
  const auto triangles = [](const nlohmann::json& chain) {
    std::vector<size_t> counts;
    for (const nlohmann::json& level : chain["levels"]) counts.push_back(level["triangles"]);
    return counts;
  };
  const auto rerun = [&](const char* first, const nlohmann::json& first_report, const char* second) {
    SCOPED_TRACE(first);
    const nlohmann::json again = lod(first, second);
    EXPECT_EQ(again.contains("static"), first_report.contains("static"));
    if (first_report.contains("static")) {
      EXPECT_EQ(triangles(again["static"]), triangles(first_report["static"]));
      EXPECT_EQ(triangles(again["animated"][0]), triangles(first_report["animated"][0]));
    }
    ASSERT_EQ(again["skinned"]["chains"].size(), 1u);
    EXPECT_EQ(triangles(again["skinned"]["chains"][0]), triangles(first_report["skinned"]["chains"][0]));
    const nlohmann::json first_doc = test::glb_json(dir / first), again_doc = test::glb_json(dir / second);
    EXPECT_EQ(again_doc["meshes"].size(), first_doc["meshes"].size());
    EXPECT_EQ(node_structure(again_doc), node_structure(first_doc));  // (the earlier levels' nodes went)
    std::set<size_t> drawn;
    for (const nlohmann::json& node : again_doc["nodes"]) {
      if (!node.contains("mesh")) {
        EXPECT_FALSE(node.contains("skin")) << node.value("name", "");
        continue;
      }
      EXPECT_TRUE(drawn.insert(node["mesh"].get<size_t>()).second) << node.value("name", "");
    }
    const Scene twice = read_scene(dir / second);
    const uint32_t character = skinned_primitives(twice).at(0).node;
    ASSERT_EQ(twice.nodes[character].lod_ids.size(), 1u);
    const Node& coarser = twice.nodes[size_t(twice.nodes[character].lod_ids[0])];
    EXPECT_EQ(coarser.name, twice.nodes[character].name + "_LOD1");
    EXPECT_GE(coarser.mesh, 0);
  };
  rerun("alone-lod.glb", alone, "alone-again.glb");
  rerun("props-lod.glb", report, "props-again.glb");
  const Scene twice = read_scene(dir / "props-again.glb");
  expect_posed_alike(in, twice, {0.0f, 0.3f, 0.7f});
}

// Border edges of a mesh welded by position (exactly equal floats): its open cracks and holes.
size_t welded_border_edges(const Mesh& m) {
  std::map<std::tuple<float, float, float>, uint32_t> id;
  std::vector<uint32_t> at(m.vertex_count());
  for (size_t v = 0; v < m.vertex_count(); ++v)
    at[v] = id.try_emplace({m.positions[v].x, m.positions[v].y, m.positions[v].z}, uint32_t(id.size())).first->second;
  std::map<std::pair<uint32_t, uint32_t>, int> uses;
  for (size_t t = 0; t < m.triangle_count(); ++t)
    for (size_t c = 0; c < 3; ++c) {
      const uint32_t a = at[m.indices[3 * t + c]], b = at[m.indices[3 * t + (c + 1) % 3]];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  return size_t(std::count_if(uses.begin(), uses.end(), [](const auto& e) { return e.second == 1; }));
}

// A skinned node drawing two primitives (materials): the humanoid (closed) split down its middle,
// x < 0 and x >= 0 by triangle centre, each half its own vertex buffer (the vertices along the cut
// in both). Simplified together: every level's glTF mesh has both halves with their materials,
// level 0 draws the input in every pose, and the cut stays closed: a level's triangles, welded by
// position, have no border edge. (Simplified apart, each half's border along the cut would move on
// its own, and open.) With one vertex buffer, each half keeps its own, which its coarser levels
// share. A .lpm holds the joined halves.
TEST(CliLod, ASkinnedNodesMaterialsAreSimplifiedTogether) {
  test::TempDir dir;
  Scene input = fixtures::humanoid_scene();
  const Mesh whole = input.primitives[0].mesh;
  ASSERT_EQ(welded_border_edges(whole), 0u);
  const std::array<Mesh, 2> halves = fixtures::halves_by_x(whole);
  ASSERT_EQ(halves[0].triangle_count() + halves[1].triangle_count(), whole.triangle_count());
  ASSERT_GT(halves[0].vertex_count() + halves[1].vertex_count(), whole.vertex_count() + 50);  // the cut's copies
  input.material_names = {"left", "right"};
  input.primitives.clear();
  // A blend shape on both halves whose displacement is linear in the position, so that wherever a
  // level's vertex lies, its displacement is known.
  const auto displacement = [](float3 p) { return float3{0.01f * p.y, 0.02f * p.x, 0}; };
  for (uint32_t h = 0; h < 2; ++h) {
    Primitive p;
    p.mesh = halves[h], p.material = int32_t(h), p.gltf_mesh = 0, p.gltf_primitive = h;
    p.targets.emplace_back();
    for (const float3& at : p.mesh.positions) p.targets[0].positions.push_back(displacement(at));
    input.primitives.push_back(std::move(p));
  }
  write_scene(input, dir / "halves.glb");
  const Scene in = read_scene(dir / "halves.glb");
  ASSERT_EQ(in.primitives.size(), 2u);
  ASSERT_EQ(skinned_primitives(in).size(), 2u);
  const size_t node = in.nodes.size() - 1;  // the skinned node (the joints come first)
  ASSERT_EQ(in.nodes[node].skin, 0);

  for (const bool shared : {false, true}) {
    SCOPED_TRACE(shared);
    std::vector<std::string> options = {"--ratios", "1,0.4,0.1", "--poses", "4", "--lpm", (dir / "h.lpm").string()};
    if (shared) options.push_back("--shared-vertices");
    const nlohmann::json report = lod_report(dir.path, "halves.glb", "lod.glb", options);
    ASSERT_EQ(report["skinned"]["chains"].size(), 1u);
    const nlohmann::json& levels = report["skinned"]["chains"][0]["levels"];
    ASSERT_EQ(levels.size(), 3u);
    EXPECT_EQ(levels[0]["triangles"], whole.triangle_count());
    const Scene out = read_scene(dir / "lod.glb");
    expect_posed_alike(in, out, {0.0f, 0.5f});
    const std::vector<int32_t>& ids = out.nodes[node].lod_ids;
    ASSERT_EQ(ids.size(), 2u);
    std::vector<int32_t> meshes = {0};
    for (const int32_t id : ids) {
      EXPECT_EQ(out.nodes[size_t(id)].skin, 0);
      meshes.push_back(out.nodes[size_t(id)].mesh);
    }
    std::array<int32_t, 2> level0 = {-1, -1};  // the halves' scene primitives at level 0
    for (size_t i = 0; i < meshes.size(); ++i) {
      SCOPED_TRACE(i);
      Mesh level;  // both halves, as one mesh
      std::vector<int32_t> materials;
      for (size_t p = 0; p < out.primitives.size(); ++p) {
        const Primitive& prim = out.primitives[p];
        if (int32_t(prim.gltf_mesh) != meshes[i]) continue;
        materials.push_back(prim.material);
        if (i == 0) level0[size_t(prim.material)] = int32_t(p);
        const uint32_t base = uint32_t(level.vertex_count());
        for (uint32_t v = 0; v < prim.mesh.vertex_count(); ++v) append_vertex(level, prim.mesh, v);
        for (const uint32_t index : prim.mesh.indices) level.indices.push_back(base + index);
      }
      EXPECT_EQ(materials, (std::vector<int32_t>{0, 1}));
      // Each half's blend shape on every level: exact at input vertices (level 0 and with one
      // buffer), else interpolated where the vertex moved: off by 0.02 times the move, which stays
      // under 1% of the diagonal (2.48). Interpolated within each half alone, two vertices by the
      // cut were off by 1.2e-3: their patch of the input lay mostly over the other half.
      for (size_t p = 0; p < out.primitives.size(); ++p) {
        if (int32_t(out.primitives[p].gltf_mesh) != meshes[i]) continue;
        const Mesh& m = out.primitives[p].mesh;
        const std::vector<MorphTarget> targets = source_morph_targets(out, p);
        ASSERT_EQ(targets.size(), 1u);
        ASSERT_EQ(targets[0].positions.size(), m.vertex_count());
        const float tolerance = i == 0 || shared ? 1e-7f : 5e-4f;
        for (size_t v = 0; v < m.vertex_count(); ++v) {
          const float3 d = targets[0].positions[v], e = displacement(m.positions[v]);
          ASSERT_NEAR(d.x, e.x, tolerance) << p << " " << v;
          ASSERT_NEAR(d.y, e.y, tolerance) << p << " " << v;
          ASSERT_EQ(d.z, 0.0f);
        }
      }
      EXPECT_EQ(level.triangle_count(), levels[i]["triangles"].get<size_t>());
      EXPECT_EQ(welded_border_edges(level), 0u);
    }
    // One vertex buffer: each coarser level's halves read level 0's halves' attributes.
    const nlohmann::json doc = glb_json(dir / "lod.glb");
    for (size_t i = 1; i < meshes.size() && shared; ++i)
      for (size_t h = 0; h < 2; ++h)
        EXPECT_EQ(doc["meshes"][size_t(meshes[i])]["primitives"][h]["attributes"]["POSITION"],
                  doc["meshes"][0]["primitives"][h]["attributes"]["POSITION"]) << i << " " << h;

    ProgressiveMesh pm = read_progressive_mesh(dir / "h.lpm");
    EXPECT_EQ(pm.input().triangle_count(), whole.triangle_count());
    EXPECT_EQ(std::set<uint32_t>(pm.input().materials.begin(), pm.input().materials.end()), (std::set<uint32_t>{1, 2}));
    pm.set_collapses(pm.collapse_count());
    EXPECT_EQ(welded_border_edges(pm.mesh()), 0u);
  }
}

// The halves with different streams: the left with normals and no UVs, the right with UVs (its
// x, y) and no normals. Joined, each gets the other's stream for the simplification (a stream one
// lacked would otherwise be dropped from both); every level gives each half its own streams back,
// and the cut stays closed.
TEST(CliLod, ASkinnedNodesMaterialsMayHaveOtherStreams) {
  test::TempDir dir;
  Scene input = fixtures::humanoid_scene();
  std::array<Mesh, 2> halves = fixtures::halves_by_x(input.primitives[0].mesh);
  halves[1].normals.clear();
  for (const float3& p : halves[1].positions) halves[1].uvs[0].push_back({p.x, p.y});
  input.material_names = {"left", "right"};
  input.primitives.clear();
  for (uint32_t h = 0; h < 2; ++h) {
    Primitive p;
    p.mesh = halves[h], p.material = int32_t(h), p.gltf_mesh = 0, p.gltf_primitive = h;
    input.primitives.push_back(std::move(p));
  }
  write_scene(input, dir / "mixed.glb");
  for (const bool shared : {false, true}) {
    SCOPED_TRACE(shared);
    std::vector<std::string> options = {"--ratios", "1,0.4,0.1", "--poses", "4"};
    if (shared) options.push_back("--shared-vertices");
    const nlohmann::json report = lod_report(dir.path, "mixed.glb", "lod.glb", options);
    const Scene out = read_scene(dir / "lod.glb");
    expect_posed_alike(read_scene(dir / "mixed.glb"), out, {0.0f, 0.5f});
    const size_t node = out.nodes.size() - 3;  // the skinned node, before its two level nodes
    ASSERT_EQ(out.nodes[node].lod_ids.size(), 2u);
    std::vector<int32_t> meshes = {out.nodes[node].mesh};
    for (const int32_t id : out.nodes[node].lod_ids) meshes.push_back(out.nodes[size_t(id)].mesh);
    for (size_t i = 0; i < meshes.size(); ++i) {
      SCOPED_TRACE(i);
      Mesh level;
      size_t seen = 0;
      for (const Primitive& prim : out.primitives) {
        if (int32_t(prim.gltf_mesh) != meshes[i]) continue;
        ++seen;
        const bool left = prim.material == 0;
        EXPECT_EQ(prim.mesh.normals.empty(), !left);
        EXPECT_EQ(prim.mesh.uvs[0].empty(), left);
        EXPECT_FALSE(prim.mesh.joints.empty());
        const uint32_t base = uint32_t(level.vertex_count());
        for (const float3& p : prim.mesh.positions) level.positions.push_back(p);
        for (const uint32_t index : prim.mesh.indices) level.indices.push_back(base + index);
      }
      EXPECT_EQ(seen, 2u);
      EXPECT_EQ(level.triangle_count(), report["skinned"]["chains"][0]["levels"][i]["triangles"].get<size_t>());
      EXPECT_EQ(welded_border_edges(level), 0u);
    }
  }
}

// A crowd: the humanoid's glTF mesh drawn by a second node with a skin of its own (a copy of the
// skeleton 1.5 to the side, walking with it: the clip's channels copied to the copy). One chain,
// whose level meshes both nodes draw, each with its own skin, listed in its own MSFT_lod; level 0
// draws the input. In the walk, each of the twin's levels, skinned by its skin, is the humanoid's
// 1.5 to the side (the twin's level node with the humanoid's skin or another mesh would not be).
// On its own output, lod replaces both nodes' levels.
// A crowd: a second skeleton in the humanoid scene, a copy of its joints below a node 1.5 to the
// side with a skin of its own, and a node ("twin") drawing the humanoid's mesh with that skin.
// Returns the copy of each joint node.
std::map<int32_t, int32_t> add_twin(Scene& input, uint32_t humanoid) {
  Skin twin_skin = input.skins[0];
  twin_skin.name = "twin_skin";
  std::map<int32_t, int32_t> copy_of;
  // (Below a node 1.5 to the side: the clip moves the hips.)
  Node aside;
  aside.name = "aside", aside.translation = {1.5f, 0, 0};
  const int32_t aside_node = int32_t(input.nodes.size());
  input.roots.push_back(aside_node);
  input.nodes.push_back(aside);
  for (const int32_t j : input.skins[0].joints) copy_of[j] = int32_t(input.nodes.size() + copy_of.size());
  for (const int32_t j : input.skins[0].joints) {
    Node copy = input.nodes[size_t(j)];
    copy.name = "twin_" + copy.name;
    for (int32_t& c : copy.children) c = copy_of.at(c);
    if (copy.parent >= 0) {
      copy.parent = copy_of.at(copy.parent);
    } else {
      copy.parent = aside_node;
      input.nodes[size_t(aside_node)].children.push_back(copy_of.at(j));
    }
    input.nodes.push_back(std::move(copy));
  }
  for (int32_t& j : twin_skin.joints) j = copy_of.at(j);
  if (twin_skin.skeleton >= 0) twin_skin.skeleton = copy_of.at(twin_skin.skeleton);
  input.skins.push_back(twin_skin);
  Node twin;
  twin.name = "twin", twin.mesh = input.nodes[humanoid].mesh, twin.skin = int32_t(input.skins.size() - 1);
  input.roots.push_back(int32_t(input.nodes.size()));
  input.nodes.push_back(twin);
  return copy_of;
}

TEST(CliLod, ASkinnedMeshDrawnByTwoSkeletonsGetsOneChainForBoth) {
  test::TempDir dir;
  Scene input = fixtures::humanoid_scene();
  ASSERT_EQ(input.skins.size(), 1u);
  const uint32_t humanoid = skinned_primitives(input).at(0).node;
  const std::map<int32_t, int32_t> copy_of = add_twin(input, humanoid);
  const uint32_t twin_node = uint32_t(input.nodes.size() - 1);
  std::vector<AnimationChannel> walking;
  for (const AnimationChannel& ch : input.animations[0].channels)
    if (copy_of.count(ch.node)) walking.push_back(ch), walking.back().node = copy_of.at(ch.node);
  ASSERT_FALSE(walking.empty());
  input.animations[0].channels.insert(input.animations[0].channels.end(), walking.begin(), walking.end());
  write_scene(input, dir / "crowd.glb");

  const nlohmann::json report = lod_report(dir.path, "crowd.glb", "crowd-lod.glb", {"--ratios", "1,0.4,0.1", "--poses", "4"});
  ASSERT_EQ(report["skinned"]["chains"].size(), 1u);
  EXPECT_EQ(report["skinned"]["chains"][0]["node"], input.nodes[humanoid].name + ", twin");
  const Scene in = read_scene(dir / "crowd.glb"), out = read_scene(dir / "crowd-lod.glb");
  expect_posed_alike(in, out, {0.0f, 0.3f, 0.7f});
  const Node &first = out.nodes[humanoid], &second = out.nodes[twin_node];
  ASSERT_EQ(first.lod_ids.size(), 2u);
  ASSERT_EQ(second.lod_ids.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    SCOPED_TRACE(i + 1);
    const Node &a = out.nodes[size_t(first.lod_ids[i])], &b = out.nodes[size_t(second.lod_ids[i])];
    EXPECT_EQ(b.name, "twin_LOD" + std::to_string(i + 1));
    EXPECT_GE(a.mesh, int32_t(in.gltf_mesh_count));
    EXPECT_EQ(b.mesh, a.mesh);
    EXPECT_EQ(a.skin, 0);
    EXPECT_EQ(b.skin, 1);
    const Mesh* level = nullptr;
    for (const Primitive& p : out.primitives)
      if (p.gltf_mesh == uint32_t(b.mesh)) level = &p.mesh;
    ASSERT_NE(level, nullptr);
    EXPECT_EQ(level->triangle_count(), size_t(report["skinned"]["chains"][0]["levels"][i + 1]["triangles"]));
    for (const float time : {0.0f, 0.3f, 0.7f}) {
      Pose pose = rest_pose(out);
      sample_animation(out, 0, time, pose);
      const std::vector<mat4> world = world_matrices(out, pose);
      SkinnedVertices left, right;
      skin_vertices(*level, joint_matrices(out, size_t(a.skin), world), left);
      skin_vertices(*level, joint_matrices(out, size_t(b.skin), world), right);
      float worst = 0;
      for (size_t v = 0; v < level->vertex_count(); ++v) {
        const float3 p = left.positions[v], q = right.positions[v];
        worst = std::max({worst, std::abs(q.x - p.x - 1.5f), std::abs(q.y - p.y), std::abs(q.z - p.z)});
      }
      EXPECT_LT(worst, 1e-4f) << "at " << time;
    }
  }

  const nlohmann::json again = lod_report(dir.path, "crowd-lod.glb", "crowd-again.glb", {"--ratios", "1,0.4,0.1", "--poses", "4"});
  ASSERT_EQ(again["skinned"]["chains"].size(), 1u);
  EXPECT_EQ(test::glb_json(dir / "crowd-again.glb")["meshes"].size(), test::glb_json(dir / "crowd-lod.glb")["meshes"].size());
  EXPECT_EQ(node_structure(test::glb_json(dir / "crowd-again.glb")), node_structure(test::glb_json(dir / "crowd-lod.glb")));
}

// A crowd whose second skeleton moves as the first never does: the humanoid walks and waves, and
// a third clip folds the twin forward at the waist (spine and chest 60 degrees each) and turns its
// head. The crowd's chain (multipose) holds in the poses of both skeletons: each level, as the twin
// folds it, is as close to the input folded as it is to the input in the humanoid's own walk,
// within 1.5x (the Hausdorff distances of the posed surfaces: 0.70x and 0.71x, each skeleton's poses
// sampled over the clips that move it; 0.93x and 0.79x with every clip sampled for each, the fold
// a rest pose for the humanoid and the walk and wave for the twin; simplified in the humanoid's
// poses alone, 2.1x and 1.7x).
TEST(CliLod, ACrowdsChainHoldsInEverySkeletonsPoses) {
  test::TempDir dir;
  Scene input = fixtures::humanoid_scene();
  const uint32_t humanoid = skinned_primitives(input).at(0).node;
  const std::map<int32_t, int32_t> copy_of = add_twin(input, humanoid);
  const uint32_t twin_node = uint32_t(input.nodes.size() - 1);
  Animation fold;
  fold.name = "fold";
  for (const auto& [joint, angle] : std::vector<std::pair<fixtures::Joint, float>>{{fixtures::spine, 1.047f}, {fixtures::chest, 1.047f}}) {
    AnimationChannel ch{.node = copy_of.at(int32_t(joint)), .path = AnimationPath::rotation, .times = {0, 1}, .values = {}, .components = 4};
    const float4 rest = input.nodes[size_t(joint)].rotation;
    ch.values = {rest.x, rest.y, rest.z, rest.w};
    // The rest rotation, then a turn of `angle` about x after it (T-pose joints rest unrotated).
    ASSERT_EQ(rest, (float4{0, 0, 0, 1}));
    ch.values.insert(ch.values.end(), {std::sin(angle / 2), 0, 0, std::cos(angle / 2)});
    fold.channels.push_back(ch);
  }
  AnimationChannel turn{.node = copy_of.at(int32_t(fixtures::neck)), .path = AnimationPath::rotation, .times = {0, 1},
                        .values = {0, 0, 0, 1, 0, std::sin(0.6f), 0, std::cos(0.6f)}, .components = 4};
  fold.channels.push_back(turn);
  input.animations.push_back(fold);
  write_scene(input, dir / "crowd.glb");
  const nlohmann::json report = lod_report(dir.path, "crowd.glb", "crowd-lod.glb", {"--ratios", "1,0.3,0.1", "--poses", "8"});
  ASSERT_EQ(report["skinned"]["chains"].size(), 1u);
  const Scene in = read_scene(dir / "crowd.glb"), out = read_scene(dir / "crowd-lod.glb");
  const size_t fold_clip = in.animations.size() - 1;
  // A mesh as `skin` poses it in clip `clip` at `time`.
  const auto posed_by = [](const Scene& scene, const Mesh& mesh, size_t skin, size_t clip, float time) {
    Pose pose = rest_pose(scene);
    sample_animation(scene, clip, time, pose);
    SkinnedVertices v;
    skin_vertices(mesh, joint_matrices(scene, skin, world_matrices(scene, pose)), v);
    Mesh m;
    m.positions = v.positions, m.indices = mesh.indices;
    return m;
  };
  const Mesh& input_mesh = in.primitives.at(0).mesh;
  const Node& twin = out.nodes[twin_node];
  ASSERT_EQ(twin.lod_ids.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    SCOPED_TRACE(i + 1);
    const Mesh* level = nullptr;
    for (const Primitive& p : out.primitives)
      if (p.gltf_mesh == uint32_t(out.nodes[size_t(twin.lod_ids[i])].mesh)) level = &p.mesh;
    ASSERT_NE(level, nullptr);
    double walking = 0;  // the level's worst distance in the humanoid's walk
    for (const float time : {0.3f, 0.6f, 0.9f})
      walking = std::max(walking, compare(posed_by(out, *level, 0, 0, time), posed_by(in, input_mesh, 0, 0, time)).hausdorff);
    const double folded = compare(posed_by(out, *level, 1, fold_clip, 1.0f), posed_by(in, input_mesh, 1, fold_clip, 1.0f)).hausdorff;
    EXPECT_GT(walking, 0);
    EXPECT_LE(folded, 1.5 * walking);
  }
}

// Two skinned meshes of one skin (the humanoid's halves, each its own glTF mesh and node): built in
// one batch, side by side with two threads, each chain is the one its mesh gets alone, and the
// output does not depend on the thread count.
TEST(CliLod, SkinnedMeshesOfOneSkinAreBuiltTogether) {
  test::TempDir dir;
  const Scene humanoid = fixtures::humanoid_scene();
  const std::array<Mesh, 2> halves = fixtures::halves_by_x(humanoid.primitives[0].mesh);
  Scene both = humanoid;
  both.primitives[0].mesh = halves[0];
  Primitive right;
  right.mesh = halves[1], right.gltf_mesh = 1;
  both.primitives.push_back(right);
  Node second = both.nodes.back();  // the skinned node, after the joints
  second.name = "right", second.mesh = 1;
  both.nodes.push_back(second);
  both.roots.push_back(int32_t(both.nodes.size() - 1));
  write_scene(both, dir / "both.glb");
  Scene left = humanoid, alone_right = humanoid;
  left.primitives[0].mesh = halves[0];
  alone_right.primitives[0].mesh = halves[1];
  write_scene(left, dir / "left.glb");
  write_scene(alone_right, dir / "right.glb");

  const std::vector<std::string> options = {"--ratios", "1,0.4,0.1", "--poses", "4"};
  const nlohmann::json report = lod_report(dir.path, "both.glb", "both-lod.glb", options);
  ASSERT_EQ(report["skinned"]["chains"].size(), 2u);
  EXPECT_EQ(report["skinned"]["chains"][1]["node"], "right");
  EXPECT_EQ(report["skinned"]["chains"][0]["levels"], lod_report(dir.path, "left.glb", "left-lod.glb", options)["skinned"]["chains"][0]["levels"]);
  EXPECT_EQ(report["skinned"]["chains"][1]["levels"], lod_report(dir.path, "right.glb", "right-lod.glb", options)["skinned"]["chains"][0]["levels"]);
  std::vector<std::string> one = options;
  one.insert(one.end(), {"--threads", "1"});
  lod_report(dir.path, "both.glb", "both-1.glb", one);
  EXPECT_EQ(test::read_bytes(dir / "both-lod.glb"), test::read_bytes(dir / "both-1.glb"));
  expect_posed_alike(read_scene(dir / "both.glb"), read_scene(dir / "both-lod.glb"), {0.0f, 0.5f});
}

TEST(CliLod, SkinnedInputRefusesWhatItCannotDoYet) {
  test::TempDir dir;
  write_scene(fixtures::humanoid_scene(), dir / "humanoid.glb");
  // A character alone has nothing for --morph to morph (props would: SkinnedCharactersPropsGetChainsToo).
  for (const char* flag : {"--morph"}) {
    const test::RunResult r = test::run_cli({"lod", (dir / "humanoid.glb").string(), "-o", (dir / "x.glb").string(), flag});
    EXPECT_EQ(r.exit_code, 1) << flag << ": " << r.err;
    EXPECT_NE(r.err.find("nothing else to morph"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "x.glb"));
  }
  const test::RunResult bad = test::run_cli(
      {"lod", (dir / "humanoid.glb").string(), "-o", (dir / "x.glb").string(), "--skin-mode", "rigid"});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("--skin-mode"), std::string::npos) << bad.err;
}

// The skinned options are checked before the input is read, so a mistake shows on a mesh without
// skins too, rather than being ignored there.
TEST(CliLod, SkinOptionsAreCheckedForAnyInput) {
  test::TempDir dir;
  write_mesh(shapes::icosphere(2), dir / "ball.off");
  const test::RunResult mode =
      test::run_cli({"lod", (dir / "ball.off").string(), "-o", (dir / "x.glb").string(), "--skin-mode", "rigid"});
  EXPECT_EQ(mode.exit_code, 1);
  EXPECT_NE(mode.err.find("--skin-mode: 'rigid' is not houle, subset or multipose"), std::string::npos) << mode.err;
  const test::RunResult poses = test::run_cli({"lod", (dir / "ball.off").string(), "-o", (dir / "x.glb").string(), "--poses", "0"});
  EXPECT_EQ(poses.exit_code, 1);
  EXPECT_NE(poses.err.find("--poses must be at least 1"), std::string::npos) << poses.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.glb"));
  EXPECT_EQ(test::run_cli({"lod", (dir / "ball.off").string(), "-o", (dir / "x.glb").string(), "--skin-mode", "houle"}).exit_code, 0);
}

}  // namespace
}  // namespace lod
