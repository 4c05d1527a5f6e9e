// Eight influences per vertex (issue 7: "up to 4 influences now, and 8 if the input has them"): a
// second set in Mesh::joints1/weights1 is skinned against hand computations, simplified in every mode
// with valid influences, morphed, carried by every stream operation (weld, remap, subdivide, flatten,
// PLY, .lpm), read and written as glTF JOINTS_1/WEIGHTS_1 and run through `lodkit lod`.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <numbers>
#include <tuple>

#include "lodkit/error.h"
#include "lodkit/measure.h"
#include "lodkit/optimize.h"
#include "lodkit/skin.h"
#include "skin/fixtures.h"
#include "skin/skin_test_support.h"
#include "test_support.h"

namespace lod {
namespace {

using fixtures::tentacle_bones;
using skin_test::expect_valid_influences;
using skin_test::skinned;

mat4 translation(float x, float y, float z) { return compose_trs({x, y, z}, {0, 0, 0, 1}, {1, 1, 1}); }

// The tentacle's joint matrices with every joint turned by `angle` radians about +z, through the
// library's scene code (TRS, world and joint matrices).
std::vector<mat4> curled(const Scene& scene, float angle) {
  Pose pose = rest_pose(scene);
  for (uint32_t j = 0; j < tentacle_bones; ++j) pose.rotation[j] = {0, 0, std::sin(angle / 2), std::cos(angle / 2)};
  return joint_matrices(scene, 0, world_matrices(scene, pose));
}

// The tentacle with its first influence set only (its heaviest four), renormalised.
Mesh heaviest_four(const Mesh& m) {
  Mesh four = m;
  four.joints1.clear(), four.weights1.clear();
  for (float4& w : four.weights) {
    const float s = w.x + w.y + w.z + w.w;
    w = {w.x / s, w.y / s, w.z / s, w.w / s};
  }
  return four;
}

// By hand, in double: joint i of the curled chain is T(i) R T(-i) after joint i - 1's, so a point is
// turned about the pivots x = i, i - 1, ..., 0 in that order; the vertex is sum_i w_i(x) J_i p.
float3 curled_by_hand(const float3& p, double angle) {
  const std::array<double, tentacle_bones> w = fixtures::tentacle_weights(p.x);
  const double c = std::cos(angle), s = std::sin(angle);
  double out[3] = {0, 0, 0};
  for (uint32_t i = 0; i < tentacle_bones; ++i) {
    double x = p.x, y = p.y;
    for (uint32_t k = i + 1; k-- > 0;) {
      const double dx = x - k;
      x = k + c * dx - s * y;
      y = s * dx + c * y;
    }
    out[0] += w[i] * x, out[1] += w[i] * y, out[2] += w[i] * p.z;
  }
  return {float(out[0]), float(out[1]), float(out[2])};
}

double distance(const float3& a, const float3& b) {
  const double x = double(a.x) - b.x, y = double(a.y) - b.y, z = double(a.z) - b.z;
  return std::sqrt(x * x + y * y + z * z);
}

// The tentacle's influences are a function of x: every vertex of `out` at an input position carries
// exactly the four streams of the input vertices there.
void expect_influences_follow_positions(const Mesh& out, const Mesh& in) {
  using Key = std::tuple<float, float, float>;
  std::map<Key, uint32_t> at;
  for (uint32_t v = 0; v < in.vertex_count(); ++v) at.emplace(Key{in.positions[v].x, in.positions[v].y, in.positions[v].z}, v);
  ASSERT_EQ(out.joints1.size(), out.vertex_count());
  ASSERT_EQ(out.weights1.size(), out.vertex_count());
  for (size_t v = 0; v < out.vertex_count(); ++v) {
    const auto it = at.find(Key{out.positions[v].x, out.positions[v].y, out.positions[v].z});
    ASSERT_NE(it, at.end()) << "vertex " << v << " is not at an input position";
    const uint32_t o = it->second;
    ASSERT_EQ(out.joints[v], in.joints[o]) << v;
    ASSERT_EQ(out.weights[v], in.weights[o]) << v;
    ASSERT_EQ(out.joints1[v], in.joints1[o]) << v;
    ASSERT_EQ(out.weights1[v], in.weights1[o]) << v;
  }
}

// ---- linear blend skinning ---------------------------------------------------------------------------

// Joints 0..7 translate by (i, 10 i, 0), except joint 7: R_z(90) then a translation by (7, 70, 0).
std::vector<mat4> eight_joints() {
  std::vector<mat4> joints;
  for (int i = 0; i < 7; ++i) joints.push_back(translation(float(i), 10.0f * float(i), 0));
  joints.push_back(multiply(translation(7, 70, 0), compose_trs({}, {0, 0, std::sqrt(0.5f), std::sqrt(0.5f)}, {1, 1, 1})));
  return joints;
}

TEST(EightInfluences, LbsMatchesAHandComputedExample) {
  Mesh m;
  m.positions = {{1, 0, 0}, {0, 0, 2}};
  m.normals = {{1, 0, 0}, {1, 0, 0}};
  // Vertex 0: 0.1 on joints 0..3 (first set), 0.15 on joints 4..6 and 0.15 on joint 7 (second set).
  // Vertex 1: the whole weight on joint 7, in the second set.
  m.joints = {{0, 1, 2, 3}, {0, 0, 0, 0}};
  m.weights = {{0.1f, 0.1f, 0.1f, 0.1f}, {0, 0, 0, 0}};
  m.joints1 = {{4, 5, 6, 7}, {0, 7, 0, 0}};
  m.weights1 = {{0.15f, 0.15f, 0.15f, 0.15f}, {0, 1, 0, 0}};
  validate(m);
  SkinnedVertices out;
  skin_vertices(m, eight_joints(), out);
  // Vertex 0: translations 0.1 (0+1+2+3) + 0.15 (4+5+6) = 0.6 + 2.25 = 2.85 along x (times 10 along y),
  // plus 0.15 of joint 7: R_z(90) (1,0,0) + (7,70,0) = (7,71,0). And 0.85 of the point (1,0,0) itself.
  // x = 0.85 + 2.85 + 0.15 * 7 = 4.75; y = 28.5 + 0.15 * 71 = 39.15.
  EXPECT_NEAR(out.positions[0].x, 4.75f, 1e-5f);
  EXPECT_NEAR(out.positions[0].y, 39.15f, 1e-4f);
  EXPECT_NEAR(out.positions[0].z, 0.0f, 1e-6f);
  // Its normal: 0.85 (1,0,0) + 0.15 (0,1,0), normalised.
  const float len = std::sqrt(0.85f * 0.85f + 0.15f * 0.15f);
  EXPECT_NEAR(out.normals[0].x, 0.85f / len, 1e-6f);
  EXPECT_NEAR(out.normals[0].y, 0.15f / len, 1e-6f);
  // Vertex 1: joint 7 alone: R_z(90) (0,0,2) + (7,70,0); the normal turns to +y.
  EXPECT_NEAR(out.positions[1].x, 7.0f, 1e-5f);
  EXPECT_NEAR(out.positions[1].y, 70.0f, 1e-5f);
  EXPECT_NEAR(out.positions[1].z, 2.0f, 1e-6f);
  EXPECT_NEAR(out.normals[1].x, 0.0f, 1e-6f);
  EXPECT_NEAR(out.normals[1].y, 1.0f, 1e-6f);
  // blend_matrix with both sets agrees.
  const mat4 b = blend_matrix(eight_joints(), m.joints[0], m.weights[0], m.joints1[0], m.weights1[0]);
  const float3 p = transform_point(b, m.positions[0]);
  EXPECT_NEAR(p.x, 4.75f, 1e-5f);
  EXPECT_NEAR(p.y, 39.15f, 1e-4f);
  // A joint outside the matrices in the second set is refused, as in the first.
  Mesh bad = m;
  bad.joints1[1] = {0, 8, 0, 0};
  EXPECT_THROW(skin_vertices(bad, eight_joints(), out), Error);
  EXPECT_THROW(blend_matrix(eight_joints(), bad.joints[1], bad.weights[1], bad.joints1[1], bad.weights1[1]), Error);
  bad = m;
  bad.weights1.pop_back();
  EXPECT_THROW(skin_vertices(bad, eight_joints(), out), Error);
}

TEST(EightInfluences, TentacleSkinsLikeTheDirectSumOverItsBones) {
  const Scene scene = fixtures::tentacle_scene();
  const Mesh& m = scene.primitives[0].mesh;
  validate(m, "tentacle", {.weight_tolerance = 1e-6f});
  EXPECT_EQ(m.influence_slots(), 8u);
  const Mesh first_set_only = heaviest_four(m);  // what a four-influence reader would have skinned
  for (const float angle : {0.0f, 0.2f, 0.35f}) {
    const std::vector<mat4> pose = curled(scene, angle);
    SkinnedVertices out, four;
    skin_vertices(m, pose, out, 2);
    skin_vertices(first_set_only, pose, four);
    double worst = 0, worst_four = 0;
    for (size_t v = 0; v < m.vertex_count(); ++v) {
      const float3 expected = curled_by_hand(m.positions[v], angle);
      worst = std::max(worst, distance(out.positions[v], expected));
      worst_four = std::max(worst_four, distance(four.positions[v], expected));
    }
    EXPECT_LE(worst, 2e-5) << "angle " << angle;
    if (angle > 0.1f) {
      EXPECT_GT(worst_four, 0.05) << "the second set should matter at angle " << angle;
    }
  }
}

// ---- simplification ------------------------------------------------------------------------------

std::vector<std::vector<mat4>> tentacle_poses(const Scene& scene, int count) {
  std::vector<std::vector<mat4>> poses;
  for (int k = 0; k < count; ++k) poses.push_back(curled(scene, 0.35f * float(k) / float(count - 1)));
  return poses;
}

TEST(EightInfluences, EveryModeKeepsEightValidInfluences) {
  const Scene scene = fixtures::tentacle_scene();
  const Mesh& m = scene.primitives[0].mesh;
  const auto poses = tentacle_poses(scene, 6);
  for (const SkinMode mode : {SkinMode::houle, SkinMode::subset, SkinMode::multipose}) {
    SCOPED_TRACE(skin_mode_name(mode));
    const SimplifyResult r = skin_test::simplify_in_mode(m, mode, 0.15f, poses, 3);
    EXPECT_LE(r.mesh.triangle_count(), m.triangle_count() * 0.15 + 2);
    const size_t wide = expect_valid_influences(r.mesh, tentacle_bones);
    // Most of the tentacle blends more than four bones; the output must still.
    EXPECT_GT(wide, r.mesh.vertex_count() / 2);
    switch (mode) {
      case SkinMode::subset: {
        // Input vertices with their influences: they skin exactly as their origins.
        const Mesh a = skinned(r.mesh, poses[5]), b = skinned(m, poses[5]);
        for (size_t v = 0; v < r.mesh.vertex_count(); ++v) ASSERT_EQ(a.positions[v], b.positions[r.vertex_origin[v]]) << v;
        expect_influences_follow_positions(r.mesh, m);
        break;
      }
      case SkinMode::houle: {
        // Skinned in its pose, the result is the static simplification of the posed tentacle: the way
        // back to bind space went through all eight influences.
        const SimplifyResult s = simplify(skinned(m, poses[3]), {.target_ratio = 0.15f});
        ASSERT_EQ(r.mesh.indices, s.mesh.indices);
        const Mesh back = skinned(r.mesh, poses[3]);
        double worst = 0;
        for (size_t v = 0; v < back.vertex_count(); ++v) worst = std::max(worst, distance(back.positions[v], s.mesh.positions[v]));
        EXPECT_LE(worst, 1e-5 * r.diagonal);
        for (size_t v = 0; v < r.mesh.vertex_count(); ++v) {
          ASSERT_EQ(r.mesh.joints1[v], m.joints1[r.vertex_origin[v]]) << v;
          ASSERT_EQ(r.mesh.weights1[v], m.weights1[r.vertex_origin[v]]) << v;
        }
        break;
      }
      case SkinMode::multipose: break;
    }
  }
}

// The worst distance over the range of motion between the skinned tentacle and the skinned LOD.
double worst_over_motion(const Mesh& original, const Mesh& lod, const Scene& scene) {
  double worst = 0;
  for (int k = 0; k <= 8; ++k) {
    const std::vector<mat4> pose = curled(scene, 0.35f * float(k) / 8);
    worst = std::max(worst, compare(skinned(original, pose), skinned(lod, pose), {.samples = 20'000}).hausdorff);
  }
  return worst;
}

// Keeping eight influences is the point: the multi-pose LOD of the eight-influence tentacle follows it
// closer over the range of motion than the same LOD built from its heaviest four influences.
TEST(EightInfluences, MultiposeWithEightFollowsTheMotionBetterThanWithFour) {
  const Scene scene = fixtures::tentacle_scene();
  const Mesh& m = scene.primitives[0].mesh;
  const Mesh four = heaviest_four(m);
  SkinSimplifyOptions o;
  o.simplify.target_ratio = 0.1f;
  o.poses = tentacle_poses(scene, 8);
  const SimplifyResult eight_lod = simplify_skinned(m, o), four_lod = simplify_skinned(four, o);
  EXPECT_TRUE(four_lod.mesh.joints1.empty());
  const double with_eight = worst_over_motion(m, eight_lod.mesh, scene);
  const double with_four = worst_over_motion(m, four_lod.mesh, scene);
  EXPECT_LT(with_eight, 0.5 * with_four) << with_eight << " vs " << with_four;
}

// A second set of weight 0 changes nothing: the two-bone arm simplifies to the very same mesh with and
// without it (the candidates and their blends never have more than four influences there).
TEST(EightInfluences, AnEmptySecondSetChangesNothing) {
  const Mesh arm = fixtures::arm();
  Mesh padded = arm;
  padded.joints1.assign(arm.vertex_count(), {});
  padded.weights1.assign(arm.vertex_count(), {});
  std::vector<std::vector<mat4>> poses;
  for (int k = 0; k < 6; ++k) poses.push_back(fixtures::bent(2.0f * float(k) / 5));
  for (const SkinMode mode : {SkinMode::houle, SkinMode::subset, SkinMode::multipose}) {
    SCOPED_TRACE(skin_mode_name(mode));
    const SimplifyResult a = skin_test::simplify_in_mode(arm, mode, 0.1f, poses, 2);
    const SimplifyResult b = skin_test::simplify_in_mode(padded, mode, 0.1f, poses, 2);
    EXPECT_EQ(a.mesh.indices, b.mesh.indices);
    EXPECT_EQ(a.mesh.positions, b.mesh.positions);
    EXPECT_EQ(a.mesh.joints, b.mesh.joints);
    EXPECT_EQ(a.mesh.weights, b.mesh.weights);
    EXPECT_EQ(a.error, b.error);
    ASSERT_EQ(b.mesh.weights1.size(), b.mesh.vertex_count());
    for (size_t v = 0; v < b.mesh.vertex_count(); ++v) ASSERT_EQ(b.mesh.weights1[v], float4{}) << v;
  }
}

// ---- skeletal geomorph -------------------------------------------------------------------------------

TEST(EightInfluences, GeomorphEndsAreTheSkinnedLevels) {
  const Scene scene = fixtures::tentacle_scene();
  const LodChain chain = skin_test::multipose_chain(scene.primitives[0].mesh, tentacle_poses(scene, 6), {1.0f, 0.3f});
  ASSERT_EQ(chain.levels.size(), 2u);
  EXPECT_GT(expect_valid_influences(chain.levels[1].mesh, tentacle_bones), 0u);
  for (const float angle : {0.1f, 0.3f}) {
    SCOPED_TRACE(angle);
    skin_test::expect_geomorph_ends(chain, curled(scene, angle), 1e-5f);
  }
}

// Two levels that differ only in the second set: every vertex moves, and t = 1 is the coarser skin.
TEST(EightInfluences, GeomorphComparesTheSecondSet) {
  const Scene scene = fixtures::tentacle_scene(16, 8);
  const Mesh& finer = scene.primitives[0].mesh;
  Mesh coarser = finer;
  for (size_t v = 0; v < coarser.vertex_count(); ++v) std::swap(coarser.joints1[v][0], coarser.joints1[v][3]);
  Geomorph table;
  for (uint32_t v = 0; v < finer.vertex_count(); ++v) table.target.push_back(v);
  SkinnedGeomorph morph(finer, coarser, table);
  EXPECT_EQ(morph.moving_vertices(), finer.vertex_count());
  const std::vector<mat4> pose = curled(scene, 0.3f);
  SkinnedVertices out, coarse;
  morph.evaluate(pose, 1.0f, out);
  skin_vertices(coarser, pose, coarse);
  EXPECT_EQ(out.positions, coarse.positions);
  Mesh four = finer;
  four.joints1.clear(), four.weights1.clear();
  EXPECT_THROW(SkinnedGeomorph(finer, four, table), Error);
}

// ---- streams: every operation keeps the second set with its vertex --------------------------------

TEST(EightInfluences, StreamOperationsCarryTheSecondSet) {
  const Mesh m = fixtures::tentacle_mesh(16, 8);
  {
    SCOPED_TRACE("optimize: vertex cache order and vertex fetch remap");
    const OptimizeResult r = optimize(m);
    expect_influences_follow_positions(r.mesh, m);
  }
  {
    SCOPED_TRACE("simplify, subset placement");
    const SimplifyResult r = simplify(m, {.target_ratio = 0.3f, .keep_vertices = true});
    expect_influences_follow_positions(r.mesh, m);
  }
  {
    SCOPED_TRACE("simplify, optimal placement: influences of the surviving vertex");
    const SimplifyResult r = simplify(m, {.target_ratio = 0.3f});
    for (size_t v = 0; v < r.mesh.vertex_count(); ++v) {
      ASSERT_EQ(r.mesh.joints1[v], m.joints1[r.vertex_origin[v]]);
      ASSERT_EQ(r.mesh.weights1[v], m.weights1[r.vertex_origin[v]]);
    }
  }
  {
    SCOPED_TRACE("progressive mesh and its .lpm file");
    const SimplifyResult r = simplify(m, {.target_ratio = 0.2f, .keep_vertices = true});
    ProgressiveMesh pm(m, r.record);
    const std::string bytes = encode_progressive_mesh(pm);
    ProgressiveMesh back = decode_progressive_mesh(test::bytes_of(bytes), "tentacle.lpm");
    EXPECT_EQ(test::mesh_difference(back.input(), m), "");
    back.set_collapses(back.collapse_count() / 2);
    expect_influences_follow_positions(back.mesh(), m);
  }
  {
    SCOPED_TRACE("subdivision: midpoints blend both sets where the ends name the same joints");
    const Mesh s = subdivide_midpoint(m);
    validate(s, "subdivided", {.weight_tolerance = 1e-5f});
    ASSERT_EQ(s.joints1.size(), s.vertex_count());
    for (size_t v = 0; v < m.vertex_count(); ++v) ASSERT_EQ(s.weights1[v], m.weights1[v]);
    // Each edge's midpoint (found by its position) blends both sets when the ends name the same joints
    // in both, and copies the lower-numbered end's otherwise.
    using Key = std::tuple<float, float, float>;
    std::map<Key, size_t> at;
    for (size_t v = m.vertex_count(); v < s.vertex_count(); ++v) at[{s.positions[v].x, s.positions[v].y, s.positions[v].z}] = v;
    auto mid = [](const float4& a, const float4& b) {
      return float4{(a.x + b.x) * 0.5f, (a.y + b.y) * 0.5f, (a.z + b.z) * 0.5f, (a.w + b.w) * 0.5f};
    };
    size_t checked = 0, blended = 0;
    for (size_t t = 0; t < m.triangle_count(); ++t)
      for (size_t c = 0; c < 3; ++c) {
        const uint32_t a = std::min(m.indices[3 * t + c], m.indices[3 * t + (c + 1) % 3]);
        const uint32_t b = std::max(m.indices[3 * t + c], m.indices[3 * t + (c + 1) % 3]);
        const float3 &pa = m.positions[a], &pb = m.positions[b];
        const auto it = at.find({(pa.x + pb.x) * 0.5f, (pa.y + pb.y) * 0.5f, (pa.z + pb.z) * 0.5f});
        ASSERT_NE(it, at.end());
        const size_t v = it->second;
        const bool same = m.joints[a] == m.joints[b] && m.joints1[a] == m.joints1[b];
        ASSERT_EQ(s.joints1[v], m.joints1[a]);
        ASSERT_EQ(s.weights1[v], same ? mid(m.weights1[a], m.weights1[b]) : m.weights1[a]);
        ASSERT_EQ(s.weights[v], same ? mid(m.weights[a], m.weights[b]) : m.weights[a]);
        ++checked;
        blended += same && !(m.weights1[a] == m.weights1[b]);
      }
    EXPECT_GT(blended, 0u);
    EXPECT_GT(checked, 0u);
  }
}

uint32_t crc32_of(const std::string& bytes, size_t from) {
  uint32_t crc = 0xFFFFFFFFu;
  for (size_t i = from; i < bytes.size(); ++i) {
    crc ^= uint8_t(bytes[i]);
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1)));
  }
  return ~crc;
}

// Older .lpm files still read: the version 3 file of a four-influence mesh simplified without
// influence changes is, without the empty influence array at its end, a version 2 file, and that,
// without the two empty second-set arrays, a version 1 file.
TEST(EightInfluences, LpmVersionsOneAndTwoStillRead) {
  const Mesh m = fixtures::arm(8, 6);
  const SimplifyResult r = simplify(m, {.target_ratio = 0.3f});
  ASSERT_TRUE(r.record.influences.empty());
  const std::string v3 = encode_progressive_mesh(ProgressiveMesh(m, r.record));
  uint32_t version;
  std::memcpy(&version, v3.data() + 4, 4);
  ASSERT_EQ(version, 3u);
  const auto with_header = [](std::string bytes, uint32_t v) {
    const uint32_t crc = crc32_of(bytes, 20);
    const uint64_t payload = bytes.size() - 20;
    std::memcpy(bytes.data() + 4, &v, 4);
    std::memcpy(bytes.data() + 8, &payload, 8);
    std::memcpy(bytes.data() + 16, &crc, 4);
    return bytes;
  };
  ASSERT_EQ(v3.substr(v3.size() - 8), std::string(8, '\0'));
  const std::string v2 = with_header(v3.substr(0, v3.size() - 8), 2);
  // Header 20 bytes; positions, normals, tangents (none), 4 uv sets (none), colours (none), joints,
  // weights; each array is a u64 count and its elements.
  const size_t n = m.vertex_count();
  const size_t at = 20 + (8 + 12 * n) + (8 + 12 * n) + 8 + 4 * 8 + 8 + (8 + 8 * n) + (8 + 16 * n);
  ASSERT_EQ(v2.substr(at, 16), std::string(16, '\0'));
  const std::string v1 = with_header(v2.substr(0, at) + v2.substr(at + 16), 1);
  for (const std::string& old : {v2, v1}) {
    const ProgressiveMesh back = decode_progressive_mesh(test::bytes_of(old), "old.lpm");
    EXPECT_EQ(test::mesh_difference(back.input(), m), "");
    EXPECT_EQ(back.collapse_count(), r.record.collapses.size());
  }
  // The same bytes under version 3 lack the influence array: truncated.
  EXPECT_THROW(decode_progressive_mesh(test::bytes_of(with_header(v2.substr(0), 3)), "short.lpm"), Error);
}

TEST(EightInfluences, WeldComparesTheSecondSet) {
  Mesh m = fixtures::tentacle_mesh(4, 6);
  const uint32_t n = uint32_t(m.vertex_count());
  append_vertex(m, m, 0);  // an exact copy of vertex 0: welds into it
  append_vertex(m, m, 1);  // a copy of vertex 1 naming other joints in its second set: stays apart
  std::swap(m.joints1[n + 1][0], m.joints1[n + 1][1]);
  m.indices.insert(m.indices.end(), {n, n + 1, 2});
  const WeldResult w = weld(m);
  EXPECT_EQ(w.output_vertices, n + 1);
  EXPECT_EQ(w.remap[n], w.remap[0]);
  EXPECT_NE(w.remap[n + 1], w.remap[1]);
  EXPECT_EQ(w.mesh.joints1[w.remap[n + 1]], m.joints1[n + 1]);
  for (uint32_t v = 0; v < m.vertex_count(); ++v) {
    ASSERT_EQ(w.mesh.joints1[w.remap[v]], m.joints1[v]);
    ASSERT_EQ(w.mesh.weights1[w.remap[v]], m.weights1[v]);
  }
  // Weights in the second set are compared with the tolerance too.
  Mesh near = fixtures::tentacle_mesh(4, 6);
  append_vertex(near, near, 0);
  near.weights1.back().x += 1e-4f;
  near.weights.back().x -= 1e-4f;
  near.indices.insert(near.indices.end(), {n, 1, 2});
  EXPECT_EQ(weld(near).output_vertices, n + 1);
  EXPECT_EQ(weld(near, {.weight_tolerance = 1e-3f}).output_vertices, n);
}

TEST(EightInfluences, ValidateChecksBothSets) {
  const Mesh m = fixtures::tentacle_mesh(4, 6);
  validate(m);
  auto refused = [](const Mesh& bad, const char* what) {
    try {
      validate(bad, "t");
    } catch (const Error& e) {
      EXPECT_EQ(e.category(), ErrorCategory::bad_input) << what;
      return;
    }
    ADD_FAILURE() << what << " was accepted";
  };
  Mesh bad = m;
  bad.weights1[3].y += 0.01f;  // sums to 1.01 over both sets
  refused(bad, "a sum over both sets of 1.01");
  bad = m;
  bad.weights1.clear();  // what is left sums to less than 1, and joints1 has no weights
  refused(bad, "joints1 without weights1");
  bad = m;
  bad.joints1.pop_back(), bad.weights1.pop_back();
  refused(bad, "a short second set");
  bad = m;
  bad.weights1[0].x = -bad.weights1[0].x;
  refused(bad, "a negative second-set weight");
  bad = m;
  bad.weights1[1].x = std::nanf("");
  refused(bad, "a NaN second-set weight");
  bad = m;
  bad.joints.clear(), bad.weights.clear();
  refused(bad, "a second set without the first");
}

TEST(EightInfluences, FlattenPadsPartsWithFourInfluences) {
  Scene scene = fixtures::tentacle_scene(4, 6);
  Primitive four;
  four.mesh = fixtures::arm(4, 6);
  scene.primitives.push_back(four);
  scene.nodes.push_back({});
  scene.nodes.back().mesh = 1;
  scene.primitives[1].gltf_mesh = 1;
  scene.roots.push_back(int32_t(scene.nodes.size() - 1));
  const Mesh flat = flatten(scene);
  const size_t n = scene.primitives[0].mesh.vertex_count();
  ASSERT_EQ(flat.vertex_count(), n + four.mesh.vertex_count());
  ASSERT_EQ(flat.joints1.size(), flat.vertex_count());
  validate(flat, "flat", {.weight_tolerance = 1e-6f});
  for (size_t v = 0; v < n; ++v) ASSERT_EQ(flat.weights1[v], scene.primitives[0].mesh.weights1[v]);
  for (size_t v = n; v < flat.vertex_count(); ++v) ASSERT_EQ(flat.weights1[v], float4{});
}

TEST(EightInfluences, PlyRoundTrip) {
  const Mesh m = fixtures::tentacle_mesh(4, 6);
  test::TempDir dir;
  for (const bool binary : {true, false}) {
    SCOPED_TRACE(binary ? "binary" : "ascii");
    write_mesh(m, dir / "t.ply", {.binary = binary});
    Mesh back = read_mesh(dir / "t.ply");
    EXPECT_EQ(test::mesh_difference(back, m), "");
  }
}

// ---- glTF ------------------------------------------------------------------------------------------

TEST(EightInfluences, GltfRoundTripAndValidator) {
  const Scene scene = fixtures::tentacle_scene(16, 8);
  test::TempDir dir;
  for (const char* name : {"tentacle.glb", "tentacle.gltf"}) {
    SCOPED_TRACE(name);
    write_scene(scene, dir / name);
    const Scene back = read_scene(dir / name);
    ASSERT_EQ(back.primitives.size(), 1u);
    EXPECT_EQ(test::mesh_difference(back.primitives[0].mesh, scene.primitives[0].mesh), "");
    // And a simplified level written into the document it came from.
    Scene lod = back;
    SkinSimplifyOptions o;
    o.simplify.target_ratio = 0.3f;
    o.poses = tentacle_poses(back, 4);
    lod.primitives[0].mesh = simplify_skinned(back.primitives[0].mesh, o).mesh;
    write_scene(lod, dir / (std::string("lod-") + name));
    EXPECT_EQ(test::mesh_difference(read_scene(dir / (std::string("lod-") + name)).primitives[0].mesh, lod.primitives[0].mesh), "");
  }
  if (!test::validator_available()) GTEST_SKIP() << "gltf-validator not installed (scripts/setup.sh installs it)";
  const test::ValidatorRun run = test::run_validator(
      {dir / "tentacle.glb", dir / "tentacle.gltf", dir / "lod-tentacle.glb", dir / "lod-tentacle.gltf"});
  EXPECT_EQ(run.status, 0) << run.output;
}

// A hand-written glTF: one triangle with unsigned-byte joints and normalized unsigned-byte weights in
// both sets (64 + 32 + 32 + 32 and 32 + 32 + 16 + 15 of 255).
std::string byte_influence_gltf(bool with_first_set) {
  std::string bin;
  const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  bin.append(reinterpret_cast<const char*>(positions), sizeof positions);
  const uint8_t joints0[4] = {0, 1, 2, 3}, weights0[4] = {64, 32, 32, 32}, joints1[4] = {4, 5, 6, 7},
                weights1[4] = {32, 32, 16, 15};
  for (const uint8_t* stream : {joints0, weights0, joints1, weights1})
    for (int v = 0; v < 3; ++v) bin.append(reinterpret_cast<const char*>(stream), 4);
  const std::string b64 = test::base64(test::bytes_of(bin));
  std::string attributes = R"("POSITION": 0, "JOINTS_1": 3, "WEIGHTS_1": 4)";
  if (with_first_set) attributes += R"(, "JOINTS_0": 1, "WEIGHTS_0": 2)";
  auto view = [](size_t offset, size_t length) {
    return "{\"buffer\": 0, \"byteOffset\": " + std::to_string(offset) + ", \"byteLength\": " + std::to_string(length) + "}";
  };
  return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
    "meshes": [{"primitives": [{"attributes": {)" + attributes + R"(}}]}],
    "buffers": [{"byteLength": )" + std::to_string(bin.size()) + R"(, "uri": "data:application/octet-stream;base64,)" + b64 + R"("}],
    "bufferViews": [)" + view(0, 36) + ", " + view(36, 12) + ", " + view(48, 12) + ", " + view(60, 12) + ", " + view(72, 12) + R"(],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
      {"bufferView": 1, "componentType": 5121, "count": 3, "type": "VEC4"},
      {"bufferView": 2, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC4"},
      {"bufferView": 3, "componentType": 5121, "count": 3, "type": "VEC4"},
      {"bufferView": 4, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC4"}]})";
}

TEST(EightInfluences, GltfReadsByteJointsAndNormalizedByteWeightsInBothSets) {
  test::TempDir dir;
  test::write_text(dir / "bytes.gltf", byte_influence_gltf(true));
  const Mesh m = read_mesh(dir / "bytes.gltf");
  ASSERT_EQ(m.vertex_count(), 3u);
  ASSERT_EQ(m.joints1.size(), 3u);
  ASSERT_EQ(m.weights1.size(), 3u);
  EXPECT_EQ(m.joints[2], (ushort4{0, 1, 2, 3}));
  EXPECT_EQ(m.joints1[2], (ushort4{4, 5, 6, 7}));
  EXPECT_EQ(m.weights[1], (float4{64 / 255.0f, 32 / 255.0f, 32 / 255.0f, 32 / 255.0f}));
  EXPECT_EQ(m.weights1[1], (float4{32 / 255.0f, 32 / 255.0f, 16 / 255.0f, 15 / 255.0f}));
  validate(m, "bytes.gltf");
  // The second set alone is malformed.
  test::write_text(dir / "second-only.gltf", byte_influence_gltf(false));
  try {
    read_mesh(dir / "second-only.gltf");
    ADD_FAILURE() << "JOINTS_1 without JOINTS_0 was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.category(), ErrorCategory::bad_input);
    EXPECT_NE(std::string(e.what()).find("JOINTS_1"), std::string::npos) << e.what();
  }
}

// End to end: `lodkit lod` on an eight-influence character writes levels that keep eight valid
// influences, and the file passes the validator.
TEST(EightInfluences, CliLodKeepsEightInfluences) {
  test::TempDir dir;
  write_scene(fixtures::tentacle_scene(), dir / "tentacle.glb");
  const test::RunResult r = test::run_cli({"lod", (dir / "tentacle.glb").string(), "-o", (dir / "lod.glb").string(),
                                           "--ratios", "1,0.4,0.1", "--poses", "6"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Scene out = read_scene(dir / "lod.glb");
  ASSERT_EQ(out.primitives.size(), 3u);
  for (size_t p = 1; p < out.primitives.size(); ++p) {
    SCOPED_TRACE("level " + std::to_string(p));
    const Mesh& level = out.primitives[p].mesh;
    EXPECT_LT(level.triangle_count(), out.primitives[p - 1].mesh.triangle_count());
    EXPECT_GT(expect_valid_influences(level, tentacle_bones), 0u);
  }
  test::expect_valid_gltf({dir / "lod.glb"});
}

}  // namespace
}  // namespace lod
