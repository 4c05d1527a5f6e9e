// glTF reader and writer: exact round trips, pass-through of everything lodkit does not change
// (checked against the values put into hand-built files), malformed input, and the Khronos validator.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>
#include <string>
#include <tuple>
#include <vector>

#include "core/shapes.h"
#include "io/lod_chain_scene.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "skin/fixtures.h"
#include "test_support.h"

namespace lod {
namespace {

using Json = nlohmann::json;
using test::mesh_difference;
using test::TempDir;

constexpr int kFloat = 5126, kUByte = 5121, kUShort = 5123, kUInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

// A 2x2 RGBA PNG (76 bytes, deliberately not a multiple of 4).
const std::vector<uint8_t> kPng = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00, 0x00,
    0x02, 0x00, 0x00, 0x00, 0x02, 0x08, 0x06, 0x00, 0x00, 0x00, 0x72, 0xb6, 0x0d, 0x24, 0x00, 0x00, 0x00, 0x13, 0x49,
    0x44, 0x41, 0x54, 0x78, 0xda, 0x63, 0xf8, 0xcf, 0xc0, 0xf0, 0x1f, 0x0c, 0x81, 0x34, 0x08, 0x34, 0x00, 0x00, 0x49,
    0x49, 0x09, 0x78, 0x9c, 0x51, 0x17, 0x92, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};

using test::base64;

std::vector<uint8_t> base64_decode(const std::string& text) {
  std::vector<uint8_t> out;
  uint32_t bits = 0;
  int count = 0;
  for (char c : text) {
    int v = c >= 'A' && c <= 'Z' ? c - 'A' : c >= 'a' && c <= 'z' ? c - 'a' + 26 : c >= '0' && c <= '9' ? c - '0' + 52
          : c == '+' ? 62 : c == '/' ? 63 : -1;
    if (v < 0) continue;
    bits = bits << 6 | uint32_t(v);
    if ((count += 6) >= 8) {
      count -= 8;
      out.push_back(uint8_t(bits >> count));
    }
  }
  return out;
}

// A glTF document written by hand: binary data appended 4-byte aligned, JSON as nlohmann objects.
struct HandBuilt {
  Json doc = {{"asset", {{"version", "2.0"}}}};
  std::vector<uint8_t> bin;

  int view(const void* data, size_t bytes, int target = 0, int stride = 0) {
    while (bin.size() % 4) bin.push_back(0);
    Json v = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes}};
    if (target) v["target"] = target;
    if (stride) v["byteStride"] = stride;
    const auto* p = static_cast<const uint8_t*>(data);
    bin.insert(bin.end(), p, p + bytes);
    doc["bufferViews"].push_back(v);
    return int(doc["bufferViews"].size() - 1);
  }
  template <class T>
  int accessor(const std::vector<T>& values, int component_type, const char* type, size_t components, int target = 0,
               Json extra = Json::object()) {
    Json a = {{"bufferView", view(values.data(), values.size() * sizeof(T), target)},
              {"componentType", component_type},
              {"count", values.size() / components},
              {"type", type}};
    a.update(extra);
    doc["accessors"].push_back(a);
    return int(doc["accessors"].size() - 1);
  }
  // A sparse part for a float accessor: its elements `indices` (u8) become `values`.
  void make_sparse(int accessor, const std::vector<uint8_t>& indices, const std::vector<float>& values) {
    const int index_view = view(indices.data(), indices.size());
    const int value_view = view(values.data(), values.size() * 4);
    doc["accessors"][size_t(accessor)]["sparse"] = {{"count", indices.size()},
                                                     {"indices", {{"bufferView", index_view}, {"componentType", kUByte}}},
                                                     {"values", {{"bufferView", value_view}}}};
  }
  // POSITION with the min/max glTF requires.
  int positions(const std::vector<float>& xyz) {
    Json lo = Json::array(), hi = Json::array();
    for (int c = 0; c < 3; ++c) {
      float mn = xyz[size_t(c)], mx = xyz[size_t(c)];
      for (size_t i = size_t(c); i < xyz.size(); i += 3) mn = std::min(mn, xyz[i]), mx = std::max(mx, xyz[i]);
      lo.push_back(mn);
      hi.push_back(mx);
    }
    return accessor(xyz, kFloat, "VEC3", 3, kArrayBuffer, {{"min", lo}, {"max", hi}});
  }

  std::vector<uint8_t> glb() const {
    Json d = doc;
    if (!bin.empty()) d["buffers"] = Json::array({{{"byteLength", bin.size()}}});
    return test::glb_bytes({d, bin});
  }
  std::string gltf() const {  // the buffer as a data: URI
    Json d = doc;
    if (!bin.empty())
      d["buffers"] = Json::array({{{"byteLength", bin.size()}, {"uri", "data:application/octet-stream;base64," + base64(bin)}}});
    return d.dump();
  }
};

std::span<const uint8_t> span_of(const std::string& s) { return {reinterpret_cast<const uint8_t*>(s.data()), s.size()}; }

// A written file, parsed without lodkit: the JSON and the bytes of buffer 0.
struct Written {
  Json doc;
  std::vector<uint8_t> bin;
};

uint32_t get_u32(std::span<const uint8_t> b, size_t at) {
  return uint32_t(b[at]) | uint32_t(b[at + 1]) << 8 | uint32_t(b[at + 2]) << 16 | uint32_t(b[at + 3]) << 24;
}

std::string uri_decode(const std::string& uri) {
  std::string out;
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size()) {
      out += char(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += uri[i];
    }
  }
  return out;
}

Written load_written(const std::filesystem::path& path) {
  Written w;
  const FileBytes bytes = read_file_bytes(path);
  if (path.extension() == ".glb") {
    EXPECT_GE(bytes.size(), 20u);
    EXPECT_EQ(get_u32(bytes, 0), 0x46546C67u);
    EXPECT_EQ(get_u32(bytes, 4), 2u);
    EXPECT_EQ(get_u32(bytes, 8), bytes.size());
    const uint32_t json_size = get_u32(bytes, 12);
    EXPECT_EQ(json_size % 4, 0u);
    w.doc = Json::parse(bytes.begin() + 20, bytes.begin() + 20 + json_size);
    const size_t bin_at = 20 + size_t(json_size);
    if (bin_at < bytes.size()) {
      EXPECT_EQ(get_u32(bytes, bin_at + 4), 0x004E4942u);
      w.bin.assign(bytes.begin() + ptrdiff_t(bin_at + 8), bytes.begin() + ptrdiff_t(bin_at + 8 + get_u32(bytes, bin_at)));
      EXPECT_EQ(bin_at + 8 + get_u32(bytes, bin_at), bytes.size()) << "exactly one BIN chunk";
    }
  } else {
    w.doc = Json::parse(bytes.begin(), bytes.end());
    if (w.doc.contains("buffers")) {
      const FileBytes bin = read_file_bytes(path.parent_path() / uri_decode(w.doc["buffers"][0]["uri"]));
      w.bin.assign(bin.begin(), bin.end());
    }
  }
  if (w.doc.contains("buffers")) {
    EXPECT_EQ(w.doc["buffers"].size(), 1u);
    EXPECT_LE(w.doc["buffers"][0]["byteLength"].get<size_t>(), w.bin.size());
  }
  return w;
}

std::vector<uint8_t> view_bytes(const Written& w, int view) {
  const Json& v = w.doc["bufferViews"][size_t(view)];
  const size_t offset = v.value("byteOffset", size_t(0)), length = v["byteLength"];
  return {w.bin.begin() + ptrdiff_t(offset), w.bin.begin() + ptrdiff_t(offset + length)};
}

// Float accessor contents, read straight from the bytes.
std::vector<float> accessor_floats(const Written& w, int index) {
  const Json& a = w.doc["accessors"][size_t(index)];
  EXPECT_EQ(a["componentType"], kFloat);
  const std::string type = a["type"];
  const size_t n = type == "SCALAR" ? 1 : type == "VEC2" ? 2 : type == "VEC3" ? 3 : type == "VEC4" ? 4 : 16;
  const Json& v = w.doc["bufferViews"][a["bufferView"].get<size_t>()];
  const size_t stride = v.value("byteStride", n * 4);
  const size_t base = v.value("byteOffset", size_t(0)) + a.value("byteOffset", size_t(0));
  std::vector<float> out(a["count"].get<size_t>() * n);
  for (size_t i = 0; i < a["count"].get<size_t>(); ++i) std::memcpy(&out[i * n], &w.bin[base + i * stride], n * 4);
  return out;
}

// Every stream lodkit maps, with values the glTF validator accepts (unit normals and tangents,
// tangent w = +-1, colors in [0, 1], distinct joints, weights summing to exactly 1).
Mesh with_all_streams(Mesh m) {
  const size_t n = m.vertex_count();
  m.tangents.resize(n);
  m.uvs[1].resize(n);
  m.colors.resize(n);
  m.joints.resize(n);
  m.weights.resize(n);
  if (m.uvs[0].empty())
    for (const float3& p : m.positions) m.uvs[0].push_back({p.x, p.y});
  for (size_t i = 0; i < n; ++i) {
    const float3 nrm = m.normals[i];
    const float3 axis = std::fabs(nrm.x) < 0.9f ? float3{1, 0, 0} : float3{0, 1, 0};
    float3 t = {nrm.y * axis.z - nrm.z * axis.y, nrm.z * axis.x - nrm.x * axis.z, nrm.x * axis.y - nrm.y * axis.x};
    const float len = std::sqrt(t.x * t.x + t.y * t.y + t.z * t.z);
    m.tangents[i] = {t.x / len, t.y / len, t.z / len, i % 2 ? -1.0f : 1.0f};
    m.uvs[1][i] = {m.positions[i].z * 0.5f, float(i % 13) / 13.0f};
    m.colors[i] = {float(i % 7) / 6.0f, float(i % 5) / 4.0f, float(i % 3) / 2.0f, i % 2 ? 0.5f : 1.0f};
    const uint16_t j = uint16_t(i % 4);
    m.joints[i] = {j, uint16_t((j + 1) % 4), uint16_t((j + 2) % 4), uint16_t((j + 3) % 4)};
    m.weights[i] = i % 2 ? float4{0.5f, 0.25f, 0.125f, 0.125f} : float4{1, 0, 0, 0};
  }
  return m;
}

// ---- round trips ----------------------------------------------------------------------------------

struct NamedShape {
  const char* name;
  Mesh mesh;
};
std::vector<NamedShape> test_shapes() {
  return {{"torus", shapes::torus(1.0f, 0.25f, 24, 12)},
          {"cube", shapes::cube()},
          {"cylinder", shapes::cylinder(12)},
          {"icosphere", shapes::icosphere(2)}};
}

TEST(GltfRoundTrip, ShapesWithAllStreamsAreBitIdentical) {
  TempDir dir;
  for (const NamedShape& shape : test_shapes()) {
    for (const char* ext : {".glb", ".gltf"}) {
      SCOPED_TRACE(std::string(shape.name) + ext);
      const Mesh mesh = with_all_streams(shape.mesh);
      const auto first_path = dir / (std::string(shape.name) + "-1" + ext);
      write_mesh(mesh, first_path);
      const Scene first = read_scene(first_path);
      ASSERT_EQ(first.primitives.size(), 1u);
      EXPECT_EQ(mesh_difference(mesh, first.primitives[0].mesh), "");
      EXPECT_EQ(mesh_difference(mesh, read_mesh(first_path)), "");

      const auto second_path = dir / (std::string(shape.name) + "-2" + ext);
      write_scene(first, second_path);
      const Scene second = read_scene(second_path);
      ASSERT_EQ(second.primitives.size(), 1u);
      EXPECT_EQ(mesh_difference(first.primitives[0].mesh, second.primitives[0].mesh), "");
      EXPECT_EQ(mesh_difference(mesh, read_mesh(second_path)), "");
    }
  }
}

TEST(GltfRoundTrip, GltfWritesItsBinBesideItWithAnEscapedUri) {
  TempDir dir;
  write_mesh(shapes::cube(), dir / "my cube.gltf");
  const Written w = load_written(dir / "my cube.gltf");
  EXPECT_EQ(w.doc["buffers"][0]["uri"], "my%20cube.bin");
  EXPECT_TRUE(std::filesystem::exists(dir / "my cube.bin"));
  EXPECT_EQ(mesh_difference(shapes::cube(), read_mesh(dir / "my cube.gltf")), "");
}

TEST(GltfRoundTrip, LargeMeshUses32BitIndices) {
  TempDir dir;
  const Mesh grid = shapes::grid(300, 300);  // 90601 vertices
  ASSERT_GT(grid.vertex_count(), 65535u);
  write_mesh(grid, dir / "grid.glb");
  const Written w = load_written(dir / "grid.glb");
  EXPECT_EQ(w.doc["accessors"][w.doc["meshes"][0]["primitives"][0]["indices"].get<size_t>()]["componentType"], kUInt);
  EXPECT_EQ(mesh_difference(grid, read_mesh(dir / "grid.glb")), "");

  write_mesh(shapes::cube(), dir / "cube.glb");
  const Written small = load_written(dir / "cube.glb");
  EXPECT_EQ(small.doc["accessors"][small.doc["meshes"][0]["primitives"][0]["indices"].get<size_t>()]["componentType"],
            kUShort);
}

TEST(GltfRoundTrip, MultiMaterialMeshBecomesOnePrimitivePerMaterial) {
  TempDir dir;
  Mesh mesh = shapes::cube();  // 12 triangles, 4 vertices per face
  mesh.materials.assign(12, 0);
  for (size_t t = 4; t < 12; ++t) mesh.materials[t] = t < 8 ? 1 : 2;
  mesh.material_names = {"red", "green", "blue"};
  write_mesh(mesh, dir / "colored.glb");
  const Written w = load_written(dir / "colored.glb");
  ASSERT_EQ(w.doc["materials"].size(), 3u);
  EXPECT_EQ(w.doc["materials"][0]["name"], "red");
  EXPECT_EQ(w.doc["materials"][2]["name"], "blue");
  ASSERT_EQ(w.doc["meshes"].size(), 1u);
  ASSERT_EQ(w.doc["nodes"].size(), 1u);
  const Json& primitives = w.doc["meshes"][0]["primitives"];
  ASSERT_EQ(primitives.size(), 3u);
  for (int m = 0; m < 3; ++m) EXPECT_EQ(primitives[size_t(m)]["material"], m);

  const Mesh flat = read_mesh(dir / "colored.glb");
  // glTF material k is id k + 1; the cube's faces are in material order, so the mesh is unchanged.
  ASSERT_EQ(flat.material_names, (std::vector<std::string>{"", "red", "green", "blue"}));
  ASSERT_EQ(flat.materials.size(), 12u);
  for (size_t t = 0; t < 12; ++t) EXPECT_EQ(flat.materials[t], mesh.materials[t] + 1);
  Mesh expected = mesh;
  expected.materials = flat.materials;
  EXPECT_EQ(mesh_difference(expected, flat), "");
}

// ---- the hand-built scene -------------------------------------------------------------------------

struct SceneInput {
  HandBuilt file;
  std::vector<float> ibm;          // 2 matrices
  std::vector<float> times;        // animation input
  std::vector<float> rotations;    // animation output
  std::vector<float> quad, tri, skinned;  // positions
  std::vector<uint16_t> quad_indices;
};

// 2 meshes / 3 triangle primitives, a node hierarchy with TRS, a textured material with an embedded
// PNG, a skin with inverse bind matrices and a rotation animation.
SceneInput hand_built_scene() {
  SceneInput in;
  HandBuilt& f = in.file;
  in.quad = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  in.quad_indices = {0, 1, 2, 0, 2, 3};
  in.tri = {0, 0, 1, 1, 0, 1, 0, 1, 1};
  in.skinned = {0, 0, 0, 0, 1, 0, 0.5f, 2, 0};
  const std::vector<float> quad_uv = {0, 0, 1, 0, 1, 1, 0, 1};
  const std::vector<float> normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  const std::vector<uint8_t> joints = {0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0};
  const std::vector<float> weights = {1, 0, 0, 0, 0.5f, 0.5f, 0, 0, 1, 0, 0, 0};
  const std::vector<uint8_t> skinned_indices = {0, 2, 1};
  in.ibm = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1,  //
            1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -1, 0, 1};
  in.times = {0, 0.5f, 1};
  in.rotations = {0, 0, 0, 1, 0, 0, 0.6f, 0.8f, 0, 0, 1, 0};

  const int quad = f.positions(in.quad);
  const int quad_uvs = f.accessor(quad_uv, kFloat, "VEC2", 2, kArrayBuffer);
  const int quad_idx = f.accessor(in.quad_indices, kUShort, "SCALAR", 1, kElementArrayBuffer);
  const int tri = f.positions(in.tri);
  const int skinned = f.positions(in.skinned);
  const int normal = f.accessor(normals, kFloat, "VEC3", 3, kArrayBuffer);
  const int joint = f.accessor(joints, kUByte, "VEC4", 4, kArrayBuffer);
  const int weight = f.accessor(weights, kFloat, "VEC4", 4, kArrayBuffer);
  const int skinned_idx = f.accessor(skinned_indices, kUByte, "SCALAR", 1, kElementArrayBuffer);
  const int image_view = f.view(kPng.data(), kPng.size());
  const int ibm = f.accessor(in.ibm, kFloat, "MAT4", 16);
  const int input = f.accessor(in.times, kFloat, "SCALAR", 1, 0, {{"min", {0.0}}, {"max", {1.0}}});
  const int output = f.accessor(in.rotations, kFloat, "VEC4", 4);

  Json& d = f.doc;
  d["scene"] = 0;
  d["scenes"] = Json::array({{{"name", "main"}, {"nodes", {0}}}});
  d["nodes"] = Json::array({
      {{"name", "root"}, {"translation", {1.0, 2.0, 3.0}}, {"rotation", {0.0, 0.0, 0.6, 0.8}}, {"scale", {2.0, 2.0, 2.0}},
       {"children", {1, 2, 3}}, {"extras", {{"tag", "kept"}}}},
      {{"name", "static"}, {"mesh", 0}, {"translation", {0.0, 1.0, 0.0}}},
      {{"name", "skinned"}, {"mesh", 1}, {"skin", 0}},
      {{"name", "joint0"}, {"children", {4}}},
      {{"name", "joint1"}, {"translation", {0.0, 1.0, 0.0}}},
  });
  d["meshes"] = Json::array({
      {{"name", "two parts"},
       {"primitives",
        {{{"attributes", {{"POSITION", quad}, {"TEXCOORD_0", quad_uvs}}}, {"indices", quad_idx}, {"material", 0}},
         {{"attributes", {{"POSITION", tri}}}}}}},
      {{"name", "skinned"},
       {"primitives",
        {{{"attributes", {{"POSITION", skinned}, {"NORMAL", normal}, {"JOINTS_0", joint}, {"WEIGHTS_0", weight}}},
          {"indices", skinned_idx}}}}},
  });
  d["materials"] = Json::array({{{"name", "painted"},
                                 {"doubleSided", true},
                                 {"emissiveFactor", {1.0, 0.5, 0.0}},
                                 {"pbrMetallicRoughness",
                                  {{"baseColorFactor", {1.0, 0.5, 0.25, 1.0}},
                                   {"baseColorTexture", {{"index", 0}}},
                                   {"metallicFactor", 0.25},
                                   {"roughnessFactor", 0.75}}},
                                 {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 2.5}}}}},
                                 {"extras", {{"note", "keep me"}}}}});
  d["extensionsUsed"] = {"KHR_materials_emissive_strength"};
  d["textures"] = Json::array({{{"sampler", 0}, {"source", 0}}});
  d["samplers"] = Json::array({{{"magFilter", 9729}, {"minFilter", 9987}, {"wrapS", 33071}, {"wrapT", 10497}}});
  d["images"] = Json::array({{{"bufferView", image_view}, {"mimeType", "image/png"}, {"name", "checker"}}});
  d["skins"] = Json::array({{{"name", "rig"}, {"joints", {3, 4}}, {"skeleton", 3}, {"inverseBindMatrices", ibm}}});
  d["animations"] = Json::array({{{"name", "turn"},
                                  {"channels", {{{"sampler", 0}, {"target", {{"node", 3}, {"path", "rotation"}}}}}},
                                  {"samplers", {{{"input", input}, {"output", output}, {"interpolation", "LINEAR"}}}}}});
  return in;
}

std::vector<float> flat(const std::vector<float3>& v) {
  std::vector<float> out;
  for (const float3& p : v) out.insert(out.end(), {p.x, p.y, p.z});
  return out;
}

TEST(GltfHandBuilt, ReadFillsTheNeutralScene) {
  const SceneInput in = hand_built_scene();
  const std::vector<uint8_t> bytes = in.file.glb();
  const Scene scene = read_gltf(bytes, "hand.glb");
  ASSERT_EQ(scene.primitives.size(), 3u);
  EXPECT_EQ(scene.primitives[0].gltf_mesh, 0u);
  EXPECT_EQ(scene.primitives[1].gltf_primitive, 1u);
  EXPECT_EQ(scene.primitives[2].gltf_mesh, 1u);
  EXPECT_EQ(scene.primitives[0].material, 0);
  EXPECT_EQ(scene.primitives[1].material, -1);
  EXPECT_EQ(flat(scene.primitives[0].mesh.positions), in.quad);
  EXPECT_EQ(scene.primitives[0].mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
  EXPECT_EQ(scene.primitives[0].mesh.uvs[0].size(), 4u);
  EXPECT_EQ(flat(scene.primitives[1].mesh.positions), in.tri);
  EXPECT_EQ(scene.primitives[1].mesh.indices, (std::vector<uint32_t>{0, 1, 2}));  // non-indexed: 0..n-1
  const Mesh& skinned = scene.primitives[2].mesh;
  EXPECT_EQ(skinned.indices, (std::vector<uint32_t>{0, 2, 1}));
  ASSERT_EQ(skinned.joints.size(), 3u);
  EXPECT_EQ(skinned.joints[1], (ushort4{0, 1, 0, 0}));
  EXPECT_EQ(skinned.weights[1], (float4{0.5f, 0.5f, 0, 0}));
  EXPECT_EQ(skinned.normals[2], (float3{0, 0, 1}));

  ASSERT_EQ(scene.nodes.size(), 5u);
  EXPECT_EQ(scene.roots, (std::vector<int32_t>{0}));
  EXPECT_EQ(scene.nodes[0].name, "root");
  EXPECT_EQ(scene.nodes[0].children, (std::vector<int32_t>{1, 2, 3}));
  EXPECT_EQ(scene.nodes[0].translation, (float3{1, 2, 3}));
  EXPECT_EQ(scene.nodes[0].rotation, (float4{0, 0, 0.6f, 0.8f}));
  EXPECT_EQ(scene.nodes[0].scale, (float3{2, 2, 2}));
  EXPECT_EQ(scene.nodes[4].parent, 3);
  EXPECT_EQ(scene.nodes[2].skin, 0);
  EXPECT_EQ(scene.nodes[1].mesh, 0);

  ASSERT_EQ(scene.skins.size(), 1u);
  EXPECT_EQ(scene.skins[0].joints, (std::vector<int32_t>{3, 4}));
  EXPECT_EQ(scene.skins[0].skeleton, 3);
  ASSERT_EQ(scene.skins[0].inverse_bind_matrices.size(), 2u);
  for (size_t k = 0; k < 16; ++k) EXPECT_EQ(scene.skins[0].inverse_bind_matrices[1][k], in.ibm[16 + k]);

  ASSERT_EQ(scene.animations.size(), 1u);
  ASSERT_EQ(scene.animations[0].channels.size(), 1u);
  const AnimationChannel& ch = scene.animations[0].channels[0];
  EXPECT_EQ(scene.animations[0].name, "turn");
  EXPECT_EQ(ch.node, 3);
  EXPECT_EQ(ch.path, AnimationPath::rotation);
  EXPECT_EQ(ch.interpolation, Interpolation::linear);
  EXPECT_EQ(ch.components, 4u);
  EXPECT_EQ(ch.times, in.times);
  EXPECT_EQ(ch.values, in.rotations);

  EXPECT_EQ(scene.material_names, (std::vector<std::string>{"painted"}));
  EXPECT_EQ(scene.image_count, 1u);
  EXPECT_EQ(scene.texture_count, 1u);
  EXPECT_NE(scene.source, nullptr);
}

TEST(GltfHandBuilt, WriteKeepsEverythingLodkitDidNotChange) {
  const SceneInput in = hand_built_scene();
  const Json& original = in.file.doc;
  TempDir dir;
  test::write_bytes(dir / "hand.glb", in.file.glb());
  const Scene scene = read_scene(dir / "hand.glb");
  for (const char* ext : {".glb", ".gltf"}) {
    SCOPED_TRACE(ext);
    const auto out = dir / (std::string("out") + ext);
    write_scene(scene, out);
    const Written w = load_written(out);
    const Json& d = w.doc;

    // Image bytes identical, still in a bufferView.
    ASSERT_EQ(d["images"].size(), 1u);
    EXPECT_EQ(d["images"][0]["mimeType"], "image/png");
    EXPECT_EQ(d["images"][0]["name"], "checker");
    EXPECT_EQ(view_bytes(w, d["images"][0]["bufferView"]), kPng);
    // Skin and animation data identical to the values put in.
    EXPECT_EQ(accessor_floats(w, d["skins"][0]["inverseBindMatrices"]), in.ibm);
    EXPECT_EQ(d["skins"][0]["joints"], original["skins"][0]["joints"]);
    EXPECT_EQ(d["skins"][0]["skeleton"], 3);
    const Json& sampler = d["animations"][0]["samplers"][0];
    EXPECT_EQ(accessor_floats(w, sampler["input"]), in.times);
    EXPECT_EQ(accessor_floats(w, sampler["output"]), in.rotations);
    EXPECT_FALSE(sampler.contains("interpolation"));  // (LINEAR, the default, is left out)
    EXPECT_EQ(d["animations"][0]["channels"], original["animations"][0]["channels"]);
    // Node transforms, hierarchy, names, extras; materials, textures, samplers, scenes.
    EXPECT_EQ(d["nodes"], original["nodes"]);
    EXPECT_EQ(d["materials"], original["materials"]);
    EXPECT_EQ(d["textures"], original["textures"]);
    EXPECT_EQ(d["samplers"], original["samplers"]);
    EXPECT_EQ(d["scenes"], original["scenes"]);
    EXPECT_EQ(d["scene"], 0);
    EXPECT_EQ(d["extensionsUsed"], original["extensionsUsed"]);
    // Geometry regenerated: triangle lists, float streams, POSITION bounds, targets, 4-byte alignment.
    for (const Json& mesh : d["meshes"])
      for (const Json& prim : mesh["primitives"]) {
        EXPECT_EQ(prim["mode"], 4);
        const Json& pos = d["accessors"][prim["attributes"]["POSITION"].get<size_t>()];
        EXPECT_TRUE(pos.contains("min") && pos.contains("max"));
        EXPECT_EQ(d["bufferViews"][pos["bufferView"].get<size_t>()]["target"], kArrayBuffer);
        EXPECT_EQ(d["bufferViews"][d["accessors"][prim["indices"].get<size_t>()]["bufferView"].get<size_t>()]["target"],
                  kElementArrayBuffer);
      }
    for (const Json& view : d["bufferViews"]) EXPECT_EQ(view.value("byteOffset", 0) % 4, 0);
    // Nothing unreferenced survives: 3 primitives x (POSITION + indices) + uv + 3 skinned streams + ibm + 2 animation.
    EXPECT_EQ(d["accessors"].size(), 6u + 1 + 3 + 1 + 2);

    // Reading the output again gives the same scene.
    const Scene again = read_scene(out);
    ASSERT_EQ(again.primitives.size(), scene.primitives.size());
    for (size_t i = 0; i < scene.primitives.size(); ++i) {
      EXPECT_EQ(mesh_difference(scene.primitives[i].mesh, again.primitives[i].mesh), "");
      EXPECT_EQ(again.primitives[i].material, scene.primitives[i].material);
    }
    EXPECT_EQ(again.skins[0].inverse_bind_matrices, scene.skins[0].inverse_bind_matrices);
    EXPECT_EQ(again.animations[0].channels[0].values, in.rotations);
  }
}

TEST(GltfHandBuilt, ChangedGeometryIsWrittenAndUnreferencedDataDropped) {
  const SceneInput in = hand_built_scene();
  Scene scene = read_gltf(in.file.glb(), "hand.glb");
  // Drop the quad's second triangle and its unused vertex; give the lone triangle a material.
  Mesh& quad = scene.primitives[0].mesh;
  quad.indices.resize(3);
  quad.positions.resize(3);
  quad.uvs[0].resize(3);
  scene.primitives[1].material = 0;
  TempDir dir;
  write_scene(scene, dir / "edited.glb");
  const Scene again = read_scene(dir / "edited.glb");
  ASSERT_EQ(again.primitives.size(), 3u);
  EXPECT_EQ(mesh_difference(again.primitives[0].mesh, quad), "");
  EXPECT_EQ(again.primitives[1].material, 0);
  const Written w = load_written(dir / "edited.glb");
  EXPECT_EQ(w.doc["accessors"][w.doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<size_t>()]["max"],
            Json::array({1.0, 1.0, 0.0}));
  EXPECT_EQ(view_bytes(w, w.doc["images"][0]["bufferView"]), kPng);
}

// ---- attribute decoding ---------------------------------------------------------------------------

TEST(GltfRead, NormalizedIntegerAttributesAndVec3Colors) {
  HandBuilt f;
  const int pos = f.positions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  const int uv = f.accessor(std::vector<uint16_t>{0, 65535, 32768, 0, 65535, 65535}, kUShort, "VEC2", 2, kArrayBuffer,
                            {{"normalized", true}});
  const int color = f.accessor(std::vector<uint8_t>{255, 0, 51, 0, 255, 0, 0, 0, 0}, kUByte, "VEC3", 3,
                               kArrayBuffer, {{"normalized", true}});
  const int joints = f.accessor(std::vector<uint16_t>{300, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}, kUShort, "VEC4", 4,
                                kArrayBuffer);
  const int weights = f.accessor(std::vector<uint8_t>{255, 0, 0, 0, 128, 127, 0, 0, 0, 0, 0, 255}, kUByte, "VEC4", 4,
                                 kArrayBuffer, {{"normalized", true}});
  f.doc["meshes"] = Json::array({{{"primitives",
                                   {{{"attributes",
                                      {{"POSITION", pos},
                                       {"TEXCOORD_0", uv},
                                       {"COLOR_0", color},
                                       {"JOINTS_0", joints},
                                       {"WEIGHTS_0", weights}}}}}}}});
  // VEC3 u8 colors occupy 3 bytes each; the bufferView is tightly packed, which is allowed for colors.
  const Scene scene = read_gltf(span_of(f.gltf()), "normalized.gltf");
  const Mesh& m = scene.primitives[0].mesh;
  EXPECT_EQ(m.uvs[0][0], (float2{0.0f, 1.0f}));
  EXPECT_EQ(m.uvs[0][1], (float2{32768.0f / 65535.0f, 0.0f}));
  EXPECT_EQ(m.colors[0], (float4{1.0f, 0.0f, 51.0f / 255.0f, 1.0f}));  // alpha 1 for VEC3 colors
  EXPECT_EQ(m.colors[2], (float4{0.0f, 0.0f, 0.0f, 1.0f}));
  EXPECT_EQ(m.joints[0], (ushort4{300, 1, 2, 3}));
  EXPECT_EQ(m.weights[1], (float4{128.0f / 255.0f, 127.0f / 255.0f, 0, 0}));
  EXPECT_EQ(m.weights[2], (float4{0, 0, 0, 1.0f}));
}

// glTF asks unit normals and tangents (w = +-1), but files break it; Mesh::normals and tangents are
// unit all the same (make_unit_directions), so what lodkit writes validates. Vertex 0 is right and
// keeps its bits; 1 is scaled; 2 is zero and takes the triangle's normal, +z, and a tangent
// perpendicular to it; the tangents' w become their signs.
TEST(GltfRead, NormalsAndTangentsReadAtUnitLength) {
  HandBuilt f;
  const int pos = f.positions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  const int normal = f.accessor(std::vector<float>{0.6f, 0, 0.8f, 0, 3, 4, 0, 0, 0}, kFloat, "VEC3", 3, kArrayBuffer);
  const int tangent = f.accessor(std::vector<float>{1, 0, 0, -1, 0, 0, 2, 0.5f, 0, 0, 0, -3}, kFloat, "VEC4", 4, kArrayBuffer);
  f.doc["meshes"] = Json::array({{{"primitives", {{{"attributes", {{"POSITION", pos}, {"NORMAL", normal}, {"TANGENT", tangent}}}}}}}});
  const Scene scene = read_gltf(span_of(f.gltf()), "directions.gltf");
  const Mesh& m = scene.primitives[0].mesh;
  EXPECT_EQ(m.normals, (std::vector<float3>{{0.6f, 0, 0.8f}, {0, 0.6f, 0.8f}, {0, 0, 1}}));
  ASSERT_EQ(m.tangents.size(), 3u);
  EXPECT_EQ(m.tangents[0], (float4{1, 0, 0, -1}));
  EXPECT_EQ(m.tangents[1], (float4{0, 0, 1, 1}));
  const float4 t = m.tangents[2];
  EXPECT_NEAR(t.x * t.x + t.y * t.y + t.z * t.z, 1.0, 1e-6);
  EXPECT_EQ(t.z, 0.0f);  // (perpendicular to +z)
  EXPECT_EQ(t.w, -1.0f);
  TempDir dir;
  write_scene(scene, dir / "d.glb");
  test::expect_valid_gltf({dir / "d.glb"});
}

TEST(GltfRead, InterleavedStreamsWithByteStride) {
  HandBuilt f;
  // position xyz + normal xyz per vertex, 24-byte stride, one bufferView for both accessors.
  const std::vector<float> interleaved = {0, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 1};
  const int view = f.view(interleaved.data(), interleaved.size() * 4, kArrayBuffer, 24);
  f.doc["accessors"] = Json::array({{{"bufferView", view}, {"componentType", kFloat}, {"count", 3}, {"type", "VEC3"},
                                     {"min", {0, 0, 0}}, {"max", {1, 1, 0}}},
                                    {{"bufferView", view}, {"byteOffset", 12}, {"componentType", kFloat}, {"count", 3},
                                     {"type", "VEC3"}}});
  f.doc["meshes"] = Json::array({{{"primitives", {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}}}}}}}});
  const Mesh m = read_gltf(f.glb(), "interleaved.glb").primitives[0].mesh;
  EXPECT_EQ(flat(m.positions), (std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0}));
  EXPECT_EQ(flat(m.normals), (std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1}));
}

void expect_bad_input(std::span<const uint8_t> bytes, const std::string& name, const std::string& needle);

// One triangle drawn twice by EXT_mesh_gpu_instancing (under a node translated by (0, 0, 5)):
// instance 0 in place, instance 1 scaled by 2, turned 90 degrees about +z, moved by (10, 0, 0).
HandBuilt instanced_triangle() {
  HandBuilt f;
  const int pos = f.positions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  const int idx = f.accessor(std::vector<uint16_t>{0, 1, 2}, kUShort, "SCALAR", 1, kElementArrayBuffer);
  const float h = std::sqrt(0.5f);
  const int t = f.accessor(std::vector<float>{0, 0, 0, 10, 0, 0}, kFloat, "VEC3", 3);
  const int r = f.accessor(std::vector<float>{0, 0, 0, 1, 0, 0, h, h}, kFloat, "VEC4", 4);
  const int s = f.accessor(std::vector<float>{1, 1, 1, 2, 2, 2}, kFloat, "VEC3", 3);
  f.doc["meshes"] = Json::array({{{"primitives", {{{"attributes", {{"POSITION", pos}}}, {"indices", idx}}}}}});
  f.doc["nodes"] = Json::array({{{"mesh", 0},
                                 {"translation", {0, 0, 5}},
                                 {"extensions", {{"EXT_mesh_gpu_instancing",
                                                  {{"attributes", {{"TRANSLATION", t}, {"ROTATION", r}, {"SCALE", s}}}}}}}}});
  f.doc["scenes"] = Json::array({{{"nodes", {0}}}});
  f.doc["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
  return f;
}

TEST(GltfInstancing, EveryInstanceIsReadPlacedAndKept) {
  TempDir dir;
  test::write_bytes(dir / "in.glb", instanced_triangle().glb());
  test::expect_valid_gltf({dir / "in.glb"});
  Scene scene = read_scene(dir / "in.glb");
  ASSERT_EQ(scene.nodes.size(), 1u);
  ASSERT_EQ(scene.nodes[0].gpu_instances.size(), 2u);
  EXPECT_EQ(scene.nodes[0].gpu_instances[1].translation.x, 10.0f);
  EXPECT_EQ(scene.nodes[0].gpu_instances[1].scale.y, 2.0f);

  // Instance 1 maps (x, y, z) to (10 - 2y, 2x, 2z), then the node adds 5 to z.
  const Mesh flat = flatten(scene);
  ASSERT_EQ(flat.triangle_count(), 2u);
  const std::vector<float3> expected = {{0, 0, 5}, {1, 0, 5}, {0, 1, 5}, {10, 0, 5}, {10, 2, 5}, {8, 0, 5}};
  ASSERT_EQ(flat.positions.size(), expected.size());
  for (size_t v = 0; v < expected.size(); ++v) {
    EXPECT_NEAR(flat.positions[v].x, expected[v].x, 1e-5f) << v;
    EXPECT_NEAR(flat.positions[v].y, expected[v].y, 1e-5f) << v;
    EXPECT_NEAR(flat.positions[v].z, expected[v].z, 1e-5f) << v;
  }

  // Written with new geometry, the instances stay: the node's accessors are kept and renumbered.
  scene.primitives[0].mesh.positions[2] = {0, 2, 0};
  write_scene(scene, dir / "out.glb");
  test::expect_valid_gltf({dir / "out.glb"});
  const Scene back = read_scene(dir / "out.glb");
  ASSERT_EQ(back.nodes[0].gpu_instances.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const Node::GpuInstance &a = scene.nodes[0].gpu_instances[i], &b = back.nodes[0].gpu_instances[i];
    EXPECT_EQ(std::tie(a.translation.x, a.translation.y, a.translation.z), std::tie(b.translation.x, b.translation.y, b.translation.z));
    EXPECT_EQ(std::tie(a.rotation.x, a.rotation.y, a.rotation.z, a.rotation.w), std::tie(b.rotation.x, b.rotation.y, b.rotation.z, b.rotation.w));
    EXPECT_EQ(std::tie(a.scale.x, a.scale.y, a.scale.z), std::tie(b.scale.x, b.scale.y, b.scale.z));
  }
  EXPECT_EQ(back.primitives[0].mesh.positions[2].y, 2.0f);
}

// KHR_node_visibility: a triangle drawn by a root and by its child (moved up by 2). Hidden, the
// child leaves the root's triangle to flatten(); the root hidden takes both. The extension
// survives a write, and is no longer declared once no node has it; a `visible` that is not a
// boolean is refused, naming the node.
TEST(GltfRead, NodeVisibilityHidesTheNodeAndWhatIsBelowIt) {
  TempDir dir;
  const auto file = [](const Json& root_visibility, const Json& child_visibility) {
    HandBuilt f;
    const int pos = f.positions({0, 0, 0, 1, 0, 0, 0, 1, 0});
    f.doc["meshes"] = Json::array({{{"primitives", {{{"attributes", {{"POSITION", pos}}}}}}}});
    f.doc["nodes"] = Json::array({{{"mesh", 0}, {"children", {1}}}, {{"mesh", 0}, {"translation", {0, 0, 2}}}});
    for (const auto& [n, visible] : {std::pair{0, root_visibility}, std::pair{1, child_visibility}})
      if (!visible.is_null()) f.doc["nodes"][n]["extensions"] = {{"KHR_node_visibility", {{"visible", visible}}}};
    f.doc["scenes"] = Json::array({{{"nodes", {0}}}});
    f.doc["extensionsUsed"] = {"KHR_node_visibility"};
    return f.glb();
  };
  const auto triangles = [&](const Json& root, const Json& child) {
    test::write_bytes(dir / "in.glb", file(root, child));
    return flatten(read_scene(dir / "in.glb")).triangle_count();
  };
  EXPECT_EQ(triangles(nullptr, nullptr), 2u);
  EXPECT_EQ(triangles(true, true), 2u);
  EXPECT_EQ(triangles(true, false), 1u);
  EXPECT_EQ(triangles(false, true), 0u);  // (a shown child of a hidden node stays hidden)
  test::write_bytes(dir / "in.glb", file(true, false));
  test::expect_valid_gltf({dir / "in.glb"});
  const Scene scene = read_scene(dir / "in.glb");
  EXPECT_TRUE(scene.nodes[0].has_visibility && scene.nodes[0].visible);
  EXPECT_TRUE(scene.nodes[1].has_visibility && !scene.nodes[1].visible);
  EXPECT_EQ(flatten(scene).positions[2].z, 0.0f);  // the root's
  write_scene(scene, dir / "out.glb");
  EXPECT_EQ(test::glb_json(dir / "out.glb")["nodes"][1]["extensions"], test::glb_json(dir / "in.glb")["nodes"][1]["extensions"]);
  expect_bad_input(file(nullptr, "no"), "visible.glb", "nodes[1].extensions.KHR_node_visibility.visible must be true or false");
  // The only node with the extension erased (lod::erase_nodes): the document no longer declares it.
  test::write_bytes(dir / "in.glb", file(nullptr, false));
  Scene lone = read_scene(dir / "in.glb");
  ASSERT_EQ(erase_nodes(lone, {false, true}), (std::vector<int32_t>{0, -1}));
  write_scene(lone, dir / "erased.glb");
  test::expect_valid_gltf({dir / "erased.glb"});
  EXPECT_EQ(test::glb_json(dir / "erased.glb").value("extensionsUsed", Json::array()), Json::array());
  write_scene(read_scene(dir / "in.glb"), dir / "kept.glb");
  EXPECT_EQ(test::glb_json(dir / "kept.glb")["extensionsUsed"], Json::array({"KHR_node_visibility"}));
}

// Visibility set in code is written: a hidden node of a Scene built without a source, a source node
// hidden or shown again, and a hidden node added to a source all read back as set, and the
// extension is declared where it is used.
TEST(GltfWrite, NodeVisibilitySetInCodeIsWritten) {
  TempDir dir;
  Scene built;
  Primitive prim;
  prim.mesh = shapes::icosphere(1);
  built.primitives.push_back(std::move(prim));
  built.nodes.resize(2);
  built.nodes[0].mesh = 0, built.nodes[0].children = {1};
  built.nodes[1].mesh = 0, built.nodes[1].parent = 0, built.nodes[1].visible = false;
  built.roots = {0};
  write_scene(built, dir / "built.glb");
  test::expect_valid_gltf({dir / "built.glb"});
  Json doc = test::glb_json(dir / "built.glb");
  EXPECT_FALSE(doc["nodes"][0].contains("extensions"));
  EXPECT_EQ(doc["nodes"][1]["extensions"]["KHR_node_visibility"]["visible"], false);
  EXPECT_EQ(doc["extensionsUsed"], Json::array({"KHR_node_visibility"}));
  Scene scene = read_scene(dir / "built.glb");
  EXPECT_TRUE(scene.nodes[0].visible);
  EXPECT_FALSE(scene.nodes[1].visible);
  EXPECT_EQ(flatten(scene).triangle_count(), built.primitives[0].mesh.triangle_count());

  // From that source: node 1 shown again, node 0 hidden, a new hidden node under node 0.
  scene.nodes[1].visible = true;
  scene.nodes[0].visible = false;
  Node added;
  added.mesh = 0, added.parent = 0, added.visible = false;
  scene.nodes.push_back(added);
  write_scene(scene, dir / "source.glb");
  test::expect_valid_gltf({dir / "source.glb"});
  doc = test::glb_json(dir / "source.glb");
  EXPECT_EQ(doc["extensionsUsed"], Json::array({"KHR_node_visibility"}));
  const Scene back = read_scene(dir / "source.glb");
  ASSERT_EQ(back.nodes.size(), 3u);
  EXPECT_FALSE(back.nodes[0].visible);
  EXPECT_TRUE(back.nodes[1].visible && back.nodes[1].has_visibility);
  EXPECT_FALSE(back.nodes[2].visible);
  EXPECT_EQ(back.nodes[2].parent, 0);
  EXPECT_EQ(flatten(back).triangle_count(), 0u);
}

// Quantized (-q), the instanced mesh goes on the grid and each instance takes the grid in its own
// transform (T + R (S o), S s): every instance lands within the step (times its scale, 2) of the
// float file's, the node keeps its transform, and the old instance accessors are gone.
TEST(GltfInstancing, QuantizedInstancesTakeTheGrid) {
  TempDir dir;
  test::write_bytes(dir / "in.glb", instanced_triangle().glb());
  Scene scene = read_scene(dir / "in.glb");
  for (float3& p : scene.primitives[0].mesh.positions) p = {p.x + 3, p.y + 4, p.z + 1};  // the grid's offset: (3, 4, 1)
  write_scene(scene, dir / "q.glb", {.quantize = true});
  test::expect_valid_gltf({dir / "q.glb"});
  const Json doc = test::glb_json(dir / "q.glb");
  const Json& position = doc["accessors"][doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<size_t>()];
  EXPECT_EQ(position["componentType"], 5123);
  EXPECT_EQ(doc["nodes"][0]["translation"], Json::array({0.0, 0.0, 5.0}));
  EXPECT_FALSE(doc["nodes"][0].contains("scale"));
  EXPECT_EQ(doc["accessors"].size(), 5u);  // positions, indices, and the instances' T, R, S
  const Mesh a = flatten(scene), b = flatten(read_scene(dir / "q.glb"));
  ASSERT_EQ(a.vertex_count(), b.vertex_count());
  const double step = 1.0 / 16383;
  for (size_t v = 0; v < a.vertex_count(); ++v) {
    const double d = std::hypot(double(a.positions[v].x) - b.positions[v].x, double(a.positions[v].y) - b.positions[v].y,
                                double(a.positions[v].z) - b.positions[v].z);
    EXPECT_LE(d, 2 * step * std::sqrt(3.0) / 2 + 1e-5) << v;
  }
}

// An instance so large that taking the grid would push its translation past the float range
// (fuzzing found one that read back as infinite): its mesh keeps float positions instead.
TEST(GltfInstancing, InstancesBeyondTheFloatRangeKeepFloatPositions) {
  TempDir dir;
  test::write_bytes(dir / "in.glb", instanced_triangle().glb());
  Scene scene = read_scene(dir / "in.glb");
  for (float3& p : scene.primitives[0].mesh.positions) p = {p.x + 3, p.y + 4, p.z + 1};
  write_scene(scene, dir / "moved.glb");
  test::Glb glb = test::read_glb(dir / "moved.glb");
  const size_t scale = glb.doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["SCALE"];
  const Json& accessor = glb.doc["accessors"][scale];
  const size_t at = glb.doc["bufferViews"][accessor["bufferView"].get<size_t>()].value("byteOffset", size_t(0)) +
                    accessor.value("byteOffset", size_t(0));
  const float huge[3] = {1e37f, 1e37f, 1e37f};
  std::memcpy(glb.bin.data() + at + 12, huge, sizeof huge);  // instance 1's scale
  test::write_bytes(dir / "huge.glb", test::glb_bytes(glb));
  const Scene big = read_scene(dir / "huge.glb");
  ASSERT_EQ(big.nodes[0].gpu_instances[1].scale.x, 1e37f);
  write_scene(big, dir / "q.glb", {.quantize = true});
  const Json doc = test::glb_json(dir / "q.glb");
  EXPECT_EQ(doc["accessors"][doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<size_t>()]["componentType"], 5126);
  const Mesh a = flatten(big), b = flatten(read_scene(dir / "q.glb"));
  EXPECT_TRUE(a.positions == b.positions);
}

TEST(GltfInstancing, InfoCountsTheInstances) {
  TempDir dir;
  test::write_bytes(dir / "in.glb", instanced_triangle().glb());
  const test::RunResult r = test::run_cli({"info", "--json", (dir / "in.glb").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Json report = Json::parse(r.out);
  EXPECT_EQ(report["gltf"]["gpu_instances"], 2) << r.out;
  EXPECT_EQ(report["gltf"]["instanced_nodes"], 1);
  EXPECT_EQ(report["gltf"]["extensions_used"], Json::array({"EXT_mesh_gpu_instancing"}));
  EXPECT_EQ(report["stats"]["triangles"], 2);  // both instances, flattened
  EXPECT_NE(test::run_cli({"info", (dir / "in.glb").string()}).out.find("2 on 1 node\n"), std::string::npos);
}

// lodkit lod gives an instanced mesh a chain in its own space: each level's node draws both
// instances (its own EXT_mesh_gpu_instancing accessors), the first under the old node, which keeps
// its transform and loses its mesh. Level 0 draws the input, in place.
TEST(GltfInstancing, LodChainKeepsTheInstances) {
  TempDir dir;
  test::write_bytes(dir / "in.glb", instanced_triangle().glb());
  const test::RunResult r = test::run_cli({"lod", (dir / "in.glb").string(), "-o", (dir / "chain.glb").string(), "--levels", "1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  test::expect_valid_gltf({dir / "chain.glb"});
  const Json doc = test::glb_json(dir / "chain.glb");
  ASSERT_EQ(doc["nodes"].size(), 2u);
  EXPECT_FALSE(doc["nodes"][0].contains("mesh"));
  EXPECT_FALSE(doc["nodes"][0].contains("extensions")) << doc["nodes"][0].dump();
  EXPECT_EQ(doc["nodes"][0]["translation"], Json::array({0, 0, 5}));
  EXPECT_EQ(doc["nodes"][0]["children"], Json::array({1}));
  EXPECT_TRUE(doc["nodes"][1]["extensions"].contains("EXT_mesh_gpu_instancing"));
  const Scene chain = read_scene(dir / "chain.glb");
  ASSERT_EQ(chain.nodes[1].gpu_instances.size(), 2u);
  const Mesh before = flatten(read_scene(dir / "in.glb")), after = flatten(chain);
  ASSERT_EQ(after.triangle_count(), 2u);
  std::vector<std::array<float, 3>> a, b;
  for (const float3& p : before.positions) a.push_back({p.x, p.y, p.z});
  for (const float3& p : after.positions) b.push_back({p.x, p.y, p.z});
  std::sort(a.begin(), a.end()), std::sort(b.begin(), b.end());
  ASSERT_EQ(a.size(), b.size());
  for (size_t v = 0; v < a.size(); ++v)
    for (size_t c = 0; c < 3; ++c) EXPECT_NEAR(a[v][c], b[v][c], 1e-5) << v;
}

TEST(GltfInstancing, MalformedInstancingIsRefused) {
  HandBuilt f = instanced_triangle();
  f.doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["SCALE"] =
      f.accessor(std::vector<float>{1, 1, 1}, kFloat, "VEC3", 3);
  expect_bad_input(f.glb(), "count.glb", "has 1 elements, the other attributes 2");

  f = instanced_triangle();
  f.doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["TRANSLATION"] = 99;
  expect_bad_input(f.glb(), "index.glb", "TRANSLATION is not an index of accessors");

  // Custom attributes are kept, so they must name accessors too (fuzzing found the writer
  // following one out of range).
  f = instanced_triangle();
  f.doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["_ID"] = 99;
  expect_bad_input(f.glb(), "custom.glb", "_ID is not an index of accessors");

  // tinygltf would wrap 2^32 + 1 to accessor 1.
  f = instanced_triangle();
  f.doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["TRANSLATION"] = (uint64_t(1) << 32) + 1;
  expect_bad_input(f.glb(), "wrap.glb", "TRANSLATION is 4294967297, not an integer in 0..2147483647");

  f = instanced_triangle();
  f.doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["ROTATION"] =
      f.accessor(std::vector<float>{0, 0, 0, 1, 0, 0, 0}, kFloat, "VEC3", 3);
  expect_bad_input(f.glb(), "type.glb", "ROTATION is VEC3, expected VEC4");

  f = instanced_triangle();
  f.doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["TRANSLATION"] =
      f.accessor(std::vector<float>{0, 0, 0, std::numeric_limits<float>::infinity(), 0, 0}, kFloat, "VEC3", 3);
  expect_bad_input(f.glb(), "inf.glb", "TRANSLATION of instance 1 is not finite");

  f = instanced_triangle();
  f.doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"] = Json::object();
  expect_bad_input(f.glb(), "empty.glb", "EXT_mesh_gpu_instancing");
}

TEST(GltfRead, SparseAccessorsAreApplied) {
  HandBuilt f;
  const int base = f.positions({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0});
  f.make_sparse(base, {1, 3}, {5, 6, 7, 8, 9, 10});
  f.doc["accessors"][size_t(base)]["max"] = {8, 9, 10};
  // A sparse accessor without a bufferView: zeros, with one element replaced.
  const std::vector<uint16_t> one = {2};
  const std::vector<float> uv_value = {0.5f, 0.25f};
  const int one_view = f.view(one.data(), 2);
  const int uv_view = f.view(uv_value.data(), 8);
  f.doc["accessors"].push_back({{"componentType", kFloat}, {"count", 4}, {"type", "VEC2"},
                                {"sparse",
                                 {{"count", 1},
                                  {"indices", {{"bufferView", one_view}, {"componentType", kUShort}}},
                                  {"values", {{"bufferView", uv_view}}}}}});
  const size_t uvs = f.doc["accessors"].size() - 1;
  f.doc["meshes"] = Json::array({{{"primitives", {{{"attributes", {{"POSITION", base}, {"TEXCOORD_0", uvs}}}, {"mode", 5}}}}}});
  const Scene scene = read_gltf(f.glb(), "sparse.glb");
  const Mesh& m = scene.primitives[0].mesh;
  EXPECT_EQ(flat(m.positions), (std::vector<float>{0, 0, 0, 5, 6, 7, 0, 1, 0, 8, 9, 10}));
  EXPECT_EQ(m.uvs[0], (std::vector<float2>{{0, 0}, {0, 0}, {0.5f, 0.25f}, {0, 0}}));
  // Mode 5 (strip of 4 vertices): triangles (0 1 2) and (1 3 2), both counter-clockwise.
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 1, 3, 2}));
  // Writing makes the streams dense; reading back gives the same values.
  TempDir dir;
  write_scene(scene, dir / "dense.glb");
  EXPECT_EQ(mesh_difference(read_scene(dir / "dense.glb").primitives[0].mesh, m), "");
}

TEST(GltfRead, FansAndNonIndexedStripsBecomeTriangleLists) {
  HandBuilt f;
  const int fan = f.positions({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, -1, 0, 0});
  f.doc["meshes"] = Json::array({{{"primitives", {{{"attributes", {{"POSITION", fan}}}, {"mode", 6}}}}}});
  const Scene fan_scene = read_gltf(f.glb(), "fan.glb");
  const Mesh& m = fan_scene.primitives[0].mesh;
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{1, 2, 0, 2, 3, 0, 3, 4, 0}));
  // Written with Draco, the source's fan is a triangle list (a Draco primitive with mode 6 would not
  // read: found by fuzz_gltf).
  TempDir dir;
  WriteOptions o;
  o.draco = true;
  write_scene(fan_scene, dir / "fan-draco.glb", o);
  const Json doc = test::glb_json(dir / "fan-draco.glb");
  const Json& prim = doc["meshes"][0]["primitives"][0];
  EXPECT_TRUE(prim["extensions"].contains("KHR_draco_mesh_compression"));
  EXPECT_EQ(prim.value("mode", 4), 4);
  EXPECT_EQ(read_scene(dir / "fan-draco.glb").primitives[0].mesh.triangle_count(), 3u);
}

TEST(GltfWrite, PointsAndLinesAreKeptUnchanged) {
  HandBuilt f;
  const int tri = f.positions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  const std::vector<float> line_points = {0, 0, 5, 1, 1, 5};
  const int line = f.positions(line_points);
  f.doc["meshes"] = Json::array(
      {{{"primitives", {{{"attributes", {{"POSITION", line}}}, {"mode", 1}}, {{"attributes", {{"POSITION", tri}}}}}}}});
  f.doc["nodes"] = Json::array({{{"mesh", 0}}});
  const Scene scene = read_gltf(f.glb(), "lines.glb");
  ASSERT_EQ(scene.primitives.size(), 1u);  // only the triangles
  EXPECT_EQ(scene.primitives[0].gltf_primitive, 1u);
  TempDir dir;
  write_scene(scene, dir / "lines-out.glb");
  const Written w = load_written(dir / "lines-out.glb");
  const Json& prims = w.doc["meshes"][0]["primitives"];
  ASSERT_EQ(prims.size(), 2u);
  EXPECT_EQ(prims[0]["mode"], 1);
  EXPECT_EQ(accessor_floats(w, prims[0]["attributes"]["POSITION"]), line_points);
}

TEST(GltfWrite, MorphTargetsKeptWhileTheVertexCountIsUnchanged) {
  HandBuilt f;
  const int pos = f.positions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  const std::vector<float> offsets = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  const int target = f.positions(offsets);
  f.doc["meshes"] = Json::array(
      {{{"primitives", {{{"attributes", {{"POSITION", pos}}}, {"targets", {{{"POSITION", target}}}}}}}, {"weights", {0.5}}}});
  f.doc["nodes"] = Json::array({{{"mesh", 0}, {"weights", {0.25}}}});
  Scene scene = read_gltf(f.glb(), "morph.glb");
  TempDir dir;
  write_scene(scene, dir / "same.glb");
  {
    const Written w = load_written(dir / "same.glb");
    const Json& prim = w.doc["meshes"][0]["primitives"][0];
    ASSERT_EQ(prim["targets"].size(), 1u);
    EXPECT_EQ(accessor_floats(w, prim["targets"][0]["POSITION"]), offsets);
    EXPECT_EQ(w.doc["meshes"][0]["weights"], Json::array({0.5}));
  }
  // One more vertex: the targets no longer match and are dropped, with the weights that drive them.
  Mesh& m = scene.primitives[0].mesh;
  m.positions.push_back({1, 1, 0});
  m.indices.insert(m.indices.end(), {1, 3, 2});
  write_scene(scene, dir / "grown.glb");
  const Written w = load_written(dir / "grown.glb");
  EXPECT_FALSE(w.doc["meshes"][0]["primitives"][0].contains("targets"));
  EXPECT_FALSE(w.doc["meshes"][0].contains("weights"));
  EXPECT_FALSE(w.doc["nodes"][0].contains("weights"));
  EXPECT_EQ(w.doc["accessors"].size(), 2u);  // POSITION + indices
}

// Primitive::targets are written with the streams the mesh has (a NORMAL or TANGENT displacement of
// a mesh without normals or tangents would be invalid) and read back by source_morph_targets.
TEST(GltfWrite, TargetsMoveOnlyStreamsTheMeshHas) {
  TempDir dir;
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.tangents = {{1, 0, 0, 1}, {1, 0, 0, 1}, {1, 0, 0, 1}};
  m.indices = {0, 1, 2};
  Scene scene = scene_from_mesh(m);
  MorphTarget t;
  t.positions = {{0, 0, 1}, {0, 0, 2}, {0, 0, 3}};
  t.normals = {{1, 0, 0}, {1, 0, 0}, {1, 0, 0}};    // the mesh has no normals: not written
  t.tangents = {{0, 1, 0}, {0, 2, 0}, {0, 3, 0}};  // it has tangents: written
  scene.primitives[0].targets.push_back(t);
  write_scene(scene, dir / "t.glb");
  const Written w = load_written(dir / "t.glb");
  const Json& target = w.doc["meshes"][0]["primitives"][0]["targets"][0];
  EXPECT_TRUE(target.contains("POSITION"));
  EXPECT_FALSE(target.contains("NORMAL"));
  ASSERT_TRUE(target.contains("TANGENT"));
  EXPECT_EQ(accessor_floats(w, target["TANGENT"]), (std::vector<float>{0, 1, 0, 0, 2, 0, 0, 3, 0}));
  const std::vector<MorphTarget> read = source_morph_targets(read_scene(dir / "t.glb"), 0);
  ASSERT_EQ(read.size(), 1u);
  EXPECT_EQ(read[0].positions, t.positions);
  EXPECT_TRUE(read[0].normals.empty());
  EXPECT_EQ(read[0].tangents, t.tangents);
}

// Primitive::source_vertices: a renumbered subset of the source's vertices keeps the streams lodkit
// does not model (a sparse morph target, a 2-byte application attribute), each vertex's own values,
// with the target's POSITION bounds recomputed and elements padded to 4 bytes.
TEST(GltfWrite, SourceVerticesCarryMorphTargetsAndOtherAttributes) {
  HandBuilt f;
  const int pos = f.positions({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0});
  const std::vector<float> dense = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  const int target = f.positions(dense);
  f.make_sparse(target, {1, 3}, {0, 0, 2, 0, 0, 3});  // vertex 1 up by 2, vertex 3 by 3
  f.doc["accessors"][size_t(target)]["max"] = {0, 0, 3};
  const std::vector<uint16_t> ids = {10, 0, 11, 0, 12, 0, 13, 0};  // 4 elements, each padded to 4 bytes
  const int id = f.accessor(ids, kUShort, "SCALAR", 1, kArrayBuffer);
  f.doc["accessors"][size_t(id)]["count"] = 4;
  f.doc["bufferViews"][f.doc["accessors"][size_t(id)]["bufferView"].get<size_t>()]["byteStride"] = 4;
  const std::vector<uint8_t> quad = {0, 1, 2, 1, 3, 2};
  const int indices = f.accessor(quad, kUByte, "SCALAR", 1, kElementArrayBuffer);
  f.doc["meshes"] = Json::array({{{"primitives", {{{"attributes", {{"POSITION", pos}, {"_ID", id}}},
                                                   {"indices", indices},
                                                   {"targets", {{{"POSITION", target}}}}}}},
                                  {"weights", {0.5}}}});
  f.doc["nodes"] = Json::array({{{"mesh", 0}}});
  f.doc["scenes"] = Json::array({{{"nodes", {0}}}});
  TempDir dir;
  test::write_bytes(dir / "in.glb", f.glb());
  Scene scene = read_scene(dir / "in.glb");
  ASSERT_EQ(scene.primitives.size(), 1u);

  // The triangle (1 3 2) alone, its vertices renumbered 3 -> 0, 2 -> 1, 1 -> 2.
  Primitive& p = scene.primitives[0];
  const std::vector<uint32_t> source = {3, 2, 1};
  Mesh m;
  for (const uint32_t v : source) m.positions.push_back(p.mesh.positions[v]);
  m.indices = {2, 0, 1};
  p.mesh = m;
  p.source_vertices = source;
  write_scene(scene, dir / "out.glb");
  const Written w = load_written(dir / "out.glb");
  const Json& prim = w.doc["meshes"][0]["primitives"][0];
  ASSERT_EQ(prim["targets"].size(), 1u);
  EXPECT_EQ(accessor_floats(w, prim["targets"][0]["POSITION"]), (std::vector<float>{0, 0, 3, 0, 0, 0, 0, 0, 2}));
  const Json& bounds = w.doc["accessors"][prim["targets"][0]["POSITION"].get<size_t>()];
  EXPECT_EQ(bounds["min"], Json::array({0, 0, 0}));
  EXPECT_EQ(bounds["max"], Json::array({0, 0, 3}));
  const Json& ida = w.doc["accessors"][prim["attributes"]["_ID"].get<size_t>()];
  EXPECT_EQ(ida["componentType"], kUShort);
  ASSERT_EQ(ida["count"], 3);
  const Json& idv = w.doc["bufferViews"][ida["bufferView"].get<size_t>()];
  ASSERT_EQ(idv["byteStride"], 4);
  const std::vector<uint8_t> id_bytes = view_bytes(w, ida["bufferView"]);
  std::vector<uint16_t> got(3);
  for (size_t v = 0; v < 3; ++v) std::memcpy(&got[v], &id_bytes[4 * v], 2);
  EXPECT_EQ(got, (std::vector<uint16_t>{13, 12, 11}));
  EXPECT_EQ(w.doc["meshes"][0]["weights"], Json::array({0.5}));

  test::expect_valid_gltf({dir / "in.glb", dir / "out.glb"});

  // A map that names a vertex the source does not have is the caller's mistake.
  p.source_vertices = {3, 2, 4};
  try {
    write_scene(scene, dir / "bad.glb");
    FAIL() << "expected lod::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("source_vertices names vertex 4"), std::string::npos) << e.what();
  }
}

TEST(GltfRead, ExternalBinAndImagesResolveAgainstTheBaseDir) {
  HandBuilt f;
  const int pos = f.positions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  f.doc["meshes"] = Json::array({{{"primitives", {{{"attributes", {{"POSITION", pos}}}}}}}});
  f.doc["images"] = Json::array({{{"uri", "data:image/png;base64," + base64(kPng)}}, {{"uri", "textures/wood%20grain.png"}}});
  f.doc["textures"] = Json::array({{{"source", 0}}, {{"source", 1}}});
  f.doc["buffers"] = Json::array({{{"byteLength", f.bin.size()}, {"uri", "geometry.bin"}}});
  TempDir dir;
  std::filesystem::create_directory(dir / "textures");
  test::write_bytes(dir / "textures" / "wood grain.png", kPng);
  test::write_bytes(dir / "geometry.bin", f.bin);
  test::write_text(dir / "external.gltf", f.doc.dump());

  const Scene scene = read_scene(dir / "external.gltf");
  EXPECT_EQ(scene.image_count, 2u);
  EXPECT_EQ(flat(scene.primitives[0].mesh.positions), (std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0}));
  std::filesystem::create_directory(dir / "out");
  write_scene(scene, dir / "out" / "copy.gltf");
  const Written w = load_written(dir / "out" / "copy.gltf");
  const std::string data_uri = w.doc["images"][0]["uri"];
  ASSERT_EQ(data_uri.rfind("data:image/png;base64,", 0), 0u);
  EXPECT_EQ(base64_decode(data_uri.substr(22)), kPng);
  // The external image stays where it is, not copied or re-encoded: its URI now leads there from out/.
  EXPECT_EQ(w.doc["images"][1]["uri"], "../textures/wood%20grain.png");
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "textures"));
  write_scene(scene, dir / "beside.gltf");
  EXPECT_EQ(load_written(dir / "beside.gltf").doc["images"][1]["uri"], "textures/wood%20grain.png");
  // A .glb is one file: the images' bytes (the data: URI's too) go into its BIN chunk, typed by their
  // signature.
  write_scene(scene, dir / "out" / "packed.glb");
  const Written g = load_written(dir / "out" / "packed.glb");
  for (size_t i = 0; i < 2; ++i) {
    const Json& packed = g.doc["images"][i];
    EXPECT_FALSE(packed.contains("uri")) << i;
    EXPECT_EQ(packed["mimeType"], "image/png") << i;
    EXPECT_EQ(view_bytes(g, packed["bufferView"]), kPng) << i;
  }
  const Scene again = read_scene(dir / "out" / "packed.glb");
  EXPECT_EQ(again.image_count, 2u);
  test::expect_valid_gltf({dir / "out" / "copy.gltf", dir / "out" / "packed.glb"});

  // Without a base dir only data: URIs and the GLB chunk are allowed.
  const FileBytes bytes = read_file_bytes(dir / "external.gltf");
  try {
    read_gltf(bytes, "no-base.gltf");
    FAIL() << "expected lod::Error";
  } catch (const Error& e) {
    EXPECT_EQ(e.category(), ErrorCategory::bad_input);
    EXPECT_NE(std::string(e.what()).find("no-base.gltf"), std::string::npos) << e.what();
  }
}

// ---- malformed input ------------------------------------------------------------------------------

// A valid one-triangle GLB to break in one place.
HandBuilt valid_triangle() {
  HandBuilt f;
  const int pos = f.positions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  const int idx = f.accessor(std::vector<uint16_t>{0, 1, 2}, kUShort, "SCALAR", 1, kElementArrayBuffer);
  f.doc["meshes"] = Json::array({{{"primitives", {{{"attributes", {{"POSITION", pos}}}, {"indices", idx}}}}}});
  f.doc["nodes"] = Json::array({{{"mesh", 0}}});
  f.doc["scenes"] = Json::array({{{"nodes", {0}}}});
  return f;
}

// The shared bad-input check, plus the words the message must contain.
void expect_bad_input(std::span<const uint8_t> bytes, const std::string& name, const std::string& needle) {
  SCOPED_TRACE(name);
  const std::string what = test::expect_bad_input([](auto b, const auto& n) { read_gltf(b, n); },
                                                  std::string(bytes.begin(), bytes.end()), name);
  EXPECT_NE(what.find(needle), std::string::npos) << "expected '" << needle << "' in: " << what;
}

TEST(GltfMalformed, ValidBaseFileReads) {
  EXPECT_EQ(read_gltf(valid_triangle().glb(), "ok.glb").primitives.size(), 1u);
  EXPECT_EQ(read_gltf(span_of(valid_triangle().gltf()), "ok.gltf").primitives.size(), 1u);
}

TEST(GltfMalformed, GlbContainer) {
  const std::vector<uint8_t> good = valid_triangle().glb();
  std::vector<uint8_t> bad = good;
  bad[3] = 'X';
  expect_bad_input(bad, "magic.glb", "magic");
  bad = good;
  bad[4] = 1;
  expect_bad_input(bad, "version.glb", "version 1");
  bad.assign(good.begin(), good.begin() + ptrdiff_t(good.size() / 2));
  expect_bad_input(bad, "truncated.glb", "truncated");
  bad.assign(good.begin(), good.begin() + 7);
  expect_bad_input(bad, "tiny.glb", "truncated GLB header");
  bad = good;
  bad[12] = 0xF0, bad[13] = 0xFF, bad[14] = 0xFF, bad[15] = 0x0F;  // JSON chunk length
  expect_bad_input(bad, "chunk.glb", "JSON chunk length");
  bad = good;
  const size_t bin_header = 20 + get_u32(good, 12);
  bad[bin_header + 2] = 0x10;  // BIN chunk length beyond the file
  expect_bad_input(bad, "binchunk.glb", "BIN chunk length");
}

TEST(GltfMalformed, BadJson) {
  const std::string text = valid_triangle().gltf();
  expect_bad_input(span_of(text.substr(0, text.size() / 2)), "truncated.gltf", "invalid JSON");
  expect_bad_input(span_of(std::string("\x01\x02 not json at all")), "garbage.gltf", "invalid JSON");
  expect_bad_input(span_of(std::string("[1, 2, 3]")), "array.gltf", "root is not an object");
  // A number beyond double range is a JSON library error other than a parse error (found by fuzz_gltf).
  expect_bad_input(span_of(std::string(R"({"asset":{"version":"2.0"},"extras":0.70E1068})")), "overflow.gltf", "invalid JSON");
  // tinygltf converts extras recursively: this nesting would overflow its stack.
  const std::string deep = "{\"asset\":{\"version\":\"2.0\"},\"extras\":" + std::string(100000, '[') +
                           std::string(100000, ']') + "}";
  expect_bad_input(span_of(deep), "deep.gltf", "nested deeper");
  HandBuilt f = valid_triangle();
  f.doc.erase("asset");
  expect_bad_input(span_of(f.gltf()), "noasset.gltf", "asset");
}

TEST(GltfMalformed, BufferRanges) {
  HandBuilt f = valid_triangle();
  f.doc["bufferViews"][0]["byteLength"] = f.bin.size() + 100;
  expect_bad_input(f.glb(), "view.glb", "runs past the end of buffers[0]");

  f = valid_triangle();
  f.doc["bufferViews"][0]["byteStride"] = 4;  // a VEC3 float is 12 bytes
  expect_bad_input(f.glb(), "stride.glb", "accessor stride overlaps its elements");

  f = valid_triangle();
  f.doc["accessors"][0]["count"] = 1000000000000ull;
  expect_bad_input(f.glb(), "count.glb", "do not fit");

  f = valid_triangle();
  f.doc["accessors"][0]["byteOffset"] = 8;
  expect_bad_input(f.glb(), "offset.glb", "do not fit");

  f = valid_triangle();
  f.doc["accessors"][0]["bufferView"] = 7;
  expect_bad_input(f.glb(), "viewindex.glb", "bufferViews[7]");

  // The GLB buffer claims more bytes than the BIN chunk has.
  f = valid_triangle();
  Json doc = f.doc;
  doc["buffers"] = Json::array({{{"byteLength", f.bin.size() + 64}}});
  const std::vector<uint8_t> rebuilt = test::glb_bytes({doc, f.bin});
  expect_bad_input(rebuilt, "buffer.glb", "byteLength");

  // An image bufferView outside its buffer: tinygltf would read past the end before lodkit sees it.
  f = valid_triangle();
  const int image_view = f.view(kPng.data(), kPng.size());
  f.doc["bufferViews"][size_t(image_view)]["byteLength"] = 100000000;
  f.doc["images"] = Json::array({{{"bufferView", image_view}, {"mimeType", "image/png"}}});
  expect_bad_input(f.glb(), "image.glb", "runs past the end");

  f = valid_triangle();
  f.doc["accessors"][0]["sparse"] = {{"count", 1},
                                     {"indices", {{"bufferView", 1}, {"componentType", kUShort}, {"byteOffset", 6}}},
                                     {"values", {{"bufferView", 0}}}};
  expect_bad_input(f.glb(), "sparse.glb", "sparse indices");
}

// A data: URI shorter than its buffer's byteLength: 4 base64 characters hold 3 bytes, less one per
// '=' of padding; unpadded, 2 or 3 trailing characters hold 1 or 2.
TEST(GltfMalformed, ShortDataUri) {
  HandBuilt f = valid_triangle();
  Json doc = Json::parse(f.gltf());
  doc["buffers"][0]["byteLength"] = f.bin.size() + 1;
  expect_bad_input(span_of(doc.dump()), "short.gltf",
                   "buffers[0]: its data: URI holds " + std::to_string(f.bin.size()) + " bytes, fewer than its byteLength");
  const auto buffer_only = [](const std::string& base64, int length) {
    return Json{{"asset", {{"version", "2.0"}}},
                {"buffers", Json::array({{{"byteLength", length}, {"uri", "data:application/octet-stream;base64," + base64}}})}}
        .dump();
  };
  for (const auto& [base64, bytes] : std::vector<std::pair<std::string, int>>{{"AAE=", 2}, {"AA==", 1}, {"AAE", 2}, {"AA", 1}, {"AAEC", 3}}) {
    SCOPED_TRACE(base64);
    expect_bad_input(span_of(buffer_only(base64, bytes + 1)), "short.gltf", "holds " + std::to_string(bytes) + " bytes");
    EXPECT_NO_THROW(read_gltf(span_of(buffer_only(base64, bytes)), "exact.gltf"));
  }
}

TEST(GltfMalformed, Geometry) {
  HandBuilt f = valid_triangle();
  f.bin[f.bin.size() - 2] = 7;  // the last index (u16) becomes 7 with 3 vertices
  expect_bad_input(f.glb(), "index.glb", "out of range");

  f = valid_triangle();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(&f.bin[4], &nan, 4);  // y of vertex 0
  expect_bad_input(f.glb(), "nan.glb", "not finite");

  f = valid_triangle();
  const float inf = std::numeric_limits<float>::infinity();
  std::memcpy(&f.bin[24], &inf, 4);
  expect_bad_input(f.glb(), "inf.glb", "not finite");

  f = valid_triangle();
  f.doc["meshes"][0]["primitives"][0]["attributes"] = {{"NORMAL", 0}};
  expect_bad_input(f.glb(), "noposition.glb", "no POSITION");

  f = valid_triangle();
  f.doc["meshes"][0]["primitives"][0].erase("attributes");
  expect_bad_input(f.glb(), "noattributes.glb", "no attributes");

  f = valid_triangle();
  f.doc["accessors"][1]["count"] = 2;  // 2 corners
  expect_bad_input(f.glb(), "corners.glb", "not a multiple of 3");

  f = valid_triangle();
  f.doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 0;  // a VEC3
  expect_bad_input(f.glb(), "uvtype.glb", "expected VEC2");

  f = valid_triangle();
  f.doc["meshes"][0]["primitives"][0]["indices"] = 0;  // a VEC3 float accessor as indices
  expect_bad_input(f.glb(), "indextype.glb", "indices");

  f = valid_triangle();
  f.doc["meshes"][0]["primitives"][0]["mode"] = 9;
  expect_bad_input(f.glb(), "mode.glb", "mode 9");

  // Streams lodkit does not decode still need one entry per vertex (they are written back per vertex).
  f = valid_triangle();
  f.doc["meshes"][0]["primitives"][0]["attributes"]["_ID"] = 1;  // the 3 indices: right count
  EXPECT_NO_THROW(read_gltf(f.glb(), "id.glb"));
  f.doc["meshes"][0]["primitives"][0]["attributes"]["_ID"] = f.accessor(std::vector<float>{1, 2}, kFloat, "SCALAR", 1);
  expect_bad_input(f.glb(), "idcount.glb", "_ID has 2 entries for 3 vertices");
  f = valid_triangle();
  f.doc["meshes"][0]["primitives"][0]["targets"] = {{{"POSITION", f.positions({0, 0, 1, 0, 0, 1})}}};
  expect_bad_input(f.glb(), "targetcount.glb", "morph target 0 POSITION has 2 entries for 3 vertices");
  // Displacements of positions, normals and tangents are VEC3, like the three-component attributes.
  f = valid_triangle();
  f.doc["meshes"][0]["primitives"][0]["targets"] = {{{"NORMAL", f.accessor(std::vector<float>(6, 0.0f), kFloat, "VEC2", 2)}}};
  expect_bad_input(f.glb(), "targettype.glb", "morph target 0 NORMAL must be VEC3");
}

TEST(GltfMalformed, References) {
  HandBuilt f = valid_triangle();
  f.doc["nodes"] = Json::array({{{"children", {1}}}, {{"children", {0}}}});
  expect_bad_input(f.glb(), "cycle.glb", "node cycle");

  f = valid_triangle();
  f.doc["nodes"] = Json::array({{{"children", {1}}}, {{"children", {2}}}, {{"children", {1}}}});
  expect_bad_input(f.glb(), "loop.glb", "two parents");

  f = valid_triangle();
  f.doc["nodes"][0]["mesh"] = 3;
  expect_bad_input(f.glb(), "mesh.glb", "meshes[3]");

  f = valid_triangle();
  f.doc["meshes"][0]["primitives"][0]["material"] = 0;
  expect_bad_input(f.glb(), "material.glb", "materials[0]");

  // tinygltf's own check of these names neither the primitive nor the accessor.
  f = valid_triangle();
  f.doc["meshes"][0]["primitives"][0]["indices"] = 5;
  expect_bad_input(f.glb(), "indices.glb", "meshes[0].primitives[0].indices refers to accessors[5], which does not exist");

  f = valid_triangle();
  f.doc["skins"] = Json::array({{{"joints", {0}}, {"inverseBindMatrices", 0}}});  // a VEC3 accessor
  expect_bad_input(f.glb(), "skin.glb", "MAT4");

  f = valid_triangle();
  f.doc["nodes"][0]["extensions"] = {{"MSFT_lod", {{"ids", {1}}}}};
  expect_bad_input(f.glb(), "lod.glb", "MSFT_lod refers to nodes[1]");

  f = valid_triangle();
  f.doc["nodes"][0]["extensions"] = {{"MSFT_lod", {{"ids", 0}}}};
  expect_bad_input(f.glb(), "lodids.glb", "MSFT_lod ids is not an array");
}

// ---- scenes without a source ------------------------------------------------------------------------

TEST(GltfWrite, SceneFromMeshWritesMaterialsNodesAndPrimitives) {
  Mesh mesh = shapes::cube();
  mesh.materials.assign(12, 1);
  mesh.materials[0] = mesh.materials[1] = 0;
  mesh.material_names = {"wall", "floor"};
  TempDir dir;
  write_scene(scene_from_mesh(mesh), dir / "rooms.gltf");
  const Scene scene = read_scene(dir / "rooms.gltf");
  ASSERT_EQ(scene.primitives.size(), 2u);
  EXPECT_EQ(scene.primitives[0].material, 0);
  EXPECT_EQ(scene.primitives[1].material, 1);
  EXPECT_EQ(scene.primitives[0].mesh.triangle_count(), 2u);
  EXPECT_EQ(scene.primitives[0].mesh.vertex_count(), 4u);
  EXPECT_EQ(scene.primitives[1].mesh.triangle_count(), 10u);
  EXPECT_EQ(scene.material_names, (std::vector<std::string>{"wall", "floor"}));
  EXPECT_EQ(scene.roots, (std::vector<int32_t>{0}));
  ASSERT_EQ(scene.nodes.size(), 1u);
  EXPECT_EQ(scene.nodes[0].mesh, 0);
}

// A chain as lodkit lod writes one: MSFT_lod on the first node, lodkit extras on every node. The
// reader gives back the ids and the extras, and writing the read scene again keeps them (and any
// other member of a source node's MSFT_lod).
TEST(GltfWrite, LodChainReadsBackItsLodIdsAndExtras) {
  const std::vector<std::string> extras = {
      R"({"lodkit":{"error":0,"level":0},"MSFT_screencoverage":[0.5,0.25,0.125]})",
      R"({"lodkit":{"error":0.0125,"level":1}})", ""};
  const Scene chain = test::lod_chain_scene({shapes::icosphere(3), shapes::icosphere(2), shapes::icosphere(1)}, extras);
  TempDir dir;
  write_scene(chain, dir / "chain.glb");
  const Scene scene = read_scene(dir / "chain.glb");
  ASSERT_EQ(scene.nodes.size(), 3u);
  EXPECT_EQ(scene.nodes[0].lod_ids, (std::vector<int32_t>{1, 2}));
  EXPECT_TRUE(scene.nodes[1].lod_ids.empty());
  EXPECT_TRUE(scene.nodes[2].lod_ids.empty());
  EXPECT_EQ(Json::parse(scene.nodes[0].extras_json), Json::parse(extras[0]));
  EXPECT_EQ(Json::parse(scene.nodes[1].extras_json), Json::parse(extras[1]));
  EXPECT_EQ(scene.nodes[2].extras_json, "");

  write_scene(scene, dir / "again.glb");
  const Written w = load_written(dir / "again.glb");
  EXPECT_EQ(w.doc["nodes"], load_written(dir / "chain.glb").doc["nodes"]);
  const Scene again = read_scene(dir / "again.glb");
  EXPECT_EQ(again.nodes[0].lod_ids, scene.nodes[0].lod_ids);
  EXPECT_EQ(again.nodes[0].extras_json, scene.nodes[0].extras_json);

  HandBuilt f = valid_triangle();
  f.doc["nodes"] = Json::array({{{"mesh", 0}, {"extensions", {{"MSFT_lod", {{"ids", {1}}, {"note", "kept"}}}}}}, {{"mesh", 0}}});
  test::write_bytes(dir / "hand.glb", f.glb());
  const Scene hand = read_scene(dir / "hand.glb");
  EXPECT_EQ(hand.nodes[0].lod_ids, (std::vector<int32_t>{1}));
  write_scene(hand, dir / "hand-again.glb");
  EXPECT_EQ(load_written(dir / "hand-again.glb").doc["nodes"], f.doc["nodes"]);

  // No ids: the source node's MSFT_lod goes, and with no node using it, so does its declaration.
  Scene dropped = scene;
  dropped.nodes[0].lod_ids.clear();
  write_scene(dropped, dir / "dropped.glb");
  const Written d = load_written(dir / "dropped.glb");
  EXPECT_FALSE(d.doc["nodes"][0].contains("extensions"));
  EXPECT_EQ(Json::parse(read_scene(dir / "dropped.glb").nodes[0].extras_json), Json::parse(extras[0]));
  EXPECT_FALSE(d.doc.contains("extensionsUsed") && std::count(d.doc["extensionsUsed"].begin(), d.doc["extensionsUsed"].end(), "MSFT_lod"));
}

TEST(GltfWrite, EmptyMeshWritesAValidEmptyScene) {
  TempDir dir;
  write_mesh(Mesh{}, dir / "empty.glb");
  const Scene scene = read_scene(dir / "empty.glb");
  EXPECT_TRUE(scene.primitives.empty());
  EXPECT_TRUE(read_mesh(dir / "empty.glb").positions.empty());
}

// ---- the Khronos validator --------------------------------------------------------------------------

TEST(GltfValidator, WrittenFilesHaveNoErrors) {
  if (!test::validator_available())
    GTEST_SKIP() << "gltf-validator not installed: run `npm ci --prefix tests/gltf-validator` (needs node on PATH)";
  TempDir dir;
  std::vector<std::filesystem::path> files;
  for (const NamedShape& shape : test_shapes())
    for (const char* ext : {".glb", ".gltf"}) {
      files.push_back(dir / (std::string(shape.name) + ext));
      write_mesh(with_all_streams(shape.mesh), files.back());
    }
  const SceneInput in = hand_built_scene();
  test::write_bytes(dir / "hand.glb", in.file.glb());
  files.push_back(dir / "hand.glb");  // the input itself, so a problem in the test's file shows up as such
  const Scene hand = read_scene(dir / "hand.glb");
  for (const char* ext : {".glb", ".gltf"}) {
    files.push_back(dir / (std::string("hand-out") + ext));
    write_scene(hand, files.back());
  }
  Mesh multi = with_all_streams(shapes::cylinder(12));
  multi.materials.assign(multi.triangle_count(), 0);
  for (size_t t = 0; t < multi.triangle_count(); ++t) multi.materials[t] = uint32_t(t % 3);
  multi.material_names = {"side", "top", "bottom"};
  files.push_back(dir / "multi.glb");
  write_scene(scene_from_mesh(multi), files.back());
  files.push_back(dir / "multi.gltf");
  write_scene(scene_from_mesh(multi), files.back());

  const test::ValidatorRun run = test::run_validator(files);
  EXPECT_EQ(run.status, 0) << run.output;
  for (const auto& f : files) EXPECT_NE(run.output.find(f.string() + ": 0 errors"), std::string::npos) << run.output;
}

// A node lodkit adds with more morph targets than the source node whose weights it takes (a level
// with a geomorph after the blend shape): its weights and its copy of the cubic-spline clip get a 0
// after each group (in-tangent, value, out-tangent), and the source node's channel is unchanged.
TEST(GltfMorphWeights, ExtraTargetsTakeZeroInWeightsAndClips) {
  test::TempDir dir;
  Scene scene = scene_from_mesh(shapes::torus(1.0f, 0.3f, 12, 6));
  MorphTarget blend;
  for (const float3& p : scene.primitives[0].mesh.positions) blend.positions.push_back({0, 0, 0.1f * p.x});
  scene.primitives[0].targets.push_back(blend);
  scene.nodes[0].name = "source";
  scene.animations.push_back({"clip", {{.node = 0, .path = AnimationPath::weights, .interpolation = Interpolation::cubic_spline,
                                        .times = {0, 1}, .values = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f}, .components = 1}}});
  write_scene(scene, dir / "one.glb");

  Scene grown = read_scene(dir / "one.glb");
  Primitive level = grown.primitives[0];
  level.gltf_mesh = grown.gltf_mesh_count, level.gltf_primitive = 0;
  level.source_vertices.clear();
  level.targets = {blend, blend};
  grown.primitives.push_back(level);
  Node node;
  node.name = "level";
  node.mesh = int32_t(grown.gltf_mesh_count);
  node.morph_weights_of = {0};
  grown.nodes.push_back(node);
  grown.roots.push_back(int32_t(grown.nodes.size() - 1));
  write_scene(grown, dir / "grown.glb");
  test::expect_valid_gltf({dir / "grown.glb"});

  const nlohmann::json doc = test::glb_json(dir / "grown.glb");
  const nlohmann::json& anim = doc["animations"][0];
  ASSERT_EQ(anim["channels"].size(), 2u);
  for (const nlohmann::json& channel : anim["channels"]) {
    const nlohmann::json& sampler = anim["samplers"][channel["sampler"].get<size_t>()];
    EXPECT_EQ(sampler["interpolation"], "CUBICSPLINE");
    const std::vector<float> out = test::glb_floats(dir / "grown.glb", sampler["output"]);
    if (doc["nodes"][channel["target"]["node"].get<size_t>()]["name"] == "source")
      EXPECT_EQ(out, (std::vector<float>{0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f}));
    else
      EXPECT_EQ(out, (std::vector<float>{0.1f, 0, 0.2f, 0, 0.3f, 0, 0.4f, 0, 0.5f, 0, 0.6f, 0}));
  }
}

// erase_nodes: asked to erase nodes 1, 2, 3, 5, 7 and 8 of ten, it erases those nothing else needs:
// 1 (a leaf), 5 (a level of node 0's MSFT_lod) and 7 (a leaf a clip moves, by a core channel and a
// KHR_animation_pointer: both channels go). Node 2 has a camera, node 3 a child that stays (4) and
// node 8 is a skin's joint: they stay. By hand, the others renumber 0, 1, 2, 3, 4, 5, 6 (0, 2, 3, 4,
// 6, 8, 9), in the scene and in the document written back: children, the scene's roots, MSFT_lod
// ids, the skin's joints and the channels on node 9 (core and pointer). A document declaring an
// extension lodkit does not know (it might refer to nodes) keeps every node.
TEST(GltfWrite, EraseNodesRenumbersWhatRefersToThem) {
  const auto document = [](bool unknown_extension) {
    HandBuilt f;
    const int pos = f.positions({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const std::vector<uint16_t> indices = {0, 1, 2};
    const int idx = f.accessor(indices, kUShort, "SCALAR", 1, kElementArrayBuffer);
    f.doc["meshes"] = Json::array({{{"primitives", {{{"attributes", {{"POSITION", pos}}}, {"indices", idx}}}}}});
    f.doc["cameras"] = Json::array({{{"type", "perspective"}, {"perspective", {{"yfov", 1.0}, {"znear", 0.1}}}}});
    Json nodes = Json::array();
    for (const char* name : {"root", "leaf", "camera", "parent", "child", "level", "level2", "moved", "joint", "last"})
      nodes.push_back({{"name", name}});
    nodes[0].update({{"mesh", 0}, {"children", {1, 2, 3}}, {"extensions", {{"MSFT_lod", {{"ids", {5, 6}}}}}}});
    nodes[2]["camera"] = 0;
    nodes[3]["children"] = {4};
    for (const size_t n : {4, 5, 6, 9}) nodes[n]["mesh"] = 0;
    f.doc["nodes"] = nodes;
    f.doc["scenes"] = Json::array({{{"nodes", {0, 7, 8, 9}}}});
    f.doc["skins"] = Json::array({{{"joints", {8}}}});
    const std::vector<float> times = {0, 1}, moves = {0, 0, 0, 1, 0, 0}, turns = {0, 0, 0, 1, 0, 0.6f, 0, 0.8f};
    const std::vector<uint8_t> steps = {0, 0, 0, 1, 2, 3, 0, 0};  // two VEC3 keys (and padding)
    const int in = f.accessor(times, kFloat, "SCALAR", 1, 0, {{"min", {0}}, {"max", {1}}});
    const int move = f.accessor(moves, kFloat, "VEC3", 3), turn = f.accessor(turns, kFloat, "VEC4", 4);
    const int bytes = f.accessor(steps, kUByte, "VEC3", 3);
    f.doc["accessors"][size_t(bytes)]["count"] = 2;
    const auto pointer = [](int sampler, const std::string& to) {
      return Json{{"sampler", sampler}, {"target", {{"path", "pointer"}, {"extensions", {{"KHR_animation_pointer", {{"pointer", to}}}}}}}};
    };
    f.doc["animations"] = Json::array(
        {{{"samplers", {{{"input", in}, {"output", move}}, {{"input", in}, {"output", turn}}, {{"input", in}, {"output", bytes}}}},
          {"channels",
           {{{"sampler", 0}, {"target", {{"node", 7}, {"path", "translation"}}}},
            {{"sampler", 1}, {"target", {{"node", 9}, {"path", "rotation"}}}}, pointer(2, "/nodes/7/translation"),
            pointer(2, "/nodes/9/translation")}}}});
    f.doc["extensionsUsed"] = {"MSFT_lod", "KHR_animation_pointer"};
    if (unknown_extension) f.doc["extensionsUsed"].push_back("VENDOR_node_links");
    return f;
  };
  TempDir dir;
  test::write_bytes(dir / "in.glb", document(false).glb());
  test::expect_valid_gltf({dir / "in.glb"});
  Scene scene = read_scene(dir / "in.glb");
  ASSERT_EQ(scene.nodes.size(), 10u);
  std::vector<bool> erase(10, false);
  for (const size_t n : {1, 2, 3, 5, 7, 8}) erase[n] = true;
  const std::vector<int32_t> remap = erase_nodes(scene, erase);
  EXPECT_EQ(remap, (std::vector<int32_t>{0, -1, 1, 2, 3, -1, 4, -1, 5, 6}));
  ASSERT_EQ(scene.nodes.size(), 7u);
  EXPECT_EQ(scene.nodes[0].children, (std::vector<int32_t>{1, 2}));
  EXPECT_EQ(scene.nodes[0].lod_ids, (std::vector<int32_t>{4}));
  EXPECT_EQ(scene.nodes[2].children, (std::vector<int32_t>{3}));
  EXPECT_EQ(scene.nodes[3].parent, 2);
  EXPECT_EQ(scene.roots, (std::vector<int32_t>{0, 5, 6}));
  EXPECT_EQ(scene.skins[0].joints, (std::vector<int32_t>{5}));
  ASSERT_EQ(scene.animations[0].channels.size(), 1u);  // (the pointers' bytes are the source's alone)
  EXPECT_EQ(scene.animations[0].channels[0].node, 6);
  write_scene(scene, dir / "out.glb");
  test::expect_valid_gltf({dir / "out.glb"});
  const Json doc = test::glb_json(dir / "out.glb");
  std::vector<std::string> names;
  for (const Json& node : doc["nodes"]) names.push_back(node["name"]);
  EXPECT_EQ(names, (std::vector<std::string>{"root", "camera", "parent", "child", "level2", "joint", "last"}));
  EXPECT_EQ(doc["nodes"][0]["children"], Json::array({1, 2}));
  EXPECT_EQ(doc["nodes"][0]["extensions"]["MSFT_lod"]["ids"], Json::array({4}));
  EXPECT_EQ(doc["nodes"][1]["camera"], 0);
  EXPECT_EQ(doc["nodes"][2]["children"], Json::array({3}));
  EXPECT_EQ(doc["scenes"][0]["nodes"], Json::array({0, 5, 6}));
  EXPECT_EQ(doc["skins"][0]["joints"], Json::array({5}));
  const Json& channels = doc["animations"][0]["channels"];
  ASSERT_EQ(channels.size(), 2u);
  EXPECT_EQ(channels[0]["target"], (Json{{"node", 6}, {"path", "rotation"}}));
  EXPECT_EQ(channels[1]["target"]["extensions"]["KHR_animation_pointer"]["pointer"], "/nodes/6/translation");
  EXPECT_EQ(doc["animations"][0]["samplers"].size(), 2u);  // (the moved node's sampler went with its channel)

  test::write_bytes(dir / "unknown.glb", document(true).glb());
  Scene kept = read_scene(dir / "unknown.glb");
  std::vector<int32_t> identity(10);
  std::iota(identity.begin(), identity.end(), 0);
  EXPECT_EQ(erase_nodes(kept, erase), identity);
  EXPECT_EQ(kept.nodes.size(), 10u);
  EXPECT_EQ(kept.nodes[0].lod_ids, (std::vector<int32_t>{5, 6}));
}

// KHR_animation_pointer: a channel without a node passes through with its sampler's keys as they
// were (a material's colour; a pointer whose output the core does not allow on a node: unsigned
// bytes, not normalized, for a translation), and a pointer to a node's rotation becomes the core
// channel the extension's README pairs it with. The extension stays declared while a pointer is
// left. Under -q a node a pointer moves keeps its transform (the grid goes to a child node).
TEST(GltfAnimationPointer, ChannelsPassThroughAndNodePropertiesBecomeCoreChannels) {
  const std::vector<float> times = {0, 1, 2}, colours = {1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 1},
                           rotations = {0, 0, 0, 1, 0, 0.6f, 0, 0.8f, 0, 1, 0, 0};
  const std::vector<uint8_t> steps = {0, 0, 0, 1, 2, 3, 4, 5, 6, 0};  // three VEC3 keys (and padding)
  const auto pointer = [](int sampler, const std::string& to) {
    return Json{{"sampler", sampler}, {"target", {{"path", "pointer"}, {"extensions", {{"KHR_animation_pointer", {{"pointer", to}}}}}}}};
  };
  // `which`: the channels the clip has (c colour, r rotation, t bytes translation).
  const auto document = [&](const std::string& which) {
    HandBuilt f;
    const int pos = f.positions({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0});
    const std::vector<uint16_t> indices = {0, 1, 2, 2, 1, 3};
    const int idx = f.accessor(indices, kUShort, "SCALAR", 1, kElementArrayBuffer);
    f.doc["materials"] = Json::array({{{"pbrMetallicRoughness", {{"baseColorFactor", {1, 1, 1, 1}}}}}});
    f.doc["meshes"] = Json::array({{{"primitives", {{{"attributes", {{"POSITION", pos}}}, {"indices", idx}, {"material", 0}}}}}});
    f.doc["nodes"] = Json::array({{{"mesh", 0}, {"translation", {5, 0, 0}}}});
    f.doc["scenes"] = Json::array({{{"nodes", {0}}}});
    const int in = f.accessor(times, kFloat, "SCALAR", 1, 0, {{"min", {0}}, {"max", {2}}});
    const int colour = f.accessor(colours, kFloat, "VEC4", 4), rotation = f.accessor(rotations, kFloat, "VEC4", 4);
    const int bytes = f.accessor(steps, kUByte, "VEC3", 3);
    f.doc["accessors"][size_t(bytes)]["count"] = 3;
    Json anim = {{"name", "clip"},
                 {"samplers", {{{"input", in}, {"output", colour}}, {{"input", in}, {"output", rotation}}, {{"input", in}, {"output", bytes}}}},
                 {"channels", Json::array()}};
    if (which.find('c') != std::string::npos) anim["channels"].push_back(pointer(0, "/materials/0/pbrMetallicRoughness/baseColorFactor"));
    if (which.find('r') != std::string::npos) anim["channels"].push_back(pointer(1, "/nodes/0/rotation"));
    if (which.find('t') != std::string::npos) anim["channels"].push_back(pointer(2, "/nodes/0/translation"));
    f.doc["animations"] = Json::array({anim});
    f.doc["extensionsUsed"] = {"KHR_animation_pointer"};
    return f;
  };
  TempDir dir;
  const auto keys = [&](const std::filesystem::path& file, const Json& channel) {
    const Json doc = test::glb_json(file);
    const Json& sampler = doc["animations"][0]["samplers"][channel["sampler"].get<size_t>()];
    return std::pair{test::glb_floats(file, sampler["input"]), test::glb_floats(file, sampler["output"])};
  };
  const auto pointer_of = [](const Json& channel) {
    return channel["target"]["extensions"]["KHR_animation_pointer"]["pointer"].get<std::string>();
  };

  test::write_bytes(dir / "crt.glb", document("crt").glb());
  test::expect_valid_gltf({dir / "crt.glb"});
  write_scene(read_scene(dir / "crt.glb"), dir / "out.glb");
  test::expect_valid_gltf({dir / "out.glb"});
  {
    const Json doc = test::glb_json(dir / "out.glb");
    const Json& channels = doc["animations"][0]["channels"];
    ASSERT_EQ(channels.size(), 3u);
    EXPECT_EQ(channels[0]["target"]["path"], "pointer");
    EXPECT_FALSE(channels[0]["target"].contains("node"));
    EXPECT_EQ(pointer_of(channels[0]), "/materials/0/pbrMetallicRoughness/baseColorFactor");
    EXPECT_EQ(keys(dir / "out.glb", channels[0]), std::pair(times, colours));
    EXPECT_EQ(channels[1]["target"], (Json{{"node", 0}, {"path", "rotation"}}));
    EXPECT_EQ(keys(dir / "out.glb", channels[1]), std::pair(times, rotations));
    EXPECT_EQ(pointer_of(channels[2]), "/nodes/0/translation");
    const Json& bytes = doc["accessors"][doc["animations"][0]["samplers"][channels[2]["sampler"].get<size_t>()]["output"].get<size_t>()];
    EXPECT_EQ(bytes["componentType"], kUByte);
    EXPECT_FALSE(bytes.value("normalized", false));
    EXPECT_TRUE(doc["extensionsUsed"].dump().find("KHR_animation_pointer") != std::string::npos);
  }
  // Only the rotation: it becomes a core channel and the extension goes.
  test::write_bytes(dir / "r.glb", document("r").glb());
  write_scene(read_scene(dir / "r.glb"), dir / "r-out.glb");
  test::expect_valid_gltf({dir / "r-out.glb"});
  {
    const Json doc = test::glb_json(dir / "r-out.glb");
    EXPECT_EQ(doc["animations"][0]["channels"], (Json::array({{{"sampler", 0}, {"target", {{"node", 0}, {"path", "rotation"}}}}})));
    EXPECT_EQ(doc.value("extensionsUsed", Json::array()).dump().find("KHR_animation_pointer"), std::string::npos);
  }
  // -q with the colour and the bytes translation: node 0 keeps its translation and scale, a child
  // draws the mesh on the grid; the colour's keys are as they were.
  test::write_bytes(dir / "ct.glb", document("ct").glb());
  write_scene(read_scene(dir / "ct.glb"), dir / "ct-q.glb", {.quantize = true});
  test::expect_valid_gltf({dir / "ct-q.glb"});
  {
    const Json doc = test::glb_json(dir / "ct-q.glb");
    ASSERT_EQ(doc["nodes"].size(), 2u);
    EXPECT_EQ(doc["nodes"][0]["translation"], Json::array({5.0, 0.0, 0.0}));
    EXPECT_FALSE(doc["nodes"][0].contains("scale"));
    EXPECT_FALSE(doc["nodes"][0].contains("mesh"));
    EXPECT_EQ(doc["nodes"][0]["children"], Json::array({1}));
    EXPECT_EQ(doc["nodes"][1]["mesh"], 0);
    EXPECT_NE(doc["accessors"][doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<size_t>()]["componentType"], kFloat);
    const Json& channels = doc["animations"][0]["channels"];
    ASSERT_EQ(channels.size(), 2u);
    EXPECT_EQ(keys(dir / "ct-q.glb", channels[0]), std::pair(times, colours));
    EXPECT_EQ(pointer_of(channels[1]), "/nodes/0/translation");
  }
}

// -q reduces a pointer's float keys as it does a scale's (within 2^-14 of the largest component):
// a material's colour baked at 60 Hz for 10 s on a straight ramp keeps its two ends, its emissive
// colour on a slow smooth curve loses most keys and stays within the bound at every baked time (the
// curves interpolated here), a STEP metallic factor keeps the keys where it changes, a normal
// texture's offset (VEC2) sliding on a line keeps its ends.
TEST(GltfAnimationPointer, QuantizeReducesFloatPointerKeys) {
  HandBuilt f;
  const int pos = f.positions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  const int uv = f.accessor(std::vector<float>{0, 0, 1, 0, 0, 1}, kFloat, "VEC2", 2, kArrayBuffer);
  f.doc["images"] = Json::array({{{"uri", "data:image/png;base64," + base64(kPng)}}});
  f.doc["textures"] = Json::array({{{"source", 0}}});
  f.doc["materials"] = Json::array({{{"pbrMetallicRoughness", {{"baseColorFactor", {1, 1, 1, 1}}, {"metallicFactor", 0.0}}},
                                     {"normalTexture", {{"index", 0}, {"extensions", {{"KHR_texture_transform", {{"offset", {0, 0}}}}}}}}}});
  f.doc["meshes"] = Json::array({{{"primitives", {{{"attributes", {{"POSITION", pos}, {"TEXCOORD_0", uv}}}, {"material", 0}}}}}});
  f.doc["nodes"] = Json::array({{{"mesh", 0}}});
  f.doc["scenes"] = Json::array({{{"nodes", {0}}}});
  std::vector<float> times, ramp, glow, metal, slide;
  for (int k = 0; k <= 600; ++k) {
    const float t = float(k) / 60;
    times.push_back(t);
    ramp.insert(ramp.end(), {t / 10, 1 - t / 10, 0.5f, 1});
    glow.insert(glow.end(), {0.5f + 0.5f * std::sin(0.2f * t), 0.25f, 0.5f + 0.25f * std::cos(0.1f * t)});
    metal.push_back(std::floor(t / 2) / 5);
    slide.insert(slide.end(), {t / 4, -t / 8});
  }
  const int in = f.accessor(times, kFloat, "SCALAR", 1, 0, {{"min", {0}}, {"max", {10}}});
  Json anim = {{"samplers", {{{"input", in}, {"output", f.accessor(ramp, kFloat, "VEC4", 4)}},
                             {{"input", in}, {"output", f.accessor(glow, kFloat, "VEC3", 3)}},
                             {{"input", in}, {"output", f.accessor(metal, kFloat, "SCALAR", 1)}, {"interpolation", "STEP"}},
                             {{"input", in}, {"output", f.accessor(slide, kFloat, "VEC2", 2)}}}},
               {"channels", Json::array()}};
  const char* pointers[4] = {"/materials/0/pbrMetallicRoughness/baseColorFactor", "/materials/0/emissiveFactor",
                             "/materials/0/pbrMetallicRoughness/metallicFactor",
                             "/materials/0/normalTexture/extensions/KHR_texture_transform/offset"};
  for (int c = 0; c < 4; ++c)
    anim["channels"].push_back({{"sampler", c}, {"target", {{"path", "pointer"}, {"extensions", {{"KHR_animation_pointer", {{"pointer", pointers[c]}}}}}}}});
  f.doc["animations"] = Json::array({anim});
  f.doc["extensionsUsed"] = {"KHR_animation_pointer", "KHR_texture_transform"};
  TempDir dir;
  test::write_bytes(dir / "in.glb", f.glb());
  test::expect_valid_gltf({dir / "in.glb"});
  write_scene(read_scene(dir / "in.glb"), dir / "q.glb", {.quantize = true});
  test::expect_valid_gltf({dir / "q.glb"});
  const Json doc = test::glb_json(dir / "q.glb");
  const Json& channels = doc["animations"][0]["channels"];
  ASSERT_EQ(channels.size(), 4u);
  const std::vector<float>* baked[4] = {&ramp, &glow, &metal, &slide};
  const size_t components[4] = {4, 3, 1, 2};
  std::vector<size_t> kept;
  for (size_t c = 0; c < 4; ++c) {
    SCOPED_TRACE(pointers[c]);
    EXPECT_EQ(channels[c]["target"]["extensions"]["KHR_animation_pointer"]["pointer"], pointers[c]);
    const Json& sampler = doc["animations"][0]["samplers"][channels[c]["sampler"].get<size_t>()];
    const bool step = sampler.value("interpolation", "LINEAR") == "STEP";
    const std::vector<float> t = test::glb_floats(dir / "q.glb", sampler["input"]), v = test::glb_floats(dir / "q.glb", sampler["output"]);
    const size_t n = components[c];
    ASSERT_EQ(v.size(), t.size() * n);
    ASSERT_GE(t.size(), 2u);
    EXPECT_EQ(t.front(), 0.0f);
    EXPECT_EQ(t.back(), 10.0f);
    kept.push_back(t.size());
    double largest = 0;
    for (const float x : *baked[c]) largest = std::max(largest, std::fabs(double(x)));
    double worst = 0;
    for (size_t k = 0; k < times.size(); ++k) {
      // The reduced curve at the baked time: the segment holding it, interpolated (or held).
      const size_t i = size_t(std::upper_bound(t.begin(), t.end(), times[k]) - t.begin());
      const size_t hi = std::min(i, t.size() - 1), lo = i == 0 ? 0 : i - 1;
      const double w = step || hi == lo ? 0 : (double(times[k]) - t[lo]) / (double(t[hi]) - t[lo]);
      for (size_t j = 0; j < n; ++j) {
        const double got = (1 - w) * v[lo * n + j] + w * v[hi * n + j];
        worst = std::max(worst, std::fabs(got - (*baked[c])[k * n + j]));
      }
    }
    EXPECT_LE(worst, largest / 16384 + 1e-6);
  }
  EXPECT_EQ(kept[0], 2u);     // the ramp
  EXPECT_LT(kept[1], 300u);   // the smooth curve
  EXPECT_EQ(kept[2], 6u);     // where the STEP changes (t = 0, 2, 4, 6, 8) and the last
  EXPECT_EQ(kept[3], 2u);     // the slide
  const Json& accessor = doc["accessors"][doc["animations"][0]["samplers"][channels[3]["sampler"].get<size_t>()]["output"].get<size_t>()];
  EXPECT_EQ(accessor["type"], "VEC2");
}

// A pointer to a mesh's own morph weights ("/meshes/M/weights") follows the mesh: renumbered when
// an earlier mesh goes, gone with the mesh or with its morph targets.
TEST(GltfAnimationPointer, MeshWeightsFollowTheirMesh) {
  HandBuilt f;
  const int pos = f.positions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  const int target = f.positions({0, 0, 1, 0, 0, 1, 0, 0, 1});
  const Json mesh = {{"primitives", {{{"attributes", {{"POSITION", pos}}}, {"targets", {{{"POSITION", target}}}}}}}, {"weights", {0.5}}};
  f.doc["meshes"] = Json::array({mesh, mesh});
  f.doc["nodes"] = Json::array({{{"mesh", 0}}, {{"mesh", 1}}});
  f.doc["scenes"] = Json::array({{{"nodes", {0, 1}}}});
  const std::vector<float> times = {0, 1}, first = {0.25f, 0.75f}, second = {0.125f, 0.375f};
  const int in = f.accessor(times, kFloat, "SCALAR", 1, 0, {{"min", {0}}, {"max", {1}}});
  const int out0 = f.accessor(first, kFloat, "SCALAR", 1), out1 = f.accessor(second, kFloat, "SCALAR", 1);
  Json anim = {{"samplers", {{{"input", in}, {"output", out0}}, {{"input", in}, {"output", out1}}}}, {"channels", Json::array()}};
  for (int m = 0; m < 2; ++m)
    anim["channels"].push_back({{"sampler", m},
                                {"target", {{"path", "pointer"},
                                            {"extensions", {{"KHR_animation_pointer", {{"pointer", "/meshes/" + std::to_string(m) + "/weights"}}}}}}}});
  f.doc["animations"] = Json::array({anim});
  f.doc["extensionsUsed"] = {"KHR_animation_pointer"};
  TempDir dir;
  test::write_bytes(dir / "in.glb", f.glb());
  test::expect_valid_gltf({dir / "in.glb"});
  Scene scene = read_scene(dir / "in.glb");
  ASSERT_EQ(scene.primitives.size(), 2u);
  // Mesh 0 loses its triangles: mesh 1 becomes mesh 0, its channel with it.
  scene.primitives[0].mesh.indices.clear();
  write_scene(scene, dir / "renumbered.glb");
  test::expect_valid_gltf({dir / "renumbered.glb"});
  {
    const Json doc = test::glb_json(dir / "renumbered.glb");
    ASSERT_EQ(doc["meshes"].size(), 1u);
    const Json& channels = doc["animations"][0]["channels"];
    ASSERT_EQ(channels.size(), 1u);
    EXPECT_EQ(channels[0]["target"]["extensions"]["KHR_animation_pointer"]["pointer"], "/meshes/0/weights");
    const Json& sampler = doc["animations"][0]["samplers"][channels[0]["sampler"].get<size_t>()];
    EXPECT_EQ(test::glb_floats(dir / "renumbered.glb", sampler["output"]), second);
  }
  // Mesh 1 grows a vertex as well: its targets no longer fit and go, the clip with them.
  scene.primitives[1].mesh.positions.push_back({1, 1, 0});
  scene.primitives[1].mesh.indices.insert(scene.primitives[1].mesh.indices.end(), {1, 3, 2});
  write_scene(scene, dir / "gone.glb");
  test::expect_valid_gltf({dir / "gone.glb"});
  {
    const Json doc = test::glb_json(dir / "gone.glb");
    EXPECT_FALSE(doc.contains("animations"));
    EXPECT_EQ(doc.value("extensionsUsed", Json::array()).dump().find("KHR_animation_pointer"), std::string::npos);
  }
}

// The reader takes a mesh's weights pointer ("/meshes/M/weights") as the weights channel of each node
// drawing M without weights of its own (node 0 and 2 here; node 1's own weights override the
// mesh's), after the clip's core channels, so that node 2's own channel is the one that drives it.
// A pointer to a mesh no node draws stays in the source; a malformed one is refused.
TEST(GltfAnimationPointer, MeshWeightsDriveTheNodesWithoutWeightsOfTheirOwn) {
  const auto document = [](const std::string& output_type) {
    HandBuilt f;
    const int pos = f.positions({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const int target = f.positions({0, 0, 1, 0, 0, 1, 0, 0, 1});
    const Json mesh = {{"primitives", {{{"attributes", {{"POSITION", pos}}}, {"targets", {{{"POSITION", target}}}}}}}};
    f.doc["meshes"] = Json::array({mesh, mesh});
    f.doc["nodes"] = Json::array({{{"mesh", 0}}, {{"mesh", 0}, {"weights", {0.5}}}, {{"mesh", 0}}});
    f.doc["scenes"] = Json::array({{{"nodes", {0, 1, 2}}}});
    const int in = f.accessor(std::vector<float>{0, 1}, kFloat, "SCALAR", 1, 0, {{"min", {0}}, {"max", {1}}});
    const int mesh_keys = output_type == "SCALAR" ? f.accessor(std::vector<float>{0.25f, 0.75f}, kFloat, "SCALAR", 1)
                                                  : f.accessor(std::vector<float>{0, 0, 0, 1, 1, 1}, kFloat, "VEC3", 3);
    const int node_keys = f.accessor(std::vector<float>{1, 0}, kFloat, "SCALAR", 1);
    const auto pointer = [](int sampler, const std::string& to) {
      return Json{{"sampler", sampler}, {"target", {{"path", "pointer"}, {"extensions", {{"KHR_animation_pointer", {{"pointer", to}}}}}}}};
    };
    f.doc["animations"] = Json::array({{{"samplers", {{{"input", in}, {"output", mesh_keys}}, {{"input", in}, {"output", node_keys}}}},
                                        {"channels", {pointer(0, "/meshes/0/weights"), {{"sampler", 1}, {"target", {{"node", 2}, {"path", "weights"}}}},
                                                      pointer(0, "/meshes/1/weights")}}}});
    f.doc["extensionsUsed"] = {"KHR_animation_pointer"};
    return f.glb();
  };
  TempDir dir;
  test::write_bytes(dir / "in.glb", document("SCALAR"));
  test::expect_valid_gltf({dir / "in.glb"});
  const Scene scene = read_scene(dir / "in.glb");
  ASSERT_EQ(scene.animations.size(), 1u);
  const Animation& clip = scene.animations[0];
  ASSERT_EQ(clip.channels.size(), 3u);
  const int32_t nodes[3] = {2, 0, 2};
  const std::vector<float> values[3] = {{1, 0}, {0.25f, 0.75f}, {0.25f, 0.75f}};
  for (size_t c = 0; c < 3; ++c) {
    SCOPED_TRACE(c);
    EXPECT_EQ(clip.channels[c].node, nodes[c]);
    EXPECT_EQ(clip.channels[c].path, AnimationPath::weights);
    EXPECT_EQ(clip.channels[c].components, 1u);
    EXPECT_EQ(clip.channels[c].times, (std::vector<float>{0, 1}));
    EXPECT_EQ(clip.channels[c].values, values[c]);
  }
  EXPECT_EQ(weights_channel(clip, 1), nullptr);
  EXPECT_EQ(weights_channel(clip, 2)->values, values[0]);
  // Written back, the channels are as they were.
  write_scene(scene, dir / "out.glb");
  EXPECT_EQ(test::glb_json(dir / "out.glb")["animations"][0]["channels"], test::glb_json(dir / "in.glb")["animations"][0]["channels"]);
  expect_bad_input(document("VEC3"), "vec3.glb", "animations[0].channels[0] sampler output");
}

// Float weights are written summing to 1 as the validator counts it (in float, within 2e-7 per
// nonzero weight): a vertex off by Draco's 12-bit steps (1 + 1.6e-4) is scaled back, in proportion;
// a vertex already within is written bit for bit.
TEST(GltfWrite, FloatWeightsSumToOne) {
  TempDir dir;
  Scene scene = fixtures::humanoid_scene();
  size_t skinned = scene.primitives.size();
  for (size_t i = 0; i < scene.primitives.size(); ++i)
    if (!scene.primitives[i].mesh.weights.empty()) skinned = i;
  ASSERT_LT(skinned, scene.primitives.size());
  Mesh& mesh = scene.primitives[skinned].mesh;
  const auto float_sum = [](const float4& w) { return ((w.x + w.y) + w.z) + w.w; };
  const auto nonzero = [](const float4& w) { return float((w.x != 0) + (w.y != 0) + (w.z != 0) + (w.w != 0)); };
  const std::vector<float4> original = mesh.weights;
  for (const float4& w : original) ASSERT_LE(std::fabs(float_sum(w) - 1), 2e-7f * nonzero(w));  // (the fixture's are)
  for (size_t v = 0; v < mesh.weights.size(); v += 2)
    for (float* c : {&mesh.weights[v].x, &mesh.weights[v].y, &mesh.weights[v].z, &mesh.weights[v].w}) *c *= 1.00016f;
  write_scene(scene, dir / "w.glb");
  const Mesh back = read_scene(dir / "w.glb").primitives[skinned].mesh;
  ASSERT_EQ(back.weights.size(), original.size());
  for (size_t v = 0; v < original.size(); ++v) {
    SCOPED_TRACE(v);
    const float4& w = back.weights[v];
    EXPECT_LE(std::fabs(float_sum(w) - 1), 2e-7f * nonzero(w));
    if (v % 2) {
      EXPECT_EQ(std::memcmp(&w, &original[v], sizeof(float4)), 0);
    } else {
      for (int k = 0; k < 4; ++k) EXPECT_NEAR((&w.x)[k], (&original[v].x)[k], 3e-7);
    }
  }
  test::expect_valid_gltf({dir / "w.glb"});
}

}  // namespace
}  // namespace lod
