// MTL material libraries: the statements read (values derived by hand), malformed input, and an
// OBJ's materials carried into glTF (factors, textures embedded in a .glb or referred to from a
// .gltf, checked against the files and by the Khronos validator).
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lodkit/error.h"
#include "lodkit/io.h"
#include "test_support.h"

namespace lod {
namespace {

using test::bytes_of;

const std::string tiny_png = test::tiny_png();

TEST(Mtl, ReadsWhatGltfsCoreHasRoomFor) {
  const std::string text =
      "# made by hand\n"
      "newmtl stone\nKd 0.8 0.5 0.3\nd 0.5\nNs 98\nKa 0 0 0\nillum 2\n"
      "map_Kd -s 1 1 1 -bm 0.5 -clamp on textures\\stone wall.png\n"
      "newmtl glow\nKd 0.25\nTr 0.75\nKe 1 0.5 0\nPm 0.7\nPr 0.2\nNs 10\nnorm -bm 2 n.png\nmap_Ke /abs/e.png\n"
      "newmtl plain\n"
      "newmtl bright\nKd 2 0.5 -1\nKe 1.5\n";
  const std::vector<MtlMaterial> m = read_mtl(bytes_of(text), "scene.mtl", "/models");
  ASSERT_EQ(m.size(), 4u);
  EXPECT_EQ(m[0].name, "stone");
  EXPECT_EQ(m[0].look.base_color, (float4{0.8f, 0.5f, 0.3f, 0.5f}));
  EXPECT_NEAR(m[0].look.roughness, std::sqrt(2.0 / 100.0), 1e-7);  // GGX roughness of Phong exponent 98
  EXPECT_EQ(m[0].look.metallic, 0.0f);
  EXPECT_EQ(m[0].look.base_color_texture, "/models/textures/stone wall.png");
  EXPECT_EQ(m[1].name, "glow");
  EXPECT_EQ(m[1].look.base_color, (float4{0.25f, 0.25f, 0.25f, 0.25f}));  // one Kd value for all three; d = 1 - Tr
  EXPECT_EQ(m[1].look.emissive, (float3{1, 0.5f, 0}));
  EXPECT_EQ(m[1].look.metallic, 0.7f);
  EXPECT_EQ(m[1].look.roughness, 0.2f);  // Pr, not Ns
  EXPECT_EQ(m[1].look.normal_texture, "/models/n.png");
  EXPECT_EQ(m[1].look.emissive_texture, "/abs/e.png");
  EXPECT_EQ(m[2].name, "plain");
  EXPECT_TRUE(m[2].look == MaterialLook{});
  // Colours are clamped to [0, 1], as glTF's factors must be.
  EXPECT_EQ(m[3].look.base_color, (float4{1, 0.5f, 0, 1}));
  EXPECT_EQ(m[3].look.emissive, (float3{1, 1, 1}));
}

TEST(Mtl, RejectsMalformedStatementsNamingTheLine) {
  const auto message = [](const std::string& text) {
    try {
      read_mtl(bytes_of(text), "bad.mtl");
    } catch (const Error& e) {
      EXPECT_EQ(e.category(), ErrorCategory::bad_input);
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("newmtl a\n\nKd 1 x 1\n").find("bad.mtl:3"), std::string::npos) << message("newmtl a\n\nKd 1 x 1\n");
  EXPECT_NE(message("Kd 1 1 1\n").find("bad.mtl:1"), std::string::npos);
  EXPECT_NE(message("newmtl a\nmap_Kd -bm 1\n").find("no file"), std::string::npos);
  EXPECT_NE(message("newmtl\n").find("names no material"), std::string::npos);
  EXPECT_NE(message("newmtl a\nd nan\n").find("bad.mtl:2"), std::string::npos);
}

// An OBJ's mtllib, beside it: its materials' looks on the mesh, then in glTF. Material "stone" is in
// the library with a texture; "lost" is in none (a warning). The .glb embeds the texture's bytes;
// a .gltf in a subfolder refers to it as ../tex.png; both validate.
TEST(Mtl, ObjMaterialsReachGltf) {
  test::TempDir dir;
  test::write_text(dir / "tex.png", tiny_png);
  test::write_text(dir / "m.mtl", "newmtl stone\nKd 0.8 0.5 0.3\nPr 0.4\nmap_Kd tex.png\n");
  test::write_text(dir / "quad.obj",
                   "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                   "usemtl stone\nf 1/1 2/2 3/3\nusemtl lost\nf 1/1 3/3 4/4\n");
  std::vector<std::string> warnings;
  const ReadOptions options{.warning = [&](const std::string& w) { warnings.push_back(w); }};
  const Mesh mesh = read_mesh(dir / "quad.obj", options);
  ASSERT_EQ(mesh.material_names, (std::vector<std::string>{"stone", "lost"}));
  ASSERT_EQ(mesh.material_looks.size(), 2u);
  EXPECT_EQ(mesh.material_looks[0].base_color, (float4{0.8f, 0.5f, 0.3f, 1}));
  EXPECT_EQ(mesh.material_looks[0].roughness, 0.4f);
  EXPECT_TRUE(mesh.material_looks[1] == MaterialLook{});
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("1 material(s) in no material library (lost)"), std::string::npos) << warnings[0];

  std::filesystem::create_directory(dir / "out");
  write_mesh(mesh, dir / "out" / "quad.glb");
  const test::Glb glb = test::read_glb(dir / "out" / "quad.glb");
  const nlohmann::json& stone = glb.doc["materials"][0];
  EXPECT_EQ(stone["name"], "stone");
  EXPECT_EQ(stone["pbrMetallicRoughness"]["baseColorFactor"], (std::vector<double>{0.8f, 0.5f, 0.3f, 1}));
  EXPECT_EQ(stone["pbrMetallicRoughness"]["roughnessFactor"], double(0.4f));
  const nlohmann::json& image = glb.doc["images"][glb.doc["textures"][stone["pbrMetallicRoughness"]["baseColorTexture"]["index"].get<size_t>()]["source"].get<size_t>()];
  EXPECT_EQ(image["mimeType"], "image/png");
  const nlohmann::json& view = glb.doc["bufferViews"][image["bufferView"].get<size_t>()];
  const size_t offset = view.value("byteOffset", size_t(0));
  ASSERT_EQ(view["byteLength"], tiny_png.size());
  EXPECT_TRUE(std::string(glb.bin.begin() + ptrdiff_t(offset), glb.bin.begin() + ptrdiff_t(offset + tiny_png.size())) == tiny_png);
  EXPECT_FALSE(glb.doc["materials"][1].contains("pbrMetallicRoughness") &&
               glb.doc["materials"][1]["pbrMetallicRoughness"].contains("baseColorTexture"));

  write_mesh(mesh, dir / "out" / "quad.gltf");
  const nlohmann::json doc = nlohmann::json::parse(test::read_bytes(dir / "out" / "quad.gltf"));
  ASSERT_EQ(doc["images"].size(), 1u);
  EXPECT_EQ(doc["images"][0]["uri"], "../tex.png");
  test::expect_valid_gltf({dir / "out" / "quad.glb", dir / "out" / "quad.gltf"});

  // Without UVs a texture cannot be drawn (and glTF's validator refuses it): the factors stay.
  test::write_text(dir / "flat.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl stone\nf 1 2 3\n");
  write_mesh(read_mesh(dir / "flat.obj"), dir / "out" / "flat.glb");
  const nlohmann::json flat = test::glb_json(dir / "out" / "flat.glb");
  EXPECT_FALSE(flat.contains("images"));
  EXPECT_EQ(flat["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"][0], double(0.8f));
  test::expect_valid_gltf({dir / "out" / "flat.glb"});

  // `info` lists the texture files the library names.
  const test::RunResult info = test::run_cli({"info", (dir / "quad.obj").string(), "--json"});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["material_textures"], (std::vector<std::string>{(dir / "tex.png").string()}));

  // The commands that write a glTF from the OBJ keep the looks (lod builds a new document).
  for (const std::vector<std::string>& args : {std::vector<std::string>{"lod", (dir / "quad.obj").string(), "-o", (dir / "out" / "lod.glb").string()},
                                               {"simplify", (dir / "quad.obj").string(), "-o", (dir / "out" / "lod.glb").string(), "--ratio", "0.5"}}) {
    SCOPED_TRACE(args[0]);
    const test::RunResult r = test::run_cli(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json out = test::glb_json(dir / "out" / "lod.glb");
    EXPECT_EQ(out["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"][1], double(0.5f));
    EXPECT_EQ(out["images"].size(), 1u);
  }
}

// An OBJ written from a mesh with looks gets an MTL library beside it, named first by mtllib, with
// texture paths relative to its folder: read back, the looks are the same (textures the same files).
// The material no triangle uses is left out.
TEST(Mtl, ObjOutputWritesItsLibrary) {
  test::TempDir dir;
  test::write_text(dir / "tex.png", tiny_png);
  Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  mesh.uvs[0] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  mesh.materials = {1, 2};
  mesh.material_names = {"unused", "stone", "glass"};
  mesh.material_looks.resize(3);
  mesh.material_looks[1] = {.base_color = {0.8f, 0.5f, 0.3f, 1}, .metallic = 0.25f, .roughness = 0.4f,
                            .base_color_texture = (dir / "tex.png").string()};
  mesh.material_looks[2] = {.base_color = {0.1f, 0.2f, 0.3f, 0.5f}, .emissive = {1, 0, 0.5f}, .roughness = 0.05f,
                            .normal_texture = (dir / "tex.png").string()};
  std::filesystem::create_directory(dir / "out");
  write_mesh(mesh, dir / "out" / "q.obj");
  EXPECT_EQ(test::read_bytes(dir / "out" / "q.obj").rfind("mtllib q.mtl\n", 0), 0u);
  const std::string library = test::read_bytes(dir / "out" / "q.mtl");
  EXPECT_NE(library.find("map_Kd ../tex.png\n"), std::string::npos) << library;
  EXPECT_NE(library.find("norm ../tex.png\n"), std::string::npos) << library;
  EXPECT_EQ(library.find("unused"), std::string::npos) << library;
  const Mesh back = read_mesh(dir / "out" / "q.obj");
  ASSERT_EQ(back.material_names, (std::vector<std::string>{"stone", "glass"}));
  ASSERT_EQ(back.material_looks.size(), 2u);
  EXPECT_TRUE(back.material_looks[0] == mesh.material_looks[1]);
  EXPECT_TRUE(back.material_looks[1] == mesh.material_looks[2]);
  // Ns, for readers without Pr, is the exponent whose roughness read_mtl gives: 2 / 0.05^2 - 2.
  EXPECT_NE(library.find("Ns 798\n"), std::string::npos) << library;
}

// OBJ knows a material by its name alone: materials without one, or sharing one (glTF allows
// both), are told apart ("default", "default_2", "stone_4"), each with its own look.
TEST(Mtl, ObjOutputTellsNamelessAndSameNamedMaterialsApart) {
  test::TempDir dir;
  Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  mesh.indices = {0, 1, 2, 0, 2, 3, 0, 1, 3, 1, 2, 3};
  mesh.materials = {1, 2, 3, 4};
  mesh.material_names = {"x", "", "", "stone", "stone"};
  mesh.material_looks.resize(5);
  for (size_t id = 1; id < 5; ++id) mesh.material_looks[id].roughness = float(id) / 8;
  write_mesh(mesh, dir / "m.obj");
  const Mesh back = read_mesh(dir / "m.obj");
  ASSERT_EQ(back.material_names, (std::vector<std::string>{"default", "default_2", "stone", "stone_4"}));
  EXPECT_EQ(back.materials, (std::vector<uint32_t>{0, 1, 2, 3}));
  ASSERT_EQ(back.material_looks.size(), 4u);
  for (size_t id = 0; id < 4; ++id) EXPECT_EQ(back.material_looks[id].roughness, float(id + 1) / 8) << id;
  // One material for every triangle (no per-triangle ids), unnamed: its look still reaches the library.
  Mesh one = mesh;
  one.materials.clear();
  one.material_names.clear();
  one.material_looks = {MaterialLook{.roughness = 0.25f}};
  write_mesh(one, dir / "one.obj");
  const Mesh one_back = read_mesh(dir / "one.obj");
  ASSERT_EQ(one_back.material_looks.size(), 1u);
  EXPECT_EQ(one_back.material_looks[0].roughness, 0.25f);
}

// A glTF's materials reach an OBJ's library too: factors, and a texture that is a file beside it.
TEST(Mtl, GltfMaterialsReachObj) {
  test::TempDir dir;
  test::write_text(dir / "tex.png", tiny_png);
  test::write_text(dir / "m.mtl", "newmtl stone\nKd 0.8 0.5 0.3\nPm 0.5\nPr 0.4\nKe 0 1 0\nmap_Kd tex.png\n");
  test::write_text(dir / "quad.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nusemtl stone\nf 1/1 2/2 3/3\n");
  write_mesh(read_mesh(dir / "quad.obj"), dir / "quad.gltf");  // refers to tex.png
  const Mesh back = read_mesh(dir / "quad.gltf");
  ASSERT_EQ(back.material_looks.size(), 2u);  // (flattened: id 0 is "no material")
  const MaterialLook& stone = back.material_looks[1];
  EXPECT_EQ(stone.base_color, (float4{0.8f, 0.5f, 0.3f, 1}));
  EXPECT_EQ(stone.metallic, 0.5f);
  EXPECT_EQ(stone.roughness, 0.4f);
  EXPECT_EQ(stone.emissive, (float3{0, 1, 0}));
  EXPECT_EQ(std::filesystem::path(stone.base_color_texture), dir / "tex.png");
  write_mesh(back, dir / "again.obj");
  EXPECT_NE(test::read_bytes(dir / "again.mtl").find("map_Kd tex.png\n"), std::string::npos);
}

// A glTF's embedded images (BIN chunk, data: URI) reach the mesh as bytes; an OBJ or a PLY gets
// them as files beside it (OUT_k.png), a glTF written from the mesh embeds them again.
TEST(Mtl, EmbeddedImagesGoBesideAnObjOrPly) {
  test::TempDir dir;
  test::write_text(dir / "tex.png", tiny_png);
  test::write_text(dir / "m.mtl", "newmtl stone\nKd 0.8 0.5 0.3\nmap_Kd tex.png\n");
  test::write_text(dir / "quad.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nusemtl stone\nf 1/1 2/2 3/3\n");
  write_mesh(read_mesh(dir / "quad.obj"), dir / "a.glb");  // tex.png into the BIN chunk
  std::filesystem::remove(dir / "tex.png");
  const auto image_text = [](const MaterialLook& look, size_t slot) {
    return look.images[slot] ? std::string(look.images[slot]->begin(), look.images[slot]->end()) : std::string("(none)");
  };
  const Mesh mesh = read_mesh(dir / "a.glb");
  ASSERT_EQ(mesh.material_looks.size(), 2u);  // (flattened: id 0 is "no material")
  EXPECT_EQ(mesh.material_looks[1].base_color_texture, "");
  EXPECT_TRUE(image_text(mesh.material_looks[1], 0) == tiny_png);
  EXPECT_FALSE(mesh.material_looks[1].images[1] || mesh.material_looks[1].images[2]);
  // The scene leaves the image in its document (which a glTF written from it keeps): no copy.
  const Scene scene = read_scene(dir / "a.glb");
  ASSERT_EQ(scene.material_looks.size(), 1u);
  EXPECT_FALSE(scene.material_looks[0].images[0]);
  EXPECT_TRUE(image_text(source_material_looks(scene)[0], 0) == tiny_png);

  std::filesystem::create_directory(dir / "out");
  const WriteReport obj = write_mesh(mesh, dir / "out" / "b.obj");
  EXPECT_EQ(test::read_bytes(dir / "out" / "b_0.png"), tiny_png);
  EXPECT_NE(test::read_bytes(dir / "out" / "b.mtl").find("map_Kd b_0.png\n"), std::string::npos);
  EXPECT_EQ(obj.bytes, std::filesystem::file_size(dir / "out" / "b.obj") + std::filesystem::file_size(dir / "out" / "b.mtl") + tiny_png.size());
  const Mesh from_obj = read_mesh(dir / "out" / "b.obj");
  ASSERT_EQ(from_obj.material_looks.size(), 1u);
  EXPECT_EQ(std::filesystem::path(from_obj.material_looks[0].base_color_texture), dir / "out" / "b_0.png");

  write_mesh(mesh, dir / "out" / "c.ply");
  EXPECT_EQ(test::read_bytes(dir / "out" / "c_0.png"), tiny_png);
  EXPECT_NE(test::read_bytes(dir / "out" / "c.ply").find("comment TextureFile c_0.png\n"), std::string::npos);

  // A .gltf written from the mesh: a data: URI, which reads back as the same bytes.
  write_mesh(mesh, dir / "d.gltf");
  const nlohmann::json doc = nlohmann::json::parse(test::read_bytes(dir / "d.gltf"));
  ASSERT_EQ(doc["images"].size(), 1u);
  EXPECT_EQ(doc["images"][0]["uri"].get<std::string>().rfind("data:image/png;base64,", 0), 0u);
  test::expect_valid_gltf({dir / "d.gltf"});
  // (Material 0, "no material" in the flattened mesh, became a material of its own: stone is last.)
  EXPECT_TRUE(image_text(read_mesh(dir / "d.gltf").material_looks.back(), 0) == tiny_png);

  // A name a look already gives a texture file is passed over: that file is not replaced.
  Mesh taken = mesh;
  taken.material_looks[1].normal_texture = (dir / "out" / "e_0.png").string();
  write_mesh(taken, dir / "out" / "e.obj");
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "e_0.png"));
  EXPECT_EQ(test::read_bytes(dir / "out" / "e_1.png"), tiny_png);
  {  // the same with the output named relative to the current folder
    const std::filesystem::path was = std::filesystem::current_path();
    std::filesystem::current_path(dir / "out");
    taken.material_looks[1].normal_texture = (dir / "out" / "g_0.png").string();
    write_mesh(taken, "g.obj");
    std::filesystem::current_path(was);
    EXPECT_FALSE(std::filesystem::exists(dir / "out" / "g_0.png"));
    EXPECT_TRUE(std::filesystem::exists(dir / "out" / "g_1.png"));
  }
  // Only the materials triangles use: none here, so no image.
  Mesh unused = mesh;
  unused.materials.assign(unused.triangle_count(), 0);
  write_mesh(unused, dir / "out" / "f.obj");
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "f_0.png"));
}

// The CLI refuses an .obj output whose library would be written over the one the input reads.
TEST(Mtl, CommandsRefuseToWriteOverTheInputsLibrary) {
  test::TempDir dir;
  test::write_text(dir / "m.mtl", "newmtl stone\nKd 0.8 0.5 0.3\n");
  test::write_text(dir / "in.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl stone\nf 1 2 3\nf 1 3 4\n");
  const std::string library = test::read_bytes(dir / "m.mtl");
  const std::string in = (dir / "in.obj").string(), out = (dir / "m.obj").string();
  for (const std::vector<std::string>& args : {std::vector<std::string>{"convert", in, out}, {"simplify", in, "-o", out, "--ratio", "0.5"},
                                               {"optimize", in, "-o", out}}) {
    SCOPED_TRACE(args[0]);
    const test::RunResult r = test::run_cli(args);
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("which the input reads"), std::string::npos) << r.err;
    EXPECT_EQ(test::read_bytes(dir / "m.mtl"), library);
    EXPECT_FALSE(std::filesystem::exists(out));
  }
  EXPECT_EQ(test::run_cli({"convert", in, (dir / "other.obj").string()}).exit_code, 0);
  EXPECT_NE(test::read_bytes(dir / "other.mtl").find("newmtl stone"), std::string::npos);
}

// A library that is not there is a warning: the mesh reads, its materials keep their names.
TEST(Mtl, AMissingLibraryIsAWarning) {
  test::TempDir dir;
  test::write_text(dir / "a.obj", "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n");
  std::vector<std::string> warnings;
  const Mesh mesh = read_mesh(dir / "a.obj", {.warning = [&](const std::string& w) { warnings.push_back(w); }});
  EXPECT_EQ(mesh.material_names, (std::vector<std::string>{"red"}));
  EXPECT_TRUE(mesh.material_looks.empty());
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("material library gone.mtl not found"), std::string::npos) << warnings[0];
}

}  // namespace
}  // namespace lod
