// Compressed glTF input: EXT_meshopt_compression and KHR_draco_mesh_compression files made by
// independent encoders (Debian's gltfpack and draco_transcoder, installed by scripts/setup.sh), read
// against their uncompressed twin or their source within the quantization step; and broken copies
// of them, refused with a message.
#include <gtest/gtest.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "core/shapes.h"
#include "skin/fixtures.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "test_support.h"

namespace lod {
namespace {

using Json = nlohmann::json;
using test::TempDir;

constexpr const char* kMeshopt = "EXT_meshopt_compression";
constexpr const char* kDraco = "KHR_draco_mesh_compression";

// A torus with normals and UVs (UV seam rows duplicated), written as a plain .glb.
std::filesystem::path write_torus(const TempDir& dir) {
  const std::filesystem::path path = dir / "torus.glb";
  write_scene(scene_from_mesh(shapes::torus(1.0f, 0.25f, 24, 12)), path);
  return path;
}

void run_tool(const std::vector<std::string>& argv) {
  const test::RunResult r = test::run_program(argv);
  ASSERT_EQ(r.exit_code, 0) << argv[0] << ": " << r.err << r.out;
}

const Mesh& only_mesh(const Scene& scene) {
  EXPECT_EQ(scene.primitives.size(), 1u);
  return scene.primitives.at(0).mesh;
}

bool contains(const Json& list, const std::string& name) {
  return list.is_array() && std::find(list.begin(), list.end(), name) != list.end();
}
bool contains(const std::vector<std::string>& list, const std::string& name) {
  return std::find(list.begin(), list.end(), name) != list.end();
}

// Every bufferView's (mode, filter) under the meshopt extension.
std::vector<std::pair<std::string, std::string>> meshopt_views(const Json& doc) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const Json& view : doc["bufferViews"])
    if (view.contains("extensions") && view["extensions"].contains(kMeshopt)) {
      const Json& e = view["extensions"][kMeshopt];
      out.emplace_back(e["mode"].get<std::string>(), e.value("filter", std::string("NONE")));
    }
  return out;
}

float dot3(const float3& a, const float3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
float length3(const float3& a) { return std::sqrt(dot3(a, a)); }
float cosine(const float3& a, const float3& b) { return dot3(a, b) / (length3(a) * length3(b)); }

// `b` is `a` with its vertices and triangles reordered: each vertex of b has exactly the position of
// one vertex of a (a's positions being distinct), its normal exactly (normal_cos 1) or within
// `normal_cos`, and the triangles through that match are a's.
void expect_same_up_to_order(const Mesh& a, const Mesh& b, float normal_cos) {
  ASSERT_EQ(a.vertex_count(), b.vertex_count());
  ASSERT_EQ(a.normals.size(), b.normals.size());
  std::map<std::array<float, 3>, uint32_t> by_position;
  for (size_t v = 0; v < a.vertex_count(); ++v) by_position[{a.positions[v].x, a.positions[v].y, a.positions[v].z}] = uint32_t(v);
  ASSERT_EQ(by_position.size(), a.vertex_count());
  std::vector<uint32_t> match(b.vertex_count());
  size_t unequal_normals = 0;
  float worst = 1.0f;
  for (size_t v = 0; v < b.vertex_count(); ++v) {
    auto it = by_position.find({b.positions[v].x, b.positions[v].y, b.positions[v].z});
    ASSERT_NE(it, by_position.end()) << "vertex " << v << " has no twin";
    match[v] = it->second;
    if (a.normals.empty()) continue;
    const float3 n = b.normals[v], m = a.normals[it->second];
    unequal_normals += n.x != m.x || n.y != m.y || n.z != m.z;
    worst = std::min(worst, cosine(n, m));
  }
  if (normal_cos >= 1.0f) EXPECT_EQ(unequal_normals, 0u);
  else EXPECT_GE(worst, normal_cos);
  EXPECT_EQ(test::canonical_triangles(b.indices, &match), test::canonical_triangles(a.indices));
}

TEST(GltfCompression, MeshoptFilesReadLikeTheirUncompressedTwin) {
  if (!test::program_available("gltfpack")) GTEST_SKIP() << "gltfpack not installed (scripts/setup.sh installs it)";
  TempDir dir;
  const std::string torus = write_torus(dir).string();
  // gltfpack quantizes the same way with and without -c; -c then compresses the same bytes.
  run_tool({"gltfpack", "-i", torus, "-o", (dir / "plain.glb").string()});
  run_tool({"gltfpack", "-i", torus, "-o", (dir / "c.glb").string(), "-c"});
  run_tool({"gltfpack", "-i", torus, "-o", (dir / "cc.glb").string(), "-cc"});
  run_tool({"gltfpack", "-i", torus, "-o", (dir / "cf.glb").string(), "-cf"});

  // The files really are compressed: triangles and attributes, and -cc's octahedral normals.
  const Json c = test::glb_json(dir / "c.glb");
  ASSERT_TRUE(contains(c["extensionsRequired"], kMeshopt));
  const auto c_views = meshopt_views(c);
  EXPECT_NE(std::count(c_views.begin(), c_views.end(), std::pair<std::string, std::string>{"TRIANGLES", "NONE"}), 0);
  EXPECT_NE(std::count(c_views.begin(), c_views.end(), std::pair<std::string, std::string>{"ATTRIBUTES", "NONE"}), 0);
  const auto cc_views = meshopt_views(test::glb_json(dir / "cc.glb"));
  ASSERT_NE(std::count(cc_views.begin(), cc_views.end(), std::pair<std::string, std::string>{"ATTRIBUTES", "OCTAHEDRAL"}), 0);

  // gltfpack orders vertices and triangles for compression with -c, so the twins are compared up to
  // order: the same quantized vertices (matched by position; the torus has no two alike once UVs
  // are gone) and the same triangles, winding included.
  const Scene plain = read_scene(dir / "plain.glb");
  const Mesh& reference = only_mesh(plain);
  ASSERT_EQ(reference.triangle_count(), 576u);
  ASSERT_FALSE(reference.normals.empty());
  for (const char* name : {"c.glb", "cf.glb", "cc.glb"}) {
    SCOPED_TRACE(name);
    const Scene scene = read_scene(dir / name);
    const Mesh& mesh = only_mesh(scene);
    // -cc stores the normals octahedrally (8 bits) instead of as int8 xyz: within a few degrees.
    const float normal_cos = std::string(name) == "cc.glb" ? std::cos(3.0f * 3.14159265f / 180.0f) : 1.0f;
    expect_same_up_to_order(reference, mesh, normal_cos);
  }
  // info names the decoded extension, from the scene and on the command line; the plain twin has none.
  EXPECT_TRUE(contains(read_scene(dir / "c.glb").extensions_used, kMeshopt));
  EXPECT_TRUE(plain.extensions_used.empty() || !contains(plain.extensions_used, kMeshopt));
  const test::RunResult info = test::run_cli({"info", "--json", (dir / "c.glb").string()});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const Json report = Json::parse(info.out);
  EXPECT_TRUE(contains(report["gltf"]["extensions_used"], kMeshopt)) << info.out;
  EXPECT_EQ(report["stats"]["triangles"], 576);
  EXPECT_NE(test::run_cli({"info", (dir / "c.glb").string()}).out.find(kMeshopt), std::string::npos);

  // A decoder never needs -cf's fallback file.
  std::filesystem::remove(dir / "cf.fallback.bin");
  expect_same_up_to_order(reference, only_mesh(read_scene(dir / "cf.glb")), 1.0f);

  // Written back, the file is plain glTF: no compression left, valid, and the same mesh.
  const test::RunResult r = test::run_cli({"convert", (dir / "c.glb").string(), (dir / "out.glb").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Json out = test::glb_json(dir / "out.glb");
  EXPECT_FALSE(contains(out["extensionsUsed"], kMeshopt)) << out.dump();
  EXPECT_FALSE(contains(out["extensionsRequired"], kMeshopt));
  EXPECT_TRUE(meshopt_views(out).empty());
  EXPECT_EQ(out["buffers"].size(), 1u);
  EXPECT_EQ(test::mesh_difference(only_mesh(read_scene(dir / "c.glb")), only_mesh(read_scene(dir / "out.glb"))), "");
  test::expect_valid_gltf({dir / "out.glb"});
}

// The angle between two directions, in degrees: atan2 of |a x b| and a . b in doubles (their lengths
// cancel), well conditioned near 0 where a cosine cannot tell 1e-4 rad from 0.
double degrees(float3 a, float3 b) {
  const double x = double(a.y) * b.z - double(a.z) * b.y, y = double(a.z) * b.x - double(a.x) * b.z, z = double(a.x) * b.y - double(a.y) * b.x;
  return std::atan2(std::hypot(x, y, z), double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z) * 180 / M_PI;
}

// Draco quantizes each attribute on a grid of 2^bits - 1 steps over its largest extent, so a value
// moves at most half a step per component. Returns, per decoded vertex, the one source vertex
// within that of it (positions at `position_bits` over `extent`; UVs at 12 bits over the torus's
// span of 1; the seam copies share positions, not UVs), its 10-bit octahedral normal within a
// degree (a fraction of one in fact).
std::vector<uint32_t> match_within_quantization(const Mesh& source, const Mesh& decoded, int position_bits, float extent) {
  const float position_bound = std::sqrt(3.0f) * 0.5f * extent / float((1 << position_bits) - 1) + 1e-6f;
  const float uv_bound = std::sqrt(2.0f) * 0.5f * 1.0f / float((1 << 12) - 1) + 1e-6f;
  EXPECT_EQ(decoded.normals.size(), source.normals.size() ? decoded.vertex_count() : 0);
  EXPECT_EQ(decoded.uvs[0].size(), source.uvs[0].size() ? decoded.vertex_count() : 0);
  std::vector<uint32_t> match(decoded.vertex_count(), 0);
  for (size_t v = 0; v < decoded.vertex_count(); ++v) {
    int found = 0;
    for (size_t s = 0; s < source.vertex_count(); ++s) {
      const float3 a = decoded.positions[v], b = source.positions[s];
      const float3 d = {a.x - b.x, a.y - b.y, a.z - b.z};
      float uv = 0;
      if (!source.uvs[0].empty()) uv = std::hypot(decoded.uvs[0][v].x - source.uvs[0][s].x, decoded.uvs[0][v].y - source.uvs[0][s].y);
      if (length3(d) <= position_bound && uv <= uv_bound) {
        match[v] = uint32_t(s);
        ++found;
      }
    }
    EXPECT_EQ(found, 1) << "decoded vertex " << v;
    if (!source.normals.empty()) {
      EXPECT_GT(cosine(decoded.normals[v], source.normals[match[v]]), std::cos(3.14159265f / 180.0f)) << "vertex " << v;
    }
  }
  return match;
}

TEST(GltfCompression, DracoFileMatchesItsSourceWithinTheQuantizationStep) {
  if (!test::program_available("draco_transcoder")) GTEST_SKIP() << "draco_transcoder not installed (scripts/setup.sh installs it)";
  TempDir dir;
  const std::filesystem::path torus = write_torus(dir);
  run_tool({"draco_transcoder", "-i", torus.string(), "-o", (dir / "d.glb").string(), "-qp", "14", "-qn", "10", "-qt", "12"});
  const Json doc = test::glb_json(dir / "d.glb");
  ASSERT_TRUE(contains(doc["extensionsRequired"], kDraco));

  const Mesh source = only_mesh(read_scene(torus));
  const Scene decoded_scene = read_scene(dir / "d.glb");
  const Mesh& decoded = only_mesh(decoded_scene);
  ASSERT_EQ(decoded.triangle_count(), source.triangle_count());
  ASSERT_EQ(decoded.normals.size(), decoded.vertex_count());
  ASSERT_EQ(decoded.uvs[0].size(), decoded.vertex_count());

  const std::vector<uint32_t> match = match_within_quantization(source, decoded, 14, 2.5f);
  EXPECT_EQ(test::canonical_triangles(decoded.indices, &match), test::canonical_triangles(source.indices));  // winding included

  // Written back: plain, valid glTF with the decoded mesh.
  const test::RunResult r = test::run_cli({"convert", (dir / "d.glb").string(), (dir / "out.glb").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Json out = test::glb_json(dir / "out.glb");
  EXPECT_FALSE(contains(out["extensionsUsed"], kDraco)) << out.dump();
  EXPECT_FALSE(out["meshes"][0]["primitives"][0].contains("extensions"));
  EXPECT_EQ(test::mesh_difference(decoded, only_mesh(read_scene(dir / "out.glb"))), "");
  test::expect_valid_gltf({dir / "out.glb"});
}

// A skinned, animated character through gltfpack -cc uses all four meshopt filters: octahedral
// normals, quaternion rotations and exponential translations besides plain attributes. Its clips read
// like those of gltfpack's uncompressed output, within the two quantizations.
TEST(GltfCompression, AnimatedCharacterThroughEveryMeshoptFilter) {
  if (!test::program_available("gltfpack")) GTEST_SKIP() << "gltfpack not installed (scripts/setup.sh installs it)";
  TempDir dir;
  write_scene(fixtures::humanoid_scene(), dir / "humanoid.glb");
  run_tool({"gltfpack", "-i", (dir / "humanoid.glb").string(), "-o", (dir / "plain.glb").string()});
  run_tool({"gltfpack", "-i", (dir / "humanoid.glb").string(), "-o", (dir / "cc.glb").string(), "-cc"});
  const auto views = meshopt_views(test::glb_json(dir / "cc.glb"));
  for (const char* filter : {"OCTAHEDRAL", "QUATERNION", "EXPONENTIAL"})
    EXPECT_NE(std::count(views.begin(), views.end(), std::pair<std::string, std::string>{"ATTRIBUTES", filter}), 0) << filter;

  const Scene plain = read_scene(dir / "plain.glb"), packed = read_scene(dir / "cc.glb");
  expect_same_up_to_order(only_mesh(plain), only_mesh(packed), std::cos(3.0f * 3.14159265f / 180.0f));
  ASSERT_EQ(plain.animations.size(), 2u);
  ASSERT_EQ(packed.animations.size(), plain.animations.size());
  size_t rotations = 0, translations = 0;
  for (size_t a = 0; a < plain.animations.size(); ++a) {
    const auto& pc = plain.animations[a].channels;
    const auto& cc = packed.animations[a].channels;
    ASSERT_EQ(pc.size(), cc.size());
    for (size_t c = 0; c < pc.size(); ++c) {
      SCOPED_TRACE("animation " + std::to_string(a) + " channel " + std::to_string(c));
      ASSERT_EQ(pc[c].node, cc[c].node);
      ASSERT_EQ(pc[c].path, cc[c].path);
      EXPECT_EQ(pc[c].times, cc[c].times);  // key times are stored without a filter: exact
      ASSERT_EQ(pc[c].values.size(), cc[c].values.size());
      float largest = 0.0f, worst = 0.0f;
      for (float v : pc[c].values) largest = std::max(largest, std::abs(v));
      if (pc[c].path == AnimationPath::rotation) {
        // q and -q are the same rotation, and the quaternion filter rebuilds the largest component
        // as positive: each key is compared with the nearer sign.
        for (size_t k = 0; k + 3 < pc[c].values.size(); k += 4) {
          float same = 0.0f, flipped = 0.0f;
          for (size_t i = k; i < k + 4; ++i) {
            same = std::max(same, std::abs(pc[c].values[i] - cc[c].values[i]));
            flipped = std::max(flipped, std::abs(pc[c].values[i] + cc[c].values[i]));
          }
          worst = std::max(worst, std::min(same, flipped));
        }
        // 12-bit rotations (gltfpack's default) both ways: each component within 2^-11 of the
        // original in each file, so within 2^-10 of each other; twice that for the renormalization.
        EXPECT_LE(worst, 2.0f / 1024.0f);
        ++rotations;
      } else if (pc[c].path == AnimationPath::translation) {
        for (size_t k = 0; k < pc[c].values.size(); ++k) worst = std::max(worst, std::abs(pc[c].values[k] - cc[c].values[k]));
        // 16-bit mantissas (gltfpack's default) against the largest value of the track.
        EXPECT_LE(worst, 2.0f * largest / 65536.0f + 1e-7f);
        ++translations;
      }
    }
  }
  EXPECT_GT(rotations, 0u);
  EXPECT_GT(translations, 0u);
}

void expect_refused(const test::Glb& glb, const std::string& name, const std::string& needle) {
  SCOPED_TRACE(name);
  const std::vector<uint8_t> bytes = test::glb_bytes(glb);
  const std::string what = test::expect_bad_input([](auto b, const auto& n) { read_gltf(b, n); },
                                                  std::string(bytes.begin(), bytes.end()), name);
  EXPECT_NE(what.find(needle), std::string::npos) << "expected '" << needle << "' in: " << what;
}

TEST(GltfCompression, BrokenMeshoptFilesAreRefused) {
  if (!test::program_available("gltfpack")) GTEST_SKIP() << "gltfpack not installed (scripts/setup.sh installs it)";
  TempDir dir;
  run_tool({"gltfpack", "-i", write_torus(dir).string(), "-o", (dir / "c.glb").string(), "-c"});
  const test::Glb good = test::read_glb(dir / "c.glb");
  ASSERT_NO_THROW(read_gltf(test::glb_bytes(good), "good.glb"));
  // The views in gltfpack's order: one per stream; find the index stream.
  size_t tri = 0;
  while (tri < good.doc["bufferViews"].size() && good.doc["bufferViews"][tri]["extensions"][kMeshopt]["mode"] != "TRIANGLES") ++tri;
  ASSERT_LT(tri, good.doc["bufferViews"].size());
  auto ext = [](test::Glb& g, size_t view) -> Json& { return g.doc["bufferViews"][view]["extensions"][kMeshopt]; };

  test::Glb g = good;
  ext(g, 0)["byteLength"] = good.bin.size() * 2;
  expect_refused(g, "past.glb", "runs past the end of buffers[0]");

  // A declared count far beyond what the compressed bytes can hold: refused before allocating.
  g = good;
  ext(g, tri)["count"] = 2'100'000'000ull;
  g.doc["bufferViews"][tri]["byteLength"] = 2'100'000'000ull * ext(g, tri)["byteStride"].get<uint64_t>();
  expect_refused(g, "count.glb", "cannot come from");

  // Numbers tinygltf would wrap to int (2^32 + 5 reading as 5) are refused on the JSON.
  g = good;
  ext(g, tri)["byteOffset"] = (uint64_t(1) << 32) + 5;
  expect_refused(g, "wrap.glb", "not an integer in 0..2147483647");

  g = good;
  ext(g, tri)["mode"] = "FANS";
  expect_refused(g, "mode.glb", "is not ATTRIBUTES, TRIANGLES or INDICES");

  g = good;
  ext(g, tri)["filter"] = "OCTAHEDRAL";
  expect_refused(g, "filter.glb", "needs mode ATTRIBUTES");

  g = good;
  g.doc["bufferViews"][tri]["byteLength"] = g.doc["bufferViews"][tri]["byteLength"].get<uint64_t>() + 2;
  expect_refused(g, "length.glb", "is not byteStride");

  g = good;
  ext(g, tri)["buffer"] = 1;  // the fallback buffer, which holds nothing
  expect_refused(g, "fallback.glb", "holds no bytes");

  g = good;
  g.bin[ext(g, tri).value("byteOffset", size_t(0))] = 0x00;  // the stream's header byte
  expect_refused(g, "header.glb", "do not decode as TRIANGLES");

  // A vertex stream of codec version 1 (0xa1: meshoptimizer 0.23's, which KHR_meshopt_compression
  // allows) is named as such, not as corrupt.
  size_t attributes = 0;
  while (attributes < good.doc["bufferViews"].size() && good.doc["bufferViews"][attributes]["extensions"][kMeshopt]["mode"] != "ATTRIBUTES")
    ++attributes;
  ASSERT_LT(attributes, good.doc["bufferViews"].size());
  g = good;
  ASSERT_EQ(g.bin[ext(g, attributes).value("byteOffset", size_t(0))], 0xa0);  // version 0, as the spec says
  // A version 0 stream relabelled version 1 (whose blocks start with control bytes) no longer
  // fits its length; an unknown version is named.
  g.bin[ext(g, attributes).value("byteOffset", size_t(0))] = 0xa1;
  expect_refused(g, "v1.glb", "do not decode as ATTRIBUTES data: byte ");
  g.bin[ext(g, attributes).value("byteOffset", size_t(0))] = 0xa2;
  expect_refused(g, "v2.glb", "header 0xa2 is not 0xa0 or 0xa1 (vertex codec version 0 or 1)");

  // Flipped bytes anywhere in the compressed data: read, or refused with a message (never a crash).
  std::mt19937 rng(12345);
  for (int trial = 0; trial < 300; ++trial) {
    g = good;
    for (int k = 0; k < 4; ++k) g.bin[rng() % g.bin.size()] ^= uint8_t(1u << (rng() % 8));
    try {
      read_gltf(test::glb_bytes(g), "flipped.glb");
    } catch (const Error& e) {
      EXPECT_EQ(e.category(), ErrorCategory::bad_input) << e.what();
    }
  }
}

TEST(GltfCompression, BrokenDracoFilesAreRefused) {
  if (!test::program_available("draco_transcoder")) GTEST_SKIP() << "draco_transcoder not installed (scripts/setup.sh installs it)";
  TempDir dir;
  run_tool({"draco_transcoder", "-i", write_torus(dir).string(), "-o", (dir / "d.glb").string()});
  const test::Glb good = test::read_glb(dir / "d.glb");
  ASSERT_NO_THROW(read_gltf(test::glb_bytes(good), "good.glb"));
  auto ext = [](test::Glb& g) -> Json& { return g.doc["meshes"][0]["primitives"][0]["extensions"][kDraco]; };
  const size_t view = ext(const_cast<test::Glb&>(good))["bufferView"].get<size_t>();

  test::Glb g = good;
  g.doc["bufferViews"][view]["byteLength"] = 16;
  expect_refused(g, "truncated.glb", "does not decode as a Draco mesh");

  g = good;
  const size_t position = g.doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<size_t>();
  g.doc["accessors"][position]["count"] = g.doc["accessors"][position]["count"].get<uint64_t>() + 1;
  expect_refused(g, "count.glb", "but the Draco mesh has");

  g = good;
  ext(g)["attributes"]["POSITION"] = 99;
  expect_refused(g, "id.glb", "no attribute with unique id 99");

  g = good;
  ext(g)["attributes"]["TEXCOORD_5"] = 0;
  expect_refused(g, "semantic.glb", "has no TEXCOORD_5 attribute");

  g = good;
  g.doc["meshes"][0]["primitives"][0]["mode"] = 5;
  expect_refused(g, "strip.glb", "Draco triangle lists");

  // Fewer trials than for meshopt: Draco 1.5.5 spends seconds on some corrupted streams (a UV
  // prediction's declared orientation count, up to 2^31, drives a bit-decoding loop).
  std::mt19937 rng(54321);
  const size_t offset = good.doc["bufferViews"][view].value("byteOffset", size_t(0));
  const size_t length = good.doc["bufferViews"][view]["byteLength"].get<size_t>();
  for (int trial = 0; trial < 60; ++trial) {
    g = good;
    for (int k = 0; k < 4; ++k) g.bin[offset + rng() % length] ^= uint8_t(1u << (rng() % 8));
    try {
      read_gltf(test::glb_bytes(g), "flipped.glb");
    } catch (const Error& e) {
      EXPECT_EQ(e.category(), ErrorCategory::bad_input) << e.what();
    }
  }
}

// A file that declares a compression extension it never uses reads as it is, and is written
// without the declaration.
TEST(GltfCompression, UnusedDeclarationsAreDropped) {
  TempDir dir;
  write_scene(scene_from_mesh(shapes::cube()), dir / "cube.glb");
  test::Glb g = test::read_glb(dir / "cube.glb");
  g.doc["extensionsUsed"] = {kDraco, kMeshopt};
  g.doc["extensionsRequired"] = {kDraco, kMeshopt};
  test::write_bytes(dir / "declared.glb", test::glb_bytes(g));
  const Scene scene = read_scene(dir / "declared.glb");
  EXPECT_EQ(test::mesh_difference(only_mesh(scene), only_mesh(read_scene(dir / "cube.glb"))), "");
  write_scene(scene, dir / "out.glb");
  const Json out = test::glb_json(dir / "out.glb");
  EXPECT_FALSE(out.contains("extensionsUsed")) << out.dump();
  EXPECT_FALSE(out.contains("extensionsRequired"));
}

// ---- writing --------------------------------------------------------------------------------------

// `b` is `a` but for the index codec's rotations: every stream equal, and triangle t of each the same
// three vertices in the same cyclic order (winding kept).
std::string difference_but_rotations(const Mesh& a, const Mesh& b) {
  if (a.indices.size() != b.indices.size()) return "triangle counts differ";
  Mesh rotated = b;
  for (size_t t = 0; t + 2 < a.indices.size(); t += 3) {
    bool found = false;
    for (size_t r = 0; r < 3 && !found; ++r)
      if (b.indices[t + r] == a.indices[t] && b.indices[t + (r + 1) % 3] == a.indices[t + 1] &&
          b.indices[t + (r + 2) % 3] == a.indices[t + 2])
        found = true;
    if (!found) return "triangle " + std::to_string(t / 3) + " is not a rotation of the input's";
    std::copy(a.indices.begin() + ptrdiff_t(t), a.indices.begin() + ptrdiff_t(t + 3), rotated.indices.begin() + ptrdiff_t(t));
  }
  return test::mesh_difference(a, rotated);
}

// The compressed bytes of each meshopt view: (mode, first byte), from a .glb lodkit wrote (one BIN).
std::vector<std::pair<std::string, uint8_t>> meshopt_headers(const test::Glb& glb) {
  std::vector<std::pair<std::string, uint8_t>> out;
  for (const Json& view : glb.doc["bufferViews"])
    if (view.contains("extensions") && view["extensions"].contains(kMeshopt)) {
      const Json& e = view["extensions"][kMeshopt];
      EXPECT_EQ(e["buffer"], 0);
      out.emplace_back(e["mode"].get<std::string>(), glb.bin.at(e["byteOffset"].get<size_t>()));
    }
  return out;
}

// Written with WriteOptions::meshopt_compression, a mesh reads back as its plain twin (bit for bit
// but for triangles starting at another corner), from a smaller file that declares and requires the extension, keeps every compressed view's place
// in a fallback buffer without bytes, and passes the Khronos validator. The streams start with the
// codec versions EXT_meshopt_compression admits: 0xa0 (vertex codec 0), 0xe1 (index codec 1).
TEST(GltfCompression, MeshoptOutputReadsBackExactly) {
  TempDir dir;
  const Scene torus = scene_from_mesh(shapes::torus(1.0f, 0.25f, 96, 48));
  write_scene(torus, dir / "plain.glb");
  write_scene(torus, dir / "c.glb", {.meshopt_compression = true});
  write_scene(torus, dir / "c.gltf", {.meshopt_compression = true});
  EXPECT_LT(std::filesystem::file_size(dir / "c.glb"), std::filesystem::file_size(dir / "plain.glb") * 3 / 4);

  const test::Glb c = test::read_glb(dir / "c.glb");
  EXPECT_TRUE(contains(c.doc["extensionsUsed"], kMeshopt));
  EXPECT_TRUE(contains(c.doc["extensionsRequired"], kMeshopt));
  ASSERT_EQ(c.doc["buffers"].size(), 2u);
  EXPECT_EQ(c.doc["buffers"][1]["extensions"][kMeshopt]["fallback"], true);
  EXPECT_FALSE(c.doc["buffers"][1].contains("uri"));
  const auto headers = meshopt_headers(c);
  EXPECT_NE(std::count(headers.begin(), headers.end(), std::pair<std::string, uint8_t>{"TRIANGLES", 0xe1}), 0);
  EXPECT_NE(std::count(headers.begin(), headers.end(), std::pair<std::string, uint8_t>{"ATTRIBUTES", 0xa0}), 0);
  EXPECT_EQ(headers.size(), size_t(std::count_if(headers.begin(), headers.end(), [](const auto& h) {
              return (h.first == "TRIANGLES" && h.second == 0xe1) || (h.first == "ATTRIBUTES" && h.second == 0xa0);
            })));
  for (const Json& view : c.doc["bufferViews"])  // positions, normals, UVs, indices: all compressed
    EXPECT_EQ(view["buffer"], 1) << view.dump();

  const Mesh plain = only_mesh(read_scene(dir / "plain.glb"));
  EXPECT_EQ(difference_but_rotations(plain, only_mesh(read_scene(dir / "c.glb"))), "");
  EXPECT_EQ(difference_but_rotations(plain, only_mesh(read_scene(dir / "c.gltf"))), "");
  test::expect_valid_gltf({dir / "c.glb", dir / "c.gltf"});

  // Triangles with a repeated corner (as files hold them) come back as rotations too (fuzzing found
  // the codec turning (3, 0, 3) into (3, 3, 0)).
  Mesh degenerate = shapes::torus(1.0f, 0.25f, 12, 6);
  for (size_t t = 0; t < degenerate.triangle_count(); t += 3) degenerate.indices[3 * t + 2] = degenerate.indices[3 * t];
  write_scene(scene_from_mesh(degenerate), dir / "d.glb", {.meshopt_compression = true});
  EXPECT_EQ(difference_but_rotations(degenerate, only_mesh(read_scene(dir / "d.glb"))), "");
  // (The decoder is the one the gltfpack-made files above check; gltfpack 0.18 itself refuses
  // compressed input, so it cannot check the encoder.)

  // A fallback flag that is not a boolean (malformed; fuzzing found it throwing a JSON type error
  // out of the reader): the buffer without bytes is still read as a fallback.
  test::Glb odd = c;
  odd.doc["buffers"][1]["extensions"][kMeshopt]["fallback"] = 5120;
  test::write_bytes(dir / "odd.glb", test::glb_bytes(odd));
  EXPECT_EQ(difference_but_rotations(plain, only_mesh(read_scene(dir / "odd.glb"))), "");
}

// A skinned, animated character: its mesh (joints and weights too) and skin matrices are compressed
// and read back exactly (triangles up to rotation), as do its clips, whose 80-byte tracks stay plain
// (the codec's header and tail would make them larger).
TEST(GltfCompression, MeshoptOutputOfAnAnimatedCharacterIsLossless) {
  TempDir dir;
  const Scene humanoid = fixtures::humanoid_scene();
  write_scene(humanoid, dir / "plain.glb");
  write_scene(humanoid, dir / "c.glb", {.meshopt_compression = true});
  const Scene plain = read_scene(dir / "plain.glb"), packed = read_scene(dir / "c.glb");
  EXPECT_EQ(difference_but_rotations(only_mesh(plain), only_mesh(packed)), "");
  ASSERT_EQ(plain.skins.size(), packed.skins.size());
  for (size_t s = 0; s < plain.skins.size(); ++s) EXPECT_EQ(plain.skins[s].inverse_bind_matrices, packed.skins[s].inverse_bind_matrices);
  ASSERT_EQ(plain.animations.size(), 2u);
  ASSERT_EQ(packed.animations.size(), 2u);
  for (size_t a = 0; a < 2; ++a) {
    ASSERT_EQ(plain.animations[a].channels.size(), packed.animations[a].channels.size());
    for (size_t k = 0; k < plain.animations[a].channels.size(); ++k) {
      EXPECT_EQ(plain.animations[a].channels[k].times, packed.animations[a].channels[k].times);
      EXPECT_EQ(plain.animations[a].channels[k].values, packed.animations[a].channels[k].values);
    }
  }
  // Every view of 1 KiB or more is compressed: the skin's matrices (1,088 bytes) and the mesh's streams.
  const Json doc = test::glb_json(dir / "c.glb");
  const size_t matrices = doc["accessors"][doc["skins"][0]["inverseBindMatrices"].get<size_t>()]["bufferView"];
  EXPECT_TRUE(doc["bufferViews"][matrices].contains("extensions"));
  for (const Json& view : doc["bufferViews"])
    EXPECT_EQ(view["byteLength"].get<size_t>() >= 1024, view.contains("extensions")) << view.dump();
  test::expect_valid_gltf({dir / "c.glb"});
}

// A mesh's triangles as sorted lists of their corners' values (position, normal, first UVs), each
// triangle at its smallest rotation: equal for meshes with the same triangles in any order.
std::vector<std::array<std::array<float, 8>, 3>> corner_triangles(const Mesh& m) {
  const auto corner = [&](uint32_t v) {
    const float3 n = m.normals.empty() ? float3{} : m.normals[v];
    const float2 t = m.uvs[0].empty() ? float2{} : m.uvs[0][v];
    return std::array<float, 8>{m.positions[v].x, m.positions[v].y, m.positions[v].z, n.x, n.y, n.z, t.x, t.y};
  };
  std::vector<std::array<std::array<float, 8>, 3>> out;
  for (size_t k = 0; k + 2 < m.indices.size(); k += 3) {
    const auto a = corner(m.indices[k]), b = corner(m.indices[k + 1]), c = corner(m.indices[k + 2]);
    out.push_back(std::min({std::array{a, b, c}, std::array{b, c, a}, std::array{c, a, b}}));
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The CLI's -c: a LOD chain and a simplified mesh, compressed, read back like their plain twins
// (the chain's levels in another triangle order: lod -c orders them for the codec).
TEST(GltfCompression, CommandsWriteCompressedWithDashC) {
  TempDir dir;
  write_scene(scene_from_mesh(shapes::torus(1.0f, 0.25f, 48, 24)), dir / "in.glb");
  for (const std::vector<std::string>& command : std::vector<std::vector<std::string>>{
           {"lod", "--levels", "3"}, {"simplify", "--ratio", "0.3"}, {"optimize"}, {"convert"}}) {
    SCOPED_TRACE(command[0]);
    std::vector<std::string> plain = command, packed = command;
    for (auto* args : {&plain, &packed}) args->insert(args->begin() + 1, (dir / "in.glb").string());
    plain.insert(plain.end(), {"-o", (dir / "plain.glb").string()});
    packed.insert(packed.end(), {"-o", (dir / "c.glb").string(), "-c"});
    ASSERT_EQ(test::run_cli(plain).exit_code, 0);
    const test::RunResult r = test::run_cli(packed);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(contains(test::glb_json(dir / "c.glb")["extensionsRequired"], kMeshopt));
    const Scene a = read_scene(dir / "plain.glb"), b = read_scene(dir / "c.glb");
    ASSERT_EQ(a.primitives.size(), b.primitives.size());
    for (size_t i = 0; i < a.primitives.size(); ++i) {
      if (command[0] == "lod") EXPECT_EQ(corner_triangles(a.primitives[i].mesh), corner_triangles(b.primitives[i].mesh)) << i;
      else EXPECT_EQ(difference_but_rotations(a.primitives[i].mesh, b.primitives[i].mesh), "") << i;
    }
    test::expect_valid_gltf({dir / "c.glb"});
  }
}

// ---- writing Draco ----------------------------------------------------------------------------------

// Written with WriteOptions::draco, the torus reads back within Draco's quantization steps, every
// triangle with its winding (Edgebreaker may renumber vertices and triangles), from a file much
// smaller than the plain one, whose primitive's accessors have no bufferView and that requires the
// extension; it passes the validator. Its stream decodes with Debian's draco_decoder too.
TEST(GltfCompression, DracoOutputMatchesItsSourceWithinTheQuantizationStep) {
  TempDir dir;
  const Mesh source = shapes::torus(1.0f, 0.25f, 24, 12);
  WriteOptions o;
  o.draco = true;
  write_scene(scene_from_mesh(source), dir / "d.glb", o);
  write_scene(scene_from_mesh(source), dir / "plain.glb");
  EXPECT_LT(std::filesystem::file_size(dir / "d.glb"), std::filesystem::file_size(dir / "plain.glb") / 3);
  const Json doc = test::glb_json(dir / "d.glb");
  ASSERT_TRUE(contains(doc["extensionsRequired"], kDraco));
  ASSERT_TRUE(contains(doc["extensionsUsed"], kDraco));
  const Json& prim = doc["meshes"][0]["primitives"][0];
  ASSERT_TRUE(prim["extensions"].contains(kDraco));
  for (const auto& [semantic, accessor] : prim["attributes"].items()) {
    EXPECT_FALSE(doc["accessors"][accessor.get<size_t>()].contains("bufferView")) << semantic;
    EXPECT_TRUE(prim["extensions"][kDraco]["attributes"].contains(semantic)) << semantic;
  }
  EXPECT_FALSE(doc["accessors"][prim["indices"].get<size_t>()].contains("bufferView"));
  test::expect_valid_gltf({dir / "d.glb"});

  const Mesh decoded = only_mesh(read_scene(dir / "d.glb"));
  ASSERT_EQ(decoded.triangle_count(), source.triangle_count());
  const std::vector<uint32_t> match = match_within_quantization(source, decoded, 14, 2.5f);
  EXPECT_EQ(test::canonical_triangles(decoded.indices, &match), test::canonical_triangles(source.indices));

  // Fewer position bits: a coarser grid, still within its step.
  o.position_bits = 8;
  write_scene(scene_from_mesh(source), dir / "d8.glb", o);
  const Mesh coarse = only_mesh(read_scene(dir / "d8.glb"));
  const float step = 2.5f / 255.0f;
  float worst = 0;
  for (const float3& p : coarse.positions) {
    float nearest = INFINITY;
    for (const float3& q : source.positions) nearest = std::min(nearest, length3({p.x - q.x, p.y - q.y, p.z - q.z}));
    worst = std::max(worst, nearest);
  }
  EXPECT_LE(worst, std::sqrt(3.0f) * 0.5f * step + 1e-6f);
  EXPECT_GT(worst, 0.01f * step);  // (8 bits do move the vertices)

  // normal_bits: the normals' octahedral grid, 10 bits by default. At 16, 2^6 times finer: the
  // largest angle from the source normal falls by more than 16 times (the positions, 14 bits,
  // still match each vertex to its source).
  const auto worst_normal = [&](const std::filesystem::path& path) {
    const Mesh m = only_mesh(read_scene(path));
    const std::vector<uint32_t> to = match_within_quantization(source, m, 14, 2.5f);
    double angle = 0;
    for (size_t v = 0; v < m.vertex_count(); ++v) angle = std::max(angle, degrees(m.normals[v], source.normals[to[v]]));
    return angle;
  };
  o.position_bits = 14;
  o.normal_bits = 16;
  write_scene(scene_from_mesh(source), dir / "d16.glb", o);
  const double coarse_normals = worst_normal(dir / "d.glb"), fine_normals = worst_normal(dir / "d16.glb");
  EXPECT_GT(coarse_normals, 0.0);
  EXPECT_LT(fine_normals, coarse_normals / 16);
  test::expect_valid_gltf({dir / "d16.glb"});

  if (test::program_available("draco_decoder")) {
    // The stream alone, through Draco's own command-line decoder.
    const test::Glb glb = test::read_glb(dir / "d.glb");
    const Json& view = doc["bufferViews"][prim["extensions"][kDraco]["bufferView"].get<size_t>()];
    const size_t offset = view.value("byteOffset", size_t(0)), length = view["byteLength"].get<size_t>();
    test::write_bytes(dir / "stream.drc", std::vector<uint8_t>(glb.bin.begin() + ptrdiff_t(offset), glb.bin.begin() + ptrdiff_t(offset + length)));
    run_tool({"draco_decoder", "-i", (dir / "stream.drc").string(), "-o", (dir / "stream.obj").string()});
    EXPECT_EQ(read_mesh(dir / "stream.obj").triangle_count(), source.triangle_count());
  }
}

// A morph target that displaces each vertex by a linear function of its position.
MorphTarget linear_target(const std::vector<float3>& positions) {
  MorphTarget target;
  for (const float3& p : positions) target.positions.push_back({0.5f * p.z, 0.25f * p.x, -0.4f * p.y});
  return target;
}

// The encoding method of each Draco stream in a .glb, in mesh order (the byte after the "DRACO"
// magic, the version and the encoder type: 0 sequential, 1 Edgebreaker).
std::vector<int> draco_methods(const std::filesystem::path& path) {
  const test::Glb glb = test::read_glb(path);
  std::vector<int> out;
  for (const Json& mesh : glb.doc["meshes"])
    for (const Json& prim : mesh["primitives"]) {
      if (!prim.contains("extensions") || !prim["extensions"].contains(kDraco)) continue;
      const Json& view = glb.doc["bufferViews"][prim["extensions"][kDraco]["bufferView"].get<size_t>()];
      const size_t offset = view.value("byteOffset", size_t(0));
      EXPECT_EQ(std::string(glb.bin.begin() + ptrdiff_t(offset), glb.bin.begin() + ptrdiff_t(offset + 5)), "DRACO");
      out.push_back(glb.bin.at(offset + 8));
    }
  return out;
}

// A primitive with a morph target is still encoded with Edgebreaker, which renumbers its vertices;
// the target, stored plain outside the stream, follows them: each decoded vertex's displacement is
// exactly the one of the source vertex it decodes from (matched within a position step), and the
// triangles through that match are the source's.
TEST(GltfCompression, DracoMorphTargetsFollowEdgebreakersVertexOrder) {
  TempDir dir;
  Scene scene = scene_from_mesh(shapes::torus(1.0f, 0.3f, 20, 10));
  const Mesh source = scene.primitives[0].mesh;
  MorphTarget target = linear_target(source.positions);
  for (const float3& p : source.positions) target.normals.push_back({0.1f * p.y, 0.2f * p.z, 0.3f * p.x});
  scene.primitives[0].targets.push_back(target);
  WriteOptions o;
  o.draco = true;
  write_scene(scene, dir / "m.glb", o);
  test::expect_valid_gltf({dir / "m.glb"});
  EXPECT_EQ(draco_methods(dir / "m.glb"), std::vector<int>{1});
  const Scene back = read_scene(dir / "m.glb");
  const Mesh& m = only_mesh(back);
  ASSERT_EQ(m.vertex_count(), source.vertex_count());
  const std::vector<uint32_t> match = match_within_quantization(source, m, 14, 2.6f);
  EXPECT_EQ(test::canonical_triangles(m.indices, &match), test::canonical_triangles(source.indices));
  EXPECT_NE(match, [&] {
    std::vector<uint32_t> identity(m.vertex_count());
    std::iota(identity.begin(), identity.end(), 0u);
    return identity;
  }()) << "Edgebreaker kept the order: the test shows nothing";
  const std::vector<MorphTarget> targets = source_morph_targets(back, 0);
  ASSERT_EQ(targets.size(), 1u);
  ASSERT_EQ(targets[0].positions.size(), m.vertex_count());
  ASSERT_EQ(targets[0].normals.size(), m.vertex_count());
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    EXPECT_EQ(targets[0].positions[v], target.positions[match[v]]) << v;
    EXPECT_EQ(targets[0].normals[v], target.normals[match[v]]) << v;
  }
}

// A LOD chain of a glTF source with its own morph target: each level's target is gathered from the
// source (written anew, outside the Draco stream) and follows Edgebreaker's renumbering. Against
// the same chain written plain, matched by position: the same displacement, exactly.
TEST(GltfCompression, DracoLevelsCarryTheSourcesMorphTargets) {
  TempDir dir;
  Scene scene = scene_from_mesh(shapes::torus(1.0f, 0.3f, 32, 16));
  scene.primitives[0].targets.push_back(linear_target(scene.primitives[0].mesh.positions));
  write_scene(scene, dir / "in.glb");
  for (const char* name : {"plain.glb", "d.glb"}) {
    std::vector<std::string> argv = {"lod", (dir / "in.glb").string(), "-o", (dir / name).string(), "--levels", "3"};
    if (std::string(name) == "d.glb") argv.push_back("--draco");
    const test::RunResult r = test::run_cli(argv);
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  test::expect_valid_gltf({dir / "d.glb"});
  EXPECT_EQ(draco_methods(dir / "d.glb"), (std::vector<int>{1, 1, 1}));
  const Scene plain = read_scene(dir / "plain.glb"), packed = read_scene(dir / "d.glb");
  ASSERT_EQ(packed.primitives.size(), 3u);
  ASSERT_EQ(plain.primitives.size(), 3u);
  for (size_t level = 0; level < 3; ++level) {
    const Mesh &a = plain.primitives[level].mesh, &b = packed.primitives[level].mesh;
    ASSERT_EQ(a.vertex_count(), b.vertex_count()) << level;
    const std::vector<uint32_t> match = match_within_quantization(a, b, 14, 2.6f);
    EXPECT_EQ(test::canonical_triangles(b.indices, &match), test::canonical_triangles(a.indices)) << level;
    const std::vector<MorphTarget> ta = source_morph_targets(plain, level), tb = source_morph_targets(packed, level);
    ASSERT_EQ(ta.size(), 1u);
    ASSERT_EQ(tb.size(), 1u);
    ASSERT_EQ(tb[0].positions.size(), b.vertex_count());
    size_t moved = 0;
    for (size_t v = 0; v < b.vertex_count(); ++v) {
      EXPECT_EQ(tb[0].positions[v], ta[0].positions[match[v]]) << level << " " << v;
      moved += match[v] != v;
    }
    EXPECT_GT(moved, 0u) << level;
  }
}

// `mesh` (and its one morph target) as a plain .glb whose primitive also has an application
// attribute `_ID`: each vertex's index, as a float.
void write_with_ids(const Mesh& mesh, const MorphTarget& target, const std::filesystem::path& path) {
  Scene scene = scene_from_mesh(mesh);
  scene.primitives[0].targets.push_back(target);
  write_scene(scene, path);
  test::Glb g = test::read_glb(path);
  while (g.bin.size() % 4) g.bin.push_back(0);
  const size_t offset = g.bin.size(), n = mesh.vertex_count();
  for (size_t v = 0; v < n; ++v) {
    const float id = float(v);
    const auto* bytes = reinterpret_cast<const uint8_t*>(&id);
    g.bin.insert(g.bin.end(), bytes, bytes + 4);
  }
  g.doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", 4 * n}, {"target", 34962}});
  g.doc["accessors"].push_back({{"bufferView", g.doc["bufferViews"].size() - 1}, {"componentType", 5126}, {"count", n}, {"type", "SCALAR"}});
  g.doc["meshes"][0]["primitives"][0]["attributes"]["_ID"] = g.doc["accessors"].size() - 1;
  g.doc["buffers"][0]["byteLength"] = g.bin.size();
  test::write_bytes(path, test::glb_bytes(g));
}

// The `_ID` floats of a .glb's first primitive.
std::vector<float> read_ids(const std::filesystem::path& path) {
  const test::Glb g = test::read_glb(path);
  const Json& a = g.doc["accessors"][g.doc["meshes"][0]["primitives"][0]["attributes"]["_ID"].get<size_t>()];
  const Json& view = g.doc["bufferViews"][a["bufferView"].get<size_t>()];
  const size_t stride = view.value("byteStride", size_t(4));
  const size_t offset = view.value("byteOffset", size_t(0)) + a.value("byteOffset", size_t(0));
  std::vector<float> out(a["count"].get<size_t>());
  for (size_t v = 0; v < out.size(); ++v) std::memcpy(&out[v], g.bin.data() + offset + v * stride, 4);
  return out;
}

// Written through (`convert`: the same vertices), a source's own streams that lodkit does not model
// (an application attribute, a morph target) stay outside the Draco stream and follow Edgebreaker's
// renumbering: each decoded vertex carries the id of one source vertex, lies within a position step
// of it, and has its displacement exactly. When two vertices decode alike (positions only, the
// torus's seam duplicated), their streams could not be told apart: sequential encoding keeps the
// order instead.
TEST(GltfCompression, DracoCarriesTheSourcesOwnStreamsThroughEdgebreaker) {
  TempDir dir;
  for (const bool alike : {false, true}) {
    Mesh source = shapes::torus(1.0f, 0.3f, 20, 10);
    if (alike) source.normals.clear(), source.uvs[0].clear();
    const MorphTarget target = linear_target(source.positions);
    write_with_ids(source, target, dir / "in.glb");
    const test::RunResult r = test::run_cli({"convert", (dir / "in.glb").string(), (dir / "d.glb").string(), "--draco", "--json"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    test::expect_valid_gltf({dir / "d.glb"});
    EXPECT_EQ(draco_methods(dir / "d.glb"), std::vector<int>{alike ? 0 : 1}) << alike;
    // The report says what the stream's header says, and the bytes on disk.
    const Json report = Json::parse(r.out);
    EXPECT_EQ(report["draco"]["sequential"], alike ? 1 : 0);
    EXPECT_EQ(report["draco"]["edgebreaker"], alike ? 0 : 1);
    EXPECT_EQ(report["draco"]["plain"], 0);
    EXPECT_EQ(report["output_bytes"], std::filesystem::file_size(dir / "d.glb"));
    const Scene back = read_scene(dir / "d.glb");
    const Mesh& m = only_mesh(back);
    const std::vector<float> ids = read_ids(dir / "d.glb");
    ASSERT_EQ(ids.size(), m.vertex_count());
    const std::vector<MorphTarget> targets = source_morph_targets(back, 0);
    ASSERT_EQ(targets.size(), 1u);
    ASSERT_EQ(targets[0].positions.size(), m.vertex_count());
    const float bound = std::sqrt(3.0f) * 0.5f * 2.6f / float((1 << 14) - 1) + 1e-6f;
    std::vector<uint32_t> match(m.vertex_count());
    size_t moved = 0;
    for (size_t v = 0; v < m.vertex_count(); ++v) {
      ASSERT_TRUE(ids[v] >= 0 && ids[v] < float(source.vertex_count()) && ids[v] == std::floor(ids[v])) << ids[v];
      const uint32_t s = match[v] = uint32_t(ids[v]);
      const float3 a = m.positions[v], b = source.positions[s];
      EXPECT_LE(length3({a.x - b.x, a.y - b.y, a.z - b.z}), bound) << v;
      EXPECT_EQ(targets[0].positions[v], target.positions[s]) << v;
      moved += s != v;
    }
    EXPECT_EQ(test::canonical_triangles(m.indices, &match), test::canonical_triangles(source.indices)) << alike;
    if (alike) EXPECT_EQ(moved, 0u);
    else EXPECT_GT(moved, 0u);
  }
}

// Draco with -q: a morphing sphere's positions go into the Draco stream as -q's grid coordinates
// (unsigned shorts, exact) and its morph target is stored in grid steps outside it. Flattened
// (each node's dequantizing transform applied), the file is the -q file's mesh with its vertices
// renumbered: the same positions exactly, normals within Draco's 10 bits of -q's bytes, the same
// displacement per vertex, and triangles.
TEST(GltfCompression, DracoWithQuantizationPutsTheGridInTheStream) {
  TempDir dir;
  Scene scene = scene_from_mesh(shapes::icosphere(3));
  scene.primitives[0].targets.push_back(linear_target(scene.primitives[0].mesh.positions));
  WriteOptions q;
  q.quantize = true;
  write_scene(scene, dir / "q.glb", q);
  WriteOptions dq = q;
  dq.draco = true;
  write_scene(scene, dir / "dq.glb", dq);
  test::expect_valid_gltf({dir / "dq.glb"});
  EXPECT_EQ(draco_methods(dir / "dq.glb"), std::vector<int>{1});
  const Json doc = test::glb_json(dir / "dq.glb");
  EXPECT_TRUE(contains(doc["extensionsRequired"], "KHR_mesh_quantization"));
  const Json& prim = doc["meshes"][0]["primitives"][0];
  EXPECT_EQ(doc["accessors"][prim["attributes"]["POSITION"].get<size_t>()]["componentType"], 5123);  // unsigned short
  EXPECT_EQ(doc["accessors"][prim["targets"][0]["POSITION"].get<size_t>()]["componentType"], 5122);  // short
  EXPECT_LT(std::filesystem::file_size(dir / "dq.glb"), std::filesystem::file_size(dir / "q.glb"));

  const Scene a_scene = read_scene(dir / "q.glb"), b_scene = read_scene(dir / "dq.glb");
  const Mesh a = flatten(a_scene), b = flatten(b_scene);
  expect_same_up_to_order(a, b, std::cos(2.0f * 3.14159265f / 180.0f));
  const FlatMorphTargets ta = flatten_morph_targets(a_scene), tb = flatten_morph_targets(b_scene);
  ASSERT_EQ(ta.targets.size(), 1u);
  ASSERT_EQ(tb.targets.size(), 1u);
  std::map<std::array<float, 3>, float3> displacement;
  for (size_t v = 0; v < a.vertex_count(); ++v) displacement[{a.positions[v].x, a.positions[v].y, a.positions[v].z}] = ta.targets[0].positions[v];
  ASSERT_EQ(tb.targets[0].positions.size(), b.vertex_count());
  for (size_t v = 0; v < b.vertex_count(); ++v)
    EXPECT_EQ(tb.targets[0].positions[v], displacement.at({b.positions[v].x, b.positions[v].y, b.positions[v].z})) << v;
}

// A stream as the second reader gives it (stored values), as floats: normalized integers as glTF
// defines them, other integers as they are.
std::vector<float> second_reader_floats(const Json& stream) {
  const int type = stream["type"];
  const bool normalized = stream["normalized"];
  std::vector<float> out;
  for (const Json& v : stream["values"]) {
    const double x = v.get<double>();
    if (!normalized || type == 5126) out.push_back(float(x));
    else if (type == 5120) out.push_back(std::max(float(x) / 127.0f, -1.0f));
    else if (type == 5121) out.push_back(float(x) / 255.0f);
    else if (type == 5122) out.push_back(std::max(float(x) / 32767.0f, -1.0f));
    else out.push_back(float(x) / 65535.0f);
  }
  return out;
}

// Each triple of `values` scaled to unit length in double, as glTF means a normal (a quantized one
// is off it by up to its step, and lodkit's reader gives Mesh::normals unit length).
std::vector<float> unit_triples(std::vector<float> values) {
  for (size_t i = 0; i + 2 < values.size(); i += 3) {
    const double x = values[i], y = values[i + 1], z = values[i + 2], l = std::sqrt(x * x + y * y + z * z);
    values[i] = float(x / l), values[i + 1] = float(y / l), values[i + 2] = float(z / l);
  }
  return values;
}

// a[i] and b[i] within `tolerance` for every i, and as many.
void expect_near_all(const std::vector<float>& a, const std::vector<float>& b, double tolerance, const std::string& where) {
  ASSERT_EQ(a.size(), b.size()) << where;
  for (size_t i = 0; i < a.size(); ++i) ASSERT_NEAR(a[i], b[i], tolerance) << where << " component " << i;
}

std::vector<float> components(const std::vector<float3>& v) {
  std::vector<float> out;
  for (const float3& p : v) out.insert(out.end(), {p.x, p.y, p.z});
  return out;
}

// `file` read by lodkit and by the second reader: every triangle primitive's indices, positions,
// normals and morph-target positions alike, and each POSITION accessor's min and max the bounds
// of the positions the second reader decoded (glTF requires them exact).
void expect_second_reader_agrees(const std::filesystem::path& file) {
  const Json theirs = test::read_with_second_reader(file);
  const Scene scene = read_scene(file);
  const Json doc = test::glb_json(file);
  ASSERT_EQ(theirs.size(), scene.primitives.size()) << file;
  for (size_t i = 0; i < scene.primitives.size(); ++i) {
    const Primitive& mine = scene.primitives[i];
    const std::string where = file.filename().string() + " primitive " + std::to_string(i);
    const Json* match = nullptr;
    for (const Json& p : theirs)
      if (p["mesh"] == mine.gltf_mesh && p["primitive"] == mine.gltf_primitive) match = &p;
    ASSERT_NE(match, nullptr) << where;
    const Json& p = *match;
    EXPECT_EQ(p["indices"].get<std::vector<uint32_t>>(), mine.mesh.indices) << where;
    const std::vector<float> positions = second_reader_floats(p["attributes"]["POSITION"]);
    EXPECT_EQ(positions, components(mine.mesh.positions)) << where;
    if (!mine.mesh.normals.empty()) {
      ASSERT_TRUE(p["attributes"].contains("NORMAL")) << where;
      expect_near_all(unit_triples(second_reader_floats(p["attributes"]["NORMAL"])), components(mine.mesh.normals), 1e-6, where);
    }
    const std::vector<MorphTarget> targets = source_morph_targets(scene, i);
    ASSERT_EQ(p["targets"].size(), targets.size()) << where;
    for (size_t t = 0; t < targets.size(); ++t)
      EXPECT_EQ(second_reader_floats(p["targets"][t]["POSITION"]), components(targets[t].positions)) << where << " target " << t;
    // The bounds, in stored units.
    const Json& accessor = doc["accessors"][doc["meshes"][mine.gltf_mesh]["primitives"][mine.gltf_primitive]["attributes"]["POSITION"].get<size_t>()];
    const Json& stored = p["attributes"]["POSITION"]["values"];
    for (size_t c = 0; c < 3; ++c) {
      double lo = INFINITY, hi = -INFINITY;
      for (size_t k = c; k < stored.size(); k += 3) lo = std::min(lo, stored[k].get<double>()), hi = std::max(hi, stored[k].get<double>());
      EXPECT_EQ(accessor["min"][c].get<double>(), lo) << where << " axis " << c;
      EXPECT_EQ(accessor["max"][c].get<double>(), hi) << where << " axis " << c;
    }
  }
}

// Every form lodkit writes, read by a second reader (glTF-Transform, with Google's draco3dgltf
// WebAssembly decoder and meshoptimizer's JavaScript one), gives what lodkit's own reader gives:
// a morphing torus's LOD chain with geomorphs (lodkit's targets after the source's, gathered
// through Edgebreaker's renumbering under Draco) in every flag set, and the skinned humanoid.
TEST(GltfCompression, ASecondReaderDecodesWhatLodkitReads) {
  if (!test::second_reader_available()) GTEST_SKIP() << "tests/gltf-loader not installed (scripts/setup.sh installs it)";
  TempDir dir;
  Scene scene = scene_from_mesh(shapes::torus(1.0f, 0.3f, 32, 16));
  scene.primitives[0].targets.push_back(linear_target(scene.primitives[0].mesh.positions));
  write_scene(scene, dir / "in.glb");
  write_scene(fixtures::humanoid_scene(), dir / "humanoid.glb");
  const std::vector<std::vector<std::string>> forms = {{}, {"-c"}, {"-q"}, {"-c", "-q"}, {"--draco"}, {"--draco", "-c"}, {"--draco", "-q", "-c"}};
  for (size_t f = 0; f < forms.size(); ++f) {
    const std::filesystem::path out = dir / ("chain" + std::to_string(f) + ".glb");
    std::vector<std::string> argv = {"lod", (dir / "in.glb").string(), "-o", out.string(), "--levels", "3", "--morph"};
    argv.insert(argv.end(), forms[f].begin(), forms[f].end());
    const test::RunResult r = test::run_cli(argv);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    expect_second_reader_agrees(out);
  }
  for (const std::vector<std::string>& flags : {std::vector<std::string>{"-c", "-q"}, std::vector<std::string>{"--draco", "-q", "-c"}}) {
    std::vector<std::string> argv = {"convert", (dir / "humanoid.glb").string(), (dir / "h.glb").string()};
    argv.insert(argv.end(), flags.begin(), flags.end());
    const test::RunResult r = test::run_cli(argv);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    expect_second_reader_agrees(dir / "h.glb");
  }
}

// Views that hold the same kind of data become one compressed view, as gltfpack lays them out:
// three meshes' indices one TRIANGLES view, their positions one ATTRIBUTES view (with the stride
// glTF asks of a shared vertex view), and so on; each mesh reads back exactly, by lodkit and by a
// second reader, and the file is smaller than with a view per accessor would be (the parts' sizes
// summed from one-mesh files).
TEST(GltfCompression, MeshoptPutsOneKindOfDataInOneView) {
  TempDir dir;
  Scene scene;
  const std::vector<Mesh> meshes = {shapes::torus(1.0f, 0.25f, 48, 24), shapes::icosphere(3), shapes::torus(2.0f, 0.5f, 24, 12)};
  size_t apart = 0;  // the meshes' compressed files, one each (a file's own overhead included)
  for (size_t m = 0; m < meshes.size(); ++m) {
    Primitive p;
    p.mesh = meshes[m], p.gltf_mesh = uint32_t(m);
    scene.primitives.push_back(p);
    Node node;
    node.mesh = int32_t(m), node.translation = {3.0f * float(m), 0, 0};
    scene.nodes.push_back(node);
    scene.roots.push_back(int32_t(m));
    write_scene(scene_from_mesh(meshes[m]), dir / "one.glb", {.meshopt_compression = true});
    apart += std::filesystem::file_size(dir / "one.glb");
  }
  write_scene(scene, dir / "plain.glb");
  write_scene(scene, dir / "c.glb", {.meshopt_compression = true});
  test::expect_valid_gltf({dir / "c.glb"});
  EXPECT_LT(std::filesystem::file_size(dir / "c.glb"), apart);

  const Json doc = test::glb_json(dir / "c.glb");
  size_t triangles = 0;
  for (const Json& view : doc["bufferViews"]) triangles += view["extensions"][kMeshopt]["mode"] == "TRIANGLES";
  EXPECT_EQ(triangles, 1u);
  std::set<std::string> streams;
  for (const Json& mesh : doc["meshes"])
    for (const auto& [name, index] : mesh["primitives"][0]["attributes"].items()) streams.insert(name);
  EXPECT_EQ(doc["bufferViews"].size(), streams.size() + 1);  // a view per stream, and the indices'
  std::set<size_t> position_views;
  for (const Json& mesh : doc["meshes"])
    position_views.insert(doc["accessors"][mesh["primitives"][0]["attributes"]["POSITION"].get<size_t>()]["bufferView"].get<size_t>());
  ASSERT_EQ(position_views.size(), 1u);
  EXPECT_EQ(doc["bufferViews"][*position_views.begin()]["byteStride"], 12);

  const Scene plain = read_scene(dir / "plain.glb"), packed = read_scene(dir / "c.glb");
  ASSERT_EQ(packed.primitives.size(), meshes.size());
  for (size_t m = 0; m < meshes.size(); ++m)
    EXPECT_EQ(difference_but_rotations(plain.primitives[m].mesh, packed.primitives[m].mesh), "") << m;
  if (test::second_reader_available()) expect_second_reader_agrees(dir / "c.glb");
}

// A skinned, animated character: joint indices exact, weights within a 12-bit step, positions within
// a 14-bit one; skin and clips as they were.
TEST(GltfCompression, DracoOutputOfASkinnedCharacter) {
  TempDir dir;
  const Scene input = fixtures::humanoid_scene();
  write_scene(input, dir / "plain.glb");
  WriteOptions o;
  o.draco = true;
  write_scene(input, dir / "d.glb", o);
  test::expect_valid_gltf({dir / "d.glb"});
  const Scene plain = read_scene(dir / "plain.glb"), back = read_scene(dir / "d.glb");
  const Mesh &a = only_mesh(plain), &b = only_mesh(back);
  ASSERT_EQ(a.vertex_count(), b.vertex_count());
  float3 lo, hi;
  bounding_box(a, lo, hi);
  const float extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  const float position_bound = std::sqrt(3.0f) * 0.5f * extent / float((1 << 14) - 1) + 1e-6f;
  const float weight_bound = 0.5f / float((1 << 12) - 1) + 1e-6f;
  // Match by position (the character's vertices are distinct there).
  for (size_t v = 0; v < b.vertex_count(); ++v) {
    size_t found = 0, s = 0;
    for (size_t k = 0; k < a.vertex_count(); ++k) {
      const float3 p = b.positions[v], q = a.positions[k];
      if (length3({p.x - q.x, p.y - q.y, p.z - q.z}) <= position_bound) ++found, s = k;
    }
    ASSERT_EQ(found, 1u) << v;
    EXPECT_EQ(b.joints[v], a.joints[s]) << v;
    const float4 &wb = b.weights[v], &wa = a.weights[s];
    EXPECT_LE(std::max({std::fabs(wb.x - wa.x), std::fabs(wb.y - wa.y), std::fabs(wb.z - wa.z), std::fabs(wb.w - wa.w)}), weight_bound) << v;
  }
  ASSERT_EQ(back.animations.size(), plain.animations.size());
  for (size_t k = 0; k < back.animations.size(); ++k)
    for (size_t c = 0; c < back.animations[k].channels.size(); ++c)
      EXPECT_EQ(back.animations[k].channels[c].values, plain.animations[k].channels[c].values);
  EXPECT_EQ(back.skins[0].inverse_bind_matrices, plain.skins[0].inverse_bind_matrices);
}

// libdraco 1.5.5 crashes quantizing a stream whose range overflows a float: such a stream (here the
// positions and the UVs, with coordinates near +-3e38) is stored exactly instead, the others still
// quantized. A triangle with a repeated corner is dropped by Edgebreaker (it draws nothing).
TEST(GltfCompression, DracoStoresStreamsTooWideToQuantizeExactly) {
  TempDir dir;
  Mesh m = shapes::torus(1.0f, 0.3f, 12, 6);
  m.positions[0] = {3e38f, 0, 0}, m.positions[1] = {-3e38f, 1, 0};
  m.uvs[0][0] = {3e38f, 0}, m.uvs[0][1] = {-3e38f, 0};
  m.indices.insert(m.indices.end(), {2, 2, 3});
  WriteOptions o;
  o.draco = true;
  write_scene(scene_from_mesh(m), dir / "wide.glb", o);
  const Mesh back = only_mesh(read_scene(dir / "wide.glb"));
  EXPECT_EQ(back.triangle_count(), m.triangle_count() - 1);
  const auto sorted = [](std::vector<float3> p) {
    std::sort(p.begin(), p.end(), [](const float3& a, const float3& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); });
    return p;
  };
  EXPECT_EQ(sorted(back.positions), sorted(m.positions));
  bool normals_moved = false;  // (10-bit normals: quantized as ever)
  std::map<std::array<float, 3>, float3> normal_at;
  for (size_t v = 0; v < m.vertex_count(); ++v) normal_at[{m.positions[v].x, m.positions[v].y, m.positions[v].z}] = m.normals[v];
  for (size_t v = 0; v < back.vertex_count(); ++v) {
    const float3 n = normal_at.at({back.positions[v].x, back.positions[v].y, back.positions[v].z});
    normals_moved |= !(n.x == back.normals[v].x && n.y == back.normals[v].y && n.z == back.normals[v].z);
    EXPECT_GT(cosine(n, back.normals[v]), std::cos(3.14159265f / 180.0f));
  }
  EXPECT_TRUE(normals_moved);

  // Every triangle repeats a corner: Edgebreaker refuses the mesh, sequential encoding keeps it.
  Mesh flat;
  flat.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  flat.indices = {0, 0, 1, 1, 2, 2};
  WriteReport report = write_scene(scene_from_mesh(flat), dir / "flat.glb", o);
  EXPECT_EQ(only_mesh(read_scene(dir / "flat.glb")).indices, flat.indices);
  EXPECT_TRUE(contains(test::glb_json(dir / "flat.glb")["extensionsRequired"], kDraco));
  EXPECT_EQ(draco_methods(dir / "flat.glb"), std::vector<int>{0});
  EXPECT_EQ(std::tuple(report.draco_edgebreaker, report.draco_sequential, report.draco_plain), std::tuple(0u, 1u, 0u));
  // A lone triangle with three equal corners beside unused vertices: libdraco writes a stream it
  // cannot decode, in any mode, so the primitive is written plain (found by fuzz_gltf).
  flat.positions.push_back({1, 1, 0});
  flat.indices = {0, 0, 0};
  report = write_scene(scene_from_mesh(flat), dir / "point.glb", o);
  EXPECT_EQ(only_mesh(read_scene(dir / "point.glb")).indices, flat.indices);
  const Json doc = test::glb_json(dir / "point.glb");
  EXPECT_FALSE(doc.contains("extensionsUsed") && contains(doc["extensionsUsed"], kDraco)) << doc.dump();
  test::expect_valid_gltf({dir / "point.glb"});
  EXPECT_EQ(std::tuple(report.draco_edgebreaker, report.draco_sequential, report.draco_plain), std::tuple(0u, 0u, 1u));
  EXPECT_EQ(report.bytes, std::filesystem::file_size(dir / "point.glb"));
  // The CLI says so: a warning, and the report's line.
  const test::RunResult r = test::run_cli({"convert", (dir / "point.glb").string(), (dir / "again.glb").string(), "--draco"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("1 primitive(s) written without Draco"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("1 plain"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(" + std::to_string(std::filesystem::file_size(dir / "again.glb")) + " bytes)"), std::string::npos) << r.out;
}

// -c -q: translation and scale keys go through meshopt's exponential filter (16-bit mantissas,
// one exponent per key), as gltfpack -c does; their views code smaller than -c's exact ones, and
// each key comes back within 2^-14 of its largest component. -c alone stays exact.
TEST(GltfCompression, QuantizedCompressionFiltersTranslationAndScaleKeys) {
  TempDir dir;
  Scene scene = scene_from_mesh(shapes::torus(1.0f, 0.3f, 24, 12));
  Animation clip;
  AnimationChannel move, grow;
  move.node = grow.node = 0;
  move.path = AnimationPath::translation, grow.path = AnimationPath::scale;
  for (int k = 0; k < 600; ++k) {
    const float t = float(k) / 30.0f;
    move.times.push_back(t), grow.times.push_back(t);
    move.values.insert(move.values.end(), {3.0f * std::sin(t), 0.01f * t, -2.0f + std::cos(1.3f * t)});
    grow.values.insert(grow.values.end(), {1.0f + 0.2f * std::sin(t), 1.0f, 0.5f + 0.1f * std::cos(t)});
  }
  clip.channels = {move, grow};
  scene.animations.push_back(clip);
  write_scene(scene, dir / "c.glb", {.meshopt_compression = true});
  write_scene(scene, dir / "cq.glb", {.meshopt_compression = true, .quantize = true});
  const Scene exact = read_scene(dir / "c.glb"), filtered = read_scene(dir / "cq.glb");
  ASSERT_EQ(exact.animations.size(), 1u);
  ASSERT_EQ(filtered.animations.size(), 1u);
  for (size_t c = 0; c < 2; ++c) {
    const AnimationChannel& source = clip.channels[c];
    EXPECT_EQ(exact.animations[0].channels[c].values, source.values) << c;
    const std::vector<float>& back = filtered.animations[0].channels[c].values;
    ASSERT_EQ(back.size(), source.values.size()) << c;
    EXPECT_EQ(filtered.animations[0].channels[c].times, source.times) << c;
    size_t moved = 0;
    for (size_t k = 0; k < back.size(); k += 3) {
      const double largest = std::max({std::fabs(source.values[k]), std::fabs(source.values[k + 1]), std::fabs(source.values[k + 2])});
      for (size_t i = k; i < k + 3; ++i) {
        EXPECT_LE(std::fabs(double(back[i]) - source.values[i]), largest / 16384) << c << " " << i;
        moved += back[i] != source.values[i];
      }
    }
    EXPECT_GT(moved, back.size() / 4) << c;  // the filter did apply
  }
  // The keys' views: filtered under -c -q and smaller there; exact under -c.
  const auto key_views = [](const std::filesystem::path& file) {
    const Json doc = test::glb_json(file);
    std::vector<Json> out;
    for (const Json& channel : doc["animations"][0]["channels"]) {
      const Json& sampler = doc["animations"][0]["samplers"][channel["sampler"].get<size_t>()];
      const Json& view = doc["bufferViews"][doc["accessors"][sampler["output"].get<size_t>()]["bufferView"].get<size_t>()];
      out.push_back(view["extensions"]["EXT_meshopt_compression"]);
    }
    return out;
  };
  const std::vector<Json> plain_views = key_views(dir / "c.glb"), filtered_views = key_views(dir / "cq.glb");
  ASSERT_EQ(filtered_views.size(), 2u);
  for (size_t c = 0; c < 2; ++c) {
    EXPECT_EQ(filtered_views[c].value("filter", ""), "EXPONENTIAL") << c;
    EXPECT_EQ(plain_views[c].value("filter", "NONE"), "NONE") << c;
    EXPECT_LT(filtered_views[c]["byteLength"].get<size_t>(), plain_views[c]["byteLength"].get<size_t>()) << c;
  }
  test::expect_valid_gltf({dir / "cq.glb"});
}

// -c -q: rotation keys go through meshopt's quaternion filter (the three smaller components in 16
// bits, scaled by sqrt 2; the largest rebuilt, positive), which gltfpack -c leaves out. Against the
// normalized shorts -q writes: each small component within half a step of 1/(32767 sqrt 2), the
// rebuilt one within 3 such half steps (its error is the others' weighted by their ratio to it, at
// most 1), then rounded to shorts again: a 4-vector difference of at most 6.6e-5, an angle of at
// most 1.4e-4 rad (q and -q alike: the filter keeps no sign). Under EXT_ and KHR_meshopt_compression.
TEST(GltfCompression, QuantizedCompressionFiltersRotationKeys) {
  TempDir dir;
  Scene scene = scene_from_mesh(shapes::torus(1.0f, 0.3f, 24, 12));
  Animation clip;
  AnimationChannel turn;
  turn.node = 0, turn.path = AnimationPath::rotation, turn.components = 4;
  for (int k = 0; k < 600; ++k) {  // an axis sweeping around, and an angle to 3 rad and back
    const double t = k / 30.0, angle = 3 * std::sin(0.7 * t);
    const double axis[3] = {std::cos(t), std::sin(t) * 0.6, std::sin(t) * 0.8}, s = std::sin(angle / 2);
    turn.times.push_back(float(t));
    turn.values.insert(turn.values.end(), {float(axis[0] * s), float(axis[1] * s), float(axis[2] * s), float(std::cos(angle / 2))});
  }
  clip.channels = {turn};
  scene.animations.push_back(clip);
  write_scene(scene, dir / "q.glb", {.quantize = true});
  const Scene shorts = read_scene(dir / "q.glb");
  ASSERT_EQ(shorts.animations.size(), 1u);
  const AnimationChannel& want = shorts.animations[0].channels.at(0);
  for (const bool khr : {false, true}) {
    SCOPED_TRACE(khr);
    const std::filesystem::path file = dir / (khr ? "cqk.glb" : "cq.glb");
    write_scene(scene, file, {.meshopt_compression = true, .meshopt_khr = khr, .quantize = true});
    const Json doc = test::glb_json(file);
    const Json& sampler = doc["animations"][0]["samplers"][0];
    const Json& view = doc["bufferViews"][doc["accessors"][sampler["output"].get<size_t>()]["bufferView"].get<size_t>()];
    EXPECT_EQ(view["extensions"][khr ? "KHR_meshopt_compression" : "EXT_meshopt_compression"].value("filter", ""), "QUATERNION");
    const Scene back = read_scene(file);
    ASSERT_EQ(back.animations.size(), 1u);
    const AnimationChannel& got = back.animations[0].channels.at(0);
    EXPECT_EQ(got.times, want.times);
    ASSERT_EQ(got.values.size(), want.values.size());
    double worst = 0;
    for (size_t k = 0; k < got.values.size(); k += 4) {
      double d = 0, dot = 0;
      for (size_t i = 0; i < 4; ++i) dot += double(got.values[k + i]) * want.values[k + i];
      for (size_t i = 0; i < 4; ++i) d += std::pow(double(got.values[k + i]) - (dot < 0 ? -1 : 1) * double(want.values[k + i]), 2);
      worst = std::max(worst, std::sqrt(d));
    }
    EXPECT_LE(worst, 6.6e-5);
    EXPECT_GT(worst, 0.0);  // (the filter did apply)
    test::expect_valid_gltf({file});
  }
}

// compress_more (the CLI's --cc, which implies -c -q): normals and tangents go through meshopt's
// octahedral filter, as gltfpack -cc: in 8 bits by default, from normalized bytes; with normal_bits
// N above 8 in N bits, from shorts (views of 8 bytes a vertex). The filter codes the input's floats,
// not the integers -q stores, so each normal is quantized once: the codes stored are those
// meshoptimizer's own encoder makes of the float normals (computed here, apart from lodkit, and
// read with meshoptimizer's vertex decoder). The bound against the input by hand: the filter keeps u, v of the octahedral map within
// half a step, 1 / (2 (2^(N-1) - 1)), each, which moves the unfolded point (u, v, 1 - |u| - |v|), at
// least 1/sqrt 3 long, by at most sqrt 6 times that, so the direction by at most sqrt 18 times it
// (0.96 degrees at 8 bits); the decoder's rounding to bytes or shorts adds sqrt 3 / 254 or
// sqrt 3 / 65534 rad. meshoptimizer's JavaScript decoder (the second reader) must agree; a
// tangent's handedness stays. Without compress_more, no view is filtered so.
TEST(GltfCompression, CompressMoreFiltersNormalsAndTangents) {
  TempDir dir;
  Mesh mesh = shapes::torus(1.0f, 0.3f, 48, 24);
  ASSERT_EQ(mesh.normals.size(), mesh.vertex_count());
  test::add_tangents(mesh);
  const Scene scene = scene_from_mesh(mesh);
  const auto octahedral_views = [](const std::filesystem::path& file, uint64_t stride) {
    size_t count = 0;
    const Json doc = test::glb_json(file);
    for (const Json& view : doc["bufferViews"])
      if (view.contains("extensions") && view["extensions"][kMeshopt].value("filter", "") == "OCTAHEDRAL") {
        ++count;
        EXPECT_EQ(view["extensions"][kMeshopt]["byteStride"], stride);
      }
    return count;
  };
  write_scene(scene, dir / "cq.glb", {.meshopt_compression = true, .quantize = true});
  EXPECT_EQ(octahedral_views(dir / "cq.glb", 4), 0u);
  for (const int bits : {0, 12, 16}) {
    SCOPED_TRACE(bits);
    const int n = bits ? bits : 8;
    const bool wide = n > 8;
    const std::filesystem::path cc = dir / "cc.glb";
    write_scene(scene, cc, {.meshopt_compression = true, .quantize = true, .compress_more = true, .normal_bits = bits});
    EXPECT_EQ(octahedral_views(cc, wide ? 8 : 4), 2u);  // the normals' view and the tangents'
    const Mesh got = read_scene(cc).primitives.at(0).mesh;
    ASSERT_EQ(got.normals.size(), mesh.normals.size());
    ASSERT_EQ(got.tangents.size(), mesh.tangents.size());
    // The codes stored: the normals' view decoded by meshoptimizer's vertex decoder, against its
    // filter's codes of the float normals.
    const size_t count = mesh.vertex_count(), stride = wide ? 8 : 4;
    std::vector<float> input(4 * count, 0.0f);
    for (size_t v = 0; v < count; ++v) std::memcpy(&input[4 * v], &mesh.normals[v], sizeof(float3));
    std::vector<uint8_t> expected(count * stride);
    meshopt_encodeFilterOct(expected.data(), count, stride, n, input.data());
    const test::Glb glb = test::read_glb(cc);
    const Json& normals = glb.doc["accessors"][glb.doc["meshes"][0]["primitives"][0]["attributes"]["NORMAL"].get<size_t>()];
    const Json& compressed = glb.doc["bufferViews"][normals["bufferView"].get<size_t>()]["extensions"][kMeshopt];
    ASSERT_EQ(compressed.value("filter", ""), "OCTAHEDRAL");
    std::vector<uint8_t> stored(compressed["count"].get<size_t>() * stride);
    ASSERT_EQ(meshopt_decodeVertexBuffer(stored.data(), compressed["count"].get<size_t>(), stride,
                                         glb.bin.data() + compressed.value("byteOffset", size_t(0)), compressed["byteLength"].get<size_t>()),
              0);
    const size_t first = normals.value("byteOffset", size_t(0));
    ASSERT_LE(first + count * stride, stored.size());
    EXPECT_TRUE(std::equal(expected.begin(), expected.end(), stored.begin() + ptrdiff_t(first)));
    double worst = 0;
    for (size_t v = 0; v < count; ++v) {
      const float4 &t = got.tangents[v], &k = mesh.tangents[v];
      worst = std::max({worst, degrees(got.normals[v], mesh.normals[v]), degrees({t.x, t.y, t.z}, {k.x, k.y, k.z})});
      EXPECT_EQ(t.w, k.w) << v;
    }
    const double top = wide ? 32767 : 127;
    const double bound = (std::sqrt(18.0) * 0.5 / (std::exp2(n - 1) - 1) + std::sqrt(3.0) * 0.5 / top) * 180 / M_PI;
    EXPECT_LE(worst, bound);
    EXPECT_GT(worst, bound / 8);  // (it did quantize)
    const Json second = test::read_with_second_reader(cc)[0]["attributes"]["NORMAL"]["values"];
    ASSERT_EQ(second.size(), 3 * count);
    std::vector<float> theirs;
    for (const Json& x : second) theirs.push_back(float(std::max(x.get<double>() / top, -1.0)));
    expect_near_all(unit_triples(theirs), components(got.normals), 1e-6, "normals");
    test::expect_valid_gltf({cc});
  }
}

// The CLI's --draco: a LOD chain, valid, every level compressed; with -c, meshopt takes the rest
// (the geomorphs' morph targets); with -q too, both extensions are required.
TEST(GltfCompression, CommandsWriteDracoWithDashDashDraco) {
  TempDir dir;
  write_scene(scene_from_mesh(shapes::torus(1.0f, 0.25f, 48, 24)), dir / "in.glb");
  test::RunResult r = test::run_cli({"lod", (dir / "in.glb").string(), "-o", (dir / "d.glb").string(), "--levels", "3", "--draco"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  Json doc = test::glb_json(dir / "d.glb");
  for (const Json& mesh : doc["meshes"]) EXPECT_TRUE(mesh["primitives"][0]["extensions"].contains(kDraco));
  test::expect_valid_gltf({dir / "d.glb"});
  EXPECT_EQ(read_scene(dir / "d.glb").primitives.size(), 3u);

  r = test::run_cli({"lod", (dir / "in.glb").string(), "-o", (dir / "dc.glb").string(), "--levels", "3", "--morph", "--draco", "-c"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  doc = test::glb_json(dir / "dc.glb");
  EXPECT_TRUE(contains(doc["extensionsRequired"], kDraco));
  EXPECT_TRUE(contains(doc["extensionsRequired"], kMeshopt));
  test::expect_valid_gltf({dir / "dc.glb"});

  r = test::run_cli({"convert", (dir / "in.glb").string(), (dir / "dq.glb").string(), "--draco", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  doc = test::glb_json(dir / "dq.glb");
  EXPECT_TRUE(contains(doc["extensionsRequired"], kDraco));
  EXPECT_TRUE(contains(doc["extensionsRequired"], "KHR_mesh_quantization"));
  test::expect_valid_gltf({dir / "dq.glb"});
  r = test::run_cli({"convert", (dir / "in.glb").string(), (dir / "d.obj").string(), "--draco"});
  EXPECT_NE(r.exit_code, 0);
}

// lod -c orders its levels for the codec (an LRU-style cache order): smaller than the same chain in
// its default FIFO order compressed afterwards.
TEST(GltfCompression, LodOrdersItsLevelsForTheCodec) {
  const std::filesystem::path bunny = test::corpus_dir() / "bunny00.off";
  if (!std::filesystem::exists(bunny)) GTEST_SKIP() << "corpus not fetched (scripts/fetch-corpus.sh)";
  TempDir dir;
  ASSERT_EQ(test::run_cli({"lod", bunny.string(), "-o", (dir / "chain.glb").string(), "--levels", "2"}).exit_code, 0);
  ASSERT_EQ(test::run_cli({"convert", (dir / "chain.glb").string(), (dir / "fifo-c.glb").string(), "-c"}).exit_code, 0);
  ASSERT_EQ(test::run_cli({"lod", bunny.string(), "-o", (dir / "lru-c.glb").string(), "--levels", "2", "-c"}).exit_code, 0);
  EXPECT_LT(std::filesystem::file_size(dir / "lru-c.glb"), std::filesystem::file_size(dir / "fifo-c.glb") * 99 / 100);
}

}  // namespace
}  // namespace lod
