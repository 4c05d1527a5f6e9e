#include <algorithm>
#include <cmath>
#include <limits>

#include "lodkit/mesh.h"

namespace lod {

size_t Mesh::uv_set_count() const {
  size_t n = 0;
  while (n < max_uv_sets && !uvs[n].empty()) ++n;
  return n;
}

void append_vertex(Mesh& dst, const Mesh& src, uint32_t from) {
  dst.positions.push_back(src.positions[from]);
  if (!src.normals.empty()) dst.normals.push_back(src.normals[from]);
  if (!src.tangents.empty()) dst.tangents.push_back(src.tangents[from]);
  for (size_t k = 0; k < max_uv_sets; ++k)
    if (!src.uvs[k].empty()) dst.uvs[k].push_back(src.uvs[k][from]);
  if (!src.colors.empty()) dst.colors.push_back(src.colors[from]);
  if (!src.joints.empty()) dst.joints.push_back(src.joints[from]);
  if (!src.weights.empty()) dst.weights.push_back(src.weights[from]);
  if (!src.joints1.empty()) dst.joints1.push_back(src.joints1[from]);
  if (!src.weights1.empty()) dst.weights1.push_back(src.weights1[from]);
}

void bounding_box(const Mesh& mesh, float3& min, float3& max) {
  if (mesh.positions.empty()) {
    min = max = {};
    return;
  }
  constexpr float inf = std::numeric_limits<float>::infinity();
  min = {inf, inf, inf};
  max = {-inf, -inf, -inf};
  for (const float3& p : mesh.positions) {
    min = {std::min(min.x, p.x), std::min(min.y, p.y), std::min(min.z, p.z)};
    max = {std::max(max.x, p.x), std::max(max.y, p.y), std::max(max.z, p.z)};
  }
}

}  // namespace lod
