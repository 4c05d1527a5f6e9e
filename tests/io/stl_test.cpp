// STL: welding on read, binary/ASCII detection, the facet normals we write, exact round trips.
#include <gtest/gtest.h>

#include <cstring>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "test_support.h"

namespace lod {
namespace {

using test::bytes_of;

template <class T>
void put(std::string& out, T v) {
  char raw[sizeof(T)];
  std::memcpy(raw, &v, sizeof(T));
  out.append(raw, sizeof(T));
}

// A binary STL of the given triangles (9 floats each) behind an 80-byte `header`.
std::string binary_stl(const std::vector<std::array<float, 9>>& triangles, std::string header = "hand made") {
  header.resize(80, ' ');
  std::string b = header;
  put(b, uint32_t(triangles.size()));
  for (const auto& t : triangles) {
    for (int k = 0; k < 3; ++k) put(b, 0.0f);
    for (float f : t) put(b, f);
    put(b, uint16_t(0x7fff));  // attribute bytes: ignored
  }
  return b;
}

TEST(Stl, BinaryWeldsIdenticalPositionsInFirstUseOrder) {
  // Two triangles of a unit square sharing the diagonal (1,0,0)-(0,1,0); -0 welds with +0.
  Mesh m = read_stl(bytes_of(binary_stl({{0, 0, 0, 1, 0, 0, 0, 1, 0}, {1, 0, 0, 1, 1, -0.0f, 0, 1, 0}})), "sq.stl");
  EXPECT_EQ(m.positions, (std::vector<float3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}));
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 1, 3, 2}));
}

TEST(Stl, BinaryWhoseHeaderStartsWithSolidIsStillBinary) {
  Mesh m = read_stl(bytes_of(binary_stl({{0, 0, 0, 1, 0, 0, 0, 1, 0}}, "solid but binary")), "solid.stl");
  EXPECT_EQ(m.triangle_count(), 1u);
  EXPECT_EQ(m.positions[1], (float3{1, 0, 0}));
}

TEST(Stl, AsciiWithSeveralSolidsPolygonsAndCrlf) {
  const std::string text =
      "solid first\r\n  facet normal 0 0 1\r\n    outer loop\r\n      vertex 0 0 0\r\n      vertex 1 0 0\r\n"
      "      vertex 1 1 0\r\n      vertex 0 1 0\r\n    endloop\r\n  endfacet\r\nendsolid first\r\n\r\n"
      "solid second\nfacet normal nan nan nan\nouter loop\nvertex 1 1 0\nvertex 0 1 0\nvertex 0.5 2 1e-2\nendloop\nendfacet\n"
      "endsolid\n";
  Mesh m = read_stl(bytes_of(text), "two.stl");
  EXPECT_EQ(m.positions, (std::vector<float3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5f, 2, 0.01f}}));
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 2, 3, 4}));
}

TEST(Stl, BinaryWriterHeaderSizeAndFacetNormals) {
  Mesh m;
  m.positions = {{0, 0, 0}, {2, 0, 0}, {0, 3, 0}, {0, 0, 5}};
  m.indices = {0, 1, 2, 0, 3, 1};
  std::string out;
  write_stl(m, out, {.binary = true});
  ASSERT_EQ(out.size(), 84u + 2 * 50u);
  EXPECT_NE(out.rfind("solid", 0), 0u);
  uint32_t count;
  std::memcpy(&count, out.data() + 80, 4);
  EXPECT_EQ(count, 2u);
  float n[2][3];
  std::memcpy(n[0], out.data() + 84, 12);
  std::memcpy(n[1], out.data() + 84 + 50, 12);
  // (2,0,0) x (0,3,0) points along +z; (0,0,5) x (2,0,0) along +y.
  EXPECT_EQ((std::vector<float>(n[0], n[0] + 3)), (std::vector<float>{0, 0, 1}));
  EXPECT_EQ((std::vector<float>(n[1], n[1] + 3)), (std::vector<float>{0, 1, 0}));
}

TEST(Stl, RoundTripIsExactInBothEncodings) {
  const Mesh m = shapes::icosphere(2);
  for (bool binary : {true, false}) {
    SCOPED_TRACE(binary ? "binary" : "ascii");
    std::string out;
    write_stl(m, out, {.binary = binary});
    Mesh back = read_stl(bytes_of(out), "rt.stl");
    // The icosphere has no duplicate positions and its vertices appear in first-use order only if
    // renumbered: compare corners instead of vertex ids.
    ASSERT_EQ(back.triangle_count(), m.triangle_count());
    EXPECT_EQ(back.vertex_count(), m.vertex_count());
    for (size_t c = 0; c < m.indices.size(); ++c)
      ASSERT_EQ(std::memcmp(&back.positions[back.indices[c]], &m.positions[m.indices[c]], sizeof(float3)), 0) << c;
    std::string again;
    write_stl(back, again, {.binary = binary});
    EXPECT_EQ(again, out);
  }
}

TEST(Stl, RejectsBadInput) {
  const std::string facet = "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n";
  const std::string cases[] = {
      "",
      "solid x\n" + facet,                                                   // no endsolid
      "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid\n",  // 2 corners
      "solid x\nfacet normal 0 0 1\nvertex 0 0 0\nendsolid\n",              // no outer loop
      "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0 0\nendloop\nendfacet\nendsolid\n",  // 4 coordinates
      "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 nan 0\nendloop\nendfacet\nendsolid\n",  // NaN
      "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendfacet\nendsolid\n",  // no endloop
      "solid x\nbanana\nendsolid\n",                                        // unknown keyword
      "tiny",                                                                // too short for binary
      binary_stl({{0, 0, 0, 1, 0, 0, 0, 1, 0}}).substr(0, 100),             // truncated binary
  };
  for (const std::string& text : cases) test::expect_bad_input([](auto b, const auto& n) { read_stl(b, n); }, text, "bad.stl");
  // 4e9 triangles declared in a 200-byte file: rejected from the header, before any allocation.
  std::string huge = binary_stl({});
  const uint32_t declared = 4000000000u;
  std::memcpy(huge.data() + 80, &declared, 4);
  huge.resize(200, '\0');
  const std::string message = test::expect_bad_input([](auto b, const auto& n) { read_stl(b, n); }, huge, "huge.stl");
  EXPECT_NE(message.find("4000000000"), std::string::npos) << message;
}

}  // namespace
}  // namespace lod
