// Linear blend skinning on the CPU: each vertex is moved by the weighted sum of its joints' matrices.
// The streams (positions, normals, joints, weights) are separate arrays, read and written in order;
// vertices are independent, so blocks of them run in parallel with identical results on any thread
// count.
#include <algorithm>
#include <cmath>
#include <string>

#include "core/parallel.h"
#include "lodkit/error.h"
#include "lodkit/skin.h"
#include "skin/lbs_kernel.h"

namespace lod {

using skinning::Affine;
using skinning::blend_affine;

void skinning::check_influences(const Mesh& mesh, size_t joint_count, const char* what) {
  const size_t n = mesh.vertex_count();
  if (mesh.joints.size() != n || mesh.weights.size() != n)
    throw_usage(std::string(what) + ": the mesh has " + std::to_string(mesh.joints.size()) + " joints and " +
                std::to_string(mesh.weights.size()) + " weights for " + std::to_string(n) + " vertices");
  for (size_t v = 0; v < n; ++v) {
    const float w[4] = {mesh.weights[v].x, mesh.weights[v].y, mesh.weights[v].z, mesh.weights[v].w};
    for (int i = 0; i < 4; ++i)
      if (w[i] != 0 && mesh.joints[v][size_t(i)] >= joint_count)
        throw_usage(std::string(what) + ": vertex " + std::to_string(v) + " uses joint " +
                    std::to_string(mesh.joints[v][size_t(i)]) + " of " + std::to_string(joint_count) + " joint matrices");
  }
}

size_t skinning::joints_used(const Mesh& mesh) {
  size_t used = 0;
  for (size_t v = 0; v < mesh.weights.size() && v < mesh.joints.size(); ++v) {
    const float w[4] = {mesh.weights[v].x, mesh.weights[v].y, mesh.weights[v].z, mesh.weights[v].w};
    for (int i = 0; i < 4; ++i)
      if (w[i] != 0) used = std::max(used, size_t(mesh.joints[v][size_t(i)]) + 1);
  }
  return used;
}

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
  if (!mesh.normals.empty() && mesh.normals.size() != n)
    throw_usage("skin_vertices: the mesh has " + std::to_string(mesh.normals.size()) + " normals for " + std::to_string(n) +
                " vertices");
  // Checked up front so the parallel loop below cannot read outside `joints` (or throw halfway).
  skinning::check_influences(mesh, joints.size(), "skin_vertices");
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
      out_positions[v] = skinning::apply_point(a, positions[v]);
      if (normals) out_normals[v] = skinning::apply_normal(a, normals[v]);
    }
  });
}

}  // namespace lod
