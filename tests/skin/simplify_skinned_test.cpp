// Skinned simplification (issue 7): Houle's pose round trip and limb-following displacements,
// influence validity in every mode, rigid single-bone regions, multi-pose = constrained QEM in the
// trivial case, and multi-pose against single-pose methods on a bending arm.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/measure.h"
#include "lodkit/skin.h"

namespace lod {
namespace {

constexpr float pi = std::numbers::pi_v<float>;

// A closed-ish tube along +x from 0 to 2 (radius 0.2), bone 0 = upper arm, bone 1 = forearm from the
// elbow at x = 1. Weights blend smoothly over x in [0.8, 1.2]; outside they are a single bone.
Mesh arm(uint32_t along = 60, uint32_t around = 20) {
  Mesh m;
  for (uint32_t i = 0; i <= along; ++i)
    for (uint32_t j = 0; j < around; ++j) {
      const float x = 2.0f * float(i) / float(along), a = 2 * pi * float(j) / float(around);
      // A slight wobble so the surface is not trivially flat along x.
      const float r = 0.2f + 0.03f * std::sin(7 * x) * std::cos(3 * a);
      m.positions.push_back({x, r * std::cos(a), r * std::sin(a)});
      m.normals.push_back({0, std::cos(a), std::sin(a)});  // radial (ignoring the wobble)
      const float s = std::clamp((x - 0.8f) / 0.4f, 0.0f, 1.0f), w1 = s * s * (3 - 2 * s);
      m.joints.push_back({0, 1, 0, 0});
      m.weights.push_back({1 - w1, w1, 0, 0});
    }
  for (uint32_t i = 0; i < along; ++i)
    for (uint32_t j = 0; j < around; ++j) {
      const uint32_t a = i * around + j, b = i * around + (j + 1) % around, c = a + around, d = b + around;
      m.indices.insert(m.indices.end(), {a, c, b, b, c, d});
    }
  return m;
}

// The elbow bent by `angle` about +z: joint 1 = T(1,0,0) R_z(angle) T(-1,0,0); joint 0 the identity.
std::vector<mat4> bent(float angle) {
  const float c = std::cos(angle), s = std::sin(angle);
  mat4 r = {c, s, 0, 0, -s, c, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const mat4 to = compose_trs({1, 0, 0}, {0, 0, 0, 1}, {1, 1, 1}), back = compose_trs({-1, 0, 0}, {0, 0, 0, 1}, {1, 1, 1});
  return {identity_matrix(), multiply(to, multiply(r, back))};
}

Mesh skinned(const Mesh& m, const std::vector<mat4>& pose) {
  SkinnedVertices v;
  skin_vertices(m, pose, v);
  Mesh out = m;
  out.positions = v.positions;
  out.normals.clear();
  return out;
}

double length(const float3& a) { return std::sqrt(double(a.x) * a.x + double(a.y) * a.y + double(a.z) * a.z); }
float3 sub(const float3& a, const float3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }

void expect_valid_influences(const Mesh& m, size_t joints) {
  ASSERT_EQ(m.joints.size(), m.vertex_count());
  ASSERT_EQ(m.weights.size(), m.vertex_count());
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const float4& w = m.weights[v];
    const float ws[4] = {w.x, w.y, w.z, w.w};
    double sum = 0;
    for (int i = 0; i < 4; ++i) {
      EXPECT_GE(ws[i], 0.0f) << v;
      if (ws[i] > 0) {
        EXPECT_LT(m.joints[v][size_t(i)], joints) << v;
      }
      sum += ws[i];
    }
    EXPECT_NEAR(sum, 1.0, 1e-6) << "vertex " << v;
  }
}

TEST(SimplifySkinned, HouleInItsPoseIsTheStaticSimplification) {
  const Mesh m = arm();
  const std::vector<mat4> pose = bent(pi / 2);
  SkinSimplifyOptions o;
  o.mode = SkinMode::houle;
  o.simplify.target_ratio = 0.2f;
  o.poses = {pose};
  const SimplifyResult r = simplify_skinned(m, o);
  // The independent route: skin first, simplify the static mesh with the same options.
  const SimplifyResult s = simplify(skinned(m, pose), o.simplify);
  ASSERT_EQ(r.mesh.vertex_count(), s.mesh.vertex_count());
  ASSERT_EQ(r.mesh.indices, s.mesh.indices);
  const Mesh back = skinned(r.mesh, pose);
  double worst = 0;
  for (size_t v = 0; v < back.vertex_count(); ++v) worst = std::max(worst, length(sub(back.positions[v], s.mesh.positions[v])));
  EXPECT_LE(worst, 1e-5 * r.diagonal);
  expect_valid_influences(r.mesh, 2);
}

TEST(SimplifySkinned, HouleDisplacementFollowsTheLimb) {
  // Simplify with the forearm straight up (+y). A survivor on the forearm alone that the collapse
  // moved along the forearm (along +y in that pose) must, in the bind pose (forearm along +x), have
  // moved along +x by the same amount: R_z(90)^T applied, not the world-space offset.
  const Mesh m = arm();
  const float angle = pi / 2;
  SkinSimplifyOptions o;
  o.mode = SkinMode::houle;
  o.simplify.target_ratio = 0.1f;
  o.poses = {bent(angle)};
  const SimplifyResult r = simplify_skinned(m, o);
  const Mesh posed_input = skinned(m, o.poses[0]);
  const Mesh posed_output = skinned(r.mesh, o.poses[0]);
  size_t checked = 0;
  for (size_t v = 0; v < r.mesh.vertex_count(); ++v) {
    const uint32_t origin = r.vertex_origin[v];
    if (m.weights[origin].y != 1.0f) continue;  // forearm only
    const float3 world = sub(posed_output.positions[v], posed_input.positions[origin]);
    const float3 bind = sub(r.mesh.positions[v], m.positions[origin]);
    if (length(world) < 1e-3) continue;
    // R_z(90)^T (wx, wy, wz) = (wy, -wx, wz).
    EXPECT_NEAR(bind.x, world.y, 1e-5) << v;
    EXPECT_NEAR(bind.y, -world.x, 1e-5) << v;
    EXPECT_NEAR(bind.z, world.z, 1e-5) << v;
    ++checked;
  }
  EXPECT_GT(checked, 10u);
  // And some of those moves did run along the limb, where a world-space offset would go sideways.
  size_t along = 0;
  for (size_t v = 0; v < r.mesh.vertex_count(); ++v) {
    const uint32_t origin = r.vertex_origin[v];
    if (m.weights[origin].y != 1.0f) continue;
    const float3 world = sub(posed_output.positions[v], posed_input.positions[origin]);
    along += std::fabs(world.y) > 1e-3 && std::fabs(world.y) > 2 * std::fabs(world.x);
  }
  EXPECT_GT(along, 0u);
}

TEST(SimplifySkinned, EveryModeGivesValidInfluencesAndRigidSingleBoneRegions) {
  const Mesh m = arm();
  std::vector<std::vector<mat4>> poses;
  for (int k = 0; k < 8; ++k) poses.push_back(bent(pi * 0.75f * float(k) / 7));
  for (const SkinMode mode : {SkinMode::houle, SkinMode::subset, SkinMode::multipose}) {
    SCOPED_TRACE(skin_mode_name(mode));
    SkinSimplifyOptions o;
    o.mode = mode;
    o.simplify.target_ratio = 0.15f;
    o.poses = mode == SkinMode::houle ? std::vector<std::vector<mat4>>{poses[3]} : poses;
    const SimplifyResult r = simplify_skinned(m, o);
    EXPECT_LE(r.mesh.triangle_count(), m.triangle_count() * 0.15 + 2);
    expect_valid_influences(r.mesh, 2);
    // Vertices bound to the forearm alone keep their distances in any pose.
    const Mesh a = skinned(r.mesh, bent(0.3f)), b = skinned(r.mesh, bent(2.0f));
    std::vector<uint32_t> rigid;
    for (uint32_t v = 0; v < r.mesh.vertex_count(); ++v)
      if (r.mesh.weights[v].y == 1.0f || (r.mesh.joints[v][0] == 1 && r.mesh.weights[v].x == 1.0f)) rigid.push_back(v);
    ASSERT_GT(rigid.size(), 4u);
    for (size_t i = 0; i + 1 < rigid.size(); ++i) {
      const uint32_t p = rigid[i], q = rigid[i + 1];
      EXPECT_NEAR(length(sub(a.positions[p], a.positions[q])), length(sub(b.positions[p], b.positions[q])), 1e-5);
    }
    if (mode == SkinMode::subset) {
      for (size_t v = 0; v < r.mesh.vertex_count(); ++v) {
        const uint32_t origin = r.vertex_origin[v];
        EXPECT_EQ(r.mesh.positions[v], m.positions[origin]);
        EXPECT_EQ(r.mesh.weights[v], m.weights[origin]);
      }
    }
  }
}

// With one pose where every joint is the identity and no bone-weight term, the pulled-back quadrics
// are the bind-pose quadrics: the result must be exactly constrained QEM's. (Weights in eighths, so
// that blended identity matrices are exactly the identity in floating point too.)
TEST(SimplifySkinned, MultiposeWithTheIdentityPoseIsConstrainedQem) {
  Mesh m = arm();
  for (float4& w : m.weights) w.y = std::round(w.y * 8) / 8, w.x = 1 - w.y;
  SkinSimplifyOptions o;
  o.mode = SkinMode::multipose;
  o.simplify.target_ratio = 0.2f;
  o.poses = {{identity_matrix(), identity_matrix()}};
  o.bone_weight = 0;
  const SimplifyResult r = simplify_skinned(m, o);
  SimplifyOptions plain = o.simplify;
  plain.metric = Metric::constrained_qem;
  const SimplifyResult s = simplify(m, plain);
  EXPECT_EQ(r.mesh.indices, s.mesh.indices);
  EXPECT_EQ(r.mesh.positions, s.mesh.positions);
}

// The point of multi-pose: over the whole range of motion, its worst-pose error is no worse than
// simplifying in one pose (Houle, in the mid-range pose) or keeping input vertices (subset).
TEST(SimplifySkinned, MultiposeIsBestOverTheRangeOfMotion) {
  const Mesh m = arm(80, 24);
  std::vector<std::vector<mat4>> poses;
  for (int k = 0; k < 16; ++k) poses.push_back(bent(2.0f * float(k) / 15));
  double worst[3] = {0, 0, 0};
  const SkinMode modes[3] = {SkinMode::houle, SkinMode::subset, SkinMode::multipose};
  for (int i = 0; i < 3; ++i) {
    SkinSimplifyOptions o;
    o.mode = modes[i];
    o.simplify.target_ratio = 0.05f;
    o.poses = modes[i] == SkinMode::houle ? std::vector<std::vector<mat4>>{bent(1.0f)} : poses;
    const SimplifyResult r = simplify_skinned(m, o);
    for (int k = 0; k <= 20; ++k) {
      const std::vector<mat4> pose = bent(2.0f * float(k) / 20);
      const Deviation d = compare(skinned(m, pose), skinned(r.mesh, pose), {.samples = 20'000});
      worst[i] = std::max(worst[i], d.hausdorff);
    }
  }
  EXPECT_LE(worst[2], worst[0]);
  EXPECT_LE(worst[2], worst[1]);
}

// A skinned chain built with the multi-pose simplifier, then the skeletal geomorph in several frames:
// t = 0 is the skinned finer level, t = 1 puts every vertex exactly on its skinned target.
TEST(SkinnedGeomorph, EndsAreTheSkinnedLevelsInAnyFrame) {
  const Mesh m = arm();
  std::vector<std::vector<mat4>> poses;
  for (int k = 0; k < 6; ++k) poses.push_back(bent(2.0f * float(k) / 5));
  LodOptions lo;
  lo.ratios = {1.0f, 0.4f, 0.1f};
  lo.morph = true;
  lo.measure = false;
  lo.simplifier = [&](const Mesh& mesh, const SimplifyOptions& so) {
    SkinSimplifyOptions o;
    o.simplify = so;
    o.poses = poses;
    return simplify_skinned(mesh, o);
  };
  const LodChain chain = build_lod_chain(m, lo);
  ASSERT_EQ(chain.levels.size(), 3u);
  ASSERT_EQ(chain.morphs.size(), 2u);
  for (const LodLevel& level : chain.levels) expect_valid_influences(level.mesh, 2);
  SkinnedVertices out, fine, coarse;
  for (const float angle : {0.0f, 0.7f, 1.9f}) {
    const std::vector<mat4> pose = bent(angle);
    for (size_t i = 0; i + 1 < chain.levels.size(); ++i) {
      const Mesh &finer = chain.levels[i].mesh, &coarser = chain.levels[i + 1].mesh;
      SkinnedGeomorph morph(finer, coarser, chain.morphs[i]);
      EXPECT_GT(morph.moving_vertices(), 0u);
      skin_vertices(finer, pose, fine);
      skin_vertices(coarser, pose, coarse);
      morph.evaluate(pose, 0.0f, out);
      EXPECT_EQ(out.positions, fine.positions);
      morph.evaluate(pose, 1.0f, out);
      for (size_t v = 0; v < finer.vertex_count(); ++v) {
        ASSERT_EQ(out.positions[v], coarse.positions[chain.morphs[i].target[v]]) << "level " << i << " vertex " << v;
        ASSERT_EQ(out.normals[v], coarse.normals[chain.morphs[i].target[v]]) << "level " << i << " vertex " << v;
      }
      // Half way: the midpoint of the two skinned positions.
      morph.evaluate(pose, 0.5f, out);
      for (size_t v = 0; v < finer.vertex_count(); ++v) {
        const float3 &a = fine.positions[v], &b = coarse.positions[chain.morphs[i].target[v]];
        EXPECT_NEAR(out.positions[v].x, 0.5f * (a.x + b.x), 1e-6f);
        EXPECT_NEAR(out.positions[v].y, 0.5f * (a.y + b.y), 1e-6f);
        // Normals: the normalised blend of the two skinned unit normals.
        const float3 &n = fine.normals[v], &q = coarse.normals[chain.morphs[i].target[v]];
        const float3 mid = {n.x + q.x, n.y + q.y, n.z + q.z};
        const float len = std::sqrt(mid.x * mid.x + mid.y * mid.y + mid.z * mid.z);
        if (len > 0.5f) {
          EXPECT_NEAR(out.normals[v].x, mid.x / len, 1e-5f) << v;
          EXPECT_NEAR(out.normals[v].y, mid.y / len, 1e-5f) << v;
          EXPECT_NEAR(out.normals[v].z, mid.z / len, 1e-5f) << v;
        }
      }
    }
  }
}

TEST(SimplifySkinned, BadInputIsAUsageError) {
  const Mesh m = arm(8, 6);
  SkinSimplifyOptions o;
  o.poses = {};
  EXPECT_THROW(simplify_skinned(m, o), Error);  // multipose without poses
  o.poses = {{identity_matrix()}};               // joint 1 is used but there is one matrix
  EXPECT_THROW(simplify_skinned(m, o), Error);
  Mesh bare = m;
  bare.joints.clear();
  bare.weights.clear();
  o.poses = {{identity_matrix(), identity_matrix()}};
  EXPECT_THROW(simplify_skinned(bare, o), Error);
}

}  // namespace
}  // namespace lod
