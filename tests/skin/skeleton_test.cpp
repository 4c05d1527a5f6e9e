// src/skin/skeleton.cpp: matrices, animation sampling (step, linear with slerp, glTF cubic spline),
// world and joint matrices, and the errors on malformed scenes. Every expected value is worked out by
// hand in the comments (rotations as sines and cosines of the angles involved).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "lodkit/error.h"
#include "lodkit/skin.h"

namespace lod {
namespace {

constexpr double deg = std::numbers::pi / 180.0;

float4 rotation_z(double degrees) {
  return {0, 0, float(std::sin(degrees * deg / 2)), float(std::cos(degrees * deg / 2))};
}

void expect_near3(const float3& a, const float3& b, float tolerance = 1e-6f) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}
void expect_near4(const float4& a, const float4& b, float tolerance = 1e-6f) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
  EXPECT_NEAR(a.w, b.w, tolerance);
}

ErrorCategory category_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.category();
  }
  ADD_FAILURE() << "no lod::Error thrown";
  return ErrorCategory::internal;
}

// ---- matrices -------------------------------------------------------------------------------------

TEST(SkinMatrices, ComposeTrsByHand) {
  // Scale x by 2, rotate 90 degrees about z ((x, y) -> (-y, x)), translate by (1, 2, 3):
  // columns R*S = (0, 2, 0), (-1, 0, 0), (0, 0, 1).
  const mat4 m = compose_trs({1, 2, 3}, rotation_z(90), {2, 1, 1});
  const mat4 expected = {0, 2, 0, 0, -1, 0, 0, 0, 0, 0, 1, 0, 1, 2, 3, 1};
  for (size_t i = 0; i < 16; ++i) EXPECT_NEAR(m[i], expected[i], 1e-6f) << i;
  // (1, 1, 1) -> (2, 1, 1) -> (-1, 2, 1) -> (0, 4, 4).
  expect_near3(transform_point(m, {1, 1, 1}), {0, 4, 4});
  // Directions skip the translation: (1, 0, 0) -> (2, 0, 0) -> (0, 2, 0).
  expect_near3(transform_vector(m, {1, 0, 0}), {0, 2, 0});
}

TEST(SkinMatrices, MultiplyOrder) {
  const mat4 translate = compose_trs({1, 0, 0}, {0, 0, 0, 1}, {1, 1, 1});
  const mat4 scale = compose_trs({}, {0, 0, 0, 1}, {2, 2, 2});
  // a * b applies b first: (1, 1, 1) -> (2, 2, 2) -> (3, 2, 2); the other order gives (4, 2, 2).
  EXPECT_EQ(transform_point(multiply(translate, scale), {1, 1, 1}), (float3{3, 2, 2}));
  EXPECT_EQ(transform_point(multiply(scale, translate), {1, 1, 1}), (float3{4, 2, 2}));
  EXPECT_EQ(multiply(identity_matrix(), scale), scale);
}

TEST(SkinMatrices, AffineInverse) {
  const mat4 m = compose_trs({1, 2, 3}, rotation_z(90), {2, 1, 1});
  const mat4 inverse = affine_inverse(m);
  // The inverse takes (0, 4, 4) back to (1, 1, 1) (see ComposeTrsByHand).
  expect_near3(transform_point(inverse, {0, 4, 4}), {1, 1, 1}, 1e-6f);
  EXPECT_EQ(inverse[3], 0.0f);
  EXPECT_EQ(inverse[15], 1.0f);
  const mat4 product = multiply(m, inverse);
  const mat4 identity = identity_matrix();
  for (size_t i = 0; i < 16; ++i) EXPECT_NEAR(product[i], identity[i], 1e-6f) << i;
  // A pure translation inverts exactly (skinning in the bind pose relies on it).
  const mat4 t = compose_trs({0.1f, 1.47f, -0.3f}, {0, 0, 0, 1}, {1, 1, 1});
  EXPECT_EQ(multiply(t, affine_inverse(t)), identity);
  // A singular linear part gives the identity instead of infinities.
  EXPECT_EQ(affine_inverse(compose_trs({5, 5, 5}, {0, 0, 0, 1}, {1, 0, 1})), identity);
}

// ---- animation sampling -----------------------------------------------------------------------------

Scene one_node_scene() {
  Scene scene;
  scene.nodes.resize(1);
  scene.nodes[0].translation = {7, 8, 9};
  scene.roots = {0};
  return scene;
}

AnimationChannel channel(AnimationPath path, Interpolation interpolation, std::vector<float> times, std::vector<float> values) {
  AnimationChannel ch;
  ch.node = 0;
  ch.path = path;
  ch.interpolation = interpolation;
  ch.components = path == AnimationPath::rotation ? 4 : 3;
  ch.times = std::move(times);
  ch.values = std::move(values);
  return ch;
}

Pose sample(const Scene& scene, float time) {
  Pose pose = rest_pose(scene);
  sample_animation(scene, 0, time, pose);
  return pose;
}

TEST(SkinSampling, Step) {
  Scene scene = one_node_scene();
  scene.animations.push_back({"steps", {channel(AnimationPath::scale, Interpolation::step, {0, 1, 2}, {1, 1, 1, 2, 2, 2, 3, 3, 3})}});
  EXPECT_EQ(sample(scene, -1).scale, (std::vector<float3>{{1, 1, 1}}));  // before the first key
  EXPECT_EQ(sample(scene, 0.99f).scale, (std::vector<float3>{{1, 1, 1}}));
  EXPECT_EQ(sample(scene, 1.0f).scale, (std::vector<float3>{{2, 2, 2}}));
  EXPECT_EQ(sample(scene, 1.5f).scale, (std::vector<float3>{{2, 2, 2}}));
  EXPECT_EQ(sample(scene, 2.5f).scale, (std::vector<float3>{{3, 3, 3}}));  // after the last key
  // Channels it does not have keep the rest values.
  EXPECT_EQ(sample(scene, 1.5f).translation, (std::vector<float3>{{7, 8, 9}}));
}

TEST(SkinSampling, LinearTranslation) {
  Scene scene = one_node_scene();
  scene.animations.push_back({"move", {channel(AnimationPath::translation, Interpolation::linear, {1, 3}, {0, 0, 0, 2, 4, -6})}});
  EXPECT_EQ(sample(scene, 1).translation[0], (float3{0, 0, 0}));
  EXPECT_EQ(sample(scene, 2).translation[0], (float3{1, 2, -3}));  // halfway
  expect_near3(sample(scene, 1.5f).translation[0], {0.5f, 1, -1.5f});
  EXPECT_EQ(sample(scene, 0).translation[0], (float3{0, 0, 0}));   // clamped to the first key
  EXPECT_EQ(sample(scene, 9).translation[0], (float3{2, 4, -6}));  // and to the last
  EXPECT_FLOAT_EQ(animation_duration(scene, 0), 3.0f);
}

TEST(SkinSampling, SlerpMidpointOfNinetyDegreesIsFortyFive) {
  Scene scene = one_node_scene();
  // Identity to 90 degrees about z: halfway is 45 degrees, (0, 0, sin 22.5, cos 22.5).
  const float4 q90 = rotation_z(90);
  scene.animations.push_back({"turn", {channel(AnimationPath::rotation, Interpolation::linear, {0, 1}, {0, 0, 0, 1, q90.x, q90.y, q90.z, q90.w})}});
  expect_near4(sample(scene, 0.5f).rotation[0], {0, 0, 0.38268343f, 0.92387953f});
  // A quarter of the way: 22.5 degrees, (0, 0, sin 11.25, cos 11.25); slerp is uniform in angle.
  expect_near4(sample(scene, 0.25f).rotation[0], {0, 0, 0.19509032f, 0.98078528f});
  expect_near4(sample(scene, 1.0f).rotation[0], q90);
}

TEST(SkinSampling, SlerpTakesTheShortArc) {
  Scene scene = one_node_scene();
  // The second key is -q90, the same rotation: the path must still be the 90-degree one, not 270.
  const float4 q90 = rotation_z(90);
  scene.animations.push_back(
      {"turn", {channel(AnimationPath::rotation, Interpolation::linear, {0, 1}, {0, 0, 0, 1, -q90.x, -q90.y, -q90.z, -q90.w})}});
  expect_near4(sample(scene, 0.5f).rotation[0], {0, 0, 0.38268343f, 0.92387953f});
}

TEST(SkinSampling, RotationsStayUnitLength) {
  Scene scene = one_node_scene();
  // Keys that are not unit length (2x and 0.5x) and a 170-degree turn about a skew axis.
  const float s = float(std::sin(85 * deg) / std::sqrt(3.0)), c = float(std::cos(85 * deg));
  scene.animations.push_back({"spin",
                              {channel(AnimationPath::rotation, Interpolation::linear, {0, 1, 2},
                                       {0, 0, 0, 2, s, s, s, c, 0, 0.5f, 0, 0})}});
  for (int i = 0; i <= 40; ++i) {
    const float4 q = sample(scene, 0.05f * float(i)).rotation[0];
    EXPECT_NEAR(std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w), 1.0, 1e-6) << i;
  }
  // The keys themselves come out normalised: 2 * identity -> identity.
  expect_near4(sample(scene, 0).rotation[0], {0, 0, 0, 1});
}

TEST(SkinSampling, CubicSplineByHand) {
  Scene scene = one_node_scene();
  // One interval of 2 s. Keys store (in-tangent, value, out-tangent) per component:
  //   x: value 0 -> 2, out-tangent of key 0 = 1, in-tangent of key 1 = -1
  //   y: constant 5 (zero tangents)
  //   z: value 0 -> 0, tangents 3 and 3
  // With s = t / 2 and tangents scaled by the interval (2):
  //   p(s) = h00 v0 + h10 * 2 * b0 + h01 v1 + h11 * 2 * a1,
  //   h00 = 2s^3 - 3s^2 + 1, h10 = s^3 - 2s^2 + s, h01 = -2s^3 + 3s^2, h11 = s^3 - s^2.
  // s = 0.5: h = (0.5, 0.125, 0.5, -0.125): x = 0.25 + 1 + 0.25 = 1.5, z = 6 (0.125 - 0.125) = 0.
  // s = 0.25: h = (0.84375, 0.140625, 0.15625, -0.046875):
  //   x = 0.28125 + 0.3125 + 0.09375 = 0.6875, z = 6 (0.140625 - 0.046875) = 0.5625.
  const std::vector<float> key0 = {/*in*/ 9, 9, 9, /*value*/ 0, 5, 0, /*out*/ 1, 0, 3};
  const std::vector<float> key1 = {/*in*/ -1, 0, 3, /*value*/ 2, 5, 0, /*out*/ 9, 9, 9};
  std::vector<float> values = key0;
  values.insert(values.end(), key1.begin(), key1.end());
  scene.animations.push_back({"curve", {channel(AnimationPath::translation, Interpolation::cubic_spline, {0, 2}, values)}});
  expect_near3(sample(scene, 1.0f).translation[0], {1.5f, 5, 0}, 1e-6f);
  expect_near3(sample(scene, 0.5f).translation[0], {0.6875f, 5, 0.5625f}, 1e-6f);
  // At and beyond the keys: the values, never the tangents.
  EXPECT_EQ(sample(scene, 0).translation[0], (float3{0, 5, 0}));
  EXPECT_EQ(sample(scene, 2).translation[0], (float3{2, 5, 0}));
  EXPECT_EQ(sample(scene, 3).translation[0], (float3{2, 5, 0}));
}

TEST(SkinSampling, CubicSplineRotationIsNormalised) {
  Scene scene = one_node_scene();
  // Zero tangents: at s = 0.5 the spline is (q0 + q90) / 2 = (0, 0, 0.35355, 0.85355), which
  // normalises to 45 degrees about z.
  const float4 q = rotation_z(90);
  scene.animations.push_back({"turn",
                              {channel(AnimationPath::rotation, Interpolation::cubic_spline, {0, 1},
                                       {0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, q.x, q.y, q.z, q.w, 0, 0, 0, 0})}});
  expect_near4(sample(scene, 0.5f).rotation[0], {0, 0, 0.38268343f, 0.92387953f});
}

TEST(SkinSampling, MorphWeightChannelsAreIgnored) {
  Scene scene = one_node_scene();
  AnimationChannel weights = channel(AnimationPath::weights, Interpolation::linear, {0, 1}, {0, 1});
  weights.components = 1;
  scene.animations.push_back({"morph", {weights}});
  const Pose pose = sample(scene, 0.5f);
  EXPECT_EQ(pose.translation[0], (float3{7, 8, 9}));
}

TEST(SkinSampling, MalformedClipsThrow) {
  const Scene base = one_node_scene();
  Pose pose = rest_pose(base);
  EXPECT_EQ(category_of([&] { sample_animation(base, 0, 0, pose); }), ErrorCategory::usage);  // no clip 0
  EXPECT_EQ(category_of([&] { animation_duration(base, 3); }), ErrorCategory::usage);
  auto with = [&](AnimationChannel ch) {
    Scene scene = base;
    scene.animations.push_back({"bad", {std::move(ch)}});
    return scene;
  };
  const AnimationChannel good = channel(AnimationPath::translation, Interpolation::linear, {0, 1}, {0, 0, 0, 1, 1, 1});
  AnimationChannel c = good;
  c.node = 1;  // out of range
  EXPECT_EQ(category_of([&] { sample_animation(with(c), 0, 0.5f, pose); }), ErrorCategory::bad_input);
  c = good;
  c.node = -1;
  EXPECT_EQ(category_of([&] { sample_animation(with(c), 0, 0.5f, pose); }), ErrorCategory::bad_input);
  c = good;
  c.values.pop_back();  // 5 values for 2 keys of 3
  EXPECT_EQ(category_of([&] { sample_animation(with(c), 0, 0.5f, pose); }), ErrorCategory::bad_input);
  c = good;
  c.times.push_back(2);  // 3 keys, 2 values
  EXPECT_EQ(category_of([&] { sample_animation(with(c), 0, 0.5f, pose); }), ErrorCategory::bad_input);
  c = good;
  c.interpolation = Interpolation::cubic_spline;  // needs 3 values per component and key
  EXPECT_EQ(category_of([&] { sample_animation(with(c), 0, 0.5f, pose); }), ErrorCategory::bad_input);
  c = good;
  c.components = 4;  // a translation has 3
  EXPECT_EQ(category_of([&] { sample_animation(with(c), 0, 0.5f, pose); }), ErrorCategory::bad_input);
  c = good;
  c.times = {1, 0};  // decreasing
  EXPECT_EQ(category_of([&] { sample_animation(with(c), 0, 0.5f, pose); }), ErrorCategory::bad_input);
  c = good;
  c.times = {0, NAN};
  EXPECT_EQ(category_of([&] { sample_animation(with(c), 0, 0.5f, pose); }), ErrorCategory::bad_input);
  c = good;
  c.times.clear();
  c.values.clear();
  EXPECT_EQ(category_of([&] { sample_animation(with(c), 0, 0.5f, pose); }), ErrorCategory::bad_input);
  // A pose of the wrong size is a usage error, and a failed call leaves the pose alone.
  Pose small;
  EXPECT_EQ(category_of([&] { sample_animation(with(good), 0, 0.5f, small); }), ErrorCategory::usage);
  c = good;
  c.values.pop_back();
  Scene two = with(good);
  two.animations[0].channels.push_back(c);
  Pose untouched = rest_pose(two);
  EXPECT_THROW(sample_animation(two, 0, 0.5f, untouched), Error);
  EXPECT_EQ(untouched.translation[0], (float3{7, 8, 9}));
}

// ---- world and joint matrices ------------------------------------------------------------------------

// A chain root -> middle -> leaf stored out of order (leaf 1, middle 0, root 2), so parents do not
// come first. root: T(1, 0, 0); middle: T(0, 1, 0) R(90 about z); leaf: T(1, 0, 0) S(2).
Scene chain_scene(bool set_parents, bool set_children) {
  Scene scene;
  scene.nodes.resize(3);
  Node& root = scene.nodes[2];
  Node& middle = scene.nodes[0];
  Node& leaf = scene.nodes[1];
  root.translation = {1, 0, 0};
  middle.translation = {0, 1, 0};
  middle.rotation = rotation_z(90);
  leaf.translation = {1, 0, 0};
  leaf.scale = {2, 2, 2};
  if (set_parents) middle.parent = 2, leaf.parent = 0;
  if (set_children) root.children = {0}, middle.children = {1};
  scene.roots = {2};
  return scene;
}

TEST(SkinWorld, ThreeNodeChainByHand) {
  for (const auto& [parents, children] : {std::pair{true, true}, std::pair{true, false}, std::pair{false, true}}) {
    const Scene scene = chain_scene(parents, children);
    const std::vector<mat4> world = world_matrices(scene, rest_pose(scene));
    ASSERT_EQ(world.size(), 3u);
    // root: origin at (1, 0, 0).
    expect_near3(transform_point(world[2], {0, 0, 0}), {1, 0, 0});
    // middle: origin (0, 1, 0) + (1, 0, 0); its x axis turned to +y.
    expect_near3(transform_point(world[0], {0, 0, 0}), {1, 1, 0});
    expect_near3(transform_vector(world[0], {1, 0, 0}), {0, 1, 0});
    // leaf origin: (1, 0, 0) in the middle's frame -> rotated (0, 1, 0) + (0, 1, 0) -> + (1, 0, 0) = (1, 2, 0).
    expect_near3(transform_point(world[1], {0, 0, 0}), {1, 2, 0});
    // leaf's (1, 0, 0): scaled (2, 0, 0), + (1, 0, 0) = (3, 0, 0), rotated (0, 3, 0), + (0, 1, 0), + (1, 0, 0) = (1, 4, 0).
    expect_near3(transform_point(world[1], {1, 0, 0}), {1, 4, 0});
    expect_near3(transform_vector(world[1], {0, 1, 0}), {-2, 0, 0});
  }
}

TEST(SkinWorld, PoseOverridesTheRest) {
  const Scene scene = chain_scene(true, true);
  Pose pose = rest_pose(scene);
  pose.rotation[0] = {0, 0, 0, 1};  // unbend the middle joint
  const std::vector<mat4> world = world_matrices(scene, pose);
  // leaf origin: (1, 0, 0) + (0, 1, 0) + (1, 0, 0) = (2, 1, 0).
  expect_near3(transform_point(world[1], {0, 0, 0}), {2, 1, 0});
}

TEST(SkinWorld, MatrixNodesKeepTheirMatrix) {
  Scene scene = chain_scene(true, true);
  scene.nodes[2].has_matrix = true;
  scene.nodes[2].matrix = compose_trs({0, 0, 5}, {0, 0, 0, 1}, {1, 1, 1});
  Pose pose = rest_pose(scene);
  pose.translation[2] = {100, 100, 100};  // ignored: glTF does not animate matrix nodes
  const std::vector<mat4> world = world_matrices(scene, pose);
  expect_near3(transform_point(world[2], {0, 0, 0}), {0, 0, 5});
  expect_near3(transform_point(world[1], {0, 0, 0}), {0, 2, 5});
}

TEST(SkinWorld, MalformedHierarchiesThrow) {
  Scene cycle = chain_scene(true, false);
  cycle.nodes[2].parent = 1;  // root's parent is the leaf
  EXPECT_EQ(category_of([&] { world_matrices(cycle, rest_pose(cycle)); }), ErrorCategory::bad_input);
  Scene self = chain_scene(true, false);
  self.nodes[0].parent = 0;
  EXPECT_EQ(category_of([&] { world_matrices(self, rest_pose(self)); }), ErrorCategory::bad_input);
  Scene parent_out_of_range = chain_scene(true, false);
  parent_out_of_range.nodes[0].parent = 3;
  EXPECT_EQ(category_of([&] { world_matrices(parent_out_of_range, rest_pose(parent_out_of_range)); }), ErrorCategory::bad_input);
  Scene child_out_of_range = chain_scene(true, true);
  child_out_of_range.nodes[1].children = {-5};
  EXPECT_EQ(category_of([&] { world_matrices(child_out_of_range, rest_pose(child_out_of_range)); }), ErrorCategory::bad_input);
  Scene two_parents = chain_scene(true, true);
  two_parents.nodes[2].children = {0, 1};  // the leaf's parent says the middle
  EXPECT_EQ(category_of([&] { world_matrices(two_parents, rest_pose(two_parents)); }), ErrorCategory::bad_input);
  Scene children_cycle = chain_scene(false, true);
  children_cycle.nodes[1].children = {2};  // leaf -> root closes the loop
  EXPECT_EQ(category_of([&] { world_matrices(children_cycle, rest_pose(children_cycle)); }), ErrorCategory::bad_input);
  const Scene fine = chain_scene(true, true);
  Pose short_pose = rest_pose(fine);
  short_pose.scale.pop_back();
  EXPECT_EQ(category_of([&] { world_matrices(fine, short_pose); }), ErrorCategory::usage);
}

TEST(SkinJoints, InverseBindMatricesCancelTheBindPose) {
  Scene scene = chain_scene(true, true);
  const std::vector<mat4> bind = world_matrices(scene, rest_pose(scene));
  Skin skin;
  skin.joints = {2, 0, 1};
  for (const int32_t j : skin.joints) skin.inverse_bind_matrices.push_back(affine_inverse(bind[size_t(j)]));
  scene.skins.push_back(skin);
  const std::vector<mat4> joints = joint_matrices(scene, 0, bind);
  ASSERT_EQ(joints.size(), 3u);
  for (const mat4& m : joints)
    for (size_t i = 0; i < 16; ++i) EXPECT_NEAR(m[i], identity_matrix()[i], 1e-6f);
  // Bend the middle joint back by -90 degrees: a point bound at the leaf's origin (1, 2, 0) rotates
  // about the middle joint at (1, 1, 0) to (2, 1, 0).
  Pose pose = rest_pose(scene);
  pose.rotation[0] = {0, 0, 0, 1};
  const std::vector<mat4> bent = joint_matrices(scene, 0, world_matrices(scene, pose));
  expect_near3(transform_point(bent[2], {1, 2, 0}), {2, 1, 0}, 1e-6f);
  // No inverse bind matrices: glTF's identities, the joint matrix is the world matrix.
  scene.skins[0].inverse_bind_matrices.clear();
  EXPECT_EQ(joint_matrices(scene, 0, bind)[1], bind[0]);
}

TEST(SkinJoints, MalformedSkinsThrow) {
  Scene scene = chain_scene(true, true);
  const std::vector<mat4> world = world_matrices(scene, rest_pose(scene));
  EXPECT_EQ(category_of([&] { joint_matrices(scene, 0, world); }), ErrorCategory::usage);  // no skin 0
  Skin skin;
  skin.joints = {0, 7};
  scene.skins.push_back(skin);
  EXPECT_EQ(category_of([&] { joint_matrices(scene, 0, world); }), ErrorCategory::bad_input);  // node 7
  scene.skins[0].joints = {0, 1};
  scene.skins[0].inverse_bind_matrices = {identity_matrix()};  // 1 matrix for 2 joints
  EXPECT_EQ(category_of([&] { joint_matrices(scene, 0, world); }), ErrorCategory::bad_input);
}

TEST(SkinJoints, SkinnedPrimitives) {
  Scene scene = chain_scene(true, true);
  scene.skins.push_back(Skin{.joints = {2, 0, 1}});
  Node mesh_node;
  mesh_node.mesh = 1;
  mesh_node.skin = 0;
  scene.nodes.push_back(mesh_node);
  Node static_node;  // instances the same mesh without a skin
  static_node.mesh = 1;
  scene.nodes.push_back(static_node);
  Primitive skinned, plain, other_mesh;
  skinned.gltf_mesh = 1;
  skinned.mesh.positions = {{0, 0, 0}};
  skinned.mesh.joints = {{0, 0, 0, 0}};
  skinned.mesh.weights = {{1, 0, 0, 0}};
  plain.gltf_mesh = 1;  // same glTF mesh, but no joints and weights
  plain.mesh.positions = {{0, 0, 0}};
  other_mesh = skinned;
  other_mesh.gltf_mesh = 0;
  scene.primitives = {other_mesh, plain, skinned};
  const std::vector<SkinnedPrimitive> found = skinned_primitives(scene);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].primitive, 2u);
  EXPECT_EQ(found[0].node, 3u);
  EXPECT_EQ(found[0].skin, 0u);
  scene.nodes[3].skin = 4;  // no such skin
  EXPECT_EQ(category_of([&] { skinned_primitives(scene); }), ErrorCategory::bad_input);
}

}  // namespace
}  // namespace lod
