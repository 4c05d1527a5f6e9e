#include "core/hash.h"
#include "core/heap.h"
#include "core/vec3d.h"
#include "lodkit/mesh.h"

namespace lod {

namespace core {

PositionWelder::PositionWelder(size_t expected) {
  size_t cap = 64;
  while (cap < expected * 2) cap <<= 1;
  assign_huge(slots_, cap, 0);
  mask_ = cap - 1;
  reserve_huge(unique_, expected);
}

void PositionWelder::grow() {
  std::vector<uint32_t> old = std::move(slots_);
  assign_huge(slots_, old.size() * 2, 0);
  mask_ = slots_.size() - 1;
  for (uint32_t s : old) {
    if (!s) continue;
    size_t i = hash_position(unique_[s - 1]) & mask_;
    while (slots_[i]) i = (i + 1) & mask_;
    slots_[i] = s;
  }
}

uint32_t PositionWelder::insert(const float3& p) {
  // Keep the load factor under 1/2 so linear probing stays short.
  if ((unique_.size() + 1) * 2 > slots_.size()) grow();
  size_t i = hash_position(p) & mask_;
  for (;;) {
    uint32_t s = slots_[i];
    if (!s) break;
    if (same_position(unique_[s - 1], p)) return s - 1;
    i = (i + 1) & mask_;
  }
  unique_.push_back(p);
  slots_[i] = uint32_t(unique_.size());
  return uint32_t(unique_.size() - 1);
}

}  // namespace core

PositionIds position_ids(const Mesh& mesh) {
  PositionIds result;
  core::resize_huge(result.id, mesh.positions.size());
  core::PositionWelder welder(mesh.positions.size());
  for (size_t v = 0; v < mesh.positions.size(); ++v) result.id[v] = welder.insert(mesh.positions[v]);
  result.count = welder.count();
  return result;
}

std::vector<float3> smooth_normals(const Mesh& mesh) {
  const PositionIds ids = position_ids(mesh);
  std::vector<core::vec3d> sum(ids.count);
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    const core::vec3d n = core::triangle_cross(mesh, t);
    for (int k = 0; k < 3; ++k) sum[ids.id[mesh.indices[3 * t + k]]] += n;
  }
  std::vector<float3> normals(mesh.vertex_count());
  for (size_t v = 0; v < normals.size(); ++v) normals[v] = core::unit_float3(sum[ids.id[v]], {0, 0, 0});
  return normals;
}

void make_unit_directions(Mesh& mesh) {
  std::vector<float3> smooth;  // smooth_normals, when a zero direction needs them
  const auto smooth_at = [&](size_t v) {
    if (smooth.empty()) smooth = smooth_normals(mesh);
    return core::unit_float3(core::to_double(smooth[v]), {0, 0, 1});
  };
  const auto is_zero = [](const float3& n) { return n.x == 0 && n.y == 0 && n.z == 0; };
  for (size_t v = 0; v < mesh.normals.size(); ++v) {
    float3& n = mesh.normals[v];
    const core::vec3d d = core::to_double(n);
    if (std::fabs(core::length(d) - 1) <= 1e-6) continue;
    n = core::unit_float3(d, float3{});
    if (is_zero(n)) n = smooth_at(v);
  }
  for (size_t v = 0; v < mesh.tangents.size(); ++v) {
    float4& t = mesh.tangents[v];
    if (t.w != 1 && t.w != -1) t.w = t.w < 0 ? -1.0f : 1.0f;
    const core::vec3d d{t.x, t.y, t.z};
    if (std::fabs(core::length(d) - 1) <= 1e-6) continue;
    float3 xyz = core::unit_float3(d, float3{});
    if (is_zero(xyz)) {
      // Any direction in the tangent plane beats none: the normal crossed with the axis least
      // along it.
      const core::vec3d n = core::to_double(v < mesh.normals.size() ? mesh.normals[v] : smooth_at(v));
      const core::vec3d axis = std::fabs(n.x) < 0.5 ? core::vec3d{1, 0, 0} : core::vec3d{0, 1, 0};
      xyz = core::unit_float3(core::cross(core::cross(n, axis), n), {1, 0, 0});
    }
    t = {xyz.x, xyz.y, xyz.z, t.w};
  }
}

}  // namespace lod
