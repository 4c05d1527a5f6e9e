// Internal: the per-vertex linear blend skinning kernel, shared by lod::skin_vertices and the
// skeletal geomorph (which skins and morphs in one pass).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "lodkit/skin.h"

namespace lod::skinning {

// The upper 3x4 of sum_i w_i J[j_i]: glTF joint matrices are affine, so the last row stays 0 0 0 1.
struct Affine {
  float m[12];  // column-major 3x4: m[3 * column + row]
};

// r += sum_i w_i J[j_i] over one set of four influences.
inline void add_influences(Affine& r, const mat4* joints, const ushort4& joint, const float4& weight) {
  const float w[4] = {weight.x, weight.y, weight.z, weight.w};
  for (int i = 0; i < 4; ++i) {
    if (w[i] == 0) continue;  // unused slots may hold any joint index
    const mat4& J = joints[joint[size_t(i)]];
    for (int col = 0; col < 4; ++col)
      for (int row = 0; row < 3; ++row) r.m[3 * col + row] += w[i] * J[size_t(4 * col + row)];
  }
}

inline Affine blend_affine(const mat4* joints, const ushort4& joint, const float4& weight) {
  Affine r{};
  add_influences(r, joints, joint, weight);
  return r;
}

// A mesh's influence streams as raw pointers for the hot loops; the second set is null when the mesh
// has four influences per vertex. The sets are summed in order, so a four-influence mesh blends
// exactly as with blend_affine.
struct InfluenceStreams {
  const ushort4* joint = nullptr;
  const float4* weight = nullptr;
  const ushort4* joint1 = nullptr;
  const float4* weight1 = nullptr;

  explicit InfluenceStreams(const Mesh& mesh)
      : joint(mesh.joints.data()),
        weight(mesh.weights.data()),
        joint1(mesh.joints1.empty() ? nullptr : mesh.joints1.data()),
        weight1(mesh.joints1.empty() ? nullptr : mesh.weights1.data()) {}

  Affine blend(const mat4* joints, size_t v) const {
    Affine r{};
    add_influences(r, joints, joint[v], weight[v]);
    if (joint1) add_influences(r, joints, joint1[v], weight1[v]);
    return r;
  }
};

inline float3 apply_point(const Affine& a, const float3& p) {
  const float* m = a.m;
  return {m[0] * p.x + m[3] * p.y + m[6] * p.z + m[9], m[1] * p.x + m[4] * p.y + m[7] * p.z + m[10],
          m[2] * p.x + m[5] * p.y + m[8] * p.z + m[11]};
}

inline float3 apply_linear(const Affine& a, const float3& q) {
  const float* m = a.m;
  return {m[0] * q.x + m[3] * q.y + m[6] * q.z, m[1] * q.x + m[4] * q.y + m[7] * q.z, m[2] * q.x + m[5] * q.y + m[8] * q.z};
}

// Normals by the blended linear part: exact for rotations and uniform scale, the usual LBS
// approximation otherwise. Renormalised because blending rotations shortens vectors.
inline float3 unit(float3 r) {
  const float len = std::sqrt(r.x * r.x + r.y * r.y + r.z * r.z);
  if (len > 0) r = {r.x / len, r.y / len, r.z / len};
  return r;
}

inline float3 apply_normal(const Affine& a, const float3& q) { return unit(apply_linear(a, q)); }

// The number of joint matrices the mesh needs: one past its largest joint with a non-zero weight.
size_t joints_used(const Mesh& mesh);

// Throws lod::Error (usage) unless every vertex has joints and weights (and the second set, if any,
// has one entry per vertex too), and every joint with a non-zero weight is below `joint_count`.
// `what` starts the message.
void check_influences(const Mesh& mesh, size_t joint_count, const char* what);

}  // namespace lod::skinning
