// src/io/gltf.cpp, the skins and animations of scenes built without a source document: written,
// read back identically (.glb and .gltf), shaped as glTF requires (shared key-time inputs with
// bounds), accepted by the Khronos validator, and refused with a usage error when invalid.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "lodkit/error.h"
#include "lodkit/skin.h"
#include "test_support.h"

namespace lod {
namespace {

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Two joints (root 0 -> child 1) and a skinned mesh node 2; one triangle bound to both joints;
// one clip with a linear rotation, a step translation and a cubic-spline scale, the first two
// sharing their key times.
Scene skinned_scene() {
  Scene scene;
  scene.nodes.resize(3);
  scene.nodes[0].name = "root";
  scene.nodes[0].translation = {0, 1, 0};
  scene.nodes[0].children = {1};
  scene.nodes[1].name = "tip";
  scene.nodes[1].parent = 0;
  scene.nodes[1].translation = {0, 0.5f, 0};
  scene.nodes[1].rotation = {0, 0, 0.38268343f, 0.92387953f};
  scene.nodes[2].name = "body";
  scene.nodes[2].mesh = 0;
  scene.nodes[2].skin = 0;
  scene.roots = {0, 2};

  Skin skin;
  skin.name = "rig";
  skin.joints = {0, 1};
  skin.skeleton = 0;
  const std::vector<mat4> world = world_matrices(scene, rest_pose(scene));
  skin.inverse_bind_matrices = {affine_inverse(world[0]), affine_inverse(world[1])};
  scene.skins.push_back(skin);

  Primitive primitive;
  Mesh& mesh = primitive.mesh;
  mesh.positions = {{0, 1, 0}, {1, 1.5f, 0}, {0, 2, 0}};
  mesh.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  mesh.joints = {{0, 0, 0, 0}, {0, 1, 0, 0}, {1, 0, 0, 0}};
  mesh.weights = {{1, 0, 0, 0}, {0.5f, 0.5f, 0, 0}, {1, 0, 0, 0}};
  mesh.indices = {0, 1, 2};
  scene.primitives.push_back(primitive);

  Animation clip;
  clip.name = "nod";
  AnimationChannel rotation;
  rotation.node = 1;
  rotation.path = AnimationPath::rotation;
  rotation.interpolation = Interpolation::linear;
  rotation.components = 4;
  rotation.times = {0, 0.5f, 1};
  rotation.values = {0, 0, 0, 1, 0, 0, 0.38268343f, 0.92387953f, 0, 0, 0, 1};
  AnimationChannel translation;
  translation.node = 0;
  translation.path = AnimationPath::translation;
  translation.interpolation = Interpolation::step;
  translation.components = 3;
  translation.times = {0, 0.5f, 1};
  translation.values = {0, 1, 0, 0, 1.25f, 0, 0, 1, 0};
  AnimationChannel scale;
  scale.node = 1;
  scale.path = AnimationPath::scale;
  scale.interpolation = Interpolation::cubic_spline;
  scale.components = 3;
  scale.times = {0.25f, 2};
  scale.values = {0, 0, 0, 1, 1, 1, 0.5f, 0.5f, 0.5f, -0.5f, -0.5f, -0.5f, 2, 2, 2, 0, 0, 0};
  clip.channels = {rotation, translation, scale};
  scene.animations.push_back(clip);
  return scene;
}

void expect_same_skins_and_animations(const Scene& back, const Scene& scene) {
  ASSERT_EQ(back.nodes.size(), scene.nodes.size());
  for (size_t n = 0; n < scene.nodes.size(); ++n) {
    EXPECT_EQ(back.nodes[n].name, scene.nodes[n].name);
    EXPECT_EQ(back.nodes[n].parent, scene.nodes[n].parent);
    EXPECT_EQ(back.nodes[n].children, scene.nodes[n].children);
    EXPECT_EQ(back.nodes[n].skin, scene.nodes[n].skin);
    EXPECT_EQ(back.nodes[n].translation, scene.nodes[n].translation);
    EXPECT_EQ(back.nodes[n].rotation, scene.nodes[n].rotation);
    EXPECT_EQ(back.nodes[n].scale, scene.nodes[n].scale);
  }
  EXPECT_EQ(back.roots, scene.roots);
  ASSERT_EQ(back.skins.size(), scene.skins.size());
  for (size_t s = 0; s < scene.skins.size(); ++s) {
    EXPECT_EQ(back.skins[s].name, scene.skins[s].name);
    EXPECT_EQ(back.skins[s].joints, scene.skins[s].joints);
    EXPECT_EQ(back.skins[s].skeleton, scene.skins[s].skeleton);
    EXPECT_EQ(back.skins[s].inverse_bind_matrices, scene.skins[s].inverse_bind_matrices);
  }
  ASSERT_EQ(back.animations.size(), scene.animations.size());
  for (size_t a = 0; a < scene.animations.size(); ++a) {
    EXPECT_EQ(back.animations[a].name, scene.animations[a].name);
    ASSERT_EQ(back.animations[a].channels.size(), scene.animations[a].channels.size());
    for (size_t c = 0; c < scene.animations[a].channels.size(); ++c) {
      const AnimationChannel& x = back.animations[a].channels[c];
      const AnimationChannel& y = scene.animations[a].channels[c];
      EXPECT_EQ(x.node, y.node) << c;
      EXPECT_EQ(x.path, y.path) << c;
      EXPECT_EQ(x.interpolation, y.interpolation) << c;
      EXPECT_EQ(x.components, y.components) << c;
      EXPECT_EQ(x.times, y.times) << c;
      EXPECT_EQ(x.values, y.values) << c;
    }
  }
  ASSERT_EQ(back.primitives.size(), scene.primitives.size());
  EXPECT_EQ(test::mesh_difference(back.primitives[0].mesh, scene.primitives[0].mesh), "");
}

TEST(GltfSkinWriter, RoundTripGlbAndGltf) {
  const Scene scene = skinned_scene();
  test::TempDir dir;
  for (const char* name : {"skinned.glb", "skinned.gltf"}) {
    write_scene(scene, dir / name);
    const Scene back = read_scene(dir / name);
    SCOPED_TRACE(name);
    expect_same_skins_and_animations(back, scene);
    // And it still animates the same: the clip at 0.75 s poses both copies alike.
    Pose a = rest_pose(scene), b = rest_pose(back);
    sample_animation(scene, 0, 0.75f, a);
    sample_animation(back, 0, 0.75f, b);
    EXPECT_EQ(world_matrices(scene, a), world_matrices(back, b));
  }
}

TEST(GltfSkinWriter, DocumentShape) {
  test::TempDir dir;
  write_scene(skinned_scene(), dir / "skinned.gltf");
  const nlohmann::json doc = nlohmann::json::parse(read_text(dir / "skinned.gltf"));
  const auto& animation = doc["animations"][0];
  ASSERT_EQ(animation["samplers"].size(), 3u);
  // The rotation and translation share their key times; the scale has its own.
  EXPECT_EQ(animation["samplers"][0]["input"], animation["samplers"][1]["input"]);
  EXPECT_NE(animation["samplers"][0]["input"], animation["samplers"][2]["input"]);
  EXPECT_FALSE(animation["samplers"][0].contains("interpolation"));  // (LINEAR, the default, is left out)
  EXPECT_EQ(animation["samplers"][1]["interpolation"], "STEP");
  EXPECT_EQ(animation["samplers"][2]["interpolation"], "CUBICSPLINE");
  const auto& scale_input = doc["accessors"][animation["samplers"][2]["input"].get<size_t>()];
  EXPECT_EQ(scale_input["min"], nlohmann::json::array({0.25}));
  EXPECT_EQ(scale_input["max"], nlohmann::json::array({2.0}));
  // 2 keys x (in-tangent, value, out-tangent).
  EXPECT_EQ(doc["accessors"][animation["samplers"][2]["output"].get<size_t>()]["count"], 6);
  EXPECT_EQ(animation["channels"][2]["target"]["path"], "scale");
  EXPECT_EQ(animation["channels"][2]["target"]["node"], 1);
  const auto& skin = doc["skins"][0];
  EXPECT_EQ(skin["joints"], nlohmann::json::array({0, 1}));
  EXPECT_EQ(skin["skeleton"], 0);
  const auto& ibm = doc["accessors"][skin["inverseBindMatrices"].get<size_t>()];
  EXPECT_EQ(ibm["type"], "MAT4");
  EXPECT_EQ(ibm["componentType"], 5126);  // FLOAT
  EXPECT_EQ(ibm["count"], 2);
  EXPECT_EQ(doc["nodes"][2]["skin"], 0);
}

// Joint indices take one byte each while every index fits (the values unchanged), two once one
// does not: a skin of 302 joints whose vertex 0 uses joint 299.
TEST(GltfSkinWriter, JointIndicesTakeBytesWhileTheyFit) {
  test::TempDir dir;
  Scene scene = skinned_scene();
  write_scene(scene, dir / "small.glb");
  const nlohmann::json small = test::glb_json(dir / "small.glb");
  EXPECT_EQ(small["accessors"][small["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"].get<size_t>()]["componentType"], 5121);
  EXPECT_EQ(test::mesh_difference(read_scene(dir / "small.glb").primitives[0].mesh, scene.primitives[0].mesh), "");

  const std::array<float, 16> some_matrix = scene.skins[0].inverse_bind_matrices[0];
  for (int32_t k = 0; k < 300; ++k) {
    Node joint;
    joint.name = "extra" + std::to_string(k);
    joint.parent = 0;  // under the skeleton's root, as glTF wants every joint
    scene.nodes[0].children.push_back(int32_t(scene.nodes.size()));
    scene.skins[0].joints.push_back(int32_t(scene.nodes.size()));
    scene.skins[0].inverse_bind_matrices.push_back(some_matrix);
    scene.nodes.push_back(joint);
  }
  scene.primitives[0].mesh.joints[0] = {299, 0, 0, 0};
  write_scene(scene, dir / "large.glb");
  const nlohmann::json large = test::glb_json(dir / "large.glb");
  EXPECT_EQ(large["accessors"][large["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"].get<size_t>()]["componentType"], 5123);
  EXPECT_EQ(test::mesh_difference(read_scene(dir / "large.glb").primitives[0].mesh, scene.primitives[0].mesh), "");
  test::expect_valid_gltf({dir / "small.glb", dir / "large.glb"});
}

TEST(GltfSkinWriter, PassesTheValidator) {
  if (!test::validator_available())
    GTEST_SKIP() << "gltf-validator not installed: run `npm ci --prefix tests/gltf-validator` (needs node on PATH)";
  test::TempDir dir;
  write_scene(skinned_scene(), dir / "skinned.glb");
  write_scene(skinned_scene(), dir / "skinned.gltf");
  const test::ValidatorRun run = test::run_validator({dir / "skinned.glb", dir / "skinned.gltf"});
  EXPECT_EQ(run.status, 0) << run.output;
}

TEST(GltfSkinWriter, InvalidSkinsAndChannelsAreUsageErrors) {
  test::TempDir dir;
  auto refused = [&](const Scene& scene) {
    try {
      write_scene(scene, dir / "bad.glb");
    } catch (const Error& e) {
      return e.category() == ErrorCategory::usage && std::string(e.what()).find("cannot write glTF") != std::string::npos;
    }
    return false;
  };
  Scene s = skinned_scene();
  s.skins[0].inverse_bind_matrices.pop_back();  // 1 matrix for 2 joints
  EXPECT_TRUE(refused(s));
  s = skinned_scene();
  s.skins[0].joints.push_back(9);
  s.skins[0].inverse_bind_matrices.push_back(identity_matrix());
  EXPECT_TRUE(refused(s));
  s = skinned_scene();
  s.skins[0].inverse_bind_matrices[1][3] = 1;  // not affine
  EXPECT_TRUE(refused(s));
  s = skinned_scene();
  s.nodes[2].skin = 3;
  EXPECT_TRUE(refused(s));
  s = skinned_scene();
  s.animations[0].channels[0].values.pop_back();
  EXPECT_TRUE(refused(s));
  s = skinned_scene();
  s.animations[0].channels[0].times = {0, 0.5f, 0.5f};  // not increasing
  EXPECT_TRUE(refused(s));
  s = skinned_scene();
  s.animations[0].channels[1].times[0] = -1;  // negative
  EXPECT_TRUE(refused(s));
  s = skinned_scene();
  s.animations[0].channels[2].node = 5;
  EXPECT_TRUE(refused(s));
  s = skinned_scene();
  s.animations[0].channels.push_back(s.animations[0].channels[0]);  // the same target twice
  EXPECT_TRUE(refused(s));
  s = skinned_scene();
  s.nodes[1].has_matrix = true;  // animated matrix node
  EXPECT_TRUE(refused(s));
  EXPECT_FALSE(refused(skinned_scene()));
}

}  // namespace
}  // namespace lod
