// Weld: merge duplicate vertices. The course's hash-based duplicate removal, extended to tolerances:
// candidates come from the exact position (a hash of the float bits) or, with a position tolerance,
// from the 27 cells of a uniform grid around the vertex (cell size = the tolerance, so any vertex
// within the tolerance lies in one of them). Every candidate is an earlier kept vertex; the first one
// that matches in every stream wins.
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "core/hash.h"
#include "lodkit/error.h"
#include "lodkit/optimize.h"

namespace lod {

namespace {

constexpr uint32_t none = 0xFFFFFFFFu;

bool near(float a, float b, float tolerance) {
  return tolerance > 0 ? std::fabs(a - b) <= tolerance : core::float_key(a) == core::float_key(b);
}
bool near(const float2& a, const float2& b, float t) { return near(a.x, b.x, t) && near(a.y, b.y, t); }
bool near(const float3& a, const float3& b, float t) { return near(a.x, b.x, t) && near(a.y, b.y, t) && near(a.z, b.z, t); }
bool near(const float4& a, const float4& b, float t) {
  return near(a.x, b.x, t) && near(a.y, b.y, t) && near(a.z, b.z, t) && near(a.w, b.w, t);
}

// Every attribute stream of v within its tolerance of r's.
bool attributes_match(const Mesh& m, uint32_t v, uint32_t r, const WeldOptions& o) {
  if (!o.vertex_classes.empty() && o.vertex_classes[v] != o.vertex_classes[r]) return false;
  if (o.ignore_attributes) return true;
  if (!m.normals.empty() && !near(m.normals[v], m.normals[r], o.normal_tolerance)) return false;
  if (!m.tangents.empty()) {
    const float4 &a = m.tangents[v], &b = m.tangents[r];
    if (!near(float3{a.x, a.y, a.z}, float3{b.x, b.y, b.z}, o.tangent_tolerance) || core::float_key(a.w) != core::float_key(b.w))
      return false;
  }
  for (size_t k = 0; k < max_uv_sets; ++k)
    if (!m.uvs[k].empty() && !near(m.uvs[k][v], m.uvs[k][r], o.uv_tolerance)) return false;
  if (!m.colors.empty() && !near(m.colors[v], m.colors[r], o.color_tolerance)) return false;
  if (!m.joints.empty() && m.joints[v] != m.joints[r]) return false;
  if (!m.weights.empty() && !near(m.weights[v], m.weights[r], o.weight_tolerance)) return false;
  if (!m.joints1.empty() && m.joints1[v] != m.joints1[r]) return false;
  if (!m.weights1.empty() && !near(m.weights1[v], m.weights1[r], o.weight_tolerance)) return false;
  return true;
}

void check_tolerance(float value, const char* name) {
  if (!(value >= 0) || !std::isfinite(value)) throw_usage(std::string("weld: ") + name + " must be finite and >= 0");
}

// Kept vertex of each input vertex, by exact position: candidates share the position id.
std::vector<uint32_t> weld_exact_positions(const Mesh& m, const WeldOptions& o) {
  const PositionIds pids = position_ids(m);
  std::vector<uint32_t> head(pids.count, none), next(m.vertex_count(), none), kept_of(m.vertex_count());
  for (uint32_t v = 0; v < m.vertex_count(); ++v) {
    const uint32_t p = pids.id[v];
    uint32_t found = none, last = none;
    for (uint32_t r = head[p]; r != none; last = r, r = next[r])
      if (attributes_match(m, v, r, o)) {
        found = r;
        break;
      }
    if (found == none) {
      // Append to keep the list in vertex order (the first match is the earliest kept vertex).
      if (last == none) head[p] = v;
      else next[last] = v;
      found = v;
    }
    kept_of[v] = found;
  }
  return kept_of;
}

// Kept vertex of each input vertex, positions within a Euclidean tolerance.
std::vector<uint32_t> weld_tolerant_positions(const Mesh& m, const WeldOptions& o) {
  const double cell = o.position_tolerance;
  const double tolerance2 = double(o.position_tolerance) * o.position_tolerance;
  auto cell_of = [&](float x) { return int64_t(std::floor(double(x) / cell)); };
  auto cell_key = [](int64_t x, int64_t y, int64_t z) {
    uint64_t h = uint64_t(x) * 0x9E3779B97F4A7C15ull;
    h ^= (h >> 29) ^ (uint64_t(y) * 0xC2B2AE3D27D4EB4Full);
    h ^= (h >> 31) ^ (uint64_t(z) * 0x165667B19E3779F9ull);
    return h;
  };
  // Cell key -> first kept vertex of the cell; kept vertices chain through next[] in vertex order.
  // Distinct cells may share a hash, which only adds candidates that the distance test rejects.
  std::unordered_map<uint64_t, uint32_t> head;
  head.reserve(m.vertex_count());
  std::vector<uint32_t> next(m.vertex_count(), none), tail_of_chain(m.vertex_count(), none), kept_of(m.vertex_count());
  for (uint32_t v = 0; v < m.vertex_count(); ++v) {
    const float3& p = m.positions[v];
    const int64_t cx = cell_of(p.x), cy = cell_of(p.y), cz = cell_of(p.z);
    // The earliest matching kept vertex over the 27 cells (chains are in vertex order).
    uint32_t found = none;
    for (int64_t dz = -1; dz <= 1; ++dz)
      for (int64_t dy = -1; dy <= 1; ++dy)
        for (int64_t dx = -1; dx <= 1; ++dx) {
          const auto it = head.find(cell_key(cx + dx, cy + dy, cz + dz));
          if (it == head.end()) continue;
          for (uint32_t r = it->second; r != none && r < found; r = next[r]) {
            const float3& q = m.positions[r];
            const double ex = double(p.x) - q.x, ey = double(p.y) - q.y, ez = double(p.z) - q.z;
            if (ex * ex + ey * ey + ez * ez <= tolerance2 && attributes_match(m, v, r, o)) {
              found = r;
              break;
            }
          }
        }
    if (found != none) {
      kept_of[v] = found;
      continue;
    }
    kept_of[v] = v;
    const uint64_t k = cell_key(cx, cy, cz);
    auto [it, inserted] = head.try_emplace(k, v);
    if (inserted) {
      tail_of_chain[v] = v;
    } else {
      const uint32_t first = it->second;
      next[tail_of_chain[first]] = v;
      tail_of_chain[first] = v;
    }
  }
  return kept_of;
}

}  // namespace

WeldResult weld(const Mesh& mesh, const WeldOptions& options) {
  check_tolerance(options.position_tolerance, "position_tolerance");
  check_tolerance(options.normal_tolerance, "normal_tolerance");
  check_tolerance(options.tangent_tolerance, "tangent_tolerance");
  check_tolerance(options.uv_tolerance, "uv_tolerance");
  check_tolerance(options.color_tolerance, "color_tolerance");
  check_tolerance(options.weight_tolerance, "weight_tolerance");
  if (!options.vertex_classes.empty() && options.vertex_classes.size() != mesh.vertex_count())
    throw_usage("weld: " + std::to_string(options.vertex_classes.size()) + " vertex classes for " +
                std::to_string(mesh.vertex_count()) + " vertices");
  const std::vector<uint32_t> kept_of = options.position_tolerance > 0 ? weld_tolerant_positions(mesh, options)
                                                                       : weld_exact_positions(mesh, options);
  WeldResult r;
  r.input_vertices = mesh.vertex_count();
  r.remap.assign(mesh.vertex_count(), none);
  Mesh& out = r.mesh;
  copy_id_tables(out, mesh);
  // Every input vertex's kept vertex is itself or an earlier one, so one pass numbers them.
  uint32_t count = 0;
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    if (kept_of[v] == v) {
      r.remap[v] = count++;
      append_vertex(out, mesh, v);
    } else {
      r.remap[v] = r.remap[kept_of[v]];
    }
  }
  r.output_vertices = count;
  const size_t F = mesh.triangle_count();
  out.indices.reserve(mesh.indices.size());
  for (size_t t = 0; t < F; ++t) {
    const uint32_t a = r.remap[mesh.indices[3 * t]], b = r.remap[mesh.indices[3 * t + 1]], c = r.remap[mesh.indices[3 * t + 2]];
    const bool degenerate = a == b || b == c || a == c;
    r.degenerate_triangles += degenerate;
    if (degenerate && options.remove_degenerate) continue;
    out.indices.insert(out.indices.end(), {a, b, c});
    if (!mesh.materials.empty()) out.materials.push_back(mesh.materials[t]);
    if (!mesh.groups.empty()) out.groups.push_back(mesh.groups[t]);
  }
  return r;
}

}  // namespace lod
