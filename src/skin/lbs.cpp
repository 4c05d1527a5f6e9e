// Linear blend skinning on the CPU: each vertex is moved by the weighted sum of its joints' matrices.
// The streams (positions, normals, joints, weights, and a second set of joints and weights for up to
// eight influences) are separate arrays, read and written in order;
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

namespace {

// f(joint, weight) for each of the vertex's four or eight influence slots, set 0 first.
template <class F>
void each_influence(const Mesh& mesh, size_t v, F f) {
  auto set = [&](const ushort4& joint, const float4& weight) {
    const float w[4] = {weight.x, weight.y, weight.z, weight.w};
    for (int i = 0; i < 4; ++i) f(joint[size_t(i)], w[i]);
  };
  set(mesh.joints[v], mesh.weights[v]);
  if (!mesh.joints1.empty()) set(mesh.joints1[v], mesh.weights1[v]);
}

}  // namespace

void skinning::check_influences(const Mesh& mesh, size_t joint_count, const char* what) {
  const size_t n = mesh.vertex_count();
  if (mesh.joints.size() != n || mesh.weights.size() != n)
    throw_usage(std::string(what) + ": the mesh has " + std::to_string(mesh.joints.size()) + " joints and " +
                std::to_string(mesh.weights.size()) + " weights for " + std::to_string(n) + " vertices");
  if (!mesh.joints1.empty() || !mesh.weights1.empty())
    if (mesh.joints1.size() != n || mesh.weights1.size() != n)
      throw_usage(std::string(what) + ": the mesh has " + std::to_string(mesh.joints1.size()) + " second-set joints and " +
                  std::to_string(mesh.weights1.size()) + " second-set weights for " + std::to_string(n) + " vertices");
  for (size_t v = 0; v < n; ++v)
    each_influence(mesh, v, [&](uint16_t joint, float weight) {
      if (weight != 0 && joint >= joint_count)
        throw_usage(std::string(what) + ": vertex " + std::to_string(v) + " uses joint " + std::to_string(joint) + " of " +
                    std::to_string(joint_count) + " joint matrices");
    });
}

size_t skinning::joints_used(const Mesh& mesh) {
  size_t used = 0;
  const bool complete = mesh.joints.size() == mesh.vertex_count() && mesh.weights.size() == mesh.vertex_count() &&
                        mesh.joints1.size() == mesh.weights1.size() &&
                        (mesh.joints1.empty() || mesh.joints1.size() == mesh.vertex_count());
  if (!complete) return 0;
  for (size_t v = 0; v < mesh.vertex_count(); ++v)
    each_influence(mesh, v, [&](uint16_t joint, float weight) {
      if (weight != 0) used = std::max(used, size_t(joint) + 1);
    });
  return used;
}

mat4 blend_matrix(std::span<const mat4> joints, const ushort4& joint, const float4& weight, const ushort4& joint1,
                  const float4& weight1) {
  auto check = [&](const ushort4& set, const float4& weight_set) {
    const float w[4] = {weight_set.x, weight_set.y, weight_set.z, weight_set.w};
    for (int i = 0; i < 4; ++i)
      if (w[i] != 0 && set[size_t(i)] >= joints.size())
        throw_usage("blend_matrix: joint index " + std::to_string(set[size_t(i)]) + " out of range for " +
                    std::to_string(joints.size()) + " joint matrices");
  };
  check(joint, weight);
  check(joint1, weight1);
  Affine a = blend_affine(joints.data(), joint, weight);
  skinning::add_influences(a, joints.data(), joint1, weight1);
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
  const skinning::InfluenceStreams influences(mesh);
  float3* out_positions = out.positions.data();
  float3* out_normals = normals ? out.normals.data() : nullptr;
  core::parallel_blocks(n, 8192, threads, [&](size_t, size_t begin, size_t end) {
    for (size_t v = begin; v < end; ++v) {
      const Affine a = influences.blend(J, v);
      out_positions[v] = skinning::apply_point(a, positions[v]);
      if (normals) out_normals[v] = skinning::apply_normal(a, normals[v]);
    }
  });
}

}  // namespace lod
