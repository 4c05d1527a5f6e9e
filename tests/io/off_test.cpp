#include <gtest/gtest.h>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "test_support.h"

namespace lod {
namespace {

using test::bytes_of;

TEST(Off, ReadsCountsOnTheKeywordLineCommentsAndPolygons) {
  const std::string text = "OFF 5 2 0 # header and counts together\n"
                           "0 0 0\n1 0 0\n1 1 0 # trailing comment\n0 1 0\n\n# a comment line\n9 9 9\n"
                           "4 0 1 2 3\n3 2 1 4 0.5 0.5 0.5\n";
  Mesh m = read_off(bytes_of(text), "hand.off");
  EXPECT_EQ(m.vertex_count(), 5u);
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 2, 1, 4}));
  EXPECT_EQ(m.positions[4], (float3{9, 9, 9}));
}

TEST(Off, ReadsByteAndFloatColoursAndNormals) {
  Mesh c = read_off(bytes_of("COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 128\n0 1 0 0 0 255\n3 0 1 2\n"), "c.off");
  ASSERT_EQ(c.colors.size(), 3u);
  EXPECT_EQ(c.colors[0], (float4{1, 0, 0, 1}));
  EXPECT_FLOAT_EQ(c.colors[1].w, 128.0f / 255.0f);
  EXPECT_EQ(c.colors[2], (float4{0, 0, 1, 1}));  // rgb only: opaque
  Mesh f = read_off(bytes_of("COFF\n3 1 0\n0 0 0 0.5 0.25 1 1\n1 0 0 0 0 0 1\n0 1 0 1 1 1 0.5\n3 0 1 2\n"), "f.off");
  EXPECT_EQ(f.colors[0], (float4{0.5f, 0.25f, 1, 1}));
  Mesh n = read_off(bytes_of("NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n"), "n.off");
  EXPECT_EQ(n.normals[2], (float3{0, 0, 1}));
}

TEST(Off, RoundTripIsExactWithEveryStream) {
  Mesh m = shapes::torus();
  for (const float3& p : m.positions) m.colors.push_back({p.x * 0.3f + 0.5f, 1.0f / 7.0f, 0.0f, 1.0f});
  std::string text;
  write_off(m, text);
  EXPECT_EQ(text.rfind("STCNOFF\n", 0), 0u);
  Mesh back = read_off(bytes_of(text), "rt.off");
  EXPECT_EQ(test::mesh_difference(m, back), "");
}

TEST(Off, RejectsBadInput) {
  const char* cases[] = {
      "",                                          // empty
      "PLY\n3 1 0\n",                              // wrong keyword
      "4OFF\n",                                    // 4D
      "OFF BINARY\n3 1 0\n",                       // binary OFF
      "OFF\n3 1 0\n0 0 0\n1 0 0\n",                // truncated vertices
      "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",  // index out of range
      "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n",  // negative index
      "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n",     // two corners
      "OFF\n3 1 0\n0 0 nan\n1 0 0\n0 1 0\n3 0 1 2\n",  // NaN
      "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n1000000 0 1 2\n",  // a million corners
      "OFF\n4000000000 4000000000 0\n0 0 0\n",       // declared counts far beyond the file
      "OFF\n3 1 0\n0 0 0 7\n1 0 0\n0 1 0\n3 0 1 2\n",  // extra value on a vertex
  };
  for (const char* text : cases) test::expect_bad_input([](auto b, const auto& n) { read_off(b, n); }, text, "bad.off");
}

}  // namespace
}  // namespace lod
