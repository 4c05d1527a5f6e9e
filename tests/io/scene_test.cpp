// flatten() and scene_from_mesh(): world transforms computed by hand, material ids, stream rules.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "test_support.h"

namespace lod {
namespace {

using test::mesh_difference;

// One triangle in the z = 0 plane, facing +z, with a tangent along +x.
Mesh unit_triangle() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  m.tangents = {{1, 0, 0, 1}, {1, 0, 0, 1}, {1, 0, 0, 1}};
  m.indices = {0, 1, 2};
  return m;
}

Primitive primitive(Mesh mesh, uint32_t gltf_mesh = 0, int32_t material = -1) {
  Primitive p;
  p.mesh = std::move(mesh);
  p.gltf_mesh = gltf_mesh;
  p.material = material;
  return p;
}

// A scene of one mesh under one root node with the given scale.
Scene scaled_scene(Mesh mesh, float3 scale) {
  Scene scene;
  scene.primitives.push_back(primitive(std::move(mesh)));
  Node node;
  node.scale = scale;
  node.mesh = 0;
  scene.nodes = {node};
  scene.roots = {0};
  return scene;
}

void expect_near(const float3& a, const float3& b) {
  EXPECT_NEAR(a.x, b.x, 1e-6f);
  EXPECT_NEAR(a.y, b.y, 1e-6f);
  EXPECT_NEAR(a.z, b.z, 1e-6f);
}

TEST(SceneFlatten, AppliesParentTimesLocal) {
  Scene scene;
  scene.primitives.push_back(primitive(unit_triangle()));
  Node root, child;
  root.translation = {1, 2, 3};
  root.scale = {2, 2, 2};
  root.children = {1};
  child.parent = 0;
  child.translation = {0, 1, 0};
  child.mesh = 0;
  scene.nodes = {root, child};
  scene.roots = {0};
  // world = T(1,2,3) * S(2) * T(0,1,0): p -> 2 * (p + (0,1,0)) + (1,2,3).
  const Mesh m = flatten(scene);
  ASSERT_EQ(m.positions.size(), 3u);
  EXPECT_EQ(m.positions[0], (float3{1, 4, 3}));
  EXPECT_EQ(m.positions[1], (float3{3, 4, 3}));
  EXPECT_EQ(m.positions[2], (float3{1, 6, 3}));
  EXPECT_EQ(m.normals[0], (float3{0, 0, 1}));  // uniform scale: renormalised, unchanged direction
  EXPECT_EQ(m.tangents[0], (float4{1, 0, 0, 1}));
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2}));
  EXPECT_TRUE(m.materials.empty());
}

// Found by fuzz_gltf: finite positions under a large node scale overflow float.
TEST(SceneFlatten, OverflowingTransformIsBadInput) {
  Mesh big = unit_triangle();
  big.positions[1].x = 3e38f;
  Scene scene = scaled_scene(big, {5121, 1, 1});
  scene.name = "huge.gltf";
  try {
    flatten(scene);
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.category(), ErrorCategory::bad_input);
    EXPECT_EQ(std::string(e.what()).rfind("huge.gltf:", 0), 0u) << e.what();
  }
}

TEST(SceneFlatten, MatrixNodesAndRotation) {
  Scene scene;
  scene.primitives.push_back(primitive(unit_triangle()));
  Node turn;  // 90 degrees about +z: x -> y, y -> -x
  turn.rotation = {0, 0, std::sqrt(0.5f), std::sqrt(0.5f)};
  turn.children = {1};
  Node moved;  // column-major matrix translating by (10, 0, 0)
  moved.parent = 0;
  moved.has_matrix = true;
  moved.matrix = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 10, 0, 0, 1};
  moved.mesh = 0;
  scene.nodes = {turn, moved};
  scene.roots = {0};
  const Mesh m = flatten(scene);
  // R * T(10,0,0) * p: vertex (1,0,0) -> (11,0,0) -> (0,11,0).
  expect_near(m.positions[0], {0, 10, 0});
  expect_near(m.positions[1], {0, 11, 0});
  expect_near(m.positions[2], {-1, 10, 0});
  expect_near(m.normals[0], {0, 0, 1});
  expect_near({m.tangents[0].x, m.tangents[0].y, m.tangents[0].z}, {0, 1, 0});
}

TEST(SceneFlatten, NonUniformScaleUsesTheInverseTranspose) {
  Mesh plane;  // a plane x + y = 1 through (1,0,0) and (0,1,0), normal (1,1,0)/sqrt(2)
  plane.positions = {{1, 0, 0}, {0, 1, 0}, {1, 0, 1}};
  const float h = std::sqrt(0.5f);
  plane.normals = {{h, h, 0}, {h, h, 0}, {h, h, 0}};
  plane.indices = {0, 1, 2};
  Scene scene = scaled_scene(plane, {2, 1, 1});
  const Mesh m = flatten(scene);
  // The scaled plane is x/2 + y = 1, whose normal is (1/2, 1, 0) -> (1, 2, 0)/sqrt(5).
  expect_near(m.normals[0], {1 / std::sqrt(5.0f), 2 / std::sqrt(5.0f), 0});
  EXPECT_EQ(m.positions[0], (float3{2, 0, 0}));
}

TEST(SceneFlatten, MirroringKeepsTrianglesCounterClockwise) {
  Scene scene = scaled_scene(unit_triangle(), {-1, 1, 1});
  const Mesh m = flatten(scene);
  EXPECT_EQ(m.positions[1], (float3{-1, 0, 0}));
  // Mirrored in x the corners 0,1,2 run clockwise seen from +z; two are swapped back.
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 2, 1}));
  expect_near(m.normals[0], {0, 0, 1});
  EXPECT_EQ(m.tangents[0].w, -1.0f);  // handedness flips with the mirror
  expect_near({m.tangents[0].x, m.tangents[0].y, m.tangents[0].z}, {-1, 0, 0});
}

TEST(SceneFlatten, MeshInstancedTwiceAppearsTwice) {
  Scene scene;
  scene.primitives.push_back(primitive(unit_triangle()));
  Node a, b;
  a.mesh = b.mesh = 0;
  b.translation = {0, 0, 5};
  scene.nodes = {a, b};
  scene.roots = {0, 1};
  const Mesh m = flatten(scene);
  ASSERT_EQ(m.positions.size(), 6u);
  EXPECT_EQ(m.positions[3], (float3{0, 0, 5}));
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 3, 4, 5}));
}

TEST(SceneFlatten, SkinnedMeshesStayInBindPose) {
  Scene scene;
  scene.primitives.push_back(primitive(unit_triangle()));
  Node node;
  node.translation = {7, 7, 7};  // glTF ignores the transform of a node with a skin
  node.mesh = 0;
  node.skin = 0;
  scene.nodes = {node};
  scene.roots = {0};
  EXPECT_EQ(flatten(scene).positions, unit_triangle().positions);
}

// Morph targets of a flattened scene, by hand: node 0 scales its mesh by (2, 1, 1), then turns it a
// quarter about +z (x to y). A displacement (1, 0, 0) becomes (0, 2, 0). A normal (0, 0, 1)
// displaced by (1, 0, 0) is (1, 0, 1), which the inverse transpose takes to (0, 0.5, 1): unit,
// (0, 0.447214, 0.894427), so the displacement is (0, 0.447214, -0.105573). A tangent (1, 0, 0)
// displaced by (0, 1, 0) is (1, 1, 0), which the 3x3 takes to (-1, 2, 0): unit, (-0.447214,
// 0.894427, 0), less the tangent's own (0, 1, 0). Node 1's mesh has no targets: zero there. Drawn by a second node too, the targets are not given (two nodes' weights).
TEST(SceneFlatten, MorphTargetsGoToWorldSpaceWithTheirNode) {
  test::TempDir dir;
  Scene scene;
  scene.primitives.push_back(primitive(unit_triangle(), 0));
  scene.primitives.push_back(primitive(unit_triangle(), 1));
  MorphTarget target;
  target.positions.assign(3, {1, 0, 0});
  target.normals.assign(3, {1, 0, 0});
  target.tangents.assign(3, {0, 1, 0});
  scene.primitives[0].targets.push_back(target);
  Node turned, plain;
  turned.mesh = 0, turned.scale = {2, 1, 1}, turned.rotation = {0, 0, std::sqrt(0.5f), std::sqrt(0.5f)};
  plain.mesh = 1, plain.translation = {0, 0, 3};
  scene.nodes = {plain, turned};
  scene.roots = {0, 1};
  write_scene(scene, dir / "morph.glb");
  const Scene read = read_scene(dir / "morph.glb");
  const Mesh flat = flatten(read);
  const FlatMorphTargets morph = flatten_morph_targets(read);
  EXPECT_EQ(morph.nodes, (std::vector<int32_t>{1}));
  EXPECT_EQ(morph.first, (std::vector<size_t>{0}));
  ASSERT_EQ(morph.targets.size(), 1u);
  ASSERT_EQ(morph.targets[0].positions.size(), flat.vertex_count());
  ASSERT_EQ(morph.targets[0].normals.size(), flat.vertex_count());
  ASSERT_EQ(morph.targets[0].tangents.size(), flat.vertex_count());
  for (size_t v = 0; v < 3; ++v) {  // node 0's vertices come first (depth-first order)
    EXPECT_EQ(morph.targets[0].positions[v], (float3{0, 0, 0}));
    EXPECT_EQ(morph.targets[0].normals[v], (float3{0, 0, 0}));
    EXPECT_EQ(morph.targets[0].tangents[v], (float3{0, 0, 0}));
  }
  for (size_t v = 3; v < 6; ++v) {
    expect_near(morph.targets[0].positions[v], {0, 2, 0});
    expect_near(morph.targets[0].normals[v], {0, 0.447214f, -0.105573f});
    expect_near(morph.targets[0].tangents[v], {-0.447214f, -0.105573f, 0});
  }

  scene.nodes.push_back(turned);
  scene.roots.push_back(2);
  write_scene(scene, dir / "twice.glb");
  // Drawn by a second node too: each node's target in turn, zero on the other's vertices.
  const FlatMorphTargets twice = flatten_morph_targets(read_scene(dir / "twice.glb"));
  EXPECT_EQ(twice.nodes, (std::vector<int32_t>{1, 2}));
  EXPECT_EQ(twice.first, (std::vector<size_t>{0, 1}));
  ASSERT_EQ(twice.targets.size(), 2u);
  for (size_t k = 0; k < 2; ++k) {
    ASSERT_EQ(twice.targets[k].positions.size(), 9u);
    for (size_t v = 0; v < 9; ++v) {
      if (v / 3 == k + 1) expect_near(twice.targets[k].positions[v], {0, 2, 0});
      else EXPECT_EQ(twice.targets[k].positions[v], (float3{0, 0, 0})) << k << " " << v;
    }
  }
}

TEST(SceneFlatten, NoNodesUsesEachMeshOnceUntransformed) {
  Scene scene;
  Mesh second = unit_triangle();
  for (float3& p : second.positions) p.z = 4;
  scene.primitives.push_back(primitive(unit_triangle(), 0));
  scene.primitives.push_back(primitive(second, 1));
  const Mesh m = flatten(scene);
  ASSERT_EQ(m.positions.size(), 6u);
  EXPECT_EQ(m.positions[4], (float3{1, 0, 4}));
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 3, 4, 5}));
  // Identity placement copies every stream bit for bit.
  Scene single;
  const Mesh torus = shapes::torus();
  single.primitives.push_back(primitive(torus));
  EXPECT_EQ(mesh_difference(flatten(single), torus), "");
}

TEST(SceneFlatten, MaterialIdsAreGltfIndexPlusOne) {
  Scene scene;
  scene.primitives.push_back(primitive(unit_triangle(), 0, -1));
  scene.primitives.push_back(primitive(unit_triangle(), 0, 1));
  scene.material_names = {"stone", "moss"};
  const Mesh m = flatten(scene);
  EXPECT_EQ(m.materials, (std::vector<uint32_t>{0, 2}));
  EXPECT_EQ(m.material_names, (std::vector<std::string>{"", "stone", "moss"}));
}

TEST(SceneFlatten, KeepsOnlyStreamsEveryPrimitiveHas) {
  Mesh with_uvs = unit_triangle();
  with_uvs.uvs[0] = {{0, 0}, {1, 0}, {0, 1}};
  with_uvs.colors.assign(3, {1, 0, 0, 1});
  Mesh without = unit_triangle();
  without.colors.assign(3, {0, 1, 0, 1});
  Scene scene;
  scene.primitives.push_back(primitive(with_uvs, 0));
  scene.primitives.push_back(primitive(without, 1));
  const Mesh m = flatten(scene);
  EXPECT_TRUE(m.uvs[0].empty());
  EXPECT_EQ(m.normals.size(), 6u);
  EXPECT_EQ(m.colors.size(), 6u);
  EXPECT_EQ(m.colors[3], (float4{0, 1, 0, 1}));
}

// With fill_streams, a stream some instance has is kept, the others getting neutral values (in world
// space like their own: a smooth normal turned with its node), and influences only when all have
// them. Values by hand: the plain triangle faces +z (its smooth normal), rotated 90 degrees about x
// by its node it faces -y; UVs 0, white, tangent +x (turned to +x: the rotation keeps x).
TEST(SceneFlatten, FillStreamsKeepsWhatAnyInstanceHas) {
  Mesh textured = unit_triangle();
  textured.uvs[1] = {{0.5f, 0}, {1, 0}, {0, 1}};
  textured.joints.assign(3, {1, 0, 0, 0});
  textured.weights.assign(3, {1, 0, 0, 0});
  Mesh plain;
  plain.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  plain.indices = {0, 1, 2};
  plain.colors.assign(3, {0, 1, 0, 1});
  Scene scene;
  scene.primitives = {primitive(textured, 0), primitive(plain, 1)};
  Node a, b;
  a.mesh = 0, b.mesh = 1;
  b.rotation = {std::sqrt(0.5f), 0, 0, std::sqrt(0.5f)};  // 90 degrees about +x: +z goes to -y
  scene.nodes = {a, b};
  scene.roots = {0, 1};
  EXPECT_EQ(stream_layout(textured), stream_normals | stream_tangents | (stream_uv0 << 1) | stream_joints | stream_weights);
  EXPECT_EQ(stream_layout(plain), stream_colors);

  const Mesh kept = flatten(scene);
  EXPECT_TRUE(kept.normals.empty() && kept.uvs[1].empty() && kept.colors.empty() && kept.joints.empty());
  const Mesh m = flatten(scene, {.fill_streams = true});
  ASSERT_EQ(m.vertex_count(), 6u);
  EXPECT_EQ(stream_layout(m), stream_normals | stream_tangents | (stream_uv0 << 1) | stream_colors);
  for (size_t v = 0; v < 3; ++v) {
    expect_near(m.normals[v], {0, 0, 1});
    expect_near(m.normals[3 + v], {0, -1, 0});
    EXPECT_EQ(m.tangents[3 + v].w, 1.0f);
    expect_near({m.tangents[3 + v].x, m.tangents[3 + v].y, m.tangents[3 + v].z}, {1, 0, 0});
    EXPECT_EQ(m.uvs[1][v], textured.uvs[1][v]);
    EXPECT_EQ(m.uvs[1][3 + v], (float2{0, 0}));
    EXPECT_EQ(m.colors[v], (float4{1, 1, 1, 1}));
    EXPECT_EQ(m.colors[3 + v], (float4{0, 1, 0, 1}));
  }
  // keep_streams takes a part back to its own streams.
  Mesh part = m;
  keep_streams(part, stream_layout(plain));
  EXPECT_EQ(stream_layout(part), stream_colors);
  // A primitive drawn twice lacking a stream gets it filled in both instances, each placed by its
  // own node (flatten fills it once and reuses the copy).
  Node c = b;
  c.translation = {5, 0, 0};
  scene.nodes.push_back(c);
  scene.roots.push_back(2);
  const Mesh twice = flatten(scene, {.fill_streams = true});
  ASSERT_EQ(twice.vertex_count(), 9u);
  for (size_t v = 0; v < 3; ++v) {
    expect_near(twice.normals[6 + v], {0, -1, 0});
    EXPECT_EQ(twice.uvs[1][6 + v], (float2{0, 0}));
    EXPECT_EQ(twice.colors[6 + v], (float4{0, 1, 0, 1}));
    EXPECT_EQ(twice.positions[6 + v].x, twice.positions[3 + v].x + 5);
  }
}

// What flatten draws: reached from a root, shown, each primitive once (mesh 0 is drawn twice), in
// order of first appearance (node 2, the first root, draws mesh 1).
TEST(SceneFlatten, FlattenedPrimitivesAreThoseItDraws) {
  Scene scene;
  for (uint32_t m = 0; m < 4; ++m) scene.primitives.push_back(primitive(unit_triangle(), m));
  scene.primitives.push_back(primitive(unit_triangle(), 1));  // mesh 1's second primitive
  Node a, b, hidden, unreached, root;
  a.mesh = 0, b.mesh = 0, hidden.mesh = 2, hidden.visible = false, unreached.mesh = 3, root.mesh = 1;
  root.children = {0, 1, 3};
  scene.nodes = {a, b, root, hidden, unreached};
  scene.nodes[0].parent = scene.nodes[1].parent = scene.nodes[3].parent = 2;
  scene.roots = {2};
  EXPECT_EQ(flattened_primitives(scene), (std::vector<size_t>{1, 4, 0}));
  EXPECT_EQ(flatten(scene).triangle_count(), 4u);
  scene.nodes.clear(), scene.roots.clear();  // no hierarchy: every primitive once
  EXPECT_EQ(flattened_primitives(scene), (std::vector<size_t>{0, 1, 2, 3, 4}));
}

TEST(SceneFromMesh, WholeMeshWhenThereIsOneMaterial) {
  const Mesh cube = shapes::cube();
  const Scene scene = scene_from_mesh(cube);
  ASSERT_EQ(scene.primitives.size(), 1u);
  EXPECT_EQ(scene.primitives[0].material, -1);
  EXPECT_TRUE(scene.material_names.empty());
  EXPECT_EQ(mesh_difference(scene.primitives[0].mesh, cube), "");
  ASSERT_EQ(scene.nodes.size(), 1u);
  EXPECT_EQ(scene.nodes[0].mesh, 0);
  EXPECT_EQ(scene.roots, (std::vector<int32_t>{0}));
  EXPECT_EQ(scene.source, nullptr);
  EXPECT_EQ(mesh_difference(flatten(scene), cube), "");

  Mesh named = cube;
  named.material_names = {"only"};
  EXPECT_EQ(scene_from_mesh(named).primitives[0].material, 0);
}

TEST(SceneFromMesh, OnePrimitivePerMaterialWithItsOwnVertices) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 2, 0}};
  m.uvs[0] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {2, 2}};
  m.indices = {0, 1, 2, 1, 3, 2, 3, 4, 2};
  m.materials = {2, 0, 2};
  m.material_names = {"a"};
  const Scene scene = scene_from_mesh(m);
  ASSERT_EQ(scene.primitives.size(), 2u);
  const Primitive& first = scene.primitives[0];
  EXPECT_EQ(first.material, 0);
  EXPECT_EQ(first.gltf_primitive, 0u);
  EXPECT_EQ(first.mesh.positions, (std::vector<float3>{{1, 0, 0}, {0, 1, 0}, {1, 1, 0}}));
  EXPECT_EQ(first.mesh.indices, (std::vector<uint32_t>{0, 2, 1}));
  EXPECT_EQ(first.mesh.uvs[0].size(), 3u);
  const Primitive& second = scene.primitives[1];
  EXPECT_EQ(second.material, 2);
  EXPECT_EQ(second.gltf_primitive, 1u);
  EXPECT_EQ(second.mesh.positions, (std::vector<float3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 2, 0}}));
  EXPECT_EQ(second.mesh.indices, (std::vector<uint32_t>{0, 1, 2, 3, 4, 2}));
  EXPECT_TRUE(second.mesh.materials.empty());
  // Names cover every material index used.
  EXPECT_EQ(scene.material_names, (std::vector<std::string>{"a", "", ""}));
}

// glTF's Hermite spline from 0 (flat) at 0 s to 1 (flat) at 1 s is 3 s^2 - 2 s^3: 0.15625 at 0.25 s
// and 0.5 at 0.5 s, with slope 6 s - 6 s^2 = 1.5 there; outside the keys it holds, slope 0. A linear
// channel's slope is its segment's, before or after a key.
TEST(AnimationSampling, ComponentsAndSlopesByHand) {
  const AnimationChannel cubic{.path = AnimationPath::weights, .interpolation = Interpolation::cubic_spline,
                               .times = {0, 1}, .values = {0, 0, 0, 0, 1, 0}, .components = 1};
  float value = 0, slope = 0;
  sample_components(cubic, 0.25f, &value, &slope);
  EXPECT_NEAR(value, 0.15625, 1e-6);
  sample_components(cubic, 0.5f, &value, &slope);
  EXPECT_NEAR(value, 0.5, 1e-6);
  EXPECT_NEAR(slope, 1.5, 1e-6);
  sample_components(cubic, 2.0f, &value, &slope);
  EXPECT_EQ(value, 1.0f);
  EXPECT_EQ(slope, 0.0f);
  const AnimationChannel linear{.path = AnimationPath::weights, .interpolation = Interpolation::linear,
                                .times = {0, 1, 3}, .values = {0, 2, 3}, .components = 1};
  sample_components(linear, 1.0f, &value, &slope, false);
  EXPECT_EQ(value, 2.0f);
  EXPECT_EQ(slope, 2.0f);  // the segment before
  sample_components(linear, 1.0f, &value, &slope, true);
  EXPECT_EQ(slope, 0.5f);  // the segment after
  sample_components(linear, 0.0f, &value, &slope, false);
  EXPECT_EQ(slope, 0.0f);  // held before the first key
}

// Merged channels reproduce each node's curve: a cubic spline (split at the other's keys), a linear
// channel (made a cubic spline) and a node at rest (its weights, held), sampled everywhere, against
// the channels themselves.
TEST(AnimationSampling, ConcatenatedWeightsFollowEveryCurve) {
  const AnimationChannel a{.path = AnimationPath::weights, .interpolation = Interpolation::cubic_spline, .times = {0, 2},
                           .values = {0, 0, 1, 5, 0.5f, 2, -1, 1, 0, 0, 3, 0}, .components = 2};
  const AnimationChannel b{.path = AnimationPath::weights, .interpolation = Interpolation::linear, .times = {1, 1.5f, 3},
                           .values = {2, 4, 1}, .components = 1};
  const std::optional<AnimationChannel> merged = concatenate_weights({{&a, {0, 0}}, {nullptr, {0.25f}}, {&b, {0}}});
  ASSERT_TRUE(merged);
  EXPECT_EQ(merged->interpolation, Interpolation::cubic_spline);
  EXPECT_EQ(merged->components, 4u);
  EXPECT_EQ(merged->times, (std::vector<float>{0, 1, 1.5f, 2, 3}));
  for (float t = -0.5f; t <= 3.5f; t += 0.0625f) {
    float all[4], one[2];
    sample_components(*merged, t, all);
    sample_components(a, t, one);
    EXPECT_NEAR(all[0], one[0], 1e-5) << t;
    EXPECT_NEAR(all[1], one[1], 1e-5) << t;
    EXPECT_EQ(all[2], 0.25f) << t;
    sample_components(b, t, one);
    EXPECT_NEAR(all[3], one[0], 1e-5) << t;
  }
  // Step curves merge as steps; a step with a smooth curve, no channel, or a weight count other
  // than the node's do not merge.
  AnimationChannel step = b;
  step.interpolation = Interpolation::step;
  const std::optional<AnimationChannel> steps = concatenate_weights({{&step, {0}}, {&step, {0}}});
  ASSERT_TRUE(steps);
  EXPECT_EQ(steps->interpolation, Interpolation::step);
  EXPECT_EQ(steps->values, (std::vector<float>{2, 2, 4, 4, 1, 1}));
  EXPECT_FALSE(concatenate_weights({{&step, {0}}, {&b, {0}}}));
  EXPECT_FALSE(concatenate_weights({{nullptr, {0}}, {nullptr, {1}}}));
  EXPECT_FALSE(concatenate_weights({{&b, {0, 0}}}));
}

}  // namespace
}  // namespace lod
