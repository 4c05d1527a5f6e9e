// Linear blend skinning on the CPU: each vertex is moved by the weighted sum of its joints' matrices.
// The streams (positions, normals, joints, weights) are separate arrays, read and written in order;
// vertices are independent, so blocks of them run in parallel with identical results on any thread
// count.
#include <cmath>
#include <string>

#include "core/parallel.h"
#include "lodkit/error.h"
#include "lodkit/skin.h"

namespace lod {

namespace {

// The upper 3x4 of sum_i w_i J[j_i]: glTF joint matrices are affine, so the last row stays 0 0 0 1.
struct Affine {
  float m[12];  // column-major 3x4: m[3 * column + row]
};

inline Affine blend_affine(const mat4* joints, const ushort4& joint, const float4& weight) {
  Affine r{};
  const float w[4] = {weight.x, weight.y, weight.z, weight.w};
  for (int i = 0; i < 4; ++i) {
    if (w[i] == 0) continue;  // unused slots may hold any joint index
    const mat4& J = joints[joint[size_t(i)]];
    for (int col = 0; col < 4; ++col)
      for (int row = 0; row < 3; ++row) r.m[3 * col + row] += w[i] * J[size_t(4 * col + row)];
  }
  return r;
}

}  // namespace

mat4 blend_matrix(std::span<const mat4> joints, const ushort4& joint, const float4& weight) {
  const float w[4] = {weight.x, weight.y, weight.z, weight.w};
  for (int i = 0; i < 4; ++i)
    if (w[i] != 0 && joint[size_t(i)] >= joints.size())
      throw_usage("blend_matrix: joint index " + std::to_string(joint[size_t(i)]) + " out of range for " +
                  std::to_string(joints.size()) + " joint matrices");
  const Affine a = blend_affine(joints.data(), joint, weight);
  mat4 m{};
  for (int col = 0; col < 4; ++col)
    for (int row = 0; row < 3; ++row) m[size_t(4 * col + row)] = a.m[3 * col + row];
  m[15] = 1;
  return m;
}

void skin_vertices(const Mesh& mesh, std::span<const mat4> joints, SkinnedVertices& out, unsigned threads) {
  const size_t n = mesh.vertex_count();
  if (mesh.joints.size() != n || mesh.weights.size() != n)
    throw_usage("skin_vertices: the mesh has " + std::to_string(mesh.joints.size()) + " joints and " +
                std::to_string(mesh.weights.size()) + " weights for " + std::to_string(n) + " vertices");
  if (!mesh.normals.empty() && mesh.normals.size() != n)
    throw_usage("skin_vertices: the mesh has " + std::to_string(mesh.normals.size()) + " normals for " + std::to_string(n) +
                " vertices");
  // Checked up front so the parallel loop below cannot read outside `joints` (or throw halfway).
  for (size_t v = 0; v < n; ++v) {
    const float w[4] = {mesh.weights[v].x, mesh.weights[v].y, mesh.weights[v].z, mesh.weights[v].w};
    for (int i = 0; i < 4; ++i)
      if (w[i] != 0 && mesh.joints[v][size_t(i)] >= joints.size())
        throw_usage("skin_vertices: vertex " + std::to_string(v) + " uses joint " + std::to_string(mesh.joints[v][size_t(i)]) +
                    " of " + std::to_string(joints.size()) + " joint matrices");
  }
  out.positions.resize(n);
  if (mesh.normals.empty())
    out.normals.clear();
  else
    out.normals.resize(n);

  const mat4* J = joints.data();
  const float3* positions = mesh.positions.data();
  const float3* normals = mesh.normals.empty() ? nullptr : mesh.normals.data();
  const ushort4* joint = mesh.joints.data();
  const float4* weight = mesh.weights.data();
  float3* out_positions = out.positions.data();
  float3* out_normals = normals ? out.normals.data() : nullptr;
  core::parallel_blocks(n, 8192, threads, [&](size_t, size_t begin, size_t end) {
    for (size_t v = begin; v < end; ++v) {
      const Affine a = blend_affine(J, joint[v], weight[v]);
      const float* m = a.m;
      const float3 p = positions[v];
      out_positions[v] = {m[0] * p.x + m[3] * p.y + m[6] * p.z + m[9], m[1] * p.x + m[4] * p.y + m[7] * p.z + m[10],
                          m[2] * p.x + m[5] * p.y + m[8] * p.z + m[11]};
      if (!normals) continue;
      // The blended linear part; exact for rotations and uniform scale, the usual LBS approximation
      // otherwise. Renormalised because blending rotations shortens vectors.
      const float3 q = normals[v];
      float3 r = {m[0] * q.x + m[3] * q.y + m[6] * q.z, m[1] * q.x + m[4] * q.y + m[7] * q.z, m[2] * q.x + m[5] * q.y + m[8] * q.z};
      const float len = std::sqrt(r.x * r.x + r.y * r.y + r.z * r.z);
      if (len > 0) r = {r.x / len, r.y / len, r.z / len};
      out_normals[v] = r;
    }
  });
}

}  // namespace lod
