// Skinned simplification (issue 7): Houle's pose round trip and limb-following displacements,
// influence validity in every mode, rigid single-bone regions, multi-pose = constrained QEM in the
// trivial case, and multi-pose against single-pose methods on a bending arm.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/lod.h"
#include "lodkit/measure.h"
#include "lodkit/skin.h"
#include "skin/fixtures.h"
#include "skin/skin_test_support.h"
#include "test_support.h"

namespace lod {
namespace {

constexpr float pi = std::numbers::pi_v<float>;

using fixtures::arm;
using fixtures::bent;
using skin_test::expect_valid_influences;
using skin_test::skinned;

double length(const float3& a) { return std::sqrt(double(a.x) * a.x + double(a.y) * a.y + double(a.z) * a.z); }
float3 sub(const float3& a, const float3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }

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
    const SimplifyResult r = skin_test::simplify_in_mode(m, mode, 0.15f, poses, 3);
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

// Asked to keep every triangle, each mode collapses nothing and keeps the input's influences (the
// multi-pose engine read its per-position choices before they existed: a crash, found by lod
// --errors, whose search asks for the source's own triangle count).
TEST(SimplifySkinned, NothingToCollapseKeepsTheInput) {
  const Mesh m = arm();
  std::vector<std::vector<mat4>> poses;
  for (int k = 0; k < 4; ++k) poses.push_back(bent(pi * 0.5f * float(k) / 3));
  for (const SkinMode mode : {SkinMode::houle, SkinMode::subset, SkinMode::multipose}) {
    SCOPED_TRACE(skin_mode_name(mode));
    const SimplifyResult r = skin_test::simplify_in_mode(m, mode, 1.0f, poses, 1);
    EXPECT_EQ(r.mesh.triangle_count(), m.triangle_count());
    ASSERT_EQ(r.vertex_origin.size(), r.mesh.vertex_count());
    expect_valid_influences(r.mesh, 2);
    // Each vertex skins where its input vertex does, in a pose none of the above is.
    const Mesh out = skinned(r.mesh, bent(1.1f)), in = skinned(m, bent(1.1f));
    for (size_t v = 0; v < r.mesh.vertex_count(); ++v)
      EXPECT_LE(length(sub(out.positions[v], in.positions[r.vertex_origin[v]])), 1e-5f) << "vertex " << v;
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
  plain.fit_iterations = 0;  // the multi-pose metric is not followed by the rest-pose fit
  plain.distance_guard = 0;  // nor guarded by rest-pose distances (qem and cqem only)
  plain.search_input_triangles = 0;  // and is made one way only
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

// Poses that are one another moved as a whole, rigidly (a crowd's skeletons in step), count once
// with their weights summed; a scaled copy, a copy with one used joint moved, and other poses stay.
// A joint no vertex weights may differ. The multi-pose simplification with the copies is the one
// with the merged pose weighted twice, bit for bit.
TEST(SimplifySkinned, RigidCopiesOfAPoseCountOnce) {
  const Mesh m = arm(40, 12);
  const mat4 moved = compose_trs({3, -2, 1}, {0, 0, std::sin(0.35f), std::cos(0.35f)}, {1, 1, 1});
  const mat4 scaled = compose_trs({0, 0, 0}, {0, 0, 0, 1}, {2, 2, 2});
  const auto times = [](const mat4& t, std::vector<mat4> pose) {
    for (mat4& j : pose) j = multiply(t, j);
    return pose;
  };
  std::vector<mat4> elbow_off = bent(0.5f);
  elbow_off[1][12] += 0.01f;
  std::vector<std::vector<mat4>> poses = {bent(0.5f), times(moved, bent(0.5f)), bent(1.5f), times(scaled, bent(0.5f)),
                                          elbow_off, times(moved, bent(1.5f))};
  std::vector<float> weights;
  EXPECT_EQ(merge_rigid_poses(m, poses, weights), 2u);
  ASSERT_EQ(poses.size(), 4u);
  EXPECT_EQ(poses[0], bent(0.5f));
  EXPECT_EQ(poses[1], bent(1.5f));
  EXPECT_EQ(weights, (std::vector<float>{2, 2, 1, 1}));
  // Given weights are summed; nothing merged leaves them as they were.
  poses = {bent(0.5f), bent(1.0f), times(moved, bent(0.5f))};
  weights = {0.25f, 1, 0.5f};
  EXPECT_EQ(merge_rigid_poses(m, poses, weights), 1u);
  EXPECT_EQ(weights, (std::vector<float>{0.75f, 1}));
  poses = {bent(0.5f), bent(1.0f)};
  weights.clear();
  EXPECT_EQ(merge_rigid_poses(m, poses, weights), 0u);
  EXPECT_TRUE(weights.empty());
  // Only the upper arm weighted: the elbow's bend changes nothing.
  Mesh upper = m;
  for (float4& w : upper.weights) w = {1, 0, 0, 0};
  poses = {bent(0.5f), bent(1.5f)};
  EXPECT_EQ(merge_rigid_poses(upper, poses, weights), 1u);

  SkinSimplifyOptions copies, merged;
  copies.simplify.target_ratio = merged.simplify.target_ratio = 0.1f;
  copies.poses = {bent(0.3f), times(moved, bent(0.3f)), bent(1.2f)};
  merged.poses = {bent(0.3f), bent(1.2f)};
  merged.pose_weights = {2, 1};
  const SimplifyResult a = simplify_skinned(m, copies), b = simplify_skinned(m, merged);
  EXPECT_EQ(a.mesh.indices, b.mesh.indices);
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  EXPECT_EQ(a.error, b.error);
}

// Poses are sampled over the clips that shape the skin. A clip that spins a node outside the
// skeleton, and one that carries the whole skeleton (its root's parent, at rest the identity),
// change neither the sampled poses nor the mid-range pose, bit for bit; a clip that bends an elbow
// does.
TEST(SkinPoses, OnlyClipsThatShapeTheSkinAreSampled) {
  const Scene base = fixtures::humanoid_scene();
  const std::vector<std::vector<mat4>> poses = sample_poses(base, 0, 8);
  const Pose mid = mid_range_pose(base, 0);
  Scene scene = base;
  const int32_t prop = int32_t(scene.nodes.size()), carrier = prop + 1;
  scene.nodes.resize(scene.nodes.size() + 2);
  scene.nodes[size_t(carrier)].children = {int32_t(fixtures::hips)};
  scene.nodes[fixtures::hips].parent = carrier;
  scene.roots = {carrier, prop, scene.roots[1]};
  for (const int32_t n : {prop, carrier}) {
    Animation clip;
    clip.channels.push_back({.node = n, .path = AnimationPath::rotation, .times = {0, 3}, .values = {0, 0, 0, 1, 0, 0, 1, 0}, .components = 4});
    clip.channels.push_back({.node = n, .path = AnimationPath::translation, .times = {0, 3}, .values = {0, 0, 0, 5, 0, 0}, .components = 3});
    scene.animations.push_back(clip);
  }
  EXPECT_EQ(sample_poses(scene, 0, 8), poses);
  const Pose carried = mid_range_pose(scene, 0);
  for (size_t n = 0; n < base.nodes.size(); ++n) {
    EXPECT_EQ(carried.rotation[n], mid.rotation[n]) << n;
    EXPECT_EQ(carried.translation[n], mid.translation[n]) << n;
  }
  Animation flex;
  flex.channels.push_back({.node = int32_t(fixtures::elbow_l), .path = AnimationPath::rotation, .times = {0, 1},
                           .values = {0, 0, 0, 1, 0, 0, std::sin(0.6f), std::cos(0.6f)}, .components = 4});
  scene.animations.push_back(flex);
  EXPECT_NE(sample_poses(scene, 0, 8), poses);
}

// A skinned chain built with the multi-pose simplifier, then the skeletal geomorph in several frames:
// t = 0 is the skinned finer level, t = 1 puts every vertex exactly on its skinned target.
TEST(SkinnedGeomorph, EndsAreTheSkinnedLevelsInAnyFrame) {
  std::vector<std::vector<mat4>> poses;
  for (int k = 0; k < 6; ++k) poses.push_back(bent(2.0f * float(k) / 5));
  const LodChain chain = skin_test::multipose_chain(arm(), poses, {1.0f, 0.4f, 0.1f});
  ASSERT_EQ(chain.levels.size(), 3u);
  ASSERT_EQ(chain.morphs.size(), 2u);
  for (const LodLevel& level : chain.levels) expect_valid_influences(level.mesh, 2);
  for (const float angle : {0.0f, 0.7f, 1.9f}) {
    SCOPED_TRACE(angle);
    skin_test::expect_geomorph_ends(chain, bent(angle), 1e-6f);
  }
}

TEST(SimplifySkinned, NormalizeInfluencesByHand) {
  Mesh m = arm(2, 3);
  ASSERT_GE(m.vertex_count(), 3u);
  m.joints[0] = {3, 4, 5, 6}, m.weights[0] = {0.2f, 0.2f, 0.4f, 0};     // sums to 4 x 0.2f: exact quarters
  m.joints[1] = {1, 1, 0, 0}, m.weights[1] = {0, 0, 0, 0};              // no weight: all on slot 0
  m.joints[2] = {1, 0, 0, 0}, m.weights[2] = {-1.0f, 0.5f, 0.5f, 0};     // negative weights count as 0
  normalize_influences(m);
  EXPECT_EQ(m.weights[0], (float4{0.25f, 0.25f, 0.5f, 0}));
  EXPECT_EQ(m.joints[0], (ushort4{3, 4, 5, 0}));
  EXPECT_EQ(m.weights[1], (float4{1, 0, 0, 0}));
  EXPECT_EQ(m.joints[1], (ushort4{1, 1, 0, 0}));
  EXPECT_EQ(m.weights[2], (float4{0, 0.5f, 0.5f, 0}));
  EXPECT_EQ(m.joints[2], (ushort4{0, 0, 0, 0}));
}

// The multi-pose record carries the joints and weights it chose: replayed on the normalised input
// it gives the output, influences included, and undone it gives that input back, bit for bit; so
// does a progressive mesh through its .lpm file. Without the influence changes the replay differs.
TEST(SimplifySkinned, MultiposeRecordReplaysItsInfluences) {
  for (const bool eight : {false, true}) {
    SCOPED_TRACE(eight ? "eight influences (tentacle)" : "four influences (arm)");
    Mesh m = eight ? fixtures::tentacle_mesh(24, 8) : arm(40, 12);
    std::vector<std::vector<mat4>> poses;
    if (eight) {
      const Scene scene = fixtures::tentacle_scene(24, 8);
      poses = sample_poses(scene, 0, 6);
    } else {
      for (int k = 0; k < 6; ++k) poses.push_back(bent(2.0f * float(k) / 5));
    }
    // Inputs as exporters write them: weights that do not quite sum to 1, in no particular order.
    for (size_t v = 0; v < m.vertex_count(); v += 3) {
      float4& w = m.weights[v];
      w = {w.x * 1.25f, w.y * 1.25f, w.z * 1.25f, w.w * 1.25f};
      std::swap(m.weights[v].x, m.weights[v].y), std::swap(m.joints[v][0], m.joints[v][1]);
    }
    SkinSimplifyOptions o;
    o.poses = poses;
    o.simplify.target_ratio = 0.1f;
    const SimplifyResult r = simplify_skinned(m, o);
    ASSERT_GT(r.record.collapses.size(), 0u);
    ASSERT_EQ(r.record.influences.size(), r.record.collapses.size());

    Mesh normalized = m;
    normalize_influences(normalized);
    EXPECT_EQ(test::mesh_difference(replay(normalized, r.record, r.record.collapses.size()), r.mesh), "");
    EXPECT_EQ(test::mesh_difference(replay_and_undo(normalized, r.record), normalized), "");
    for (size_t v = 0; v < r.mesh.vertex_count(); ++v) {
      const float4& w = r.mesh.weights[v];
      double sum = double(w.x) + w.y + w.z + w.w;
      if (eight) sum += double(r.mesh.weights1[v].x) + r.mesh.weights1[v].y + r.mesh.weights1[v].z + r.mesh.weights1[v].w;
      ASSERT_NEAR(sum, 1.0, 1e-6);
    }

    SimplifyRecord without = r.record;
    without.influences.clear();
    const Mesh plain = replay(normalized, without, without.collapses.size());
    EXPECT_NE(test::mesh_difference(plain, r.mesh), "");  // some survivors took other influences
    EXPECT_EQ(plain.positions, r.mesh.positions);

    const ProgressiveMesh pm(normalized, r.record);
    ProgressiveMesh back = decode_progressive_mesh(test::bytes_of(encode_progressive_mesh(pm)), "arm.lpm");
    back.set_collapses(back.collapse_count());
    EXPECT_EQ(test::mesh_difference(back.mesh(), r.mesh), "");
    back.set_collapses(back.collapse_count() / 2);
    expect_valid_influences(back.mesh(), eight ? fixtures::tentacle_bones : 2);
    back.set_collapses(0);
    EXPECT_EQ(test::mesh_difference(back.mesh(), replay(normalized, r.record, 0)), "");

    // A record whose influence changes do not start from the state before them is rejected.
    SimplifyRecord wrong = r.record;
    wrong.influences[0].old_value = wrong.influences[0].new_value;
    EXPECT_THROW(decode_progressive_mesh(test::bytes_of(encode_progressive_mesh(ProgressiveMesh(normalized, wrong))), "x.lpm"),
                 Error);
    wrong.influences.pop_back();
    EXPECT_THROW(ProgressiveMesh(normalized, wrong), Error);
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
