#include <algorithm>
#include <cmath>
#include <limits>

#include "lodkit/mesh.h"

namespace lod {

bool operator==(const MaterialLook& a, const MaterialLook& b) {
  const auto same_image = [](const auto& x, const auto& y) { return x == y || (x && y && *x == *y); };
  for (size_t k = 0; k < a.images.size(); ++k)
    if (!same_image(a.images[k], b.images[k])) return false;
  return a.base_color == b.base_color && a.emissive == b.emissive && a.metallic == b.metallic && a.roughness == b.roughness &&
         a.base_color_texture == b.base_color_texture && a.normal_texture == b.normal_texture && a.emissive_texture == b.emissive_texture;
}

void copy_id_tables(Mesh& to, const Mesh& from) {
  to.material_names = from.material_names;
  to.material_looks = from.material_looks;
  to.group_names = from.group_names;
}

std::vector<bool> used_materials(const Mesh& mesh, size_t count) {
  std::vector<bool> used(count, false);
  if (mesh.materials.empty() && mesh.triangle_count() > 0 && count > 0) used[0] = true;
  for (uint32_t id : mesh.materials)
    if (id < count) used[id] = true;
  return used;
}

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

namespace {
// Mesh's vertex streams in stream_layout's bit order (stream_normals up), with the value
// fill_streams gives a missing one.
template <class M, class Fn>  // M: Mesh or const Mesh
void for_each_stream(M& m, Fn&& fn) {
  fn(m.normals, [](Mesh& mesh) {
    mesh.normals = smooth_normals(mesh);
    for (float3& n : mesh.normals)
      if (n.x == 0 && n.y == 0 && n.z == 0) n = {0, 0, 1};
  });
  fn(m.tangents, [](Mesh& mesh) { mesh.tangents.assign(mesh.vertex_count(), float4{1, 0, 0, 1}); });
  for (size_t k = 0; k < max_uv_sets; ++k)
    fn(m.uvs[k], [k](Mesh& mesh) { mesh.uvs[k].assign(mesh.vertex_count(), float2{}); });
  fn(m.colors, [](Mesh& mesh) { mesh.colors.assign(mesh.vertex_count(), float4{1, 1, 1, 1}); });
  fn(m.joints, [](Mesh& mesh) { mesh.joints.assign(mesh.vertex_count(), ushort4{}); });
  fn(m.weights, [](Mesh& mesh) { mesh.weights.assign(mesh.vertex_count(), float4{1, 0, 0, 0}); });
  fn(m.joints1, [](Mesh& mesh) { mesh.joints1.assign(mesh.vertex_count(), ushort4{}); });
  fn(m.weights1, [](Mesh& mesh) { mesh.weights1.assign(mesh.vertex_count(), float4{}); });
}
}  // namespace

uint32_t stream_layout(const Mesh& m) {
  uint32_t bits = 0, bit = 1;
  for_each_stream(m, [&](const auto& stream, auto&&) {
    if (!stream.empty()) bits |= bit;
    bit <<= 1;
  });
  return bits;
}

void fill_streams(Mesh& mesh, uint32_t layout) {
  uint32_t bit = 1;
  for_each_stream(mesh, [&](auto& stream, auto&& fill) {
    if ((layout & bit) && stream.empty()) fill(mesh);
    bit <<= 1;
  });
}

void keep_streams(Mesh& mesh, uint32_t layout) {
  uint32_t bit = 1;
  for_each_stream(mesh, [&](auto& stream, auto&&) {
    if (!(layout & bit)) stream.clear();
    bit <<= 1;
  });
}

}  // namespace lod
