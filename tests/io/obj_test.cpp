#include <gtest/gtest.h>

#include <algorithm>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "test_support.h"

namespace lod {
namespace {

using test::bytes_of;

Mesh obj_round_trip(const Mesh& m) {
  std::string text;
  write_obj(m, text);
  return read_obj(bytes_of(text), "round-trip.obj");
}

TEST(Obj, ReadsPolygonsNegativeIndicesGroupsAndMaterials) {
  const std::string text =
      "# a quad and a triangle\n"
      "mtllib scene.mtl\n"
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
      "vn 0 0 1\n"
      "g floor\n"
      "usemtl stone\n"
      "f 1/1/1 2/2/1 3/3/1 4/4/1\n"
      "g roof\n"
      "usemtl wood\n"
      "f -4/-4/-1 -2/-2/-1 -1/-1/-1\n";
  Mesh m = read_obj(bytes_of(text), "hand.obj");
  // The quad is fanned from its first corner: (0,1,2), (0,2,3).
  ASSERT_EQ(m.triangle_count(), 3u);
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 2, 3}));
  ASSERT_EQ(m.vertex_count(), 4u);  // the triangle reuses v/vt/vn triples 1, 3 and 4
  EXPECT_EQ(m.positions[2], (float3{1, 1, 0}));
  EXPECT_EQ(m.uvs[0][3], (float2{0, 1}));
  EXPECT_EQ(m.normals[1], (float3{0, 0, 1}));
  EXPECT_EQ(m.materials, (std::vector<uint32_t>{0, 0, 1}));
  EXPECT_EQ(m.material_names, (std::vector<std::string>{"stone", "wood"}));
  EXPECT_EQ(m.groups, (std::vector<uint32_t>{0, 0, 1}));
  EXPECT_EQ(m.group_names, (std::vector<std::string>{"floor", "roof"}));
}

TEST(Obj, PositionOnlyFilesKeepTheirVertexList) {
  const std::string text = "v 0 0 0\nv 9 9 9\nv 1 0 0\nv 0 1 0\nf 1 3 4\n";
  Mesh m = read_obj(bytes_of(text), "p.obj");
  EXPECT_EQ(m.vertex_count(), 4u);  // the unused vertex stays, in file order
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 2, 3}));
  EXPECT_TRUE(m.normals.empty());
  EXPECT_TRUE(m.uvs[0].empty());
}

TEST(Obj, SplitsVerticesAtUvSeams) {
  // Two triangles share positions 2 and 3 but with different texture coordinates on one side.
  const std::string text =
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\n"
      "f 1/1 2/2 3/3\nf 1/5 3/3 4/4\n";
  Mesh m = read_obj(bytes_of(text), "seam.obj");
  EXPECT_EQ(m.vertex_count(), 5u);
  EXPECT_EQ(position_ids(m).count, 4u);
  EXPECT_EQ(compute_stats(m).seam_edges, 1u);  // the diagonal 1-3 has position 1 split
}

TEST(Obj, VertexColorsExtension) {
  Mesh m = read_obj(bytes_of("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n"), "c.obj");
  ASSERT_EQ(m.colors.size(), 3u);
  EXPECT_EQ(m.colors[1], (float4{0, 1, 0, 1}));
}

// OBJ normals need not be unit length, and a corner may have none; Mesh::normals are unit
// (make_unit_directions): vn 0 0 2 reads as +z, a unit vn keeps its bits, and the second triangle's
// corners (no vn) take the smooth normal of the flat square, +z. Written to glTF, they validate.
TEST(Obj, NormalsReadAtUnitLength) {
  const std::string text =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 2\nvn 0.6 0.8 0\n"
      "f 1//1 2//2 3//1\nf 2 4 3\n";
  const Mesh m = read_obj(bytes_of(text), "n.obj");
  ASSERT_EQ(m.normals.size(), m.vertex_count());
  ASSERT_EQ(m.vertex_count(), 6u);  // 2 and 3 split: with and without a normal
  size_t unit_z = 0;
  for (const float3& n : m.normals) {
    if (n.x == 0.6f) {
      EXPECT_EQ(n, (float3{0.6f, 0.8f, 0}));  // (bit for bit)
    } else {
      EXPECT_EQ(n, (float3{0, 0, 1}));
      ++unit_z;
    }
  }
  EXPECT_EQ(unit_z, 5u);
  test::TempDir dir;
  write_mesh(m, dir / "n.glb");
  test::expect_valid_gltf({dir / "n.glb"});
}

TEST(Obj, RoundTripIsExactForShapes) {
  Mesh torus = shapes::torus();
  Mesh multi = shapes::cube();
  multi.materials.resize(12);
  multi.material_names = {"red", "green", "blue"};
  multi.groups.resize(12);
  multi.group_names = {"a", "b"};
  for (uint32_t t = 0; t < 12; ++t) multi.materials[t] = t / 4, multi.groups[t] = t / 6;
  Mesh colored = shapes::icosphere(2);
  colored.normals.clear();
  for (const float3& p : colored.positions) colored.colors.push_back({p.x * 0.5f + 0.5f, 0.25f, 1.0f / 3.0f, 1});
  for (const Mesh& shape : {shapes::icosphere(2), torus, multi, shapes::cylinder(), shapes::grid(4, 4), colored}) {
    Mesh first = obj_round_trip(shape);  // vertices now in OBJ's first-use order
    Mesh second = obj_round_trip(first);
    EXPECT_EQ(test::mesh_difference(first, second), "");
    EXPECT_EQ(first.triangle_count(), shape.triangle_count());
    EXPECT_EQ(first.material_names, second.material_names);
    EXPECT_EQ(first.group_names, second.group_names);
    // Whatever the order, every triangle keeps its exact corner positions.
    for (size_t t = 0; t < shape.triangle_count(); ++t)
      for (int k = 0; k < 3; ++k) ASSERT_EQ(first.positions[first.indices[3 * t + k]], shape.positions[shape.indices[3 * t + k]]);
  }
}

TEST(Obj, WriterSharesPositionsAcrossSeams) {
  std::string text;
  write_obj(shapes::cube(), text);
  size_t v_lines = 0;
  for (size_t i = 0; (i = text.find("\nv ", i)) != std::string::npos; ++i) ++v_lines;
  EXPECT_EQ(v_lines, 8u);  // one v per position, the seams carried by vt/vn
}

// A file of many small pieces (about 6 MB): every statement kind, relative indices that reach back
// across the places where a parallel read splits the file, seams, groups and materials.
std::string many_pieces(size_t pieces) {
  std::string text = "f 1 2 3\n";  // a forward reference before any v: valid once the file defines them
  for (size_t i = 0; i < pieces; ++i) {
    const std::string k = std::to_string(i);
    text += "v " + k + " 0 0\nv " + k + " 1 0 0.5 0.25 1\nv " + k + " 0 1\nvt 0." + k + " 1\nvn 0 0 1\n";
    if (i % 97 == 0) text += "usemtl m" + std::to_string(i % 5) + "\n";
    if (i % 89 == 0) text += "g part" + std::to_string(i % 7) + "\n";
    // Absolute, relative, and relative reaching 3 pieces back (another chunk near a split).
    text += "f " + std::to_string(3 * i + 1) + "/" + std::to_string(i + 1) + "/" + std::to_string(i + 1) + " -2/-1/-1 -1/-1/-1\n";
    if (i >= 3) text += "f -12//-4 -11//-4 -1//-1 -2//-1\n";
  }
  return text;
}

TEST(Obj, ParallelReadIsIdenticalForEveryThreadCount) {
  const std::string text = many_pieces(60000);
  ASSERT_GT(text.size(), 4u << 20);
  const Mesh one = read_obj(bytes_of(text), "pieces.obj", {.threads = 1});
  EXPECT_EQ(one.triangle_count(), 1 + 60000 + 2 * (60000 - 3));
  EXPECT_EQ(one.material_names.size(), 6u);  // "" for the faces before the first usemtl, then m0..m4
  EXPECT_EQ(one.group_names.size(), 8u);
  for (unsigned threads : {2u, 3u, 4u, 7u}) {
    SCOPED_TRACE(threads);
    EXPECT_EQ(test::mesh_difference(read_obj(bytes_of(text), "pieces.obj", {.threads = threads}), one), "");
  }
}

TEST(Obj, ParallelReadReportsTheLineOfTheFirstError) {
  std::string text = many_pieces(60000);
  // Count lines up to an error placed late in the file (it lands in the last chunk).
  const size_t late = text.rfind("f ", text.size() - 100);
  const std::string before = text.substr(0, late);
  const size_t line = size_t(std::count(before.begin(), before.end(), '\n')) + 1;
  for (const char* bad : {"f 1 2 999999999\n", "f -1 -2 -999999\n", "f 1 2\n", "v 1 nan 2\n"}) {
    SCOPED_TRACE(bad);
    const std::string broken = before + bad + text.substr(late);
    for (unsigned threads : {1u, 4u}) {
      const std::string message = test::expect_bad_input(
          [threads](auto b, const auto& n) { read_obj(b, n, {.threads = threads}); }, broken, "late.obj");
      EXPECT_EQ(message.rfind("late.obj:" + std::to_string(line) + ":", 0), 0u) << message;
    }
  }
}

TEST(Obj, RejectsBadInput) {
  const char* cases[] = {
      "v 0 0 0\nv 1 0 0\nf 1 2\n",              // 2 corners
      "v 0 0 0\nf 1 2 3\n",                      // index past the end
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 0 1 2\n",    // 0 is not an OBJ index
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nf -4 1 2\n",   // relative index before the first vertex
      "v 0 nan 0\n",                             // NaN
      "v 0 inf 0\n",                             // Inf
      "v 0 0\n",                                 // missing z
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1/x 2 3\n",  // junk texture index
      "bogus statement\n",                       // unknown keyword
  };
  for (const char* text : cases) test::expect_bad_input([](auto b, const auto& n) { read_obj(b, n); }, text, "bad.obj");
}

}  // namespace
}  // namespace lod
