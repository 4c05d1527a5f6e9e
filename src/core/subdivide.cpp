#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "lodkit/mesh.h"

namespace lod {

namespace {

float3 normalized(float3 v) {
  float len = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
  return len > 0 ? float3{v.x / len, v.y / len, v.z / len} : v;
}
float2 mid(float2 a, float2 b) { return {(a.x + b.x) * 0.5f, (a.y + b.y) * 0.5f}; }
float3 mid(float3 a, float3 b) { return {(a.x + b.x) * 0.5f, (a.y + b.y) * 0.5f, (a.z + b.z) * 0.5f}; }
float4 mid(float4 a, float4 b) { return {(a.x + b.x) * 0.5f, (a.y + b.y) * 0.5f, (a.z + b.z) * 0.5f, (a.w + b.w) * 0.5f}; }

// Appends the midpoint of vertices a and b to every stream of m.
uint32_t append_midpoint(Mesh& m, uint32_t a, uint32_t b) {
  m.positions.push_back(mid(m.positions[a], m.positions[b]));
  if (!m.normals.empty()) m.normals.push_back(normalized(mid(m.normals[a], m.normals[b])));
  if (!m.tangents.empty()) {
    float3 t = normalized(mid(float3{m.tangents[a].x, m.tangents[a].y, m.tangents[a].z},
                              float3{m.tangents[b].x, m.tangents[b].y, m.tangents[b].z}));
    m.tangents.push_back({t.x, t.y, t.z, m.tangents[a].w});
  }
  for (auto& uv : m.uvs)
    if (!uv.empty()) uv.push_back(mid(uv[a], uv[b]));
  if (!m.colors.empty()) m.colors.push_back(mid(m.colors[a], m.colors[b]));
  if (!m.joints.empty()) {
    // Weights can only be blended when both ends name the same joints; otherwise keep one end's.
    const bool second = !m.joints1.empty();
    const bool same = m.joints[a] == m.joints[b] && (!second || m.joints1[a] == m.joints1[b]);
    const uint32_t from = same ? a : std::min(a, b);
    m.joints.push_back(m.joints[from]);
    m.weights.push_back(same ? mid(m.weights[a], m.weights[b]) : m.weights[from]);
    if (second) {
      m.joints1.push_back(m.joints1[from]);
      m.weights1.push_back(same ? mid(m.weights1[a], m.weights1[b]) : m.weights1[from]);
    }
  }
  return uint32_t(m.positions.size() - 1);
}

}  // namespace

Mesh subdivide_midpoint(const Mesh& mesh) {
  Mesh out = mesh;
  out.indices.clear();
  out.indices.reserve(mesh.indices.size() * 4);
  std::unordered_map<uint64_t, uint32_t> midpoint_of_edge;
  midpoint_of_edge.reserve(mesh.indices.size() * 2);
  auto midpoint = [&](uint32_t a, uint32_t b) {
    uint64_t key = (uint64_t(std::min(a, b)) << 32) | std::max(a, b);
    auto [it, inserted] = midpoint_of_edge.try_emplace(key, 0u);
    // Always build from (min, max) so both sides of an edge get the same bits.
    if (inserted) it->second = append_midpoint(out, std::min(a, b), std::max(a, b));
    return it->second;
  };
  const size_t F = mesh.triangle_count();
  for (size_t t = 0; t < F; ++t) {
    uint32_t a = mesh.indices[3 * t], b = mesh.indices[3 * t + 1], c = mesh.indices[3 * t + 2];
    uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
    const uint32_t tris[12] = {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca};
    out.indices.insert(out.indices.end(), tris, tris + 12);
  }
  auto repeat4 = [F](const std::vector<uint32_t>& per_triangle) {
    std::vector<uint32_t> r;
    r.reserve(F * 4);
    for (uint32_t v : per_triangle) r.insert(r.end(), {v, v, v, v});
    return r;
  };
  if (!mesh.materials.empty()) out.materials = repeat4(mesh.materials);
  if (!mesh.groups.empty()) out.groups = repeat4(mesh.groups);
  return out;
}

}  // namespace lod
