// PLY: hand-built files in every encoding, with expected values written down from the bytes we put
// in; exact round trips of every stream; malformed headers and bodies.
#include <gtest/gtest.h>

#include <bit>
#include <cstring>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "test_support.h"

namespace lod {
namespace {

using test::bytes_of;

// Appends `v` in the given byte order.
template <class T>
void put(std::string& out, T v, bool big_endian) {
  char raw[sizeof(T)];
  std::memcpy(raw, &v, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(raw, raw + sizeof(T));
  out.append(raw, sizeof(T));
}

Mesh read(const std::string& text) { return read_ply(bytes_of(text), "hand.ply"); }

TEST(Ply, AsciiInAnyPropertyOrderWithUnknownElementsAndProperties) {
  const std::string text =
      "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nobj_info nothing\r\n"
      "element material 1\r\nproperty float shininess\r\nproperty list uchar int tags\r\n"
      "element vertex 4\r\nproperty float z\r\nproperty uchar quality\r\nproperty float y\r\nproperty float x\r\n"
      "element face 2\r\nproperty uchar flags\r\nproperty list int uint vertex_indices\r\n"
      "element edge 1\r\nproperty int vertex1\r\nproperty int vertex2\r\nend_header\r\n"
      "0.5 3 7 8 9\r\n"                                         // material: shininess, 3 tags
      "3 7 2 1\r\n-1 0 0.25 2\r\n0 9 1 0.125\r\n1e-3 1 +4 -0\r\n"  // z quality y x
      "0 3 0 1 2\r\n1 4 0 2 3 1\r\n"                            // a triangle and a quad
      "0 1\r\n";
  Mesh m = read(text);
  ASSERT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(m.positions[0], (float3{1, 2, 3}));
  EXPECT_EQ(m.positions[1], (float3{2, 0.25f, -1}));
  EXPECT_EQ(m.positions[2], (float3{0.125f, 1, 0}));
  EXPECT_EQ(m.positions[3], (float3{-0.0f, 4, 0.001f}));
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 3, 1}));
  EXPECT_TRUE(m.normals.empty());
  EXPECT_TRUE(m.colors.empty());
}

// The same mesh, big-endian, doubles for positions, short indices with a ushort count, and a skipped
// property of every scalar type.
TEST(Ply, BinaryBigEndianWithEveryScalarType) {
  const bool be = true;
  std::string b =
      "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty char a\nproperty double x\nproperty uchar b\n"
      "property double y\nproperty short c\nproperty double z\nproperty ushort d\nproperty int e\nproperty uint f\n"
      "property float g\nproperty list uint8 float32 h\nelement face 1\nproperty list ushort short vertex_indices\nend_header\n";
  const double xyz[3][3] = {{1.5, -2, 1e-30}, {3, 4, 5}, {-0.0625, 7, 8}};
  for (int v = 0; v < 3; ++v) {
    put<int8_t>(b, -1, be), put(b, xyz[v][0], be), put<uint8_t>(b, 200, be), put(b, xyz[v][1], be);
    put<int16_t>(b, -300, be), put(b, xyz[v][2], be), put<uint16_t>(b, 60000, be), put<int32_t>(b, -7, be);
    put<uint32_t>(b, 4000000000u, be), put<float>(b, 0.5f, be);
    put<uint8_t>(b, 2, be), put<float>(b, 1, be), put<float>(b, 2, be);
  }
  put<uint16_t>(b, 3, be), put<int16_t>(b, 2, be), put<int16_t>(b, 0, be), put<int16_t>(b, 1, be);
  Mesh m = read(b);
  ASSERT_EQ(m.vertex_count(), 3u);
  EXPECT_EQ(m.positions[0], (float3{1.5f, -2, float(1e-30)}));
  EXPECT_EQ(m.positions[1], (float3{3, 4, 5}));
  EXPECT_EQ(m.positions[2], (float3{-0.0625f, 7, 8}));
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{2, 0, 1}));
}

TEST(Ply, BinaryLittleEndianStreamsColoursAndMaterials) {
  const bool be = false;
  std::string b =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "property float nx\nproperty float ny\nproperty float nz\nproperty float texture_u\nproperty float texture_v\n"
      "property uchar red\nproperty uchar green\nproperty uchar blue\n"
      "element face 2\nproperty int material_index\nproperty list uchar int vertex_indices\nend_header\n";
  for (int v = 0; v < 4; ++v) {
    put<float>(b, float(v), be), put<float>(b, 0, be), put<float>(b, 0, be);
    put<float>(b, 0, be), put<float>(b, 0, be), put<float>(b, 1, be);
    put<float>(b, 0.25f * float(v), be), put<float>(b, 1, be);
    put<uint8_t>(b, 255, be), put<uint8_t>(b, uint8_t(51 * v), be), put<uint8_t>(b, 0, be);
  }
  put<int32_t>(b, 5, be), put<uint8_t>(b, 4, be);  // a quad with material 5
  for (int32_t i : {0, 1, 2, 3}) put(b, i, be);
  put<int32_t>(b, 2, be), put<uint8_t>(b, 3, be);
  for (int32_t i : {3, 2, 1}) put(b, i, be);
  Mesh m = read(b);
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 3, 2, 1}));
  EXPECT_EQ(m.materials, (std::vector<uint32_t>{5, 5, 2}));
  ASSERT_EQ(m.normals.size(), 4u);
  EXPECT_EQ(m.normals[3], (float3{0, 0, 1}));
  ASSERT_EQ(m.uvs[0].size(), 4u);
  EXPECT_EQ(m.uvs[0][2], (float2{0.5f, 1}));
  ASSERT_EQ(m.colors.size(), 4u);
  EXPECT_EQ(m.colors[0], (float4{1, 0, 0, 1}));  // no alpha: opaque
  EXPECT_EQ(m.colors[1], (float4{1, 51.0f / 255.0f, 0, 1}));
}

// Every stream lodkit has, in both encodings: read(write(m)) == m bit for bit.
TEST(Ply, RoundTripIsExactWithEveryStream) {
  Mesh m = shapes::torus();
  const size_t n = m.vertex_count();
  for (size_t v = 0; v < n; ++v) {
    const float t = float(v) / float(n);
    m.tangents.push_back({1, 0, 0, v % 2 ? 1.0f : -1.0f});
    m.uvs[1].push_back({t, 1 - t});
    m.colors.push_back({t, 1.0f / 3.0f, 0.1f, 1});
    m.joints.push_back({uint16_t(v % 7), uint16_t(65535), 0, 3});
    m.weights.push_back({0.5f, 0.25f, 0.125f, 0.125f});
  }
  for (size_t t = 0; t < m.triangle_count(); ++t) m.materials.push_back(uint32_t(t % 3));
  for (bool binary : {true, false}) {
    SCOPED_TRACE(binary ? "binary" : "ascii");
    std::string out;
    write_ply(m, out, {.binary = binary});
    EXPECT_EQ(out.find(binary ? "format binary_little_endian 1.0\n" : "format ascii 1.0\n"), 4u);
    Mesh back = read_ply(bytes_of(out), "rt.ply");
    EXPECT_EQ(test::mesh_difference(back, m), "");
  }
}

// Colours go in unsigned bytes (PLY's custom, the only type MeshLab reads) when every channel is
// k / 255 as the reader scales it, so the round trip stays exact; in floats otherwise.
TEST(Ply, ColoursGoInBytesWhenThatIsExact) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.indices = {0, 1, 2};
  const auto byte = [](int k) { return float(double(k) * (1.0 / 255)); };
  m.colors = {{1, 0, byte(128), 1}, {byte(1), byte(254), byte(77), byte(200)}, {0, 0, 0, 0}};
  std::string text;
  write_ply(m, text, {.binary = false});
  EXPECT_NE(text.find("property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"), std::string::npos) << text;
  EXPECT_NE(text.find("end_header\n0 0 0 255 0 128 255\n1 0 0 1 254 77 200\n0 1 0 0 0 0 0\n"), std::string::npos) << text;
  for (bool binary : {true, false}) {
    std::string out;
    write_ply(m, out, {.binary = binary});
    EXPECT_EQ(test::mesh_difference(read_ply(bytes_of(out), "bytes.ply"), m), "");
  }
  // Half way between two bytes: floats, exact too.
  m.colors[2].y = 0.5f;
  std::string out;
  write_ply(m, out, {.binary = true});
  EXPECT_NE(out.find("property float red\n"), std::string::npos);
  EXPECT_EQ(test::mesh_difference(read_ply(bytes_of(out), "floats.ply"), m), "");
}

// PLY promises nothing of tangents; Mesh's are unit with w = +-1 (make_unit_directions).
TEST(Ply, TangentsReadAtUnitLength) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "property float tx\nproperty float ty\nproperty float tz\nproperty float tw\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0 3 4 0 1\n0 1 0 1 0 0 -0.5\n0 0 1 0 0 0 0\n3 0 1 2\n";
  const Mesh m = read(text);
  ASSERT_EQ(m.tangents.size(), 3u);
  EXPECT_EQ(m.tangents[0], (float4{0.6f, 0.8f, 0, 1}));
  EXPECT_EQ(m.tangents[1], (float4{1, 0, 0, -1}));
  // Zero, without normals: a direction across the triangle's normal, +x.
  const float4 t = m.tangents[2];
  EXPECT_NEAR(t.x * t.x + t.y * t.y + t.z * t.z, 1.0, 1e-6);
  EXPECT_EQ(t.x, 0.0f);
  EXPECT_EQ(t.w, 1.0f);
}

// MeshLab's textured PLY: UVs per face corner (texcoord) and the texture in a header comment. A
// vertex with two UVs becomes two vertices, in order of first use: vertex 0 has (0, 0) in the first
// face and (0.5, 0.5) in the second, vertex 2 the same (1, 1) in both.
TEST(Ply, PerCornerTexcoordsSplitVertices) {
  const std::string text =
      "ply\nformat ascii 1.0\ncomment TextureFile tex.png\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 2\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\n"
      "end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2 6 0 0 1 0 1 1\n3 0 2 3 6 0.5 0.5 1 1 0 1\n";
  std::vector<std::string> textures;
  const Mesh m = read_ply(bytes_of(text), "meshlab.ply", {}, &textures);
  EXPECT_EQ(textures, (std::vector<std::string>{"tex.png"}));
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 3, 2, 4}));
  EXPECT_EQ(m.positions, (std::vector<float3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}, {0, 1, 0}}));
  EXPECT_EQ(m.uvs[0], (std::vector<float2>{{0, 0}, {1, 0}, {1, 1}, {0.5f, 0.5f}, {0, 1}}));

  // Binary, a quad (fan-triangulated, its UVs with it), texnumber for the material.
  std::string b =
      "ply\nformat binary_little_endian 1.0\ncomment TextureFile a.png\ncomment TextureFile b.png\nelement vertex 4\n"
      "property float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar float texcoord\n"
      "property list uchar uint vertex_indices\nproperty int texnumber\nend_header\n";
  for (int v = 0; v < 4; ++v) put<float>(b, float(v), false), put<float>(b, float(v % 2), false), put<float>(b, 0, false);
  put<uint8_t>(b, 8, false);
  for (float f : {0.0f, 0.0f, 0.25f, 0.0f, 0.25f, 0.25f, 0.0f, 0.25f}) put<float>(b, f, false);
  put<uint8_t>(b, 4, false);
  for (uint32_t i : {0u, 1u, 2u, 3u}) put<uint32_t>(b, i, false);
  put<int32_t>(b, 1, false);
  textures.clear();
  const Mesh q = read_ply(bytes_of(b), "quad.ply", {}, &textures);
  EXPECT_EQ(textures, (std::vector<std::string>{"a.png", "b.png"}));
  EXPECT_EQ(q.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
  EXPECT_EQ(q.uvs[0], (std::vector<float2>{{0, 0}, {0.25f, 0}, {0.25f, 0.25f}, {0, 0.25f}}));
  EXPECT_EQ(q.materials, (std::vector<uint32_t>{1, 1}));

  // A list that does not give each corner a (u, v) is bad input, naming the face.
  for (const char* faces : {"3 0 1 2 4 0 0 1 0\n", "3 0 1 2 5 0 0 1 0 1\n"}) {
    const std::string bad = text.substr(0, text.find("3 0 1 2")) + faces + "3 0 2 3 6 0.5 0.5 1 1 0 1\n";
    try {
      read(bad);
      ADD_FAILURE() << faces;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("face 0"), std::string::npos) << e.what();
    }
  }
}

// From a file, the textures become material looks (texnumber k: texture k, beside the file), which
// a .glb embeds.
TEST(Ply, TextureFilesBecomeMaterialLooks) {
  test::TempDir dir;
  test::write_text(dir / "m.ply",
                   "ply\nformat ascii 1.0\ncomment TextureFile tex.png\nelement vertex 3\nproperty float x\n"
                   "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                   "property list uchar float texcoord\nend_header\n0 0 0\n1 0 0\n1 1 0\n3 0 1 2 6 0 0 1 0 1 1\n");
  std::vector<std::string> warnings;
  const Mesh m = read_mesh(dir / "m.ply", {.warning = [&](const std::string& w) { warnings.push_back(w); }});
  ASSERT_EQ(m.material_looks.size(), 1u);
  EXPECT_EQ(std::filesystem::path(m.material_looks[0].base_color_texture), dir / "tex.png");
  EXPECT_EQ(m.material_names, (std::vector<std::string>{"tex.png"}));
  ASSERT_EQ(warnings.size(), 1u);  // tex.png is not there yet
  EXPECT_NE(warnings[0].find("texture tex.png not found"), std::string::npos) << warnings[0];
  test::write_text(dir / "tex.png", test::tiny_png());
  write_mesh(read_mesh(dir / "m.ply"), dir / "m.glb");
  const test::Glb glb = test::read_glb(dir / "m.glb");
  ASSERT_EQ(glb.doc["images"].size(), 1u);
  EXPECT_EQ(glb.doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"], 0);
  test::expect_valid_gltf({dir / "m.glb"});
}

// Written back, the textures go out as MeshLab links them: TextureFile lines (paths from the PLY's
// folder) numbered from 0 by the used textured materials in id order, then the untextured used
// ones; MeshLab's texnumber (an int) beside per-corner UVs when there are several textures.
TEST(Ply, TexturesGoOutAsMeshLabLinksThem) {
  test::TempDir dir;
  std::filesystem::create_directories(dir / "tex");
  std::filesystem::create_directories(dir / "out");
  Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0}, {2, 1, 0}};
  mesh.uvs[0] = {{0, 0}, {0.5f, 0}, {0.5f, 1}, {0, 1}, {1, 0}, {1, 1}};
  mesh.indices = {0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 2};
  mesh.materials = {3, 1, 0, 1};
  mesh.material_looks.resize(4);
  mesh.material_looks[0].base_color_texture = (dir / "tex" / "a.png").string();
  mesh.material_looks[2].base_color_texture = (dir / "tex" / "unused.png").string();
  mesh.material_looks[3].base_color_texture = (dir / "tex" / "b.png").string();
  for (bool binary : {true, false}) {
    SCOPED_TRACE(binary ? "binary" : "ascii");
    const std::filesystem::path file = dir / "out" / "m.ply";
    write_mesh(mesh, file, {.binary = binary});
    const std::string text = test::read_bytes(file);
    const std::string header = text.substr(0, text.find("end_header"));
    EXPECT_NE(header.find("comment TextureFile ../tex/a.png\ncomment TextureFile ../tex/b.png\nelement vertex"), std::string::npos) << header;
    EXPECT_EQ(header.find("unused"), std::string::npos) << header;
    EXPECT_NE(header.find("property float texture_u\nproperty float texture_v\n"), std::string::npos) << header;
    EXPECT_NE(header.find("property list uchar float texcoord\nproperty int texnumber\n"), std::string::npos) << header;
    const Mesh back = read_mesh(file);
    // Material 0 (a.png) is texture 0, material 3 (b.png) texture 1, material 1 (none) number 2.
    EXPECT_EQ(back.materials, (std::vector<uint32_t>{1, 2, 0, 2}));
    ASSERT_EQ(back.material_looks.size(), 3u);
    EXPECT_EQ(std::filesystem::path(back.material_looks[0].base_color_texture), dir / "tex" / "a.png");
    EXPECT_EQ(std::filesystem::path(back.material_looks[1].base_color_texture), dir / "tex" / "b.png");
    EXPECT_EQ(back.material_looks[2].base_color_texture, "");
    ASSERT_EQ(back.indices.size(), mesh.indices.size());
    for (size_t c = 0; c < mesh.indices.size(); ++c) {
      EXPECT_EQ(back.positions[back.indices[c]], mesh.positions[mesh.indices[c]]) << "corner " << c;
      EXPECT_EQ(back.uvs[0][back.indices[c]], mesh.uvs[0][mesh.indices[c]]) << "corner " << c;
    }
  }
  // One texture: no per-corner UVs; every face on material 0 needs no face property at all.
  Mesh one = mesh;
  one.materials.clear();
  write_mesh(one, dir / "one.ply", {.binary = false});
  const std::string text = test::read_bytes(dir / "one.ply");
  EXPECT_NE(text.find("comment TextureFile tex/a.png\n"), std::string::npos) << text;
  EXPECT_EQ(text.find("texcoord"), std::string::npos) << text;
  EXPECT_EQ(text.find("texnumber"), std::string::npos) << text;
  const Mesh back = read_mesh(dir / "one.ply");
  ASSERT_EQ(back.material_looks.size(), 1u);
  EXPECT_EQ(std::filesystem::path(back.material_looks[0].base_color_texture), dir / "tex" / "a.png");
  // Without UVs there is nothing to link: the mesh's ids stay as they are, in material_index.
  Mesh plain = mesh;
  plain.uvs[0].clear();
  write_mesh(plain, dir / "plain.ply");
  EXPECT_EQ(test::read_bytes(dir / "plain.ply").find("TextureFile"), std::string::npos);
  EXPECT_EQ(read_mesh(dir / "plain.ply").materials, mesh.materials);
}

TEST(Ply, AFileWithoutFacesIsAPointSet) {
  Mesh m = read("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
                "1 2 3\n4 5 6\n");
  EXPECT_EQ(m.vertex_count(), 2u);
  EXPECT_EQ(m.triangle_count(), 0u);
  // No vertices at all, with attribute streams declared (found by fuzz_ply: streams had no storage).
  Mesh empty = read("ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                    "property float z\nproperty float nx\nproperty uchar red\nelement face 0\n"
                    "property list uchar int vertex_indices\nend_header\n");
  EXPECT_EQ(empty.vertex_count(), 0u);
  EXPECT_TRUE(empty.colors.empty());
  // An empty mesh written and read back (found by fuzz_ply: x, y, z were not declared).
  for (bool binary : {true, false}) {
    std::string out;
    write_ply(Mesh{}, out, {.binary = binary});
    EXPECT_EQ(read_ply(bytes_of(out), "empty.ply").vertex_count(), 0u);
  }
}

TEST(Ply, RejectsBadInput) {
  const std::string xyz = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string tri = "0 0 0\n1 0 0\n0 1 0\n";
  const std::string faces = "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string cases[] = {
      "",                                                                          // empty
      "ply\n",                                                                     // no end_header
      "ply\nformat ascii 2.0\nend_header\n",                                       // version
      "ply\nformat binary_middle_endian 1.0\nend_header\n",                        // format
      "ply\nformat ascii 1.0\nproperty float x\nend_header\n",                     // property before element
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n",  // no y, z
      "ply\nformat ascii 1.0\nend_header\n",                                       // no vertex element
      xyz + "element face 1\nproperty list float int vertex_indices\nend_header\n" + tri + "3 0 1 2\n",  // float count
      xyz + "element face 1\nproperty list uchar float vertex_indices\nend_header\n" + tri + "3 0 1 2\n",  // float index
      xyz + "element face 1\nproperty uchar flags\nend_header\n" + tri + "1\n",   // faces without corners
      xyz + faces + tri + "3 0 1 3\n",                                              // index past the end
      xyz + faces + tri + "3 0 -1 2\n",                                             // negative index
      xyz + faces + tri + "2 0 1\n",                                                // two corners
      xyz + faces + tri + "3 0 1\n",                                                // truncated list
      xyz + faces + "0 0 0\n1 0 inf\n0 1 0\n3 0 1 2\n",                             // Inf
      xyz + faces + "0 0 0\n1 0 0\n0 1 zero\n3 0 1 2\n",                            // junk
      xyz + faces + tri + "300 0 1 2\n",                                            // count does not fit uchar
      xyz + "element face 1\nproperty list int int vertex_indices\nend_header\n" + tri + "1000000 0 1 2\n",  // 10^6 corners
      xyz + "property uchar joint0\nend_header\n" + tri,                         // joints without weights
      "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n",
  };
  for (const std::string& text : cases) test::expect_bad_input([](auto b, const auto& n) { read_ply(b, n); }, text, "bad.ply");

  // Binary: offsets name the failing byte.
  std::string b = "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 0\nproperty list uchar int vertex_indices\nend_header\n";
  const size_t data = b.size();
  put<float>(b, 1, false), put<float>(b, std::numeric_limits<float>::quiet_NaN(), false), put<float>(b, 1, false);
  const std::string message = test::expect_bad_input([](auto s, const auto& n) { read_ply(s, n); }, b, "nan.ply");
  EXPECT_NE(message.find("byte " + std::to_string(data + 4)), std::string::npos) << message;
}

}  // namespace
}  // namespace lod
