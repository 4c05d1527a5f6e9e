// Progressive meshes: any size in either direction equals the simplifier's replay, and the .lpm file
// round-trips and rejects corruption.
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include <zlib.h>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/lod.h"
#include "test_support.h"

namespace lod {
namespace {

Mesh cube_with_materials() {
  Mesh cube = subdivide_midpoint(subdivide_midpoint(shapes::cube()));
  cube.materials.resize(cube.triangle_count());
  for (size_t t = 0; t < cube.triangle_count(); ++t) cube.materials[t] = uint32_t(t / (cube.triangle_count() / 6));
  cube.material_names = {"a", "b", "c", "d", "e", "f"};
  return cube;
}

ProgressiveMesh make_pm(const Mesh& mesh) {
  SimplifyResult r = simplify(mesh, {.target_ratio = 0.0f, .normal_weight = 0.5f, .uv_weight = 0.5f});
  return ProgressiveMesh(mesh, std::move(r.record));
}

TEST(ProgressiveMesh, AnySizeInEitherDirectionIsTheReplay) {
  std::mt19937 rng(7);
  for (const Mesh& mesh : {shapes::torus(1.0f, 0.3f, 24, 12), cube_with_materials(), shapes::grid(10, 7)}) {
    ProgressiveMesh pm = make_pm(mesh);
    ASSERT_GT(pm.collapse_count(), 20u);
    EXPECT_EQ(pm.positions(), pm.max_positions());
    EXPECT_EQ(pm.mesh(), replay(mesh, pm.record(), 0));
    for (int step = 0; step < 25; ++step) {
      const size_t k = std::uniform_int_distribution<size_t>(0, pm.collapse_count())(rng);
      pm.set_collapses(k);
      ASSERT_EQ(pm.collapses_applied(), k);
      ASSERT_EQ(pm.positions(), pm.max_positions() - k);
      ASSERT_EQ(pm.mesh(), replay(mesh, pm.record(), k)) << "at " << k << " collapses";
    }
    // Sizes in positions, clamped; refine_to never coarsens, coarsen_to never refines.
    pm.set_collapses(pm.collapse_count() / 2);
    const uint32_t middle = pm.positions();
    pm.refine_to(middle - 3);
    EXPECT_EQ(pm.positions(), middle);
    pm.coarsen_to(middle - 3);
    EXPECT_EQ(pm.positions(), middle - 3);
    EXPECT_EQ(pm.mesh(), replay(mesh, pm.record(), pm.max_positions() - (middle - 3)));
    pm.refine_to(middle + 5);
    EXPECT_EQ(pm.positions(), middle + 5);
    pm.coarsen_to(0);
    EXPECT_EQ(pm.positions(), pm.min_positions());
    pm.refine_to(~0u);
    EXPECT_EQ(pm.mesh(), replay(mesh, pm.record(), 0));  // fully refined (compacted like the simplifier's output)
  }
}

TEST(ProgressiveMesh, ForeignRecordIsAUsageError) {
  SimplifyResult r = simplify(shapes::torus(1.0f, 0.3f, 24, 12), {.target_ratio = 0.1f});
  try {
    ProgressiveMesh pm(shapes::icosphere(1), std::move(r.record));
    FAIL() << "accepted a record of another mesh";
  } catch (const Error& e) {
    EXPECT_EQ(e.category(), ErrorCategory::usage);
  }
}

TEST(ProgressiveMeshFile, RoundTripIsExact) {
  test::TempDir dir;
  const ProgressiveMesh pm = make_pm(cube_with_materials());
  write_progressive_mesh(pm, dir / "cube.lpm");
  ProgressiveMesh back = read_progressive_mesh(dir / "cube.lpm");
  EXPECT_EQ(back.input(), pm.input());
  ASSERT_EQ(back.collapse_count(), pm.collapse_count());
  EXPECT_EQ(encode_progressive_mesh(back), encode_progressive_mesh(pm));
  back.set_collapses(back.collapse_count());
  EXPECT_EQ(back.mesh(), replay(pm.input(), pm.record(), pm.collapse_count()));
}

// Rewrites the payload checksum so a deliberate change reaches the checks behind it.
void fix_crc(std::string& bytes) {
  const uint32_t crc = uint32_t(crc32(0L, reinterpret_cast<const Bytef*>(bytes.data()) + 20, uInt(bytes.size() - 20)));
  std::memcpy(bytes.data() + 16, &crc, 4);
}

std::string rejection(const std::string& bytes) {
  try {
    decode_progressive_mesh({reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()}, "x.lpm");
  } catch (const Error& e) {
    EXPECT_EQ(e.category(), ErrorCategory::bad_input) << e.what();
    return e.what();
  }
  return "";
}

TEST(ProgressiveMeshFile, CorruptFilesAreRejectedWithTheirOffset) {
  const std::string good = encode_progressive_mesh(make_pm(shapes::torus(1.0f, 0.3f, 12, 6)));
  ASSERT_EQ(rejection(good), "");

  // Every truncation, and every single flipped byte (sampled), is refused.
  for (size_t n = 0; n < good.size(); n += 1 + n / 16) EXPECT_NE(rejection(good.substr(0, n)), "") << "length " << n;
  for (size_t i = 0; i < good.size(); i += 1 + i / 8) {
    std::string bad = good;
    bad[i] = char(bad[i] ^ 0x20);
    EXPECT_NE(rejection(bad), "") << "byte " << i;
  }
  std::string magic = good;
  magic[0] = 'X';
  EXPECT_NE(rejection(magic).find("magic"), std::string::npos);
  std::string version = good;
  version[4] = 9;
  EXPECT_NE(rejection(version).find("version 9"), std::string::npos);
  std::string crc = good;
  crc[good.size() - 1] = char(crc[good.size() - 1] ^ 1);
  EXPECT_NE(rejection(crc).find("checksum"), std::string::npos);

  // A huge declared count (with a valid checksum) is caught before any allocation.
  std::string huge = good;
  const uint64_t count = uint64_t(1) << 60;
  std::memcpy(huge.data() + 20, &count, 8);  // the position count
  fix_crc(huge);
  const std::string message = rejection(huge);
  EXPECT_NE(message.find("byte 20"), std::string::npos) << message;
  EXPECT_NE(message.find("exceeds"), std::string::npos) << message;

  // A relink pointing past the mesh's triangles (valid checksum) names the collapse.
  const ProgressiveMesh pm = make_pm(shapes::torus(1.0f, 0.3f, 12, 6));
  const Collapse& c = pm.record().collapses[3];
  ASSERT_GT(c.relink_count, 0u);
  const Relink& relink = pm.record().relinks[c.relinks_begin];
  Relink far = relink;
  far.triangle = 1u << 30;
  std::string bytes = encode_progressive_mesh(pm);
  const auto at = bytes.find(std::string(reinterpret_cast<const char*>(&relink), sizeof(Relink)));
  ASSERT_NE(at, std::string::npos);
  std::memcpy(bytes.data() + at, &far, sizeof(Relink));
  fix_crc(bytes);
  EXPECT_NE(rejection(bytes).find("collapse"), std::string::npos);

  // In range but not what the mesh holds there (a relink from another wedge): undo would not be
  // exact, so the record is refused too.
  Relink wrong = relink;
  wrong.from = (relink.from + 1) % uint32_t(pm.input().vertex_count());
  bytes = encode_progressive_mesh(pm);
  std::memcpy(bytes.data() + at, &wrong, sizeof(Relink));
  fix_crc(bytes);
  EXPECT_NE(rejection(bytes).find("collapse 3"), std::string::npos);
}

}  // namespace
}  // namespace lod
