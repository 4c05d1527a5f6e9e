// src/skin/lbs.cpp: linear blend skinning against a two-bone example computed by hand, the blended
// matrix, thread-count independence and the errors on bad joint data.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "lodkit/error.h"
#include "lodkit/skin.h"

namespace lod {
namespace {

void expect_near3(const float3& a, const float3& b, float tolerance = 1e-6f) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}

// Joint 0: identity. Joint 1: 90 degrees about z ((x, y, z) -> (-y, x, z)), then up by (0, 0, 1).
std::vector<mat4> two_bones() {
  const float h = float(std::sqrt(0.5));
  return {identity_matrix(), compose_trs({0, 0, 1}, {0, 0, h, h}, {1, 1, 1})};
}

TEST(SkinLbs, TwoBonesByHand) {
  Mesh mesh;
  mesh.positions = {{1, 0, 0}, {0, 2, 0}, {0, 0, 0}, {3, 0, 0}};
  mesh.normals = {{1, 0, 0}, {0, 0, 1}, {0, 1, 0}, {0, 1, 0}};
  // Vertex 2 lists joint 7 (no such matrix) in slots of weight 0: unused slots are never read.
  mesh.joints = {{0, 1, 0, 0}, {1, 0, 0, 0}, {1, 7, 7, 7}, {0, 0, 0, 0}};
  mesh.weights = {{0.5f, 0.5f, 0, 0}, {0.25f, 0.75f, 0, 0}, {1, 0, 0, 0}, {1, 0, 0, 0}};
  SkinnedVertices out;
  skin_vertices(mesh, two_bones(), out);
  ASSERT_EQ(out.positions.size(), 4u);
  ASSERT_EQ(out.normals.size(), 4u);
  // v0: J0 p = (1, 0, 0), J1 p = (0, 1, 0) + (0, 0, 1); half each = (0.5, 0.5, 0.5).
  expect_near3(out.positions[0], {0.5f, 0.5f, 0.5f});
  // Its normal: (0.5 I + 0.5 R)(1, 0, 0) = (0.5, 0.5, 0), renormalised.
  expect_near3(out.normals[0], {0.70710678f, 0.70710678f, 0});
  // v1: J1 p = (-2, 0, 1) with 0.25, J0 p = (0, 2, 0) with 0.75: (-0.5, 1.5, 0.25).
  expect_near3(out.positions[1], {-0.5f, 1.5f, 0.25f});
  expect_near3(out.normals[1], {0, 0, 1});  // both bones keep +z
  // v2: joint 1 alone: the origin goes up to (0, 0, 1); the normal (0, 1, 0) turns to (-1, 0, 0).
  expect_near3(out.positions[2], {0, 0, 1});
  expect_near3(out.normals[2], {-1, 0, 0});
  // v3: joint 0 alone: unchanged.
  EXPECT_EQ(out.positions[3], (float3{3, 0, 0}));
}

TEST(SkinLbs, BlendMatrixByHand) {
  // 0.5 I + 0.5 (R, t): linear part columns (0.5, 0.5, 0), (-0.5, 0.5, 0), (0, 0, 1); translation (0, 0, 0.5).
  const mat4 m = blend_matrix(two_bones(), {0, 1, 0, 0}, {0.5f, 0.5f, 0, 0});
  const mat4 expected = {0.5f, 0.5f, 0, 0, -0.5f, 0.5f, 0, 0, 0, 0, 1, 0, 0, 0, 0.5f, 1};
  for (size_t i = 0; i < 16; ++i) EXPECT_NEAR(m[i], expected[i], 1e-6f) << i;
  EXPECT_THROW(blend_matrix(two_bones(), {0, 2, 0, 0}, {0.5f, 0.5f, 0, 0}), Error);  // joint 2 of 2
}

TEST(SkinLbs, NoNormalsNoNormalsOut) {
  Mesh mesh;
  mesh.positions = {{1, 0, 0}};
  mesh.joints = {{1, 0, 0, 0}};
  mesh.weights = {{1, 0, 0, 0}};
  SkinnedVertices out;
  out.normals = {{9, 9, 9}};  // stale output from an earlier call
  skin_vertices(mesh, two_bones(), out);
  EXPECT_TRUE(out.normals.empty());
  expect_near3(out.positions[0], {0, 1, 1});
}

TEST(SkinLbs, SameResultOnAnyThreadCount) {
  // 100k vertices (several parallel blocks) with four influences each over 8 joints.
  std::vector<mat4> joints;
  for (int j = 0; j < 8; ++j) {
    const float a = 0.3f * float(j);
    joints.push_back(compose_trs({float(j), 0.5f * float(j), -1}, {0, std::sin(a), 0, std::cos(a)}, {1, 1, 1}));
  }
  Mesh mesh;
  for (uint32_t v = 0; v < 100000; ++v) {
    const float x = float(v % 101) * 0.01f, y = float(v % 37) * 0.03f, z = float(v % 13) * 0.07f;
    mesh.positions.push_back({x, y, z});
    mesh.normals.push_back({0, 0, 1});
    mesh.joints.push_back({uint16_t(v % 8), uint16_t((v + 1) % 8), uint16_t((v + 3) % 8), uint16_t((v + 5) % 8)});
    mesh.weights.push_back({0.4f, 0.3f, 0.2f, 0.1f});
  }
  SkinnedVertices one, two, many;
  skin_vertices(mesh, joints, one, 1);
  skin_vertices(mesh, joints, two, 2);
  skin_vertices(mesh, joints, many, 7);
  EXPECT_EQ(one.positions, two.positions);
  EXPECT_EQ(one.normals, two.normals);
  EXPECT_EQ(one.positions, many.positions);
  // Spot check against blend_matrix.
  for (const uint32_t v : {0u, 12345u, 99999u})
    expect_near3(one.positions[v], transform_point(blend_matrix(joints, mesh.joints[v], mesh.weights[v]), mesh.positions[v]), 1e-5f);
}

TEST(SkinLbs, BadJointDataThrows) {
  Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}};
  mesh.joints = {{0, 0, 0, 0}, {0, 2, 0, 0}};  // joint 2 with weight 0.5, but only 2 matrices
  mesh.weights = {{1, 0, 0, 0}, {0.5f, 0.5f, 0, 0}};
  SkinnedVertices out;
  EXPECT_THROW(skin_vertices(mesh, two_bones(), out), Error);
  mesh.joints[1] = {0, 1, 0, 0};
  EXPECT_NO_THROW(skin_vertices(mesh, two_bones(), out));
  mesh.weights.pop_back();  // stream sizes differ
  EXPECT_THROW(skin_vertices(mesh, two_bones(), out), Error);
  mesh.weights.push_back({1, 0, 0, 0});
  mesh.normals = {{0, 0, 1}};  // one normal for two vertices
  EXPECT_THROW(skin_vertices(mesh, two_bones(), out), Error);
}

}  // namespace
}  // namespace lod
