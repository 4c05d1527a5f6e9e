// Skeletons and poses: 4x4 affine matrices, the nodes' local transforms, animation sampling (glTF's
// step, linear and cubic-spline samplers) and world / joint matrices.
//
// Scenes may come from any file, so everything that indexes is checked first: node, parent and child
// indices, cycles in the hierarchy, key and value counts of every sampled channel. Those are lod::Error,
// never an out-of-range read.
#include <algorithm>
#include <cmath>
#include <string>

#include "core/quaternion.h"
#include "lodkit/error.h"
#include "lodkit/skin.h"

namespace lod {

namespace {

using core::normalized;
using core::slerp;

std::string str(size_t value) { return std::to_string(value); }

// ---- channel sampling ---------------------------------------------------------------------------

// Checks one channel against the scene and the pose before any of its arrays is indexed.
void check_channel(const Scene& scene, size_t animation, size_t c, const AnimationChannel& ch, size_t node_count) {
  const std::string where = scene.name.empty() ? std::string("scene") : scene.name;
  const std::string what = "animations[" + str(animation) + "].channels[" + str(c) + "]";
  if (ch.node < 0 || size_t(ch.node) >= node_count)
    throw_bad_input(where, what + " targets node " + std::to_string(ch.node) + " of " + str(node_count));
  const size_t expected_components = ch.path == AnimationPath::rotation ? 4 : 3;
  if (ch.components != expected_components)
    throw_bad_input(where, what + " has " + str(ch.components) + " components per key, expected " + str(expected_components));
  if (ch.times.empty()) throw_bad_input(where, what + " has no keys");
  const size_t per_key = ch.interpolation == Interpolation::cubic_spline ? 3 : 1;
  // Divide rather than multiply: a huge declared count cannot overflow the comparison.
  if (ch.values.size() % (per_key * ch.components) != 0 || ch.values.size() / (per_key * ch.components) != ch.times.size())
    throw_bad_input(where, what + " has " + str(ch.values.size()) + " values for " + str(ch.times.size()) + " keys of " +
                               str(per_key * ch.components) + " numbers");
  for (size_t k = 0; k < ch.times.size(); ++k) {
    if (!std::isfinite(ch.times[k])) throw_bad_input(where, what + " key " + str(k) + " has a non-finite time");
    // Equal neighbours are harmless (that zero-length interval is never selected), decreasing ones are not.
    if (k > 0 && ch.times[k] < ch.times[k - 1])
      throw_bad_input(where, what + " key times decrease at key " + str(k));
  }
}

// Interpolates one channel at `time` into out[0 .. components): linear rotations by slerp, the rest
// component by component.
void sample_channel(const AnimationChannel& ch, float time, float* out) {
  if (ch.path != AnimationPath::rotation || ch.interpolation != Interpolation::linear || !(time > ch.times.front()) ||
      time >= ch.times.back())
    return sample_components(ch, time, out);
  // The last key at or before `time`; k + 1 < keys because time < times.back().
  const size_t k = size_t(std::upper_bound(ch.times.begin(), ch.times.end(), time) - ch.times.begin()) - 1;
  const float t0 = ch.times[k], t1 = ch.times[k + 1];
  const float interval = t1 - t0;
  const float t = interval > 0 ? std::clamp((time - t0) / interval, 0.0f, 1.0f) : 0.0f;
  const float* a = ch.values.data() + 4 * k;
  const float* b = a + 4;
  // Keys a little off unit length (quantised files) would bend the arc: normalise them first.
  const float4 q = slerp(normalized({a[0], a[1], a[2], a[3]}), normalized({b[0], b[1], b[2], b[3]}), t);
  out[0] = q.x, out[1] = q.y, out[2] = q.z, out[3] = q.w;
}

void check_pose(const Scene& scene, const Pose& pose) {
  const size_t n = scene.nodes.size();
  if (pose.translation.size() != n || pose.rotation.size() != n || pose.scale.size() != n)
    throw_usage("pose has " + str(pose.translation.size()) + "/" + str(pose.rotation.size()) + "/" + str(pose.scale.size()) +
                " node transforms for a scene of " + str(n) + " nodes");
}

}  // namespace

// ---- matrices -----------------------------------------------------------------------------------

mat4 identity_matrix() { return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}; }

mat4 multiply(const mat4& a, const mat4& b) {
  mat4 r{};
  for (int col = 0; col < 4; ++col)
    for (int row = 0; row < 4; ++row) {
      float s = 0;
      for (int k = 0; k < 4; ++k) s += a[4 * k + row] * b[4 * col + k];
      r[4 * col + row] = s;
    }
  return r;
}

mat4 affine_inverse(const mat4& m) {
  // Inverse of the 3x3 linear part by cofactors (in double), then the translation -L^-1 t.
  auto at = [&](int row, int col) { return double(m[4 * col + row]); };
  const double c00 = at(1, 1) * at(2, 2) - at(1, 2) * at(2, 1);
  const double c01 = at(1, 2) * at(2, 0) - at(1, 0) * at(2, 2);
  const double c02 = at(1, 0) * at(2, 1) - at(1, 1) * at(2, 0);
  const double det = at(0, 0) * c00 + at(0, 1) * c01 + at(0, 2) * c02;
  if (!std::isfinite(det) || std::abs(det) < 1e-30) return identity_matrix();
  const double inv = 1.0 / det;
  double l[3][3];  // l[row][col] of the inverse
  l[0][0] = c00 * inv;
  l[1][0] = c01 * inv;
  l[2][0] = c02 * inv;
  l[0][1] = (at(0, 2) * at(2, 1) - at(0, 1) * at(2, 2)) * inv;
  l[1][1] = (at(0, 0) * at(2, 2) - at(0, 2) * at(2, 0)) * inv;
  l[2][1] = (at(0, 1) * at(2, 0) - at(0, 0) * at(2, 1)) * inv;
  l[0][2] = (at(0, 1) * at(1, 2) - at(0, 2) * at(1, 1)) * inv;
  l[1][2] = (at(0, 2) * at(1, 0) - at(0, 0) * at(1, 2)) * inv;
  l[2][2] = (at(0, 0) * at(1, 1) - at(0, 1) * at(1, 0)) * inv;
  mat4 r = identity_matrix();
  for (int row = 0; row < 3; ++row) {
    double t = 0;
    for (int col = 0; col < 3; ++col) {
      r[4 * col + row] = float(l[row][col]);
      t -= l[row][col] * at(col, 3);
    }
    r[12 + row] = float(t);
  }
  return r;
}

mat4 compose_trs(const float3& translation, const float4& rotation, const float3& scale) {
  const float x = rotation.x, y = rotation.y, z = rotation.z, w = rotation.w;
  // The rotation matrix of a unit quaternion, columns scaled by the scale (T * R * S).
  mat4 m{};
  m[0] = (1 - 2 * (y * y + z * z)) * scale.x;
  m[1] = 2 * (x * y + z * w) * scale.x;
  m[2] = 2 * (x * z - y * w) * scale.x;
  m[4] = 2 * (x * y - z * w) * scale.y;
  m[5] = (1 - 2 * (x * x + z * z)) * scale.y;
  m[6] = 2 * (y * z + x * w) * scale.y;
  m[8] = 2 * (x * z + y * w) * scale.z;
  m[9] = 2 * (y * z - x * w) * scale.z;
  m[10] = (1 - 2 * (x * x + y * y)) * scale.z;
  m[12] = translation.x;
  m[13] = translation.y;
  m[14] = translation.z;
  m[15] = 1;
  return m;
}

float3 transform_point(const mat4& m, const float3& p) {
  return {m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12], m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13],
          m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14]};
}

float3 transform_vector(const mat4& m, const float3& v) {
  return {m[0] * v.x + m[4] * v.y + m[8] * v.z, m[1] * v.x + m[5] * v.y + m[9] * v.z, m[2] * v.x + m[6] * v.y + m[10] * v.z};
}

// ---- poses --------------------------------------------------------------------------------------

Pose rest_pose(const Scene& scene) {
  Pose pose;
  const size_t n = scene.nodes.size();
  pose.translation.resize(n);
  pose.rotation.assign(n, float4{0, 0, 0, 1});
  pose.scale.assign(n, float3{1, 1, 1});
  for (size_t i = 0; i < n; ++i) {
    const Node& node = scene.nodes[i];
    if (node.has_matrix) continue;  // world_matrices uses the matrix itself
    pose.translation[i] = node.translation;
    pose.rotation[i] = node.rotation;
    pose.scale[i] = node.scale;
  }
  return pose;
}

float animation_duration(const Scene& scene, size_t animation) {
  if (animation >= scene.animations.size())
    throw_usage("animation " + str(animation) + " does not exist (the scene has " + str(scene.animations.size()) + ")");
  float duration = 0;
  for (const AnimationChannel& ch : scene.animations[animation].channels)
    for (const float t : ch.times)
      if (std::isfinite(t)) duration = std::max(duration, t);
  return duration;
}

void sample_animation(const Scene& scene, size_t animation, float time, Pose& pose) {
  if (animation >= scene.animations.size())
    throw_usage("animation " + str(animation) + " does not exist (the scene has " + str(scene.animations.size()) + ")");
  check_pose(scene, pose);
  const Animation& clip = scene.animations[animation];
  // Check every channel first, so a bad clip leaves the pose untouched.
  for (size_t c = 0; c < clip.channels.size(); ++c)
    if (clip.channels[c].path != AnimationPath::weights)
      check_channel(scene, animation, c, clip.channels[c], scene.nodes.size());
  for (const AnimationChannel& ch : clip.channels) {
    float value[4];
    switch (ch.path) {
      case AnimationPath::weights: break;  // morph weights are not part of a skeleton pose
      case AnimationPath::translation:
        sample_channel(ch, time, value);
        pose.translation[size_t(ch.node)] = {value[0], value[1], value[2]};
        break;
      case AnimationPath::scale:
        sample_channel(ch, time, value);
        pose.scale[size_t(ch.node)] = {value[0], value[1], value[2]};
        break;
      case AnimationPath::rotation:
        sample_channel(ch, time, value);
        pose.rotation[size_t(ch.node)] = normalized({value[0], value[1], value[2], value[3]});
        break;
    }
  }
}

std::vector<mat4> world_matrices(const Scene& scene, const Pose& pose) {
  check_pose(scene, pose);
  const size_t n = scene.nodes.size();
  const std::string where = scene.name.empty() ? std::string("scene") : scene.name;
  // Each node's parent, from `parent` or from a parent's `children` (scenes built in memory may fill
  // either); the two must agree.
  std::vector<int32_t> parent(n, -1);
  for (size_t i = 0; i < n; ++i) {
    const int32_t p = scene.nodes[i].parent;
    if (p < -1 || p >= int64_t(n)) throw_bad_input(where, "nodes[" + str(i) + "] has parent " + std::to_string(p) + " of " + str(n));
    parent[i] = p;
  }
  for (size_t i = 0; i < n; ++i)
    for (const int32_t child : scene.nodes[i].children) {
      if (child < 0 || size_t(child) >= n)
        throw_bad_input(where, "nodes[" + str(i) + "] has child " + std::to_string(child) + " of " + str(n));
      int32_t& p = parent[size_t(child)];
      if (p == -1 && scene.nodes[size_t(child)].parent == -1)
        p = int32_t(i);
      else if (p != int32_t(i))
        throw_bad_input(where, "nodes[" + std::to_string(child) + "] has two parents (nodes[" + std::to_string(p) + "] and nodes[" +
                                   str(i) + "])");
    }
  // Parents before children: walk each node's chain up to a computed ancestor, then come back down.
  std::vector<mat4> world(n);
  std::vector<uint8_t> state(n, 0);  // 0 not yet, 1 on the current walk, 2 computed
  std::vector<size_t> chain;
  for (size_t i = 0; i < n; ++i) {
    chain.clear();
    int32_t node = int32_t(i);
    while (node != -1 && state[size_t(node)] == 0) {
      state[size_t(node)] = 1;
      chain.push_back(size_t(node));
      node = parent[size_t(node)];
    }
    if (node != -1 && state[size_t(node)] == 1) throw_bad_input(where, "nodes[" + std::to_string(node) + "] is part of a node cycle");
    for (size_t k = chain.size(); k-- > 0;) {
      const size_t c = chain[k];
      const Node& nd = scene.nodes[c];
      const mat4 local = nd.has_matrix ? nd.matrix : compose_trs(pose.translation[c], pose.rotation[c], pose.scale[c]);
      world[c] = parent[c] == -1 ? local : multiply(world[size_t(parent[c])], local);
      state[c] = 2;
    }
  }
  return world;
}

std::vector<mat4> joint_matrices(const Scene& scene, size_t skin, const std::vector<mat4>& world) {
  if (skin >= scene.skins.size())
    throw_usage("skin " + str(skin) + " does not exist (the scene has " + str(scene.skins.size()) + ")");
  const Skin& s = scene.skins[skin];
  const std::string where = scene.name.empty() ? std::string("scene") : scene.name;
  // No inverse bind matrices means identities (glTF's default).
  if (!s.inverse_bind_matrices.empty() && s.inverse_bind_matrices.size() != s.joints.size())
    throw_bad_input(where, "skins[" + str(skin) + "] has " + str(s.inverse_bind_matrices.size()) + " inverse bind matrices for " +
                               str(s.joints.size()) + " joints");
  std::vector<mat4> out(s.joints.size());
  for (size_t j = 0; j < s.joints.size(); ++j) {
    const int32_t node = s.joints[j];
    if (node < 0 || size_t(node) >= world.size())
      throw_bad_input(where, "skins[" + str(skin) + "] joint " + str(j) + " is node " + std::to_string(node) + " of " + str(world.size()));
    out[j] = s.inverse_bind_matrices.empty() ? world[size_t(node)] : multiply(world[size_t(node)], s.inverse_bind_matrices[j]);
  }
  return out;
}

std::vector<SkinnedPrimitive> skinned_primitives(const Scene& scene) {
  std::vector<SkinnedPrimitive> out;
  const std::string where = scene.name.empty() ? std::string("scene") : scene.name;
  for (size_t n = 0; n < scene.nodes.size(); ++n) {
    const Node& node = scene.nodes[n];
    if (node.skin < 0 || node.mesh < 0) continue;
    if (size_t(node.skin) >= scene.skins.size())
      throw_bad_input(where, "nodes[" + str(n) + "] uses skin " + std::to_string(node.skin) + " of " + str(scene.skins.size()));
    for (size_t p = 0; p < scene.primitives.size(); ++p) {
      const Primitive& prim = scene.primitives[p];
      if (prim.gltf_mesh != uint32_t(node.mesh) || prim.mesh.joints.empty() || prim.mesh.weights.empty()) continue;
      out.push_back({uint32_t(p), uint32_t(n), uint32_t(node.skin)});
    }
  }
  return out;
}

}  // namespace lod
