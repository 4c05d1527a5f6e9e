// Geomorphs: correspondence tables from collapse records, composition, and the morph itself.
#include <cmath>

#include "core/union_find.h"
#include "lod/internal.h"
#include "lodkit/error.h"
#include "lodkit/lod.h"

namespace lod {

namespace {
constexpr uint32_t none = ~0u;

using core::chain_end;
}  // namespace

Geomorph geomorph_from_record(const Mesh& source, const SimplifyResult& result) {
  const SimplifyRecord& record = result.record;
  const size_t n = source.vertex_count();
  // Wedges: each relink continues a removed position's wedge as one of the kept position's.
  std::vector<uint32_t> wedge_next(n, none);
  for (const Relink& r : record.relinks)
    if (wedge_next[r.from] == none && r.from != r.to) wedge_next[r.from] = r.to;
  // Positions: each collapse continues `removed` as `kept`.
  const PositionIds ids = position_ids(source);
  std::vector<uint32_t> position_next(ids.count, none);
  for (const Collapse& c : record.collapses) position_next[c.removed] = c.kept;

  std::vector<uint32_t> coarse_of(n, none);  // source vertex -> coarser vertex that continues it
  for (uint32_t j = 0; j < result.vertex_origin.size(); ++j) coarse_of[result.vertex_origin[j]] = j;
  std::vector<uint32_t> at_position(ids.count, none);  // final position -> a coarser vertex there
  for (uint32_t j = 0; j < result.vertex_origin.size(); ++j) {
    const uint32_t p = chain_end(position_next, ids.id[result.vertex_origin[j]]);
    if (at_position[p] == none) at_position[p] = j;
  }

  Geomorph g;
  g.target.resize(n);
  for (uint32_t v = 0; v < n; ++v) {
    uint32_t t = coarse_of[chain_end(wedge_next, v)];
    // A wedge whose every triangle vanished: any vertex at its final position (its triangles all
    // have zero area at t = 1 whatever attributes it takes).
    if (t == none) t = at_position[chain_end(position_next, ids.id[v])];
    g.target[v] = t == none ? 0 : t;  // none: used by no triangle at all
  }
  return g;
}

Geomorph compose(const Geomorph& a_to_b, const Geomorph& b_to_c) {
  Geomorph a_to_c;
  a_to_c.target.resize(a_to_b.target.size());
  for (size_t v = 0; v < a_to_b.target.size(); ++v) {
    if (a_to_b.target[v] >= b_to_c.target.size()) throw_usage("compose: the tables do not chain (a target is out of range)");
    a_to_c.target[v] = b_to_c.target[a_to_b.target[v]];
  }
  return a_to_c;
}

namespace {
void check_table(const Mesh& finer, const Mesh& coarser, const Geomorph& table) {
  if (table.target.size() != finer.vertex_count()) throw_usage("morph: the table is not for this finer level");
  for (const uint32_t t : table.target)
    if (t >= coarser.vertex_count() && finer.vertex_count()) throw_usage("morph: a target is not in the coarser level");
}

// (1 - t) a + t b per component. The caller handles t = 0 and t = 1 by copying, so those are exact
// (even for -0.0, which the blend would turn into +0.0).
template <class V>
V blend(const V& a, const V& b, float t) {
  V out;
  const float* pa = &a.x;
  const float* pb = &b.x;
  float* po = &out.x;
  for (size_t i = 0; i < sizeof(V) / sizeof(float); ++i) po[i] = (1 - t) * pa[i] + t * pb[i];
  return out;
}

template <class V>
void morph_stream(const std::vector<V>& finer, const std::vector<V>& coarser, const Geomorph& table, float t,
                  std::vector<V>& out) {
  if (finer.empty() || coarser.empty()) return;
  for (size_t v = 0; v < finer.size(); ++v) {
    const V& target = coarser[table.target[v]];
    out[v] = t >= 1 ? target : blend(finer[v], target, t);
  }
}
}  // namespace

void morph_positions(std::span<const float3> finer, std::span<const float3> coarser, const Geomorph& table, float t,
                     std::vector<float3>& out) {
  out.resize(finer.size());
  if (t <= 0) {
    std::copy(finer.begin(), finer.end(), out.begin());
    return;
  }
  const uint32_t* target = table.target.data();
  if (t >= 1) {
    for (size_t v = 0; v < finer.size(); ++v) out[v] = coarser[target[v]];
    return;
  }
  const float s = 1 - t;
  for (size_t v = 0; v < finer.size(); ++v) {
    const float3 &a = finer[v], &b = coarser[target[v]];
    out[v] = {s * a.x + t * b.x, s * a.y + t * b.y, s * a.z + t * b.z};
  }
}

Mesh morph(const Mesh& finer, const Mesh& coarser, const Geomorph& table, float t) {
  check_table(finer, coarser, table);
  Mesh out = finer;
  if (t <= 0) return out;
  morph_positions(finer.positions, coarser.positions, table, t, out.positions);
  morph_stream(finer.normals, coarser.normals, table, t, out.normals);
  if (t < 1)
    for (float3& n : out.normals) {
      const float l = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
      if (l > 0) n = {n.x / l, n.y / l, n.z / l};
    }
  for (size_t k = 0; k < max_uv_sets; ++k) morph_stream(finer.uvs[k], coarser.uvs[k], table, t, out.uvs[k]);
  morph_stream(finer.colors, coarser.colors, table, t, out.colors);
  return out;
}

}  // namespace lod
