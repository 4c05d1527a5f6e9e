// glTF output with WriteOptions::quantize (KHR_mesh_quantization): the stored integers against
// values worked out by hand, and whole scenes read back within the quantization step of their float
// twin, in world space: plain, matrix and animated nodes, a node with children, a skinned animated
// character (posed), morph targets; every file through the Khronos validator.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <vector>

#include "core/quaternion.h"
#include "core/shapes.h"
#include "lodkit/io.h"
#include "lodkit/skin.h"
#include "skin/fixtures.h"
#include "test_support.h"

namespace lod {
namespace {

using Json = nlohmann::json;
using test::TempDir;

bool contains(const Json& list, const std::string& name) {
  return list.is_array() && std::find(list.begin(), list.end(), name) != list.end();
}

double distance(const float3& a, const float3& b) { return std::hypot(double(a.x) - b.x, double(a.y) - b.y, double(a.z) - b.z); }

// The angle of the rotation between two unit quaternions (q and -q alike): four times the arcsine
// of half their 4D chord, well conditioned when small (written here, apart from lodkit's own).
double rotation_between(const float4& qa, const float4& qb) {
  const double s = double(qa.x) * qb.x + double(qa.y) * qb.y + double(qa.z) * qb.z + double(qa.w) * qb.w < 0 ? -1 : 1;
  const double chord = std::hypot(std::hypot(qa.x - s * qb.x, qa.y - s * qb.y), std::hypot(qa.z - s * qb.z, qa.w - s * qb.w));
  return 4 * std::asin(std::min(chord / 2, 1.0));
}

// The largest distance between corresponding points (the lists have the same length).
double largest_distance(const std::vector<float3>& a, const std::vector<float3>& b) {
  EXPECT_EQ(a.size(), b.size());
  double worst = 0;
  for (size_t v = 0; v < std::min(a.size(), b.size()); ++v) worst = std::max(worst, distance(a[v], b[v]));
  return worst;
}

// The scene written as floats (plain.glb) and quantized (q.glb) into `dir`.
void write_plain_and_quantized(const Scene& scene, const std::filesystem::path& dir) {
  write_scene(scene, dir / "plain.glb");
  write_scene(scene, dir / "q.glb", {.quantize = true});
}

// The accessor's stored components, read from the GLB's BIN chunk without lodkit (bufferView stride
// honoured), as doubles.
template <class T>
std::vector<double> stored(const test::Glb& glb, size_t accessor, size_t components) {
  const Json& a = glb.doc["accessors"][accessor];
  const Json& view = glb.doc["bufferViews"][a["bufferView"].get<size_t>()];
  const size_t stride = view.value("byteStride", components * sizeof(T));
  const size_t start = view.value("byteOffset", size_t(0)) + a.value("byteOffset", size_t(0));
  std::vector<double> out;
  for (size_t i = 0; i < a["count"].get<size_t>(); ++i)
    for (size_t c = 0; c < components; ++c) {
      T v;
      std::memcpy(&v, glb.bin.data() + start + i * stride + c * sizeof(T), sizeof v);
      out.push_back(double(v));
    }
  return out;
}

// One triangle at (1, 2, 3), (4, 2, 3), (1, 3.5, 3.75) with normal +z, on a 3-bit grid: the
// extent is 3 (x), so the step is 3/7 and the offset the low corner (1, 2, 3). By hand:
// x: 0, 7, 0; y: 0, 0, 1.5 * 7/3 = 3.5 -> 4; z: 0, 0, 0.75 * 7/3 = 1.75 -> 2. The normal in
// normalized bytes is (0, 0, 127). The node takes translation (1, 2, 3) and scale 3/7.
TEST(GltfQuantize, StoresTheGridWorkedOutByHand) {
  TempDir dir;
  Mesh m;
  m.positions = {{1, 2, 3}, {4, 2, 3}, {1, 3.5f, 3.75f}};
  m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  m.indices = {0, 1, 2};
  write_scene(scene_from_mesh(m), dir / "q.glb", {.quantize = true, .position_bits = 3});
  const test::Glb glb = test::read_glb(dir / "q.glb");
  EXPECT_TRUE(contains(glb.doc["extensionsUsed"], "KHR_mesh_quantization"));
  EXPECT_TRUE(contains(glb.doc["extensionsRequired"], "KHR_mesh_quantization"));
  const Json& prim = glb.doc["meshes"][0]["primitives"][0];
  const Json& position = glb.doc["accessors"][prim["attributes"]["POSITION"].get<size_t>()];
  EXPECT_EQ(position["componentType"], 5123);  // unsigned short
  EXPECT_FALSE(position.value("normalized", false));
  EXPECT_EQ(position["min"], Json::array({0, 0, 0}));
  EXPECT_EQ(position["max"], Json::array({7, 4, 2}));
  EXPECT_EQ(stored<uint16_t>(glb, prim["attributes"]["POSITION"], 3), (std::vector<double>{0, 0, 0, 7, 0, 0, 0, 4, 2}));
  const Json& normal = glb.doc["accessors"][prim["attributes"]["NORMAL"].get<size_t>()];
  EXPECT_EQ(normal["componentType"], 5120);  // byte
  EXPECT_TRUE(normal["normalized"].get<bool>());
  EXPECT_EQ(stored<int8_t>(glb, prim["attributes"]["NORMAL"], 3), (std::vector<double>{0, 0, 127, 0, 0, 127, 0, 0, 127}));
  const Json& node = glb.doc["nodes"][0];
  EXPECT_EQ(node["translation"], Json::array({1.0, 2.0, 3.0}));
  for (const Json& s : node["scale"]) EXPECT_DOUBLE_EQ(s.get<double>(), 3.0 / 7.0);
  // Read back and placed: the grid points, (1, 2 + 4 * 3/7, 3 + 2 * 3/7) for the third corner.
  const Mesh back = flatten(read_scene(dir / "q.glb"));
  ASSERT_EQ(back.vertex_count(), 3u);
  EXPECT_LT(distance(back.positions[0], {1, 2, 3}), 1e-6);
  EXPECT_LT(distance(back.positions[1], {4, 2, 3}), 1e-6);
  EXPECT_LT(distance(back.positions[2], {1, 2 + 12.0f / 7, 3 + 6.0f / 7}), 1e-6);
  test::expect_valid_gltf({dir / "q.glb"});
}

// A torus with normals, UVs and colours: every stream back within half its step, in world space.
TEST(GltfQuantize, StreamsComeBackWithinHalfAStep) {
  TempDir dir;
  Mesh m = shapes::torus(1.0f, 0.3f, 48, 24);
  for (size_t v = 0; v < m.vertex_count(); ++v)
    m.colors.push_back({m.uvs[0][v].x, m.uvs[0][v].y, 0.25f, 1.0f});
  const Scene scene = scene_from_mesh(m);
  for (const bool compress : {false, true}) {
    const std::filesystem::path path = dir / (compress ? "qc.glb" : "q.glb");
    write_scene(scene, path, {.meshopt_compression = compress, .quantize = true});
    const Mesh back = flatten(read_scene(path));
    ASSERT_EQ(back.vertex_count(), m.vertex_count());
    // The extent is 2.6 (x and y), on 14 bits.
    const double step = 2.6 / 16383;
    double worst = 0, worst_normal = 0, worst_uv = 0, worst_color = 0;
    for (size_t v = 0; v < m.vertex_count(); ++v) {
      const float3 &p = m.positions[v], &q = back.positions[v];
      worst = std::max({worst, std::fabs(double(p.x) - q.x), std::fabs(double(p.y) - q.y), std::fabs(double(p.z) - q.z)});
      const float3 &n = m.normals[v], &k = back.normals[v];
      worst_normal = std::max(worst_normal, distance(n, k));
      worst_uv = std::max({worst_uv, std::fabs(double(m.uvs[0][v].x) - back.uvs[0][v].x), std::fabs(double(m.uvs[0][v].y) - back.uvs[0][v].y)});
      worst_color = std::max({worst_color, std::fabs(double(m.colors[v].x) - back.colors[v].x), std::fabs(double(m.colors[v].z) - back.colors[v].z)});
    }
    EXPECT_LE(worst, step / 2 * 1.001 + 1e-6) << path;
    EXPECT_GT(worst, step / 8) << path;  // it did quantize
    // Within sqrt(3)/254 of the unit normal in bytes, then renormalized by the reader: twice that.
    EXPECT_LE(worst_normal, 2 * std::sqrt(3.0) / 254) << path;
    EXPECT_LE(worst_uv, 0.5 / 65535 + 1e-7) << path;
    EXPECT_LE(worst_color, 0.5 / 255 + 1e-6) << path;
    EXPECT_EQ(back.indices, m.indices);
  }
  // Compressed and quantized: much smaller than either alone, and the same values as quantized.
  write_scene(scene, dir / "plain.glb");
  write_scene(scene, dir / "c.glb", {.meshopt_compression = true});
  EXPECT_LT(std::filesystem::file_size(dir / "qc.glb"), std::filesystem::file_size(dir / "c.glb") * 3 / 4);
  EXPECT_LT(std::filesystem::file_size(dir / "q.glb"), std::filesystem::file_size(dir / "plain.glb") * 3 / 4);
  test::expect_valid_gltf({dir / "q.glb", dir / "qc.glb"});
}

// normal_bits above 8 (the CLI's --normal-bits): normals and tangents in normalized shorts whose
// values are multiples of 2^(16 - bits), or +-32767. By hand: a component moves by at most half a
// multiple, 2^(15 - bits) / 32767 (or 1/32767 where clamped to 32767), so a unit vector by sqrt 3
// times that, and the reader's renormalization at most doubles it. A tangent's handedness stays
// exactly +-1. Bytes make a smaller -c file than shorts.
TEST(GltfQuantize, NormalBitsStoreShortsOnTheirGrid) {
  TempDir dir;
  Mesh m = shapes::torus(1.0f, 0.3f, 48, 24);
  test::add_tangents(m);
  const Scene scene = scene_from_mesh(m);
  std::map<int, double> worst_of;
  std::map<int, uintmax_t> compressed_bytes;
  for (const int bits : {8, 12, 16}) {
    SCOPED_TRACE(bits);
    const std::filesystem::path path = dir / ("q" + std::to_string(bits) + ".glb");
    write_scene(scene, path, {.quantize = true, .normal_bits = bits});
    const test::Glb glb = test::read_glb(path);
    const Json& attributes = glb.doc["meshes"][0]["primitives"][0]["attributes"];
    for (const char* name : {"NORMAL", "TANGENT"}) {
      const Json& accessor = glb.doc["accessors"][attributes[name].get<size_t>()];
      EXPECT_EQ(accessor["componentType"], bits == 8 ? 5120 : 5122) << name;  // byte or short
      EXPECT_TRUE(accessor["normalized"].get<bool>()) << name;
    }
    if (bits > 8) {
      const double multiple = std::exp2(16 - bits);
      size_t off_grid = 0;
      for (const double q : stored<int16_t>(glb, attributes["NORMAL"], 3))
        off_grid += std::fabs(q) != 32767 && std::fmod(q, multiple) != 0;
      EXPECT_EQ(off_grid, 0u);
    }
    const Mesh back = flatten(read_scene(path));
    ASSERT_EQ(back.vertex_count(), m.vertex_count());
    double worst = 0;
    for (size_t v = 0; v < m.vertex_count(); ++v) {
      const float4 &t = m.tangents[v], &k = back.tangents[v];
      worst = std::max({worst, distance(m.normals[v], back.normals[v]), distance({t.x, t.y, t.z}, {k.x, k.y, k.z})});
      EXPECT_EQ(k.w, t.w) << v;
    }
    const double half = bits == 8 ? 0.5 / 127 : std::max(std::exp2(15 - bits), 1.0) / 32767;
    EXPECT_LE(worst, 2 * std::sqrt(3.0) * half);
    EXPECT_GT(worst, half / 8);  // (it did round)
    worst_of[bits] = worst;
    write_scene(scene, dir / "c.glb", {.meshopt_compression = true, .quantize = true, .normal_bits = bits});
    compressed_bytes[bits] = std::filesystem::file_size(dir / "c.glb");
    test::expect_valid_gltf({path, dir / "c.glb"});
  }
  EXPECT_LT(worst_of[12], worst_of[8] / 8);
  EXPECT_LT(compressed_bytes[8], compressed_bytes[12]);
  // A morph target's normal displacements take the same shorts, within the same half multiple.
  Scene morphing = scene;
  MorphTarget target;
  for (const float3& p : m.positions) target.positions.push_back({0.5f * p.z, 0.25f * p.x, -0.4f * p.y});
  for (const float3& n : m.normals) target.normals.push_back({0.1f * n.x, -0.2f * n.z, 0.3f * n.y});
  morphing.primitives[0].targets.push_back(target);
  write_scene(morphing, dir / "morph.glb", {.quantize = true, .normal_bits = 12});
  const Json doc = test::glb_json(dir / "morph.glb");
  EXPECT_EQ(doc["accessors"][doc["meshes"][0]["primitives"][0]["targets"][0]["NORMAL"].get<size_t>()]["componentType"], 5122);
  const std::vector<MorphTarget> back = source_morph_targets(read_scene(dir / "morph.glb"), 0);
  ASSERT_EQ(back.size(), 1u);
  const double worst_displacement = largest_distance(back[0].normals, target.normals);
  EXPECT_LE(worst_displacement, std::sqrt(3.0) * 8 / 32767 + 1e-7);
  EXPECT_GT(worst_displacement, 1.0 / 32767);
  test::expect_valid_gltf({dir / "morph.glb"});
  // Out of range: refused.
  EXPECT_THROW(write_scene(scene, dir / "bad.glb", {.quantize = true, .normal_bits = 7}), std::exception);
  EXPECT_THROW(write_scene(scene, dir / "bad.glb", {.quantize = true, .normal_bits = 17}), std::exception);
  // The CLI's --normal-bits: shorts with -q; out of 8-16, a usage error (exit 1) and no file.
  write_scene(scene, dir / "in.glb");
  test::RunResult r = test::run_cli({"convert", (dir / "in.glb").string(), (dir / "cli.glb").string(), "-q", "--normal-bits", "12"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Json cli = test::glb_json(dir / "cli.glb");
  EXPECT_EQ(cli["accessors"][cli["meshes"][0]["primitives"][0]["attributes"]["NORMAL"].get<size_t>()]["componentType"], 5122);
  r = test::run_cli({"convert", (dir / "in.glb").string(), (dir / "bad.glb").string(), "-q", "--normal-bits", "7"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.glb"));
}

// Four nodes draw one mesh each: a matrix node, a rotated and non-uniformly scaled node, a node with
// a child (which must not take the grid: the mesh moves to a new child), and a node whose
// translation is animated (likewise). World positions match the float file's within the step
// times each node's largest scale; the animated one at a time of its clip too.
TEST(GltfQuantize, NodesPlaceTheGridInWorldSpace) {
  TempDir dir;
  Scene scene;
  const Mesh shapes_[4] = {shapes::torus(1.0f, 0.3f, 24, 12), shapes::cube(), shapes::icosphere(2), shapes::torus(2.0f, 0.5f, 16, 8)};
  for (uint32_t k = 0; k < 4; ++k) {
    Primitive p;
    p.mesh = shapes_[k];
    p.gltf_mesh = k;
    scene.primitives.push_back(std::move(p));
  }
  scene.nodes.resize(5);
  scene.nodes[0].mesh = 0;
  scene.nodes[0].has_matrix = true;
  scene.nodes[0].matrix = {0, 2, 0, 0, -2, 0, 0, 0, 0, 0, 2, 0, 5, 1, -3, 1};  // rotate 90 about z, scale 2, move
  scene.nodes[1].mesh = 1;
  scene.nodes[1].translation = {-4, 0, 1};
  scene.nodes[1].rotation = {0.0f, 0.38268343f, 0.0f, 0.92387953f};  // 45 degrees about y
  scene.nodes[1].scale = {1, 3, 0.5f};
  scene.nodes[2].mesh = 2;
  scene.nodes[2].translation = {0, 6, 0};
  scene.nodes[2].children = {3};
  scene.nodes[3].parent = 2;
  scene.nodes[3].mesh = 3;
  scene.nodes[3].scale = {0.5f, 0.5f, 0.5f};
  scene.nodes[4].mesh = 0;  // the same mesh as node 0, animated
  scene.nodes[4].translation = {0, -6, 0};
  scene.roots = {0, 1, 2, 4};
  Animation clip;
  AnimationChannel slide;
  slide.node = 4;
  slide.times = {0.0f, 1.0f};
  slide.values = {0, -6, 0, 3, -6, 0};
  clip.channels.push_back(slide);
  scene.animations.push_back(clip);

  write_scene(scene, dir / "plain.glb");
  write_scene(scene, dir / "q.glb", {.quantize = true});
  const Scene plain = read_scene(dir / "plain.glb"), quantized = read_scene(dir / "q.glb");
  const Json doc = test::glb_json(dir / "q.glb");
  EXPECT_FALSE(doc["nodes"][2].contains("mesh"));  // moved to a new child
  EXPECT_FALSE(doc["nodes"][4].contains("mesh"));
  EXPECT_TRUE(doc["nodes"][0].contains("mesh"));
  EXPECT_TRUE(doc["nodes"][1].contains("mesh"));
  EXPECT_TRUE(doc["nodes"][3].contains("mesh"));
  ASSERT_EQ(doc["nodes"].size(), 7u);
  const auto mesh_of = [](const Scene& s, int32_t gltf_mesh) -> const Mesh& {
    for (const Primitive& p : s.primitives)
      if (p.gltf_mesh == uint32_t(gltf_mesh)) return p.mesh;
    throw std::runtime_error("no such mesh");
  };
  // The grid spans every mesh: the largest extent is torus 3's 5.0, on 14 bits; node scales up to 3.
  const double step = 5.0 / 16383;
  // Each node's mesh in world space, at rest and (the animated node) at t = 0.5 of its clip; the
  // quantized file draws it from the node itself or from the node's new child.
  for (const float time : {-1.0f, 0.5f}) {
    Pose pa = rest_pose(plain), pb = rest_pose(quantized);
    if (time >= 0) sample_animation(plain, 0, time, pa), sample_animation(quantized, 0, time, pb);
    const std::vector<mat4> wa = world_matrices(plain, pa), wb = world_matrices(quantized, pb);
    for (size_t n = 0; n < 5; ++n) {
      const size_t drawn = doc["nodes"][n].contains("mesh") ? n : doc["nodes"][n]["children"].back().get<size_t>();
      ASSERT_EQ(quantized.nodes[drawn].mesh, plain.nodes[n].mesh) << n;
      const Mesh &ma = mesh_of(plain, plain.nodes[n].mesh), &mb = mesh_of(quantized, quantized.nodes[drawn].mesh);
      ASSERT_EQ(ma.vertex_count(), mb.vertex_count());
      double worst = 0;
      for (size_t v = 0; v < ma.vertex_count(); ++v)
        worst = std::max(worst, distance(transform_point(wa[n], ma.positions[v]), transform_point(wb[drawn], mb.positions[v])));
      const double largest_scale = n == 0 ? 2 : n == 1 ? 3 : n == 3 ? 0.5 : 1;
      EXPECT_LE(worst, largest_scale * step * std::sqrt(3.0) / 2 + 1e-5) << "node " << n << " t = " << time;
      EXPECT_GT(worst, largest_scale * step / 16) << "node " << n;  // it is on the grid
    }
  }
  test::expect_valid_gltf({dir / "q.glb"});
}

// A node that also holds a camera keeps its transform (the camera must not move): a new child draws
// its mesh on the grid. A node with only its mesh takes the grid itself.
TEST(GltfQuantize, ACameraNodeKeepsItsTransform) {
  TempDir dir;
  write_scene(scene_from_mesh(shapes::torus(1.0f, 0.3f, 24, 12)), dir / "plain.glb");
  test::Glb glb = test::read_glb(dir / "plain.glb");
  glb.doc["cameras"] = Json::array({{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}}}}});
  glb.doc["nodes"][0]["camera"] = 0;
  glb.doc["nodes"][0]["translation"] = {0.0, 0.0, 5.0};
  test::write_bytes(dir / "camera.glb", test::glb_bytes(glb));
  write_scene(read_scene(dir / "camera.glb"), dir / "q.glb", {.quantize = true});
  const Json doc = test::glb_json(dir / "q.glb");
  ASSERT_EQ(doc["nodes"].size(), 2u);
  EXPECT_EQ(doc["nodes"][0]["camera"], 0);
  EXPECT_EQ(doc["nodes"][0]["translation"], Json::array({0.0, 0.0, 5.0}));
  EXPECT_FALSE(doc["nodes"][0].contains("scale"));
  EXPECT_FALSE(doc["nodes"][0].contains("mesh"));
  EXPECT_EQ(doc["nodes"][1]["mesh"], 0);
  const Mesh a = flatten(read_scene(dir / "camera.glb")), b = flatten(read_scene(dir / "q.glb"));
  ASSERT_EQ(a.vertex_count(), b.vertex_count());
  const double worst = largest_distance(a.positions, b.positions);
  EXPECT_LE(worst, 2.6 / 16383 * std::sqrt(3.0) / 2 + 1e-6);
  test::expect_valid_gltf({dir / "q.glb"});
}

// A skinned character: the grid goes into the inverse bind matrices. Posed by a clip, each vertex
// lands where the float file's lands when skinned with the same (quantized) weights, within the
// step; the weights sum to exactly 255 and unused joints are 0; rotation keys are shorts.
TEST(GltfQuantize, SkinsTakeTheGridInTheirInverseBindMatrices) {
  TempDir dir;
  write_plain_and_quantized(fixtures::humanoid_scene(), dir.path);
  const Scene plain = read_scene(dir / "plain.glb"), quantized = read_scene(dir / "q.glb");
  const std::vector<SkinnedPrimitive> sa = skinned_primitives(plain), sb = skinned_primitives(quantized);
  ASSERT_EQ(sa.size(), 1u);
  ASSERT_EQ(sb.size(), 1u);
  Mesh a = plain.primitives[sa[0].primitive].mesh;
  const Mesh& b = quantized.primitives[sb[0].primitive].mesh;
  ASSERT_EQ(a.vertex_count(), b.vertex_count());
  for (size_t v = 0; v < b.vertex_count(); ++v) {
    const float sum = b.weights[v].x + b.weights[v].y + b.weights[v].z + b.weights[v].w;
    EXPECT_NEAR(sum, 1.0f, 1e-5f) << v;
    const float w[4] = {b.weights[v].x, b.weights[v].y, b.weights[v].z, b.weights[v].w};
    for (size_t k = 0; k < 4; ++k) {
      if (w[k] == 0) EXPECT_EQ(b.joints[v][k], 0) << v;
      else EXPECT_EQ(b.joints[v][k], a.joints[v][k]) << v;
      EXPECT_NEAR(w[k], (&a.weights[v].x)[k], 2.0 / 255) << v;
    }
  }
  a.joints = b.joints, a.weights = b.weights;  // the same influences: what is left is the grid
  float3 lo, hi;
  bounding_box(a, lo, hi);
  const double step = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) / 16383;
  for (const float time : {0.0f, 0.4f}) {
    Pose pa = rest_pose(plain), pb = rest_pose(quantized);
    sample_animation(plain, 0, time, pa);
    sample_animation(quantized, 0, time, pb);
    SkinnedVertices xa, xb;
    skin_vertices(a, joint_matrices(plain, sa[0].skin, world_matrices(plain, pa)), xa);
    skin_vertices(b, joint_matrices(quantized, sb[0].skin, world_matrices(quantized, pb)), xb);
    const double worst = largest_distance(xa.positions, xb.positions);
    EXPECT_LE(worst, step * std::sqrt(3.0) / 2 + 1e-5) << "t = " << time;
  }
  // The matrices were changed in place: no stale copy is left in the file.
  const Json doc = test::glb_json(dir / "q.glb");
  EXPECT_EQ(std::count_if(doc["accessors"].begin(), doc["accessors"].end(), [](const Json& accessor) { return accessor["type"] == "MAT4"; }), 1);
  // Rotation keys in normalized shorts; translations stay floats; and the keys are those the curves
  // need: at every key time of the plain file (where the piecewise curves of both break), each node's
  // pose lies within the reduction's bound: 2^-12 of the mesh's extent per translation component,
  // at most 2^-7 rad for rotations (plus the shorts' step: 2 |dq| <= 2 / 32767), 2^-14 of a scale
  // track's largest component.
  ASSERT_EQ(plain.animations.size(), quantized.animations.size());
  size_t rotations = 0, keys = 0, kept = 0;
  for (size_t k = 0; k < plain.animations.size(); ++k) {
    ASSERT_EQ(plain.animations[k].channels.size(), quantized.animations[k].channels.size());
    double largest_scale = 0;  // (scale tracks' bound: 2^-14 of it)
    std::set<float> times;
    for (size_t c = 0; c < plain.animations[k].channels.size(); ++c) {
      const AnimationChannel &x = plain.animations[k].channels[c], &y = quantized.animations[k].channels[c];
      ASSERT_EQ(x.path, y.path);
      ASSERT_EQ(x.times.front(), y.times.front());
      ASSERT_EQ(x.times.back(), y.times.back());  // (the clip keeps its length)
      if (x.path == AnimationPath::scale)
        for (const float v : x.values) largest_scale = std::max(largest_scale, std::fabs(double(v)));
      times.insert(x.times.begin(), x.times.end());
      keys += x.times.size(), kept += y.times.size();
      rotations += x.path == AnimationPath::rotation;
    }
    for (const float time : times) {
      Pose pa = rest_pose(plain), pb = rest_pose(quantized);
      sample_animation(plain, k, time, pa);
      sample_animation(quantized, k, time, pb);
      for (size_t n = 0; n < std::min(pa.rotation.size(), pb.rotation.size()); ++n) {
        // (Each joint's own bound depends on its lever; the cap is 2^-7 rad: AnimationsKeepTheKeys
        // checks the bound itself.)
        EXPECT_LE(rotation_between(pa.rotation[n], pb.rotation[n]), 1.0 / 128 + 2.0 / 32767 + 1e-6) << k << " node " << n << " t " << time;
        EXPECT_LE(distance(pa.translation[n], pb.translation[n]), std::sqrt(3.0) * step * 16383 / 4096 + 1e-6) << k << " node " << n;
        EXPECT_LE(distance(pa.scale[n], pb.scale[n]), std::sqrt(3.0) * largest_scale / 16384 + 1e-6) << k << " node " << n;
      }
    }
  }
  EXPECT_LT(kept, keys);  // (the fixture's clips have keys their curves do not need)
  EXPECT_GT(rotations, 0u);
  for (const Json& anim : doc["animations"])
    for (const Json& channel : anim["channels"]) {
      const Json& output = doc["accessors"][anim["samplers"][channel["sampler"].get<size_t>()]["output"].get<size_t>()];
      EXPECT_EQ(output["componentType"], channel["target"]["path"] == "rotation" ? 5122 : 5126);
    }
  test::expect_valid_gltf({dir / "q.glb"});
}

// A mesh with a lines primitive beside its triangles keeps float positions (its node would take the
// grid for both, and lodkit does not rewrite lines); the triangles' normals are still quantized.
TEST(GltfQuantize, AMeshWithLinesKeepsFloatPositions) {
  TempDir dir;
  write_scene(scene_from_mesh(shapes::torus(1.0f, 0.3f, 24, 12)), dir / "plain.glb");
  test::Glb glb = test::read_glb(dir / "plain.glb");
  Json lines = glb.doc["meshes"][0]["primitives"][0];
  lines.erase("indices");
  lines["attributes"] = {{"POSITION", lines["attributes"]["POSITION"]}};
  lines["mode"] = 1;
  glb.doc["meshes"][0]["primitives"].push_back(lines);
  test::write_bytes(dir / "lines.glb", test::glb_bytes(glb));
  write_scene(read_scene(dir / "lines.glb"), dir / "q.glb", {.quantize = true});
  const Json doc = test::glb_json(dir / "q.glb");
  ASSERT_EQ(doc["meshes"][0]["primitives"].size(), 2u);
  for (const Json& prim : doc["meshes"][0]["primitives"])
    EXPECT_EQ(doc["accessors"][prim["attributes"]["POSITION"].get<size_t>()]["componentType"], 5126) << prim.dump();
  const Json& triangles = doc["meshes"][0]["primitives"][0];
  EXPECT_EQ(doc["accessors"][triangles["attributes"]["NORMAL"].get<size_t>()]["componentType"], 5120);
  EXPECT_FALSE(doc["nodes"][0].contains("scale"));
  EXPECT_TRUE(contains(doc["extensionsRequired"], "KHR_mesh_quantization"));
  test::expect_valid_gltf({dir / "q.glb"});
}

// flatten (and so info, compare, render) places a quantized skinned mesh where a viewer draws it
// at rest: every joint carries the grid's dequantization. The float file's mesh is not moved.
TEST(GltfQuantize, FlattenPlacesAQuantizedSkinnedMesh) {
  TempDir dir;
  write_plain_and_quantized(fixtures::humanoid_scene(), dir.path);
  const Scene plain = read_scene(dir / "plain.glb");
  const Mesh a = flatten(plain), b = flatten(read_scene(dir / "q.glb"));
  EXPECT_TRUE(a.positions == plain.primitives[0].mesh.positions);  // bind pose, as before
  ASSERT_EQ(a.vertex_count(), b.vertex_count());
  float3 lo, hi;
  bounding_box(a, lo, hi);
  const double step = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) / 16383;
  const double worst = largest_distance(a.positions, b.positions);
  EXPECT_LE(worst, step * std::sqrt(3.0) / 2 + 1e-5);
  const test::RunResult r = test::run_cli({"compare", (dir / "plain.glb").string(), (dir / "q.glb").string(), "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_LE(nlohmann::json::parse(r.out)["a_to_b"]["hausdorff"].get<double>(), step * std::sqrt(3.0) / 2 + 1e-5);
}

// Morph targets: displacements in grid steps (shorts), so base plus displacement lands within a
// step of the float file's, in world space; normal displacements in normalized bytes.
TEST(GltfQuantize, MorphTargetsMoveOnTheGrid) {
  TempDir dir;
  Scene scene = scene_from_mesh(shapes::torus(1.0f, 0.3f, 32, 16));
  MorphTarget target;
  for (const float3& p : scene.primitives[0].mesh.positions) target.positions.push_back({0.5f * p.z, 0.25f * p.x, -0.4f * p.y});
  for (const float3& n : scene.primitives[0].mesh.normals) target.normals.push_back({0.1f * n.x, -0.2f * n.z, 0.3f * n.y});
  scene.primitives[0].targets.push_back(target);
  // Written from the scene's targets, and from a float file's own (gathered from its accessors).
  write_scene(scene, dir / "plain.glb");
  for (const bool from_file : {false, true}) {
    SCOPED_TRACE(from_file ? "from a float file" : "from the scene");
    write_scene(from_file ? read_scene(dir / "plain.glb") : scene, dir / "q.glb", {.quantize = true});
    const test::Glb glb = test::read_glb(dir / "q.glb");
    const size_t moved = glb.doc["meshes"][0]["primitives"][0]["targets"][0]["POSITION"];
    EXPECT_EQ(glb.doc["accessors"][moved]["componentType"], 5122);  // short
    const size_t turned = glb.doc["meshes"][0]["primitives"][0]["targets"][0]["NORMAL"];
    EXPECT_EQ(glb.doc["accessors"][turned]["componentType"], 5120);  // byte, normalized
    const Scene back = read_scene(dir / "q.glb");
    const std::vector<MorphTarget> targets = source_morph_targets(back, 0);
    ASSERT_EQ(targets.size(), 1u);
    const Mesh placed = flatten(back);  // base positions in world space
    const Mesh& grid = back.primitives[0].mesh;
    // World = grid * scale + offset, so a displacement in steps times the scale is the world one.
    const double scale = glb.doc["nodes"][0]["scale"][0].get<double>(), step = 2.6 / 16383;
    EXPECT_NEAR(scale, step, step * 1e-6);
    double worst = 0;
    for (size_t v = 0; v < grid.vertex_count(); ++v) {
      const float3& d = targets[0].positions[v];
      const float3 morphed{float(placed.positions[v].x + d.x * scale), float(placed.positions[v].y + d.y * scale),
                           float(placed.positions[v].z + d.z * scale)};
      const float3& p = scene.primitives[0].mesh.positions[v];
      const float3 expected{p.x + target.positions[v].x, p.y + target.positions[v].y, p.z + target.positions[v].z};
      worst = std::max(worst, distance(morphed, expected));
    }
    EXPECT_LE(worst, step * std::sqrt(3.0) + 1e-5);  // half a step from the base, half from the displacement
    const double worst_normal = largest_distance(targets[0].normals, target.normals);
    EXPECT_LE(worst_normal, std::sqrt(3.0) * 0.5 / 127 + 1e-6);
    EXPECT_GT(worst_normal, 0.1 / 127);
    test::expect_valid_gltf({dir / "q.glb"});
  }
}

// The CLI's -q (and --position-bits, and with -c): each command's output reads back within the
// step of its float twin, placed; a non-glTF output is refused rather than silently left as it is.
// -q: UVs outside [0, 1] go in normalized shorts on a box, and every texture sampling them gets a
// KHR_texture_transform that maps the stored values back: composed with a texture's own transform
// (offset, rotation, scale), in a core texture and in a material extension's. Checked against the
// extension's formula applied here, per vertex: what each texture samples must not move by more
// than the box's half step, carried through the texture's own scale.
std::array<double, 2> apply_texture_transform(const Json& info, double u, double v) {
  if (!info.contains("extensions") || !info["extensions"].contains("KHR_texture_transform")) return {u, v};
  const Json& t = info["extensions"]["KHR_texture_transform"];
  const Json offset = t.value("offset", Json::array({0.0, 0.0})), scale = t.value("scale", Json::array({1.0, 1.0}));
  const double r = t.value("rotation", 0.0), x = scale[0].get<double>() * u, y = scale[1].get<double>() * v;
  // The extension's GLSL: rotation = mat3(cos, sin, 0, -sin, cos, 0, 0, 0, 1), columns first.
  return {offset[0].get<double>() + std::cos(r) * x - std::sin(r) * y, offset[1].get<double>() + std::sin(r) * x + std::cos(r) * y};
}

// A textured grid: TEXCOORD_0 over [-1.5, 2.25] x [0.5, 3]; material 0 samples it in a plain base
// colour texture, a normal texture with its own transform, and a clearcoat texture.
Json textured_grid_document(const std::filesystem::path& dir, Mesh& m) {
  m = shapes::grid(6, 5);
  for (float2& uv : m.uvs[0]) uv = {-1.5f + 3.75f * uv.x, 0.5f + 2.5f * uv.y};
  m.materials.assign(m.triangle_count(), 0);
  m.material_names = {"tiles"};
  write_scene(scene_from_mesh(m), dir / "plain.gltf");
  Json doc;
  {
    std::ifstream file(dir / "plain.gltf");
    doc = Json::parse(file);
  }
  doc["images"] = {{{"uri", "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg=="}}};
  doc["textures"] = {{{"source", 0}}};
  Json& material = doc["materials"][0];
  material["pbrMetallicRoughness"] = {{"baseColorTexture", {{"index", 0}}}};
  material["normalTexture"] = {{"index", 0},
                               {"extensions", {{"KHR_texture_transform", {{"offset", {0.1, -0.2}}, {"rotation", 0.3}, {"scale", {2.0, 0.5}}}}}}};
  material["extensions"] = {{"KHR_materials_clearcoat", {{"clearcoatFactor", 1.0}, {"clearcoatTexture", {{"index", 0}}}}}};
  doc["extensionsUsed"] = {"KHR_texture_transform", "KHR_materials_clearcoat"};
  return doc;
}

void write_json(const std::filesystem::path& path, const Json& doc) {
  std::ofstream file(path);
  file << doc.dump();
}

TEST(GltfQuantize, UvsOutsideTheUnitSquareTakeABoxThatTheTextureTransformsUndo) {
  TempDir dir;
  Mesh m;
  const Json in = textured_grid_document(dir.path, m);
  write_json(dir / "textured.gltf", in);
  write_scene(read_scene(dir / "textured.gltf"), dir / "q.glb", {.quantize = true});
  const test::Glb glb = test::read_glb(dir / "q.glb");
  EXPECT_TRUE(contains(glb.doc["extensionsRequired"], "KHR_texture_transform"));
  const Json& uv = glb.doc["accessors"][glb.doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"].get<size_t>()];
  ASSERT_EQ(uv["componentType"], 5123);  // unsigned short
  EXPECT_TRUE(uv.value("normalized", false));
  const std::vector<double> q = stored<uint16_t>(glb, &uv - &glb.doc["accessors"][0], 2);
  ASSERT_EQ(q.size(), 2 * m.vertex_count());
  const Json& out = glb.doc["materials"][0];
  const Json* infos[3][2] = {{&in["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"], &out["pbrMetallicRoughness"]["baseColorTexture"]},
                             {&in["materials"][0]["normalTexture"], &out["normalTexture"]},
                             {&in["materials"][0]["extensions"]["KHR_materials_clearcoat"]["clearcoatTexture"],
                              &out["extensions"]["KHR_materials_clearcoat"]["clearcoatTexture"]}};
  for (size_t t = 0; t < 3; ++t) {
    SCOPED_TRACE(t);
    // Half a step of the box (3.75 by 2.5), scaled by the texture's own transform (the normal
    // texture's 2 and 0.5), and a float's rounding of the offsets.
    const double half_step = 0.5 / 65535 * 3.75 * (t == 1 ? 2 : 1) + 1e-6;
    double worst = 0;
    for (size_t v = 0; v < m.vertex_count(); ++v) {
      const auto want = apply_texture_transform(*infos[t][0], m.uvs[0][v].x, m.uvs[0][v].y);
      const auto got = apply_texture_transform(*infos[t][1], q[2 * v] / 65535, q[2 * v + 1] / 65535);
      worst = std::max({worst, std::fabs(want[0] - got[0]), std::fabs(want[1] - got[1])});
    }
    EXPECT_LE(worst, half_step);
    EXPECT_GT(worst, half_step / 64);  // (quantized: not the floats)
  }
  // The same through glTF-Transform: its reading of the stored UVs and of every texture reference's
  // transform, the clearcoat's included.
  if (test::second_reader_available()) {
    const Json before = test::read_with_second_reader(dir / "textured.gltf", "--textures");
    const Json after = test::read_with_second_reader(dir / "q.glb", "--textures");
    const Json stream = test::read_with_second_reader(dir / "q.glb")[0]["attributes"]["TEXCOORD_0"];
    ASSERT_EQ(before.size(), 1u);
    ASSERT_EQ(after.size(), 1u);
    ASSERT_EQ(after[0].size(), 3u);
    ASSERT_EQ(stream["values"].size(), 2 * m.vertex_count());
    EXPECT_TRUE(stream["normalized"].get<bool>());
    const auto sample = [](const Json& ref, double u, double v) {
      if (!ref.contains("transform")) return std::array<double, 2>{u, v};
      const Json& t = ref["transform"];
      const double r = t["rotation"], x = t["scale"][0].get<double>() * u, y = t["scale"][1].get<double>() * v;
      return std::array<double, 2>{t["offset"][0].get<double>() + std::cos(r) * x - std::sin(r) * y,
                                   t["offset"][1].get<double>() + std::sin(r) * x + std::cos(r) * y};
    };
    for (size_t t = 0; t < 3; ++t) {
      SCOPED_TRACE(after[0][t]["slot"].get<std::string>());
      EXPECT_EQ(after[0][t]["slot"], before[0][t]["slot"]);
      EXPECT_TRUE(after[0][t].contains("transform"));
      double worst = 0;
      for (size_t v = 0; v < m.vertex_count(); ++v) {
        const auto want = sample(before[0][t], m.uvs[0][v].x, m.uvs[0][v].y);
        const auto got = sample(after[0][t], stream["values"][2 * v].get<double>() / 65535, stream["values"][2 * v + 1].get<double>() / 65535);
        worst = std::max({worst, std::fabs(want[0] - got[0]), std::fabs(want[1] - got[1])});
      }
      EXPECT_LE(worst, 0.5 / 65535 * 3.75 * 2 + 1e-6);
    }
  }
  // The rest of the material is as it was.
  EXPECT_EQ(out["extensions"]["KHR_materials_clearcoat"]["clearcoatFactor"], 1.0);
  EXPECT_EQ(out["normalTexture"]["index"], 0);
  test::expect_valid_gltf({dir / "q.glb"});
}

// uv_bits below 16 (the CLI's --uv-bits, gltfpack's -vt): every textured set goes on a box, a set
// inside [0, 1] too, its stored values from 0 to 2^bits - 1 (normalized shorts), which the
// textures' transforms map back within half a step of the box, extent / (2 (2^bits - 1)), carried
// through each texture's own scale. The meshopt codec codes the smaller integers in fewer bytes
// (the UV view's compressed length). A 64 x 64 grid textured within [0, 1], unevenly (u^2,
// 0.5 + 0.45 sin(3v + u): a regular grid's UVs code in next to nothing at any bits), with the
// material of textured_grid_document, at 8, 12 and 16 bits.
TEST(GltfQuantize, UvBitsPutEveryTexturedSetOnABox) {
  TempDir dir;
  Mesh m;
  const Json in = textured_grid_document(dir.path, m);
  write_json(dir / "textured.gltf", in);
  Scene scene = read_scene(dir / "textured.gltf");
  m = shapes::grid(64, 64);
  for (float2& uv : m.uvs[0]) uv = {uv.x * uv.x, 0.5f + 0.45f * std::sin(3 * uv.y + uv.x)};
  m.materials.assign(m.triangle_count(), 0);
  m.material_names = scene.primitives[0].mesh.material_names;
  scene.primitives[0].mesh = m;
  const std::vector<float2>& uvs = m.uvs[0];
  ASSERT_EQ(uvs.size(), m.vertex_count());
  std::map<int, uint64_t> compressed;
  for (const int bits : {8, 12, 16}) {
    SCOPED_TRACE(bits);
    write_scene(scene, dir / "q.glb", {.quantize = true, .uv_bits = bits});
    const test::Glb glb = test::read_glb(dir / "q.glb");
    const Json& uv = glb.doc["accessors"][glb.doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"].get<size_t>()];
    ASSERT_EQ(uv["componentType"], 5123);  // unsigned short
    EXPECT_TRUE(uv.value("normalized", false));
    const std::vector<double> q = stored<uint16_t>(glb, &uv - &glb.doc["accessors"][0], 2);
    ASSERT_EQ(q.size(), 2 * m.vertex_count());
    const double top = std::exp2(bits) - 1;
    EXPECT_EQ(*std::max_element(q.begin(), q.end()), top);  // (the box spans the set)
    const Json& out = glb.doc["materials"][0];
    EXPECT_EQ(out["pbrMetallicRoughness"]["baseColorTexture"].contains("extensions"), bits < 16);
    const Json* infos[2][2] = {{&in["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"], &out["pbrMetallicRoughness"]["baseColorTexture"]},
                               {&in["materials"][0]["normalTexture"], &out["normalTexture"]}};
    for (size_t t = 0; t < 2; ++t) {
      double worst = 0;
      for (size_t v = 0; v < m.vertex_count(); ++v) {
        const auto want = apply_texture_transform(*infos[t][0], uvs[v].x, uvs[v].y);
        const auto got = apply_texture_transform(*infos[t][1], q[2 * v] / 65535, q[2 * v + 1] / 65535);
        worst = std::max({worst, std::fabs(want[0] - got[0]), std::fabs(want[1] - got[1])});
      }
      // Half a step of the box (at most 1 by 1), through the normal texture's own transform
      // (rotation 0.3, scale 2 by 0.5: a component moves by at most cos 0.3 x 2 + sin 0.3 x 0.5
      // half steps), and a float's rounding of the box.
      const double half_step = 0.5 / top * (t == 1 ? std::cos(0.3) * 2 + std::sin(0.3) * 0.5 : 1);
      EXPECT_LE(worst, half_step + 1e-6) << t;
      EXPECT_GT(worst, half_step / 64) << t;  // (quantized: not the floats)
    }
    test::expect_valid_gltf({dir / "q.glb"});
    write_scene(scene, dir / "c.glb", {.meshopt_compression = true, .quantize = true, .uv_bits = bits});
    const Json c = test::glb_json(dir / "c.glb");
    const Json& view = c["bufferViews"][c["accessors"][c["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"].get<size_t>()]["bufferView"].get<size_t>()];
    compressed[bits] = view["extensions"]["EXT_meshopt_compression"]["byteLength"].get<uint64_t>();
  }
  EXPECT_LT(compressed[8], compressed[12]);
  EXPECT_LT(compressed[12], compressed[16]);
  // Out of range: refused; the CLI's --uv-bits likewise (a usage error) and in range written so.
  EXPECT_THROW(write_scene(scene, dir / "bad.glb", {.quantize = true, .uv_bits = 17}), std::exception);
  test::RunResult r = test::run_cli({"convert", (dir / "textured.gltf").string(), (dir / "cli.glb").string(), "-q", "--uv-bits", "17"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  r = test::run_cli({"convert", (dir / "textured.gltf").string(), (dir / "cli.glb").string(), "-q", "--uv-bits", "10"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const test::Glb cli = test::read_glb(dir / "cli.glb");
  const size_t accessor = cli.doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"].get<size_t>();
  const std::vector<double> q = stored<uint16_t>(cli, accessor, 2);
  EXPECT_EQ(*std::max_element(q.begin(), q.end()), 1023);
}

// Where a box could not hold, the UVs stay floats and the materials as they were: a material no
// texture of which samples the set, a box wider than 8, a lines primitive drawn with the material
// (kept as it was, in the source's UVs), an animation driving a texture's transform
// (KHR_animation_pointer: it would overwrite the box's).
TEST(GltfQuantize, UvsKeepFloatsWhereNoBoxCanHold) {
  TempDir dir;
  Mesh m;
  const Json base = textured_grid_document(dir.path, m);
  Json untextured = base, wide = base, lines = base, animated = base;
  untextured["materials"][0] = {{"name", "tiles"}};
  untextured.erase("extensionsUsed");
  {
    // TEXCOORD_0's u times 3 (over 11.25): a second buffer holding the wider UVs.
    std::vector<float> floats;
    for (const float2& uv : m.uvs[0]) floats.insert(floats.end(), {uv.x * 3, uv.y});
    const std::vector<uint8_t> bytes(reinterpret_cast<const uint8_t*>(floats.data()),
                                     reinterpret_cast<const uint8_t*>(floats.data() + floats.size()));
    wide["buffers"].push_back({{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + test::base64(bytes)}});
    wide["bufferViews"].push_back({{"buffer", wide["buffers"].size() - 1}, {"byteLength", bytes.size()}});
    Json accessor = wide["accessors"][wide["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"].get<size_t>()];
    accessor["bufferView"] = wide["bufferViews"].size() - 1;
    accessor.erase("byteOffset"), accessor.erase("min"), accessor.erase("max");
    wide["accessors"].push_back(accessor);
    wide["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = wide["accessors"].size() - 1;
  }
  {
    Json line = lines["meshes"][0]["primitives"][0];
    line["mode"] = 1;  // LINES, over the triangles' indices
    lines["meshes"][0]["primitives"].push_back(line);
  }
  {
    // The normal texture's offset from (0, 0) to (0.5, 0.5) over a second.
    const std::vector<float> floats = {0, 1, 0, 0, 0.5f, 0.5f};
    const std::vector<uint8_t> bytes(reinterpret_cast<const uint8_t*>(floats.data()),
                                     reinterpret_cast<const uint8_t*>(floats.data() + floats.size()));
    const size_t buffer = animated["buffers"].size(), view = animated["bufferViews"].size(), accessor = animated["accessors"].size();
    animated["buffers"].push_back({{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + test::base64(bytes)}});
    animated["bufferViews"].push_back({{"buffer", buffer}, {"byteLength", 8}});
    animated["bufferViews"].push_back({{"buffer", buffer}, {"byteOffset", 8}, {"byteLength", 16}});
    animated["accessors"].push_back({{"bufferView", view}, {"componentType", 5126}, {"count", 2}, {"type", "SCALAR"}, {"min", {0}}, {"max", {1}}});
    animated["accessors"].push_back({{"bufferView", view + 1}, {"componentType", 5126}, {"count", 2}, {"type", "VEC2"}});
    const Json target = {{"path", "pointer"},
                         {"extensions", {{"KHR_animation_pointer", {{"pointer", "/materials/0/normalTexture/extensions/KHR_texture_transform/offset"}}}}}};
    animated["animations"] = {{{"samplers", {{{"input", accessor}, {"output", accessor + 1}}}}, {"channels", {{{"sampler", 0}, {"target", target}}}}}};
    animated["extensionsUsed"].push_back("KHR_animation_pointer");
  }
  for (const auto& [name, doc] : {std::pair{"untextured", &untextured}, std::pair{"wide", &wide}, std::pair{"lines", &lines},
                                  std::pair{"animated", &animated}}) {
    SCOPED_TRACE(name);
    write_json(dir / "in.gltf", *doc);
    write_scene(read_scene(dir / "in.gltf"), dir / "q.glb", {.quantize = true});
    const Json out = test::glb_json(dir / "q.glb");
    EXPECT_FALSE(contains(out.value("extensionsRequired", Json::array()), "KHR_texture_transform"));
    const Json& uv = out["accessors"][out["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"].get<size_t>()];
    EXPECT_EQ(uv["componentType"], 5126);  // float
    EXPECT_EQ(out["materials"], (*doc)["materials"]);
    if (doc == &animated) {
      EXPECT_EQ(out["animations"][0]["channels"], animated["animations"][0]["channels"]);
    }
    test::expect_valid_gltf({dir / "q.glb"});
  }
}

// -q keeps the keys a curve needs (the bounds: README, -q). Clips baked at 60 Hz for 10 s: a
// translation moving on a line (2 keys are enough), a smooth translation, rotation and scale, a
// constant scale, and a STEP
// translation with runs of equal keys. A channel holding its node's own value goes (a child
// joint's), unless another clip animates that property (then it restores it) or the clip would get
// shorter. At every baked key time (where the piecewise curves of both files break) each node's
// pose lies within the bound, each channel keeps its time range, the smooth curves lose many keys,
// and the file shrinks; without -q every key stays. With animation_error 8 times the default the
// bounds are 8 times wider and fewer keys stay; at 0 only the keys a curve needs exactly (the
// line's and the constants' ends) go.
TEST(GltfQuantize, AnimationsKeepTheKeysTheirCurvesNeed) {
  TempDir dir;
  Scene scene = scene_from_mesh(shapes::torus(1.0f, 0.3f, 24, 12));
  ASSERT_EQ(scene.nodes.size(), 1u);
  Node joint;  // a child at (0, 1, 0)
  joint.name = "joint", joint.parent = 0, joint.translation = {0, 1, 0};
  scene.nodes[0].children.push_back(1);
  scene.nodes.push_back(joint);
  const auto channel = [](AnimationPath path, Interpolation interpolation, uint32_t components, auto&& f, int32_t node = 0,
                          int seconds = 10) {
    AnimationChannel ch;
    ch.node = node, ch.path = path, ch.interpolation = interpolation, ch.components = components;
    for (int k = 0; k <= 60 * seconds; ++k) {
      const float t = float(k) / 60;
      ch.times.push_back(t);
      const std::array<float, 4> v = f(t);
      ch.values.insert(ch.values.end(), v.begin(), v.begin() + components);
    }
    return ch;
  };
  const auto clip = [&](std::vector<AnimationChannel> channels) {
    Animation a;
    a.channels = std::move(channels);
    return a;
  };
  using P = AnimationPath;
  const Interpolation linear = Interpolation::linear;
  scene.animations = {
      clip({channel(P::translation, linear, 3, [](float t) { return std::array<float, 4>{2 * t, -t, 0.5f, 0}; }),
            channel(P::rotation, linear, 4, [](float t) {
              const float a = 0.8f * std::sin(1.7f * t);  // about (0, 0.6, 0.8)
              return std::array<float, 4>{0, 0.6f * std::sin(a / 2), 0.8f * std::sin(a / 2), std::cos(a / 2)};
            }),
            channel(P::scale, linear, 3, [](float) { return std::array<float, 4>{1, 2, 1, 0}; })}),
      clip({channel(P::translation, linear, 3, [](float t) { return std::array<float, 4>{3 * std::sin(0.25f * t), std::cos(0.5f * t), 0.1f * t, 0}; }),
            channel(P::scale, linear, 3, [](float t) { return std::array<float, 4>{1 + 0.3f * std::sin(0.5f * t), 1, 1, 0}; }),
            // The node's own rotation, which clip 0 animates: it stays.
            channel(P::rotation, linear, 4, [](float) { return std::array<float, 4>{0, 0, 0, 1}; }),
            // The joint's scale, steep to key 1, then flat: key 1's time snaps earlier (1/60 s to
            // 4/256), which would leave its corner to the next segment, which cannot reach it.
            channel(P::scale, linear, 3, [](float t) { return std::array<float, 4>{1 + 4 * std::min(t * 60, 1.0f), 1, 1, 0}; }, 1),
            // The joint where it stands: changes nothing, and goes.
            channel(P::translation, linear, 3, [](float) { return std::array<float, 4>{0, 1, 0, 0}; }, 1)}),
      clip({channel(P::translation, Interpolation::step, 3, [](float t) { return std::array<float, 4>{std::floor(t), 0, 0, 0}; }),
            // The joint's own scale, but for 12 s: the clip would get shorter without it, so it stays.
            channel(P::scale, linear, 3, [](float) { return std::array<float, 4>{1, 1, 1, 0}; }, 1, 12)})};
  write_scene(scene, dir / "plain.glb");
  const Scene plain = read_scene(dir / "plain.glb");
  // Keys kept per clip and channel, with animation_error `factor` times the default; the bounds
  // checked.
  const auto kept_keys = [&](double factor) {
    std::vector<std::vector<size_t>> kept;
    write_scene(scene, dir / "q.glb", {.quantize = true, .animation_error = factor / 4096});
    const Scene quantized = read_scene(dir / "q.glb");
    EXPECT_EQ(quantized.animations.size(), 3u);
    if (quantized.animations.size() != 3) return kept;
    float3 lo, hi;
    bounding_box(scene.primitives[0].mesh, lo, hi);
    const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});  // translations' tolerance: 2^-12 of it
    const size_t channels[3] = {3, 4, 2};
    for (size_t k = 0; k < 3; ++k) {
      SCOPED_TRACE(k);
      EXPECT_EQ(plain.animations[k].channels.size(), scene.animations[k].channels.size());
      EXPECT_EQ(quantized.animations[k].channels.size(), channels[k]);
      if (quantized.animations[k].channels.size() < channels[k]) return kept;
      double largest_scale = 0;  // (scale tracks' bound: 2^-14 of it)
      kept.emplace_back();
      for (size_t c = 0; c < channels[k]; ++c) {
        const AnimationChannel &x = scene.animations[k].channels[c], &y = quantized.animations[k].channels[c];
        EXPECT_EQ(y.node, x.node);
        EXPECT_EQ(y.path, x.path);
        EXPECT_EQ(plain.animations[k].channels[c].times.size(), x.times.size());  // (without -q)
        if (y.times.empty()) return kept;
        EXPECT_EQ(y.times.front(), x.times.front());
        EXPECT_EQ(y.times.back(), x.times.back());
        EXPECT_EQ(y.values.size(), y.times.size() * x.components);
        kept.back().push_back(y.times.size());
        if (x.path == P::scale)
          for (const float v : x.values) largest_scale = std::max(largest_scale, std::fabs(double(v)));
      }
      double worst[3] = {0, 0, 0};  // translation / largest, rotation (rad), scale / largest
      for (const float time : scene.animations[k].channels.back().times) {
        Pose pa = rest_pose(plain), pb = rest_pose(quantized);
        sample_animation(plain, k, time, pa);
        sample_animation(quantized, k, time, pb);
        for (size_t n = 0; n < 2; ++n) {
          worst[0] = std::max(worst[0], distance(pa.translation[n], pb.translation[n]));
          worst[1] = std::max(worst[1], rotation_between(pa.rotation[n], pb.rotation[n]));
          worst[2] = std::max(worst[2], distance(pa.scale[n], pb.scale[n]) / std::max(largest_scale, 1.0));
        }
      }
      // (+ a float's half step at 20, the largest translation, per axis)
      EXPECT_LE(worst[0], factor * std::sqrt(3.0) * extent / 4096 + std::sqrt(3.0) * 20 * 0x1p-24);
      // Node 0's rotations: the reach over its lever, the child 1 unit away plus an eighth of the
      // extent (and the shorts' step).
      EXPECT_LE(worst[1], factor * extent / 4096 / (1 + extent / 8) + 2.0 / 32767 + 1e-6);
      EXPECT_LE(worst[2], factor * std::sqrt(3.0) / 16384 + 1e-6);
    }
    return kept;
  };
  const std::vector<std::vector<size_t>> kept = kept_keys(1);
  ASSERT_EQ(kept.size(), 3u);
  EXPECT_EQ(kept[0][0], 2u);    // a line
  EXPECT_LT(kept[0][1], 300u);  // smooth: many keys go
  EXPECT_EQ(kept[0][2], 2u);    // constant
  EXPECT_LT(kept[1][0], 300u);
  EXPECT_LT(kept[1][1], 200u);
  EXPECT_EQ(kept[1][2], 2u);
  EXPECT_EQ(kept[1][3], 3u);  // 0, key 1 at its own time, the last
  EXPECT_EQ(kept[2][0], 11u);   // STEP: a key where the value changes (t = 0, 1, ..., 10; the last among them)
  EXPECT_EQ(kept[2][1], 2u);    // (constant)
  EXPECT_LT(std::filesystem::file_size(dir / "q.glb"), std::filesystem::file_size(dir / "plain.glb") / 2);
  test::expect_valid_gltf({dir / "q.glb"});
  const auto total = [](const std::vector<std::vector<size_t>>& per_clip) {
    size_t sum = 0;
    for (const auto& channels : per_clip) sum = std::accumulate(channels.begin(), channels.end(), sum);
    return sum;
  };
  const std::vector<std::vector<size_t>> coarse = kept_keys(8);
  ASSERT_EQ(coarse.size(), 3u);
  EXPECT_LT(total(coarse), total(kept) * 3 / 4);
  EXPECT_EQ(coarse[2][0], 11u);  // (STEP: exact either way)
  // At 0: the constants' inner keys go (exactly on their segments); the curves keep all 601.
  const std::vector<std::vector<size_t>> exact = kept_keys(0);
  ASSERT_EQ(exact.size(), 3u);
  EXPECT_EQ(exact[0][1], 601u);
  EXPECT_EQ(exact[0][2], 2u);
  EXPECT_EQ(exact[1][0], 601u);
  EXPECT_EQ(exact[2][0], 11u);
  test::expect_valid_gltf({dir / "q.glb"});
}

// -q takes every s-th key where that costs fewest bytes: eight joints of one clip baked at 60 Hz
// for 10 s, each turning about z by an angle linear between knots every 4 frames, the slope of each
// piece one of eight (pseudo-random per joint), so consecutive pieces seldom line up. Each curve
// needs its keys at the knots where the slope changes, different ones per joint: kept at their own
// times they would cost 4 + 8 bytes a key. Every 4th key (151 of 601) fits every curve exactly, and
// the eight share its times: 8 bytes a key and one time array. The joints then keep the same 151
// times in one accessor, and every baked pose comes back (to the shorts' step).
TEST(GltfQuantize, BakedTracksShareEveryFourthKey) {
  TempDir dir;
  Scene scene = scene_from_mesh(shapes::torus(1.0f, 0.3f, 24, 12));
  ASSERT_EQ(scene.nodes.size(), 1u);
  Animation clip;
  uint32_t state = 12345;
  const auto next = [&state] { return state = state * 1664525u + 1013904223u; };
  for (int j = 0; j < 8; ++j) {
    Node joint;
    joint.name = "joint" + std::to_string(j), joint.parent = 0, joint.translation = {0.1f * float(j), 1, 0};
    scene.nodes[0].children.push_back(uint32_t(scene.nodes.size()));
    scene.nodes.push_back(joint);
    AnimationChannel ch;
    ch.node = int32_t(scene.nodes.size() - 1), ch.path = AnimationPath::rotation, ch.components = 4;
    double angle = 0, slope = 0;
    for (int k = 0; k <= 600; ++k) {
      if (k % 4 == 0) slope = 0.01 * (double(next() >> 29) - 3.5);  // radians a frame, one of eight
      ch.times.push_back(float(k) / 60);
      ch.values.insert(ch.values.end(), {0, 0, float(std::sin(angle / 2)), float(std::cos(angle / 2))});
      angle += slope;
    }
    clip.channels.push_back(std::move(ch));
  }
  scene.animations = {clip};
  write_scene(scene, dir / "q.glb", {.quantize = true});
  const Scene back = read_scene(dir / "q.glb");
  ASSERT_EQ(back.animations.size(), 1u);
  ASSERT_EQ(back.animations[0].channels.size(), 8u);
  for (size_t c = 0; c < 8; ++c) {
    SCOPED_TRACE(c);
    const AnimationChannel &x = clip.channels[c], &y = back.animations[0].channels[c];
    ASSERT_EQ(y.times.size(), 151u);
    for (size_t k = 0; k < y.times.size(); ++k) EXPECT_EQ(y.times[k], x.times[4 * k]);
    // Every baked key, against the slerp of the kept ones around it.
    for (size_t k = 0; k < x.times.size(); ++k) {
      const size_t i = std::min(k / 4, y.times.size() - 2);
      const float s = (x.times[k] - y.times[i]) / (y.times[i + 1] - y.times[i]);
      const float4 q = core::slerp({y.values[4 * i], y.values[4 * i + 1], y.values[4 * i + 2], y.values[4 * i + 3]},
                                   {y.values[4 * i + 4], y.values[4 * i + 5], y.values[4 * i + 6], y.values[4 * i + 7]}, s);
      EXPECT_LE(rotation_between(q, {x.values[4 * k], x.values[4 * k + 1], x.values[4 * k + 2], x.values[4 * k + 3]}), 4.0 / 32767) << k;
    }
  }
  const Json doc = test::glb_json(dir / "q.glb");
  std::set<size_t> inputs;
  for (const Json& sampler : doc["animations"][0]["samplers"]) inputs.insert(sampler["input"].get<size_t>());
  EXPECT_EQ(inputs.size(), 1u);
  test::expect_valid_gltf({dir / "q.glb"});
}

// -q reduces morph weight keys too: a weight may stray by the reach (2^-12 of the extent) over the
// targets' longest displacement, so that no vertex moves by more than the reach. Two targets, a
// clip baked at 60 Hz for 10 s: one weight a sine, the other a ramp (a line for 2 keys).
TEST(GltfQuantize, MorphWeightKeysStayWithinTheirBound) {
  TempDir dir;
  Scene scene = scene_from_mesh(shapes::grid(8, 8));
  ASSERT_EQ(scene.primitives.size(), 1u);
  const Mesh& mesh = scene.primitives[0].mesh;
  double longest = 0;
  for (int k = 0; k < 2; ++k) {
    MorphTarget target;
    for (const float3& p : mesh.positions) target.positions.push_back({0, 0, k == 0 ? 0.25f * p.x : 0.1f * p.y});
    for (const float3& d : target.positions) longest = std::max(longest, std::hypot(double(d.x), double(d.y), double(d.z)));
    scene.primitives[0].targets.push_back(std::move(target));
  }
  AnimationChannel weights;
  weights.node = 0, weights.path = AnimationPath::weights, weights.components = 2;
  for (int k = 0; k <= 600; ++k) {
    const float t = float(k) / 60;
    weights.times.push_back(t);
    weights.values.insert(weights.values.end(), {0.5f + 0.5f * std::sin(t), t / 10});
  }
  Animation clip;
  clip.channels = {weights};
  scene.animations = {clip};
  write_scene(scene, dir / "plain.glb");
  write_scene(scene, dir / "q.glb", {.quantize = true});
  const Scene plain = read_scene(dir / "plain.glb"), quantized = read_scene(dir / "q.glb");
  ASSERT_EQ(quantized.animations.size(), 1u);
  ASSERT_EQ(quantized.animations[0].channels.size(), 1u);
  const AnimationChannel &x = plain.animations[0].channels[0], &y = quantized.animations[0].channels[0];
  ASSERT_EQ(y.components, 2u);
  EXPECT_EQ(x.times.size(), 601u);
  EXPECT_LT(y.times.size(), 300u);
  EXPECT_EQ(y.times.front(), x.times.front());
  EXPECT_EQ(y.times.back(), x.times.back());
  // The grid spans 1 (x and y); the reach is 1/4096, the longest displacement 0.25.
  const double bound = 1.0 / 4096 / longest;
  double worst = 0;
  for (const float t : x.times) {
    float a[2], b[2];
    sample_components(x, t, a);
    sample_components(y, t, b);
    worst = std::max({worst, std::fabs(double(a[0]) - b[0]), std::fabs(double(a[1]) - b[1])});
  }
  EXPECT_LE(worst, bound + 1e-6);
  EXPECT_GT(worst, bound / 64);  // (keys went)
  test::expect_valid_gltf({dir / "q.glb"});
}

TEST(GltfQuantize, CommandsQuantizeWithDashQ) {
  TempDir dir;
  write_scene(scene_from_mesh(shapes::torus(1.0f, 0.25f, 48, 24)), dir / "in.glb");
  for (const std::vector<std::string>& command : std::vector<std::vector<std::string>>{
           {"lod", "--levels", "3"}, {"simplify", "--ratio", "0.3"}, {"optimize"}, {"convert"}}) {
    // (--cc implies -c -q)
    for (const std::vector<std::string>& flags :
         std::vector<std::vector<std::string>>{{"-q"}, {"-q", "-c", "--position-bits", "10"}, {"--cc"}}) {
      SCOPED_TRACE(command[0] + " " + flags.back());
      const bool compressed = flags.size() > 1 || flags[0] == "--cc";
      std::vector<std::string> plain = command, packed = command;
      for (auto* args : {&plain, &packed}) args->insert(args->begin() + 1, (dir / "in.glb").string());
      plain.insert(plain.end(), {"-o", (dir / "plain.glb").string()});
      if (compressed) plain.push_back("-c");  // (lod -c orders its levels for the codec)
      packed.insert(packed.end(), {"-o", (dir / "q.glb").string()});
      packed.insert(packed.end(), flags.begin(), flags.end());
      ASSERT_EQ(test::run_cli(plain).exit_code, 0);
      const test::RunResult r = test::run_cli(packed);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      EXPECT_TRUE(contains(test::glb_json(dir / "q.glb")["extensionsRequired"], "KHR_mesh_quantization"));
      EXPECT_EQ(contains(test::glb_json(dir / "q.glb")["extensionsRequired"], "EXT_meshopt_compression"), compressed);
      const Scene a = read_scene(dir / "plain.glb");
      const Mesh pa = flatten(a), pb = flatten(read_scene(dir / "q.glb"));
      ASSERT_EQ(pa.vertex_count(), pb.vertex_count());
      float3 lo, hi;
      bounding_box(pa, lo, hi);
      const double bits = flags.size() > 1 ? 10 : 14;
      const double step = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) / (std::exp2(bits) - 1);
      const double worst = largest_distance(pa.positions, pb.positions);
      EXPECT_LE(worst, step * std::sqrt(3.0) / 2 * 1.001 + 1e-6);
      EXPECT_GT(worst, step / 8);
      test::expect_valid_gltf({dir / "q.glb"});
    }
  }
  const test::RunResult r = test::run_cli({"convert", (dir / "in.glb").string(), (dir / "out.obj").string(), "-q"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("glTF output"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.obj"));

  // --anim-error: a turn baked at 60 Hz keeps fewer keys at 8 times the default; out of [0, 1] the
  // command refuses.
  Scene turning = scene_from_mesh(shapes::torus(1.0f, 0.25f, 48, 24));
  AnimationChannel turn{.node = 0, .path = AnimationPath::rotation, .components = 4};
  for (int k = 0; k <= 600; ++k) {
    const float t = float(k) / 60, half = 0.4f * std::sin(1.3f * t);
    turn.times.push_back(t);
    turn.values.insert(turn.values.end(), {0, std::sin(half), 0, std::cos(half)});
  }
  turning.animations.push_back({"turn", {turn}});
  write_scene(turning, dir / "turn.glb");
  const auto keys = [&](const std::vector<std::string>& flags) {
    std::vector<std::string> args = {"convert", (dir / "turn.glb").string(), (dir / "k.glb").string(), "-q"};
    args.insert(args.end(), flags.begin(), flags.end());
    const test::RunResult run = test::run_cli(args);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    const Scene back = read_scene(dir / "k.glb");
    return back.animations.size() == 1 ? back.animations[0].channels.at(0).times.size() : size_t(0);
  };
  const size_t fine = keys({}), coarse = keys({"--anim-error", "0.001953125"});
  EXPECT_LT(fine, 601u);
  EXPECT_LT(coarse, fine / 2);
  EXPECT_GT(coarse, 2u);
  for (const std::string bad : {"-1", "2", "nan"}) {
    const test::RunResult refused = test::run_cli({"convert", (dir / "turn.glb").string(), (dir / "k.glb").string(), "-q", "--anim-error", bad});
    EXPECT_NE(refused.exit_code, 0) << bad;
  }
}

}  // namespace
}  // namespace lod
