// tests/skin/fixtures.cpp: the skinned test characters are valid (weights, joints, closed outward
// tubes), deterministic, skin to themselves in the bind pose, move single-bone regions rigidly, pose
// the skeleton as the clips say (hand-computed joint positions), and export as valid glTF.
#include "skin/fixtures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "lodkit/skin.h"
#include "test_support.h"

namespace lod {
namespace {

constexpr double deg = std::numbers::pi / 180.0;

double distance(const float3& a, const float3& b) {
  const double dx = double(a.x) - b.x, dy = double(a.y) - b.y, dz = double(a.z) - b.z;
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

const Scene& humanoid() {
  static const Scene scene = fixtures::humanoid_scene();
  return scene;
}

std::filesystem::path man_off() {
  const std::filesystem::path dir = test::corpus_dir();
  return dir.empty() ? dir : dir / "man.off";
}

// Weights sum to 1 within 1e-6, are non-negative, and every used joint index exists.
void expect_valid_influences(const Mesh& mesh, size_t joint_count) {
  ASSERT_EQ(mesh.joints.size(), mesh.vertex_count());
  ASSERT_EQ(mesh.weights.size(), mesh.vertex_count());
  size_t bad = 0;
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    const float4& w = mesh.weights[v];
    const float ws[4] = {w.x, w.y, w.z, w.w};
    double sum = 0;
    for (size_t k = 0; k < 4; ++k) {
      sum += ws[k];
      if (ws[k] < 0 || mesh.joints[v][k] >= joint_count) ++bad;
      // Unused slots hold joint 0 (the glTF validator flags a zero weight on any other joint).
      if (ws[k] == 0 && mesh.joints[v][k] != 0) ++bad;
    }
    if (std::abs(sum - 1.0) > 1e-6) ++bad;
  }
  EXPECT_EQ(bad, 0u);
  EXPECT_NO_THROW(validate(mesh, "fixture", {.weight_tolerance = 1e-6f}));
}

// Skinned positions in the rest pose (which is the bind pose) equal the bind positions.
void expect_bind_pose_identity(const Scene& scene) {
  const Mesh& mesh = scene.primitives[0].mesh;
  const std::vector<mat4> joints = joint_matrices(scene, 0, world_matrices(scene, rest_pose(scene)));
  SkinnedVertices out;
  skin_vertices(mesh, joints, out);
  double worst = 0, worst_normal = 0;
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    worst = std::max(worst, distance(out.positions[v], mesh.positions[v]));
    worst_normal = std::max(worst_normal, distance(out.normals[v], mesh.normals[v]));
  }
  EXPECT_LE(worst, 1e-6);
  EXPECT_LE(worst_normal, 1e-6);
}

// Vertices bound to `joint` alone keep their pairwise distances in a posed frame, and do move.
void expect_rigid_region(const Scene& scene, uint32_t joint, size_t clip, float time) {
  const Mesh& mesh = scene.primitives[0].mesh;
  std::vector<uint32_t> region;
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v)
    if (mesh.joints[v][0] == joint && mesh.weights[v].x == 1.0f) region.push_back(v);
  ASSERT_GE(region.size(), 20u) << fixtures::joint_name(joint);
  Pose pose = rest_pose(scene);
  sample_animation(scene, clip, time, pose);
  SkinnedVertices out;
  skin_vertices(mesh, joint_matrices(scene, 0, world_matrices(scene, pose)), out);
  double worst = 0, moved = 0;
  const size_t step = std::max<size_t>(1, region.size() / 60);  // about 60 x 60 pairs
  for (size_t i = 0; i < region.size(); i += step) {
    moved = std::max(moved, distance(out.positions[region[i]], mesh.positions[region[i]]));
    for (size_t k = i + step; k < region.size(); k += step) {
      const double before = distance(mesh.positions[region[i]], mesh.positions[region[k]]);
      const double after = distance(out.positions[region[i]], out.positions[region[k]]);
      worst = std::max(worst, std::abs(after - before));
    }
  }
  EXPECT_LE(worst, 2e-6) << fixtures::joint_name(joint);
  EXPECT_GE(moved, 0.01) << fixtures::joint_name(joint) << " does not move in this frame";
}

TEST(SkinFixtures, HumanoidShape) {
  const Scene& scene = humanoid();
  ASSERT_EQ(scene.primitives.size(), 1u);
  const Mesh& mesh = scene.primitives[0].mesh;
  EXPECT_EQ(mesh.triangle_count(), fixtures::humanoid_triangles);
  EXPECT_EQ(mesh.vertex_count(), fixtures::humanoid_vertices);
  EXPECT_EQ(mesh.normals.size(), mesh.vertex_count());
  // Seven closed manifold tubes: torso, 2 arms, 2 legs, 2 feet.
  const MeshStats stats = compute_stats(mesh);
  ASSERT_EQ(stats.components.size(), 7u);
  for (const ComponentStats& c : stats.components) {
    EXPECT_TRUE(c.closed);
    EXPECT_TRUE(c.manifold);
    EXPECT_EQ(c.genus, 0);
  }
  // Outward winding: every tube encloses a positive volume (divergence theorem, per triangle).
  double volume = 0;
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    const float3 a = mesh.positions[mesh.indices[3 * t]], b = mesh.positions[mesh.indices[3 * t + 1]],
                 c = mesh.positions[mesh.indices[3 * t + 2]];
    volume += (double(a.x) * (double(b.y) * c.z - double(b.z) * c.y) - double(a.y) * (double(b.x) * c.z - double(b.z) * c.x) +
               double(a.z) * (double(b.x) * c.y - double(b.y) * c.x)) / 6;
  }
  // Seven tubes of radius 0.03-0.17 m: between 0.02 and 0.2 cubic metres (a person is about 0.07).
  EXPECT_GT(volume, 0.02);
  EXPECT_LT(volume, 0.2);
  EXPECT_NEAR(stats.bbox_max.y - stats.bbox_min.y, 1.85 - 0.025, 0.01);  // feet soles to head top
  EXPECT_NEAR(stats.bbox_max.x - stats.bbox_min.x, 2 * 0.83, 1e-5);     // finger tip to finger tip
}

TEST(SkinFixtures, HumanoidSkeletonAndClips) {
  const Scene& scene = humanoid();
  ASSERT_EQ(scene.nodes.size(), size_t(fixtures::joint_count) + 1);
  ASSERT_EQ(scene.skins.size(), 1u);
  EXPECT_EQ(scene.skins[0].joints.size(), size_t(fixtures::joint_count));
  for (uint32_t j = 0; j < fixtures::joint_count; ++j) {
    EXPECT_EQ(scene.nodes[j].name, fixtures::joint_name(j));
    EXPECT_EQ(scene.nodes[j].parent, fixtures::joint_parent(j));
    EXPECT_EQ(scene.skins[0].joints[j], int32_t(j));
  }
  EXPECT_EQ(scene.nodes[fixtures::joint_count].skin, 0);
  EXPECT_EQ(skinned_primitives(scene).size(), 1u);
  ASSERT_EQ(scene.animations.size(), 2u);
  EXPECT_EQ(scene.animations[0].name, "walk");
  EXPECT_EQ(scene.animations[1].name, "wave");
  EXPECT_FLOAT_EQ(animation_duration(scene, 0), 1.2f);
  EXPECT_FLOAT_EQ(animation_duration(scene, 1), 2.0f);
  // T-pose: the left wrist sits at (0.72, 1.47, 0).
  const std::vector<mat4> rest = world_matrices(scene, rest_pose(scene));
  const float3 wrist = transform_point(rest[fixtures::wrist_l], {0, 0, 0});
  EXPECT_NEAR(wrist.x, 0.72, 1e-6);
  EXPECT_NEAR(wrist.y, 1.47, 1e-6);
  EXPECT_NEAR(wrist.z, 0.0, 1e-6);
}

TEST(SkinFixtures, HumanoidClipsPoseTheSkeletonAsWritten) {
  const Scene& scene = humanoid();
  // walk, t = 0.45: halfway between the left knee's keys of 5 degrees (0.3 s) and 15 degrees (0.6 s),
  // so 10 degrees about +x: (sin 5, 0, 0, cos 5).
  Pose pose = rest_pose(scene);
  sample_animation(scene, 0, 0.45f, pose);
  const float4 knee = pose.rotation[fixtures::knee_l];
  EXPECT_NEAR(knee.x, std::sin(5 * deg), 1e-6);
  EXPECT_NEAR(knee.y, 0, 1e-6);
  EXPECT_NEAR(knee.z, 0, 1e-6);
  EXPECT_NEAR(knee.w, std::cos(5 * deg), 1e-6);
  // The hips bob: -0.03 at 0.3 s and 0 at 0.6 s, so 1 - 0.015 at 0.45 s.
  EXPECT_NEAR(pose.translation[fixtures::hips].y, 0.985, 1e-6);

  // wave, t = 1.0 (a key): shoulder_r at -20 degrees about z, elbow_r at -60. The upper arm
  // (-0.28, 0, 0) turns by -20 degrees: (-0.28 cos 20, 0.28 sin 20); the forearm (-0.26, 0, 0) by
  // -80 in all: (-0.26 cos 80, 0.26 sin 80). From the shoulder at (-0.18, 1.47, 0):
  pose = rest_pose(scene);
  sample_animation(scene, 1, 1.0f, pose);
  const std::vector<mat4> world = world_matrices(scene, pose);
  const float3 elbow = transform_point(world[fixtures::elbow_r], {0, 0, 0});
  const float3 wrist = transform_point(world[fixtures::wrist_r], {0, 0, 0});
  const double elbow_x = -0.18 - 0.28 * std::cos(20 * deg), elbow_y = 1.47 + 0.28 * std::sin(20 * deg);
  EXPECT_NEAR(elbow.x, elbow_x, 1e-5);
  EXPECT_NEAR(elbow.y, elbow_y, 1e-5);
  EXPECT_NEAR(elbow.z, 0, 1e-6);
  EXPECT_NEAR(wrist.x, elbow_x - 0.26 * std::cos(80 * deg), 1e-5);
  EXPECT_NEAR(wrist.y, elbow_y + 0.26 * std::sin(80 * deg), 1e-5);
  // Every rotation key of both clips is a unit quaternion.
  for (const Animation& clip : scene.animations)
    for (const AnimationChannel& ch : clip.channels)
      if (ch.path == AnimationPath::rotation)
        for (size_t k = 0; k < ch.times.size(); ++k) {
          const float* q = &ch.values[4 * k];
          EXPECT_NEAR(std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]), 1.0, 1e-6);
        }
}

TEST(SkinFixtures, HumanoidInfluences) {
  const Mesh& mesh = humanoid().primitives[0].mesh;
  expect_valid_influences(mesh, fixtures::joint_count);
  // Near the joints, 2-3 bones blend: some vertices have 2 and some 3 influences, and many 1.
  size_t counts[5] = {0, 0, 0, 0, 0};
  for (const float4& w : mesh.weights) counts[(w.x > 0) + (w.y > 0) + (w.z > 0) + (w.w > 0)]++;
  EXPECT_EQ(counts[0], 0u);
  EXPECT_GT(counts[1], mesh.vertex_count() / 5);
  EXPECT_GT(counts[2], 200u);
  EXPECT_GT(counts[3], 10u);
}

TEST(SkinFixtures, HumanoidIsDeterministic) {
  const Scene again = fixtures::humanoid_scene();
  EXPECT_EQ(test::mesh_difference(again.primitives[0].mesh, humanoid().primitives[0].mesh), "");
  EXPECT_EQ(again.skins[0].inverse_bind_matrices, humanoid().skins[0].inverse_bind_matrices);
  ASSERT_EQ(again.animations.size(), humanoid().animations.size());
  for (size_t a = 0; a < again.animations.size(); ++a)
    for (size_t c = 0; c < again.animations[a].channels.size(); ++c)
      EXPECT_EQ(again.animations[a].channels[c].values, humanoid().animations[a].channels[c].values);
}

TEST(SkinFixtures, HumanoidBindPoseSkinsToItself) { expect_bind_pose_identity(humanoid()); }

TEST(SkinFixtures, HumanoidSingleBoneRegionsMoveRigidly) {
  expect_rigid_region(humanoid(), fixtures::elbow_l, 0, 0.45f);   // left forearm, walking
  expect_rigid_region(humanoid(), fixtures::knee_r, 0, 0.3f);     // right shin, mid swing
  expect_rigid_region(humanoid(), fixtures::elbow_r, 1, 0.75f);   // waving forearm, between keys
  expect_rigid_region(humanoid(), fixtures::shoulder_r, 1, 1.2f); // raised upper arm
}

TEST(SkinFixtures, ManRigged) {
  const std::filesystem::path off = man_off();
  if (off.empty() || !std::filesystem::exists(off)) GTEST_SKIP() << "corpus absent (scripts/fetch-corpus.sh): no man.off";
  const Scene scene = fixtures::rigged_man_scene(off);
  const Mesh& mesh = scene.primitives[0].mesh;
  EXPECT_EQ(mesh.triangle_count(), 34986u);
  EXPECT_EQ(mesh.vertex_count(), 17495u);
  expect_valid_influences(mesh, fixtures::joint_count);
  expect_bind_pose_identity(scene);
  ASSERT_EQ(scene.animations.size(), 1u);
  EXPECT_EQ(scene.animations[0].name, "bend");
  EXPECT_FLOAT_EQ(animation_duration(scene, 0), 2.0f);
  // Joints sit where they were placed: the file's (x, y, z) is glTF's (x, z, -y).
  const std::vector<mat4> rest = world_matrices(scene, rest_pose(scene));
  for (uint32_t j = 0; j < fixtures::joint_count; ++j) {
    const float* p = fixtures::joint_positions_man[j].position;
    const float3 at = transform_point(rest[j], {0, 0, 0});
    EXPECT_NEAR(at.x, p[0], 1e-6);
    EXPECT_NEAR(at.y, p[2], 1e-6);
    EXPECT_NEAR(at.z, -p[1], 1e-6);
  }
  // Every joint inside the figure's bounds (placed on this mesh, not on another one).
  float3 lo, hi;
  bounding_box(mesh, lo, hi);
  for (const mat4& m : rest) {
    const float3 at = transform_point(m, {0, 0, 0});
    EXPECT_TRUE(at.x > lo.x && at.x < hi.x && at.y > lo.y && at.y < hi.y && at.z > lo.z && at.z < hi.z);
  }
  // (The man's forearms are too short for a single-bone band; his hands and upper arms have one.)
  expect_rigid_region(scene, fixtures::knee_l, 0, 0.5f);
  expect_rigid_region(scene, fixtures::shoulder_r, 0, 1.0f);
  expect_rigid_region(scene, fixtures::wrist_r, 0, 1.0f);
}

TEST(SkinFixtures, ExportedFilesAreValidGltf) {
  test::TempDir dir;
  const std::filesystem::path off = man_off();
  const std::vector<std::filesystem::path> files = fixtures::write_fixtures(dir.path, off);
  ASSERT_GE(files.size(), 1u);
  // Read back: the skin, the clips and the geometry survive.
  const Scene back = read_scene(files[0]);
  ASSERT_EQ(back.skins.size(), 1u);
  EXPECT_EQ(back.skins[0].inverse_bind_matrices, humanoid().skins[0].inverse_bind_matrices);
  EXPECT_EQ(back.animations.size(), 2u);
  EXPECT_EQ(test::mesh_difference(back.primitives[0].mesh, humanoid().primitives[0].mesh), "");
  if (!test::validator_available())
    GTEST_SKIP() << "gltf-validator not installed: run `npm ci --prefix tests/gltf-validator` (needs node on PATH)";
  const test::ValidatorRun run = test::run_validator(files);
  EXPECT_EQ(run.status, 0) << run.output;
}

}  // namespace
}  // namespace lod
