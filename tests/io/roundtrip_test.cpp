// Round trips through every writer and reader, on every corpus mesh: read -> write -> read is exact
// (bitwise) from the first read on, and no format moves a triangle corner.
#include <gtest/gtest.h>

#include <cstring>

#include "lodkit/error.h"
#include "lodkit/io.h"
#include "test_support.h"

namespace lod {
namespace {

struct Target {
  const char* extension;
  bool binary;
};
constexpr Target targets[] = {{".obj", false}, {".off", false}, {".ply", true}, {".ply", false},
                              {".stl", true},  {".stl", false}, {".glb", true}, {".gltf", true}};

// Triangle i of `a` and of `b` have bit-identical corner positions.
std::string corner_difference(const Mesh& a, const Mesh& b) {
  if (a.triangle_count() != b.triangle_count())
    return "triangle count " + std::to_string(a.triangle_count()) + " vs " + std::to_string(b.triangle_count());
  for (size_t c = 0; c < a.indices.size(); ++c) {
    const float3 &p = a.positions[a.indices[c]], &q = b.positions[b.indices[c]];
    if (std::memcmp(&p, &q, sizeof p) != 0) return "corner " + std::to_string(c) + " moved";
  }
  return {};
}

TEST(RoundTrip, EveryFormatOnEveryCorpusMesh) {
  auto files = test::corpus_files();
  if (files.empty()) GTEST_SKIP() << "corpus absent: run scripts/fetch-corpus.sh";
  test::TempDir dir;
  size_t checked = 0;
  for (const auto& file : files) {
    if (file.filename() == "SOURCE") continue;
    SCOPED_TRACE(file.filename().string());
    Mesh original;
    try {
      original = read_mesh(file);
    } catch (const Error& e) {
      ADD_FAILURE() << e.what();
      continue;
    }
    for (const Target& t : targets) {
      SCOPED_TRACE(std::string(t.extension) + (t.binary ? " binary" : " text"));
      auto path1 = dir / (std::string("first") + t.extension), path2 = dir / (std::string("second") + t.extension);
      try {
        write_mesh(original, path1, {.binary = t.binary});
        Mesh first = read_mesh(path1);
        write_mesh(first, path2, {.binary = t.binary});
        Mesh second = read_mesh(path2);
        EXPECT_EQ(test::mesh_difference(first, second), "");
        EXPECT_EQ(corner_difference(original, first), "");
      } catch (const Error& e) {
        ADD_FAILURE() << e.what();
      }
    }
    ++checked;
  }
  EXPECT_GT(checked, 140u);
}

}  // namespace
}  // namespace lod
