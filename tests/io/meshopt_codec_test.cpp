// lodkit's own meshopt vertex decoder (versions 0 and 1) and COLOR and OCTAHEDRAL filters, against
// meshoptimizer: its JavaScript encoder and decoder (tests/gltf-loader/meshopt_vectors.mjs) make the
// test data, and Debian's libmeshoptimizer decodes the version 0 streams too.
#include "io/meshopt_codec.h"

#include <gtest/gtest.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "core/shapes.h"
#include "lodkit/io.h"
#include "skin/fixtures.h"
#include "test_support.h"

namespace lod {
namespace {

using io::decode_meshopt_vertices;
using Json = nlohmann::json;

std::filesystem::path vectors_script() { return std::filesystem::path(LODKIT_SOURCE_DIR) / "tests/gltf-loader/meshopt_vectors.mjs"; }

// The vectors, made once for the whole test program (about a second of Node).
const Json& vectors() {
  static const Json doc = [] {
    test::TempDir dir;
    const test::RunResult r = test::run_program({"node", vectors_script().string(), "vectors", (dir / "v.json").string()});
    EXPECT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(dir / "v.json");
    return r.exit_code == 0 ? Json::parse(in) : Json::object();
  }();
  return doc;
}

struct Stream {
  size_t stride = 0, count = 0;
  int version = 0, level = 0;
  std::string kind;
  std::vector<uint8_t> source, encoded;
};

std::vector<Stream> streams() {
  std::vector<Stream> out;
  if (!vectors().contains("streams")) return out;
  for (const Json& s : vectors()["streams"])
    out.push_back({s["stride"], s["count"], s["version"], s["level"], s["kind"], test::from_base64(s["source"]),
                   test::from_base64(s["encoded"])});
  return out;
}

std::string name(const Stream& s) {
  return s.kind + " stride " + std::to_string(s.stride) + " count " + std::to_string(s.count) + " v" +
         std::to_string(s.version) + " level " + std::to_string(s.level);
}

#define SKIP_WITHOUT_NODE() \
  if (!test::second_reader_available()) GTEST_SKIP() << "tests/gltf-loader is not installed (scripts/setup.sh)"

// Every stream meshoptimizer encodes decodes to its source bytes; the version 1 ones use every
// control mode and every channel mode (else this test would not cover them).
TEST(MeshoptCodec, DecodesWhatMeshoptimizerEncodes) {
  SKIP_WITHOUT_NODE();
  const std::vector<Stream> all = streams();
  ASSERT_GT(all.size(), 200u);
  size_t versions[2] = {}, controls[4] = {}, channels[3] = {};
  for (const Stream& s : all) {
    ASSERT_EQ(s.source.size(), s.count * s.stride) << name(s);
    std::vector<uint8_t> out(s.source.size(), 0xcd);
    EXPECT_EQ(decode_meshopt_vertices(out.data(), s.count, s.stride, s.encoded), "") << name(s);
    EXPECT_EQ(out, s.source) << name(s);
    ++versions[s.version];
    if (s.version == 1) {
      for (size_t k = 0; k < s.stride; ++k) ++controls[(s.encoded[1 + k / 4] >> (2 * (k % 4))) & 3];  // the first block's
      for (size_t c = 0; c < s.stride / 4; ++c) ++channels[std::min(2, s.encoded[s.encoded.size() - s.stride / 4 + c] & 15)];
    } else {
      // Debian's meshoptimizer agrees.
      std::vector<uint8_t> theirs(s.source.size());
      EXPECT_EQ(meshopt_decodeVertexBuffer(theirs.data(), s.count, s.stride, s.encoded.data(), s.encoded.size()), 0) << name(s);
      EXPECT_EQ(theirs, s.source) << name(s);
    }
  }
  EXPECT_GT(versions[0], 200u);
  EXPECT_GT(versions[1], 200u);
  for (size_t m = 0; m < 4; ++m) EXPECT_GT(controls[m], 0u) << "control mode " << m;
  for (size_t m = 0; m < 3; ++m) EXPECT_GT(channels[m], 0u) << "channel mode " << m;
}

// lodkit's version 1 encoder: every source stream comes back through its own decoder and through
// meshoptimizer's JavaScript one, and the streams are no larger in sum than meshoptimizer's own
// version 1 encoding at its densest levels (2 and 3) of the same data.
TEST(MeshoptCodec, EncoderOutputDecodesInMeshoptimizer) {
  SKIP_WITHOUT_NODE();
  const std::vector<Stream> all = streams();
  ASSERT_FALSE(all.empty());
  test::TempDir dir;
  Json mine = Json::array();
  std::vector<const Stream*> sources;
  size_t ours = 0, theirs = 0;
  for (const Stream& s : all) {
    if (s.version != 1) continue;
    const std::vector<uint8_t> encoded = io::encode_meshopt_vertices(s.source.data(), s.count, s.stride);
    ASSERT_EQ(encoded[0], 0xa1) << name(s);
    std::vector<uint8_t> back(s.source.size());
    EXPECT_EQ(decode_meshopt_vertices(back.data(), s.count, s.stride, encoded), "") << name(s);
    EXPECT_EQ(back, s.source) << name(s);
    EXPECT_EQ(io::encode_meshopt_vertices(s.source.data(), s.count, s.stride), encoded) << name(s);  // deterministic
    if (s.level >= 2) ours += encoded.size(), theirs += s.encoded.size();
    mine.push_back({{"count", s.count}, {"stride", s.stride}, {"encoded", test::base64(encoded)}});
    sources.push_back(&s);
  }
  {
    std::ofstream(dir / "mine.json") << mine.dump();
  }
  const test::RunResult r =
      test::run_program({"node", vectors_script().string(), "decode", (dir / "mine.json").string(), (dir / "back.json").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(dir / "back.json");
  const Json back = Json::parse(in);
  ASSERT_EQ(back.size(), sources.size());
  for (size_t i = 0; i < sources.size(); ++i) {
    ASSERT_TRUE(back[i].is_string()) << name(*sources[i]) << ": meshoptimizer refuses it";
    EXPECT_EQ(test::from_base64(back[i]), sources[i]->source) << name(*sources[i]);
  }
  EXPECT_LE(ours, theirs) << "lodkit " << ours << " bytes, meshoptimizer " << theirs;
}

// COLOR: the spec allows one unit in the last place against meshoptimizer's decoder.
TEST(MeshoptCodec, ColorFilterMatchesMeshoptimizer) {
  SKIP_WITHOUT_NODE();
  ASSERT_TRUE(vectors().contains("colors"));
  for (const Json& c : vectors()["colors"]) {
    const size_t stride = c["stride"], count = c["count"];
    const std::string what = "stride " + std::to_string(stride) + " bits " + std::to_string(c["bits"].get<int>());
    const std::vector<uint8_t> encoded = test::from_base64(c["encoded"]), filtered = test::from_base64(c["filtered"]),
                               expected = test::from_base64(c["decoded"]);
    std::vector<uint8_t> out(count * stride);
    ASSERT_EQ(decode_meshopt_vertices(out.data(), count, stride, encoded), "") << what;
    EXPECT_EQ(out, filtered) << what;
    io::decode_meshopt_color_filter(out.data(), count, stride);
    size_t exact = 0;
    for (size_t i = 0; i < count * 4; ++i) {
      const int a = stride == 4 ? out[i] : out[2 * i] | out[2 * i + 1] << 8;
      const int b = stride == 4 ? expected[i] : expected[2 * i] | expected[2 * i + 1] << 8;
      EXPECT_LE(std::abs(a - b), 1) << what << " component " << i;
      exact += a == b;
    }
    EXPECT_GT(exact, count * 4 * 99 / 100) << what;  // off by one only at rounding ties
  }
}

// OCTAHEDRAL, against the specification's formula worked in double precision here: every 8-bit
// input (x, y within one = 127) and a spread of 16-bit ones (one = 2^(K-1) - 1 for K 4..16) decode
// to the rounded unit vector, exactly where the double value is not near a rounding tie (within
// 1e-3 units in 8 bits, 0.033 in 16: float32's rounding may go either way there), and to a unit vector within one unit everywhere;
// the fourth component stays. Debian's meshoptimizer (whose SSE path scales by the processor's
// approximate rsqrtps) stays within one unit of it. A zero "one" (malformed) decodes to zeros.
TEST(MeshoptCodec, OctahedralFilterFollowsTheSpecification) {
  for (const size_t stride : {4u, 8u}) {
    std::vector<std::array<int32_t, 4>> inputs;
    if (stride == 4) {
      for (int32_t x = -127; x <= 127; ++x)
        for (int32_t y = -127; y <= 127; ++y) inputs.push_back({x, y, 127, (x * 7 + y) & 0x7f});
    } else {
      std::mt19937 rng(7);
      for (int32_t k = 4; k <= 16; ++k) {
        const int32_t one = (1 << (k - 1)) - 1;
        std::uniform_int_distribution<int32_t> d(-one, one);
        for (int i = 0; i < 4000; ++i) inputs.push_back({d(rng), d(rng), one, d(rng)});
        inputs.push_back({one, 0, one, 0}), inputs.push_back({-one, -one, one, -1}), inputs.push_back({0, one, one, 5});
      }
    }
    inputs.push_back({5, -3, 0, 9});  // malformed: a zero "one"
    const auto put = [&](std::vector<uint8_t>& bytes, size_t i, size_t k, int32_t v) {
      if (stride == 4) bytes[i * 4 + k] = uint8_t(int8_t(v));
      else bytes[i * 8 + 2 * k] = uint8_t(uint16_t(int16_t(v))), bytes[i * 8 + 2 * k + 1] = uint8_t(uint16_t(int16_t(v)) >> 8);
    };
    const auto get = [&](const std::vector<uint8_t>& bytes, size_t i, size_t k) {
      return stride == 4 ? int32_t(int8_t(bytes[i * 4 + k])) : int32_t(int16_t(uint16_t(bytes[i * 8 + 2 * k] | bytes[i * 8 + 2 * k + 1] << 8)));
    };
    std::vector<uint8_t> data(inputs.size() * stride);
    for (size_t i = 0; i < inputs.size(); ++i)
      for (size_t k = 0; k < 4; ++k) put(data, i, k, inputs[i][k]);
    std::vector<uint8_t> peer = data;
    io::decode_meshopt_octahedral_filter(data.data(), inputs.size(), stride);
    meshopt_decodeFilterOct(peer.data(), inputs.size() - 1, stride);  // (not the malformed one)
    const double top = stride == 4 ? 127 : 32767;
    const double near = std::max(1e-3, top * 1e-6);  // float32's error in v * top: about 2^-22 of top
    size_t ties = 0;
    for (size_t i = 0; i + 1 < inputs.size(); ++i) {
      SCOPED_TRACE(testing::Message() << "stride " << stride << " input " << inputs[i][0] << ", " << inputs[i][1] << " / " << inputs[i][2]);
      double x = double(inputs[i][0]) / inputs[i][2], y = double(inputs[i][1]) / inputs[i][2];
      const double z = 1 - std::abs(x) - std::abs(y);
      if (z < 0) {  // the lower hemisphere: |x|, |y| swapped for 1 - |y|, 1 - |x|, signs kept
        const double ax = 1 - std::abs(y), ay = 1 - std::abs(x);
        x = std::copysign(ax, x), y = std::copysign(ay, y);
      }
      const double len = std::sqrt(x * x + y * y + z * z), want[3] = {x / len * top, y / len * top, z / len * top};
      double length = 0;
      for (size_t k = 0; k < 3; ++k) {
        const int32_t got = get(data, i, k);
        length += double(got) * got;
        EXPECT_LE(std::abs(got - want[k]), 0.5 + near) << "component " << k;
        if (std::abs(std::abs(want[k] - std::trunc(want[k])) - 0.5) > near) EXPECT_EQ(got, std::lround(want[k])) << "component " << k;
        else ++ties;
        EXPECT_LE(std::abs(got - get(peer, i, k)), 1) << "component " << k;
      }
      EXPECT_NEAR(std::sqrt(length) / top, 1.0, 1.5 * std::sqrt(3.0) / top);
      EXPECT_EQ(get(data, i, 3), inputs[i][3]);
    }
    EXPECT_LT(double(ties), 4 * near * 3 * double(inputs.size()));  // (about the band's share of values)
    const size_t bad = inputs.size() - 1;
    for (size_t k = 0; k < 3; ++k) EXPECT_EQ(get(data, bad, k), 0);
    EXPECT_EQ(get(data, bad, 3), 9);
  }
}

// A truncated or padded stream, and a bad channel mode, are refused with the byte where it goes
// wrong; random damage never reads or writes out of bounds (run under ASan by the sanitizer preset),
// and on version 0 lodkit's decoder accepts exactly what meshoptimizer's does, with the same output.
TEST(MeshoptCodec, DamagedStreamsAreRefusedLikeMeshoptimizerRefusesThem) {
  SKIP_WITHOUT_NODE();
  const std::vector<Stream> all = streams();
  ASSERT_FALSE(all.empty());
  const Stream* v1 = nullptr;
  for (const Stream& s : all)
    if (s.version == 1 && s.kind == "smooth-float" && s.stride == 16 && s.count == 1000) v1 = &s;
  ASSERT_NE(v1, nullptr);
  std::vector<uint8_t> out(v1->source.size());
  std::vector<uint8_t> shorter(v1->encoded.begin(), v1->encoded.end() - 1), longer = v1->encoded;
  longer.insert(longer.begin() + ptrdiff_t(longer.size() - 24), 0);
  EXPECT_NE(decode_meshopt_vertices(out.data(), v1->count, v1->stride, shorter), "");
  EXPECT_NE(decode_meshopt_vertices(out.data(), v1->count, v1->stride, longer).find("left over"), std::string::npos);
  std::vector<uint8_t> bad_channel = v1->encoded;
  bad_channel.back() = 0x13;  // mode 3, which does not exist
  EXPECT_NE(decode_meshopt_vertices(out.data(), v1->count, v1->stride, bad_channel).find("channel mode 0x13"), std::string::npos);
  bad_channel.back() = 0x11;  // a rotation on 2-byte deltas
  EXPECT_NE(decode_meshopt_vertices(out.data(), v1->count, v1->stride, bad_channel).find("channel mode 0x11"), std::string::npos);

  std::mt19937 rng(7);
  size_t agreed_ok = 0, agreed_refused = 0;
  for (const Stream& s : all) {
    for (int trial = 0; trial < 8; ++trial) {
      std::vector<uint8_t> damaged = s.encoded;
      const size_t flips = 1 + rng() % 3;
      for (size_t f = 0; f < flips; ++f) damaged[rng() % damaged.size()] ^= uint8_t(1u << (rng() % 8));
      std::vector<uint8_t> mine(s.source.size());
      const bool ok = decode_meshopt_vertices(mine.data(), s.count, s.stride, damaged).empty();
      if (s.version != 0 || damaged[0] != 0xa0) continue;
      std::vector<uint8_t> theirs(s.source.size());
      const bool their_ok = meshopt_decodeVertexBuffer(theirs.data(), s.count, s.stride, damaged.data(), damaged.size()) == 0;
      EXPECT_EQ(ok, their_ok) << name(s) << " trial " << trial;
      if (ok && their_ok) {
        EXPECT_EQ(mine, theirs) << name(s) << " trial " << trial;
      }
      (ok ? agreed_ok : agreed_refused) += ok == their_ok;
    }
  }
  EXPECT_GT(agreed_ok, 20u);
  EXPECT_GT(agreed_refused, 20u);
}

// Two scenes' primitives (streams, morph targets) and animations are the same, bit for bit.
void expect_same_content(const Scene& a, const Scene& b, const std::string& what) {
  ASSERT_EQ(a.primitives.size(), b.primitives.size()) << what;
  for (size_t p = 0; p < a.primitives.size(); ++p) {
    EXPECT_EQ(test::mesh_difference(a.primitives[p].mesh, b.primitives[p].mesh), "") << what << " primitive " << p;
    const std::vector<MorphTarget> ta = source_morph_targets(a, p), tb = source_morph_targets(b, p);
    ASSERT_EQ(ta.size(), tb.size()) << what << " primitive " << p;
    for (size_t k = 0; k < ta.size(); ++k) EXPECT_TRUE(ta[k] == tb[k]) << what << " primitive " << p << " target " << k;
  }
  ASSERT_EQ(a.animations.size(), b.animations.size()) << what;
  for (size_t k = 0; k < a.animations.size(); ++k) {
    ASSERT_EQ(a.animations[k].channels.size(), b.animations[k].channels.size()) << what;
    for (size_t c = 0; c < a.animations[k].channels.size(); ++c) {
      EXPECT_EQ(a.animations[k].channels[c].times, b.animations[k].channels[c].times) << what;
      EXPECT_EQ(a.animations[k].channels[c].values, b.animations[k].channels[c].values) << what;
    }
  }
}

// The file requires KHR_meshopt_compression, has no EXT_meshopt_compression left, and each of its
// (several) compressed vertex streams is at codec version 1.
void expect_khr_version1(const std::filesystem::path& file) {
  const test::Glb glb = test::read_glb(file);
  EXPECT_NE(glb.doc["extensionsRequired"].dump().find("KHR_meshopt_compression"), std::string::npos) << file;
  EXPECT_EQ(glb.doc.dump().find("EXT_meshopt_compression"), std::string::npos) << file;
  size_t version1 = 0;
  for (const Json& view : glb.doc["bufferViews"])
    if (view.contains("extensions") && view["extensions"]["KHR_meshopt_compression"].value("mode", "") == "ATTRIBUTES") {
      ++version1;
      EXPECT_EQ(glb.bin.at(view["extensions"]["KHR_meshopt_compression"].value("byteOffset", size_t(0))), 0xa1) << file;
    }
  EXPECT_GT(version1, 3u) << file;
}

// The test files: a skinned, animated character, and a torus's LOD chain with geomorph morph targets.
std::vector<std::filesystem::path> content_files(const test::TempDir& dir) {
  write_scene(fixtures::humanoid_scene(), dir / "humanoid.glb");
  write_scene(scene_from_mesh(shapes::torus(1.0f, 0.3f, 64, 32)), dir / "torus.glb");
  const test::RunResult r = test::run_cli({"lod", (dir / "torus.glb").string(), "-o", (dir / "chain.glb").string(), "--levels", "3", "--morph"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return {dir / "humanoid.glb", dir / "chain.glb"};
}

// lodkit's -c --meshopt-khr files: valid, every vertex stream at version 1, and what meshoptimizer's
// decoder makes of them (written back as EXT_meshopt_compression at version 0, read through
// Debian's library) is what -c's file holds; and they are smaller than -c's.
TEST(MeshoptCodec, WritesKhrMeshoptCompressionThatMeshoptimizerReads) {
  SKIP_WITHOUT_NODE();
  test::TempDir dir;
  for (const std::filesystem::path& plain : content_files(dir)) {
    const std::string stem = plain.stem().string();
    const auto khr = dir / (stem + "-khr.glb"), ext = dir / (stem + "-ext.glb"), back = dir / (stem + "-back.glb");
    test::RunResult r = test::run_cli({"convert", plain.string(), khr.string(), "-c", "--meshopt-khr"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = test::run_cli({"convert", plain.string(), ext.string(), "-c"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    test::expect_valid_gltf({khr});
    expect_khr_version1(khr);
    EXPECT_LT(std::filesystem::file_size(khr), std::filesystem::file_size(ext)) << stem;
    r = test::run_program({"node", vectors_script().string(), "ext", khr.string(), back.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(test::read_glb(back).doc.dump().find("KHR_meshopt_compression"), std::string::npos) << stem;
    // (Against -c's file, whose index codec starts triangles at the same corners.)
    expect_same_content(read_scene(ext), read_scene(back), stem);
    expect_same_content(read_scene(ext), read_scene(khr), stem);
  }
  const test::RunResult r = test::run_cli({"convert", (dir / "torus.glb").string(), (dir / "x.glb").string(), "--meshopt-khr"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("add -c"), std::string::npos) << r.err;
}

// What a viewer makes of a file: three.js's GLTFLoader (tests/gltf-loader/three_load.mjs), each
// primitive's triangles put in one order, each started at its smallest index (the index codec may
// start one at another corner; the order is the file's).
Json read_with_three(const std::filesystem::path& file) {
  const test::RunResult r =
      test::run_program({"node", (std::filesystem::path(LODKIT_SOURCE_DIR) / "tests/gltf-loader/three_load.mjs").string(), file.string()});
  EXPECT_EQ(r.exit_code, 0) << file << ": " << r.err;
  if (r.exit_code != 0) return Json();
  Json doc = Json::parse(r.out);
  for (Json& p : doc["primitives"]) {
    if (p["indices"].is_null()) continue;
    p["indices"] = test::canonical_triangles(p["indices"].get<std::vector<uint32_t>>());
  }
  return doc;
}

// A viewer reads lodkit's -c --meshopt-khr files as it reads -c's and the plain ones: three.js's
// GLTFLoader gets the same attributes, morph targets, triangles and clip tracks from each; with
// -q, the same from KHR_meshopt_compression as from EXT_meshopt_compression.
TEST(MeshoptCodec, ThreeJsReadsKhrMeshoptCompression) {
  SKIP_WITHOUT_NODE();
  if (!std::filesystem::exists(std::filesystem::path(LODKIT_SOURCE_DIR) / "tests/gltf-loader/node_modules/three"))
    GTEST_SKIP() << "three.js is not installed in tests/gltf-loader (scripts/setup.sh)";
  test::TempDir dir;
  for (const std::filesystem::path& plain : content_files(dir)) {
    const std::string stem = plain.stem().string();
    const auto file = [&](const std::string& suffix) { return dir / (stem + suffix + ".glb"); };
    for (const auto& [suffix, flags] : std::vector<std::pair<std::string, std::vector<std::string>>>{
             {"-khr", {"-c", "--meshopt-khr"}}, {"-ext", {"-c"}}, {"-khrq", {"-c", "-q", "--meshopt-khr"}}, {"-extq", {"-c", "-q"}}}) {
      std::vector<std::string> args = {"convert", plain.string(), file(suffix).string()};
      args.insert(args.end(), flags.begin(), flags.end());
      const test::RunResult r = test::run_cli(args);
      ASSERT_EQ(r.exit_code, 0) << r.err;
    }
    const Json seen = read_with_three(plain), khr = read_with_three(file("-khr"));
    ASSERT_FALSE(seen["primitives"].empty()) << stem;
    EXPECT_FALSE(seen["primitives"][0]["attributes"].empty()) << stem;
    EXPECT_TRUE(khr == seen) << stem;
    EXPECT_TRUE(khr == read_with_three(file("-ext"))) << stem;
    // Under -q a view of translation or scale keys keeps the exponential filter (16-bit mantissas,
    // one exponent per key) only where the codec makes it smaller, which may hold for one version
    // of the vertex codec and not the other: the keys agree within the filter's step.
    const Json khrq = read_with_three(file("-khrq")), extq = read_with_three(file("-extq"));
    EXPECT_TRUE(khrq["primitives"] == extq["primitives"]) << stem;
    ASSERT_EQ(khrq["clips"].size(), extq["clips"].size()) << stem;
    for (size_t c = 0; c < khrq["clips"].size(); ++c) {
      ASSERT_EQ(khrq["clips"][c].size(), extq["clips"][c].size()) << stem;
      for (size_t t = 0; t < khrq["clips"][c].size(); ++t) {
        const Json &a = khrq["clips"][c][t], &b = extq["clips"][c][t];
        EXPECT_EQ(a["name"], b["name"]);
        EXPECT_EQ(a["times"], b["times"]) << a["name"];
        const std::vector<double> va = a["values"], vb = b["values"];
        ASSERT_EQ(va.size(), vb.size()) << a["name"];
        double largest = 0;
        for (const double v : vb) largest = std::max(largest, std::abs(v));
        for (size_t k = 0; k < va.size(); ++k) EXPECT_LE(std::abs(va[k] - vb[k]), std::ldexp(largest, -15)) << a["name"] << " " << k;
      }
    }
    if (stem == "humanoid") {
      EXPECT_FALSE(seen["clips"].empty());
    } else {
      EXPECT_FALSE(seen["primitives"][0]["targets"].empty());  // (the geomorphs)
    }
  }
}

// A constant stream (a flat grid's normals) costs version 1 only its control bytes, 2 bits per byte
// position per 256 elements: over 64 times smaller than the data, the most version 0 allows, which
// the reader's size check took for a lie.
TEST(MeshoptCodec, ConstantStreamsReadBack) {
  test::TempDir dir;
  Mesh grid;
  const uint32_t n = 120;
  for (uint32_t j = 0; j < n; ++j)
    for (uint32_t i = 0; i < n; ++i) grid.positions.push_back({float(i), float(j), 0}), grid.normals.push_back({0, 0, 1});
  for (uint32_t j = 0; j + 1 < n; ++j)
    for (uint32_t i = 0; i + 1 < n; ++i) {
      const uint32_t a = j * n + i;
      grid.indices.insert(grid.indices.end(), {a, a + 1, a + n, a + 1, a + n + 1, a + n});
    }
  WriteOptions o;
  o.meshopt_compression = true;
  write_scene(scene_from_mesh(grid), dir / "ext.glb", o);
  o.meshopt_khr = true;
  write_scene(scene_from_mesh(grid), dir / "khr.glb", o);
  const test::Glb glb = test::read_glb(dir / "khr.glb");
  size_t smallest = SIZE_MAX;
  for (const Json& view : glb.doc["bufferViews"])
    if (view.contains("extensions")) smallest = std::min<size_t>(smallest, view["extensions"]["KHR_meshopt_compression"]["byteLength"]);
  EXPECT_LT(smallest * 64, size_t(n) * n * 12);  // the normals' stream
  const Scene ext = read_scene(dir / "ext.glb"), khr = read_scene(dir / "khr.glb");
  ASSERT_EQ(khr.primitives.size(), 1u);
  EXPECT_EQ(test::mesh_difference(ext.primitives[0].mesh, khr.primitives[0].mesh), "");
}

// A whole file in KHR_meshopt_compression with vertex codec version 1 (lodkit's -c output encoded
// again by meshoptimizer's JavaScript encoder) reads as the -c file it came from: a skinned,
// animated character and a torus's LOD chain with geomorph morph targets.
TEST(MeshoptCodec, ReadsKhrMeshoptCompressionVersion1Files) {
  SKIP_WITHOUT_NODE();
  test::TempDir dir;
  size_t channel_modes = 0;
  for (const std::filesystem::path& plain : content_files(dir)) {
    const std::string stem = plain.stem().string();
    const auto ext = dir / (stem + "-ext.glb"), khr = dir / (stem + "-khr.glb");
    test::RunResult r = test::run_cli({"convert", plain.string(), ext.string(), "-c"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = test::run_program({"node", vectors_script().string(), "khr", ext.string(), khr.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Json modes = Json::parse(r.out);
    for (const auto& [mode, n] : modes["channelModes"].items()) channel_modes += mode != "0" ? n.get<size_t>() : 0;
    expect_khr_version1(khr);  // (the file is what this test means it to be)
    expect_same_content(read_scene(ext), read_scene(khr), stem);
  }
  EXPECT_GT(channel_modes, 0u);  // the encoder chose 2-byte or XOR deltas somewhere
}

}  // namespace
}  // namespace lod
