// The whole consolidation on a Mesh: weld, orient, order triangles per material for the vertex cache
// (or as strips; optionally then for overdraw), then vertices by first use.
#include <algorithm>
#include <chrono>
#include <numeric>

#include "lodkit/error.h"
#include "lodkit/optimize.h"

namespace lod {

namespace {
double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}
}  // namespace

OptimizeResult optimize(const Mesh& mesh, const OptimizeOptions& options) {
  if (options.overdraw && options.strips) throw_usage("optimize: the overdraw order and strips exclude each other");
  OptimizeResult r;
  Mesh m = mesh;
  r.source_vertices.resize(m.vertex_count());
  std::iota(r.source_vertices.begin(), r.source_vertices.end(), 0u);
  auto start = std::chrono::steady_clock::now();
  if (options.weld) {
    r.weld = weld(m, options.weld_options);
    m = std::move(r.weld.mesh);
    r.weld.mesh = {};
    // Each output vertex's source: the first input vertex welded into it.
    std::vector<uint32_t> source(m.vertex_count(), UINT32_MAX);
    for (uint32_t v = 0; v < r.weld.remap.size(); ++v)
      if (source[r.weld.remap[v]] == UINT32_MAX) source[r.weld.remap[v]] = v;
    r.source_vertices = std::move(source);
    r.weld_seconds = seconds_since(start);
  }
  start = std::chrono::steady_clock::now();
  if (options.orient) {
    r.orient = orient(m, options.orient_options);
    m = std::move(r.orient.mesh);
    r.orient.mesh = {};
    r.orient_seconds = seconds_since(start);
  }
  r.cache_before = analyze_vertex_cache(m.indices, m.vertex_count(), options.cache);

  start = std::chrono::steady_clock::now();
  // Material ranges, each ordered on its own.
  const uint32_t F = uint32_t(m.triangle_count());
  std::vector<uint32_t> by_material(F);
  for (uint32_t t = 0; t < F; ++t) by_material[t] = t;
  if (!m.materials.empty())
    std::stable_sort(by_material.begin(), by_material.end(), [&](uint32_t a, uint32_t b) { return m.materials[a] < m.materials[b]; });
  std::vector<uint32_t> order;
  order.reserve(F);
  r.strips.use_restart = options.strip_options.use_restart;
  r.strips.restart_index = options.strip_options.restart_index;
  std::vector<uint32_t> range_indices;
  for (uint32_t begin = 0; begin < F;) {
    uint32_t end = begin + 1;
    while (end < F && m.material(by_material[end]) == m.material(by_material[begin])) ++end;
    range_indices.clear();
    for (uint32_t k = begin; k < end; ++k)
      for (uint32_t c = 0; c < 3; ++c) range_indices.push_back(m.indices[3 * size_t(by_material[k]) + c]);
    if (options.strips) {
      StripOptions so = options.strip_options;
      so.cache_size = options.cache.cache_size;
      Strips s = stripify(range_indices, m.vertex_count(), so);
      // Strip order, then the degenerate triangles the strips leave out.
      std::vector<uint8_t> in_strip(end - begin, 0);
      for (uint32_t& t : s.triangle_order) in_strip[t] = 1, t = by_material[begin + t];
      order.insert(order.end(), s.triangle_order.begin(), s.triangle_order.end());
      for (uint32_t k = begin; k < end; ++k)
        if (!in_strip[k - begin]) order.push_back(by_material[k]);
      append_strips(r.strips, s);
    } else {
      const std::vector<uint32_t> cache_order = vertex_cache_order(range_indices, m.vertex_count(), options.cache);
      if (options.overdraw) {
        // The overdraw pass reorders clusters of the cache order (meshoptimizer's recommended sequence).
        const auto overdraw_start = std::chrono::steady_clock::now();
        std::vector<uint32_t> ordered(range_indices.size());
        for (size_t k = 0; k < cache_order.size(); ++k)
          for (uint32_t c = 0; c < 3; ++c) ordered[3 * k + c] = range_indices[3 * size_t(cache_order[k]) + c];
        for (const uint32_t k : overdraw_order(ordered, m.positions,
                                               {.cache_size = options.cache.cache_size, .threshold = options.overdraw_threshold}))
          order.push_back(by_material[begin + cache_order[k]]);
        r.overdraw_seconds += seconds_since(overdraw_start);
      } else {
        for (const uint32_t t : cache_order) order.push_back(by_material[begin + t]);
      }
    }
    begin = end;
  }
  m = reorder_triangles(m, order);
  {
    // The strips' triangle order, in the output mesh's triangle numbers.
    std::vector<uint32_t> output_of(F);
    for (uint32_t k = 0; k < F; ++k) output_of[order[k]] = k;
    for (uint32_t& t : r.strips.triangle_order) t = output_of[t];
  }

  r.order_seconds = seconds_since(start);
  start = std::chrono::steady_clock::now();
  if (options.vertex_fetch) {
    const std::vector<uint32_t> remap = vertex_fetch_remap(m.indices, m.vertex_count());
    m = remap_vertices(m, remap, m.vertex_count());
    std::vector<uint32_t> source(r.source_vertices.size());
    for (size_t v = 0; v < remap.size(); ++v) source[remap[v]] = r.source_vertices[v];
    r.source_vertices = std::move(source);
    for (uint32_t& i : r.strips.indices)
      if (!(r.strips.use_restart && i == r.strips.restart_index)) i = remap[i];
    r.fetch_seconds = seconds_since(start);
  }
  r.cache_after = analyze_vertex_cache(m.indices, m.vertex_count(), options.cache);
  r.mesh = std::move(m);
  return r;
}

}  // namespace lod
