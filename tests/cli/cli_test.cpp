// The CLI as a user drives it: exit codes, --json, atomic writes and the refusal to overwrite input.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "core/shapes.h"
#include <fmt/format.h>

#include "lodkit/io.h"
#include "lodkit/lod.h"
#include "lodkit/simplify.h"
#include "test_support.h"

namespace lod {
namespace {

TEST(Cli, InfoJsonMatchesTheLibrary) {
  test::TempDir dir;
  Mesh torus = shapes::torus(1.0f, 0.3f, 20, 10);
  write_mesh(torus, dir / "torus.obj");
  test::RunResult r = test::run_cli({"info", "--json", (dir / "torus.obj").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["stats"]["triangles"], 400);
  EXPECT_EQ(j["stats"]["unique_positions"], 200);
  EXPECT_EQ(j["stats"]["euler_characteristic"], 0);
  EXPECT_EQ(j["stats"]["components"][0]["genus"], 1);
  EXPECT_EQ(j["format"], "OBJ");
}

// Several materials in a non-glTF file: info counts every triangle, and convert keeps the material ids
// and the vertex order (a regression: both once went through a per-material scene split).
TEST(Cli, MultiMaterialFilesKeepEveryTriangle) {
  test::TempDir dir;
  Mesh cube = shapes::cube();
  for (size_t t = 0; t < cube.triangle_count(); ++t) cube.materials.push_back(uint32_t(t / 4));  // 3 materials
  cube.material_names = {"red", "green", "blue"};
  write_mesh(cube, dir / "cube.obj");
  test::RunResult r = test::run_cli({"info", "--json", (dir / "cube.obj").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["stats"]["triangles"], 12);
  EXPECT_EQ(j["stats"]["materials"], 3);
  for (const char* out : {"cube.ply", "cube2.obj"}) {
    r = test::run_cli({"convert", (dir / "cube.obj").string(), (dir / out).string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    Mesh back = read_mesh(dir / out);
    EXPECT_EQ(back.materials, cube.materials) << out;
    EXPECT_EQ(back.positions, read_mesh(dir / "cube.obj").positions) << out;
  }
}

TEST(Cli, InfoTablePrintsAlignedRows) {
  test::TempDir dir;
  write_mesh(shapes::cube(), dir / "cube.off");
  test::RunResult r = test::run_cli({"info", (dir / "cube.off").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("unique positions        8\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("triangles               12\n"), std::string::npos) << r.out;
}

// info on a progressive mesh: the torus of 20 x 10 (200 positions, 400 triangles) and its record;
// the base mesh has one position less per collapse. A corrupt file is rejected with its byte offset.
TEST(Cli, InfoDescribesAProgressiveMesh) {
  test::TempDir dir;
  const Mesh torus = shapes::torus(1.0f, 0.3f, 20, 10);
  const SimplifyResult s = simplify(torus, {.target_triangles = 60});
  const ProgressiveMesh pm(torus, s.record);
  write_progressive_mesh(pm, dir / "torus.lpm");
  test::RunResult r = test::run_cli({"info", "--json", (dir / "torus.lpm").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["format"], "lpm");
  EXPECT_EQ(j["stats"]["triangles"], 400);
  const auto& p = j["progressive"];
  EXPECT_EQ(p["collapses"], s.record.collapses.size());
  EXPECT_EQ(p["max_positions"], 200);
  EXPECT_EQ(p["min_positions"], 200 - s.record.collapses.size());
  EXPECT_EQ(p["max_triangles"], 400);
  EXPECT_LE(p["min_triangles"].get<int>(), 60);
  EXPECT_EQ(p["influence_changes"], false);

  r = test::run_cli({"info", (dir / "torus.lpm").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find(fmt::format("progressive mesh        {} collapses: 200 > {} positions, 400 > ",
                                   s.record.collapses.size(), 200 - s.record.collapses.size())),
            std::string::npos)
      << r.out;

  std::string bytes = encode_progressive_mesh(pm);
  bytes[bytes.size() / 2] ^= 0x5a;
  test::write_text(dir / "bad.lpm", bytes);
  r = test::run_cli({"info", (dir / "bad.lpm").string()});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("checksum"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("bad.lpm"), std::string::npos) << r.err;
}

TEST(Cli, UsageErrorsExitWith1) {
  test::TempDir dir;
  EXPECT_EQ(test::run_cli({}).exit_code, 1);
  EXPECT_EQ(test::run_cli({"frobnicate"}).exit_code, 1);
  EXPECT_EQ(test::run_cli({"info"}).exit_code, 1);
  write_mesh(shapes::cube(), dir / "cube.obj");
  EXPECT_EQ(test::run_cli({"info", (dir / "cube.xyz").string()}).exit_code, 1);  // unknown extension
  EXPECT_EQ(test::run_cli({"convert", (dir / "cube.obj").string()}).exit_code, 1);  // no output
  EXPECT_EQ(test::run_cli({"info", "--help"}).exit_code, 0);
}

TEST(Cli, ConvertBetweenEveryPairOfTextFormatsKeepsTheSurface) {
  test::TempDir dir;
  Mesh sphere = shapes::icosphere(2);
  write_mesh(sphere, dir / "in.off");
  for (const char* ext : {".obj", ".off"}) {
    auto out = dir / (std::string("out") + ext);
    test::RunResult r = test::run_cli({"convert", (dir / "in.off").string(), out.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    Mesh back = read_mesh(out);
    EXPECT_EQ(back.triangle_count(), sphere.triangle_count());
    for (size_t t = 0; t < sphere.triangle_count(); ++t)
      for (int k = 0; k < 3; ++k) ASSERT_EQ(back.positions[back.indices[3 * t + k]], sphere.positions[sphere.indices[3 * t + k]]);
  }
}

// (And every command refuses an output whose folder is missing.)
TEST(Cli, ConvertRefusesToOverwriteItsInputUnlessForced) {
  test::TempDir dir;
  auto path = dir / "mesh.obj";
  write_mesh(shapes::cube(), path);
  auto before = std::filesystem::file_size(path);
  test::RunResult r = test::run_cli({"convert", path.string(), path.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--force"), std::string::npos) << r.err;
  EXPECT_EQ(std::filesystem::file_size(path), before);
  // Also through another spelling of the same path.
  r = test::run_cli({"convert", path.string(), "-o", (dir / "." / "mesh.obj").string()});
  EXPECT_EQ(r.exit_code, 1);
  r = test::run_cli({"convert", path.string(), path.string(), "--force"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_mesh(path).triangle_count(), 12u);
  // An output in a folder that does not exist is refused before any work (it used to fail only
  // when written, after the simplification, the chain, the measurement or the drawing).
  const std::string in = path.string(), out = (dir / "missing" / "out.glb").string();
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"convert", in, "-o", out}, {"simplify", in, "-o", out, "--ratio", "0.5"}, {"optimize", in, "-o", out},
        {"lod", in, "-o", out}, {"render", in, "-o", (dir / "missing" / "x.png").string()},
        {"compare", in, in, "--heatmap", (dir / "missing" / "h.ply").string()}}) {
    r = test::run_cli(args);
    EXPECT_EQ(r.exit_code, 2) << args[0] << ": " << r.err;  // (as a failed write: bad input)
    EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "missing"));
}

// A .gltf output writes OUT.bin beside it: named after the input's buffer, it would write over a
// file the input reads (scene.gltf reading data.bin, written as data.gltf). Every command that
// writes a file refuses, and leaves the buffer as it was; --force allows it; another name is fine.
TEST(Cli, RefusesToWriteOverABufferTheInputReads) {
  test::TempDir dir;
  write_scene(scene_from_mesh(shapes::icosphere(2)), dir / "scene.gltf");
  ASSERT_TRUE(std::filesystem::exists(dir / "scene.bin"));
  std::filesystem::rename(dir / "scene.bin", dir / "data.bin");
  std::string json = test::read_bytes(dir / "scene.gltf");
  const size_t at = json.find("\"scene.bin\"");
  ASSERT_NE(at, std::string::npos);
  json.replace(at, 11, "\"data.bin\"");
  test::write_text(dir / "scene.gltf", json);
  const std::string in = (dir / "scene.gltf").string(), out = (dir / "data.gltf").string();
  const std::string buffer = test::read_bytes(dir / "data.bin");
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"simplify", in, "-o", out, "--ratio", "0.5"}, {"optimize", in, "-o", out}, {"convert", in, out},
        {"lod", in, "-o", out}, {"lod", in, "-o", (dir / "l.glb").string(), "--lpm", (dir / "data.bin").string()},
        {"optimize", in, "-o", (dir / "o.glb").string(), "--strips", "best", "--strip-indices", (dir / "data.bin").string()},
        {"compare", in, in, "--heatmap", out}}) {
    SCOPED_TRACE(args[0]);
    const test::RunResult r = test::run_cli(args);
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("which the input reads"), std::string::npos) << r.err;
    EXPECT_TRUE(test::read_bytes(dir / "data.bin") == buffer);
  }
  EXPECT_EQ(test::run_cli({"convert", in, (dir / "other.gltf").string()}).exit_code, 0);
  EXPECT_EQ(test::run_cli({"convert", in, out, "--force"}).exit_code, 0);
  EXPECT_EQ(read_scene(out).primitives.size(), 1u);  // (forced: data.bin is the output's buffer now)
}

// A glTF extension the file requires and lodkit does not know is kept, with a warning on stderr
// from every command that reads the file (once per read), since what lodkit changes may no longer
// agree with it; a required extension lodkit knows (KHR_materials_unlit) gives none.
TEST(Cli, WarnsOfARequiredExtensionItDoesNotKnow) {
  test::TempDir dir;
  write_scene(scene_from_mesh(shapes::icosphere(2)), dir / "scene.glb");
  test::Glb glb = test::read_glb(dir / "scene.glb");
  glb.doc["extensionsUsed"] = {"ABC_geometry_magic", "KHR_materials_unlit"};
  glb.doc["extensionsRequired"] = glb.doc["extensionsUsed"];
  glb.doc["meshes"][0]["primitives"][0]["extensions"]["ABC_geometry_magic"] = {{"level", 1}};
  const std::string in = (dir / "in.glb").string(), out = (dir / "out.glb").string();
  test::write_bytes(dir / "in.glb", test::glb_bytes(glb));
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"simplify", in, "-o", out, "--ratio", "0.5"}, {"optimize", in, "-o", out}, {"convert", in, out},
        {"lod", in, "-o", out}, {"info", in}}) {
    SCOPED_TRACE(args[0]);
    const test::RunResult r = test::run_cli(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string warning = "lodkit: warning: " + in + ": the file requires ABC_geometry_magic, which lodkit does not know";
    const size_t at = r.err.find(warning);
    ASSERT_NE(at, std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("ABC_geometry_magic", at + warning.size()), std::string::npos) << r.err;  // once
    EXPECT_EQ(r.err.find("KHR_materials_unlit"), std::string::npos) << r.err;
    if (args[0] == "info") continue;
    const nlohmann::json doc = test::glb_json(out);
    EXPECT_EQ(doc["extensionsRequired"], glb.doc["extensionsRequired"]);
  }
}

TEST(Cli, FailedConvertLeavesNoPartialOutput) {
  test::TempDir dir;
  auto bad = dir / "bad.off";
  test::write_text(bad, "OFF\n3 1 0\n0 0 0\n1 0 0\n");
  auto out = dir / "out.obj";
  test::RunResult r = test::run_cli({"convert", bad.string(), out.string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_FALSE(std::filesystem::exists(out));
  // A write into a folder that does not exist fails cleanly too, and leaves no temporary file.
  write_mesh(shapes::cube(), dir / "cube.obj");
  r = test::run_cli({"convert", (dir / "cube.obj").string(), (dir / "no-such-dir" / "x.obj").string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  size_t files = 0;
  for (auto& e : std::filesystem::directory_iterator(dir.path)) files += e.is_regular_file();
  EXPECT_EQ(files, 2u);  // bad.off and cube.obj only
}

TEST(AtomicFile, ReplacesExistingFileCompletely) {
  test::TempDir dir;
  auto path = dir / "f.txt";
  write_file_atomic(path, std::string(1000, 'a'));
  write_file_atomic(path, std::string("short"));
  auto bytes = read_file_bytes(path);
  EXPECT_EQ(std::string(bytes.begin(), bytes.end()), "short");
  size_t entries = 0;
  for (auto& e : std::filesystem::directory_iterator(dir.path)) (void)e, ++entries;
  EXPECT_EQ(entries, 1u);
}

}  // namespace
}  // namespace lod
