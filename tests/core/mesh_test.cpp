#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/mesh.h"

namespace lod {
namespace {

double total_area(const Mesh& m) {
  double area = 0;
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    const float3 &a = m.positions[m.indices[3 * t]], &b = m.positions[m.indices[3 * t + 1]], &c = m.positions[m.indices[3 * t + 2]];
    double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z, vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
    double cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
    area += 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
  }
  return area;
}

TEST(PositionIds, CubeSharesEightPositions) {
  Mesh m = shapes::cube();
  PositionIds ids = position_ids(m);
  EXPECT_EQ(ids.count, 8u);
  ASSERT_EQ(ids.id.size(), 24u);
  for (size_t a = 0; a < 24; ++a)
    for (size_t b = 0; b < 24; ++b) EXPECT_EQ(ids.id[a] == ids.id[b], m.positions[a] == m.positions[b]);
}

TEST(PositionIds, DenseInOrderOfFirstAppearance) {
  Mesh m;
  m.positions = {{1, 2, 3}, {4, 5, 6}, {1, 2, 3}, {7, 8, 9}, {4, 5, 6}};
  PositionIds ids = position_ids(m);
  EXPECT_EQ(ids.count, 3u);
  EXPECT_EQ(ids.id, (std::vector<uint32_t>{0, 1, 0, 2, 1}));
}

TEST(PositionIds, ManyPositionsGrowTheTable) {
  Mesh m;
  for (int i = 0; i < 100000; ++i) m.positions.push_back({float(i % 1000), float(i / 1000), 0});
  for (int i = 0; i < 100000; ++i) m.positions.push_back(m.positions[size_t(i)]);
  PositionIds ids = position_ids(m);
  EXPECT_EQ(ids.count, 100000u);
  for (size_t i = 0; i < 100000; ++i) ASSERT_EQ(ids.id[i], ids.id[i + 100000]);
}

// Hand-derived: a triangle in the z = 0 plane, wound counter-clockwise, faces +z; the same triangle
// twice, once reversed, cancels. On a torus every vertex's normal is within the facets' tilt of the
// round torus's, and the UV seam's copies of a position share one.
TEST(SmoothNormals, AreaWeightedAtPositions) {
  Mesh one;
  one.positions = {{0, 0, 0}, {2, 0, 0}, {0, 3, 0}};
  one.indices = {0, 1, 2};
  for (const float3& n : smooth_normals(one)) EXPECT_EQ(n, (float3{0, 0, 1}));
  one.indices.insert(one.indices.end(), {0, 2, 1});
  for (const float3& n : smooth_normals(one)) EXPECT_EQ(n, (float3{0, 0, 0}));

  const Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);
  const std::vector<float3> normals = smooth_normals(torus);
  ASSERT_EQ(normals.size(), torus.vertex_count());
  const PositionIds ids = position_ids(torus);
  std::vector<size_t> first(ids.count, SIZE_MAX);
  for (size_t v = 0; v < torus.vertex_count(); ++v) {
    const float3 &p = torus.positions[v], &n = normals[v];
    const double r = std::hypot(double(p.x), double(p.y));
    const double tx = (p.x - p.x / r) / 0.3, ty = (p.y - p.y / r) / 0.3, tz = p.z / 0.3;  // the round torus's
    EXPECT_GT(n.x * tx + n.y * ty + n.z * tz, std::cos(0.1)) << v;  // (facets 9 and 18 degrees wide)
    if (first[ids.id[v]] == SIZE_MAX) first[ids.id[v]] = v;
    EXPECT_EQ(n, normals[first[ids.id[v]]]) << v;
  }
}

TEST(Validate, AcceptsShapesAndRejectsBadData) {
  for (const Mesh& m : {shapes::icosphere(2), shapes::torus(), shapes::grid(3, 4), shapes::cube(), shapes::cylinder(), shapes::fin()})
    EXPECT_NO_THROW(validate(m));
  auto expect_bad = [](Mesh m, const char* why) {
    try {
      validate(m, "test-mesh");
      ADD_FAILURE() << "accepted: " << why;
    } catch (const Error& e) {
      EXPECT_EQ(e.category(), ErrorCategory::bad_input) << why;
      EXPECT_NE(std::string(e.what()).find("test-mesh"), std::string::npos) << e.what();
    }
  };
  Mesh m = shapes::cube();
  m.indices[5] = 24;
  expect_bad(m, "index out of range");
  m = shapes::cube();
  m.positions[3].y = std::numeric_limits<float>::quiet_NaN();
  expect_bad(m, "NaN position");
  m = shapes::cube();
  m.normals.pop_back();
  expect_bad(m, "short normal stream");
  m = shapes::cube();
  m.indices.pop_back();
  expect_bad(m, "index count not a multiple of 3");
  m = shapes::cube();
  m.joints.assign(24, {0, 1, 0, 0});
  m.weights.assign(24, {0.5f, 0.25f, 0, 0});
  expect_bad(m, "weights summing to 0.75");
  m.weights.assign(24, {0.5f, 0.5f, 0, 0});
  EXPECT_NO_THROW(validate(m));
  m.materials.assign(11, 0);
  expect_bad(m, "material stream of the wrong size");
}

TEST(Shapes, CountsMatchTheirDefinitions) {
  EXPECT_EQ(shapes::icosphere(0).vertex_count(), 12u);
  EXPECT_EQ(shapes::icosphere(2).vertex_count(), 162u);  // 10 * 4^2 + 2
  Mesh cube = shapes::cube();
  EXPECT_EQ(cube.vertex_count(), 24u);
  EXPECT_EQ(cube.triangle_count(), 12u);
  EXPECT_NEAR(total_area(cube), 24.0, 1e-9);  // six 2 x 2 faces
  EXPECT_NEAR(total_area(shapes::grid(5, 3)), 1.0, 1e-6);
  Mesh f = shapes::fin();
  EXPECT_EQ(f.vertex_count(), 5u);
  EXPECT_EQ(f.triangle_count(), 3u);
}

TEST(Subdivide, QuadruplesTrianglesAndKeepsTheSurface) {
  Mesh grid = shapes::grid(3, 2);
  Mesh fine = subdivide_midpoint(grid);
  EXPECT_EQ(fine.triangle_count(), 4 * grid.triangle_count());
  EXPECT_NEAR(total_area(fine), total_area(grid), 1e-6);
  // V' = V + E for a 1 -> 4 split: a 3 x 2 grid has 12 vertices and 23 edges.
  EXPECT_EQ(fine.vertex_count(), 12u + 23u);
  MeshStats s = compute_stats(fine);
  EXPECT_EQ(s.boundary_loops, 1u);
  EXPECT_EQ(s.euler_characteristic, 1);
  EXPECT_NO_THROW(validate(fine));
  // Attributes are interpolated: the uv of a grid vertex equals its xy.
  for (size_t v = 0; v < fine.vertex_count(); ++v) {
    EXPECT_FLOAT_EQ(fine.uvs[0][v].x, fine.positions[v].x);
    EXPECT_FLOAT_EQ(fine.uvs[0][v].y, fine.positions[v].y);
  }
}

TEST(Subdivide, KeepsClosedSurfacesClosedAndCarriesMaterials) {
  Mesh cube = shapes::cube();
  cube.materials.resize(12);
  for (uint32_t t = 0; t < 12; ++t) cube.materials[t] = t / 2;
  Mesh fine = subdivide_midpoint(subdivide_midpoint(cube));
  EXPECT_EQ(fine.triangle_count(), 12u * 16u);
  ASSERT_EQ(fine.materials.size(), fine.triangle_count());
  for (size_t t = 0; t < fine.triangle_count(); ++t) EXPECT_EQ(fine.materials[t], uint32_t(t / 32));
  MeshStats s = compute_stats(fine);
  EXPECT_EQ(s.boundary_edges, 0u);
  EXPECT_EQ(s.euler_characteristic, 2);
  EXPECT_NEAR(total_area(fine), 24.0, 1e-5);
}

}  // namespace
}  // namespace lod
