// Analyzers: simulate the post-transform vertex cache (FIFO or LRU), the memory fetches behind its
// misses, and read strip buffers.
#include <algorithm>

#include "lodkit/error.h"
#include "lodkit/optimize.h"

namespace lod {

const char* cache_policy_name(CachePolicy policy) { return policy == CachePolicy::fifo ? "fifo" : "lru"; }

namespace {

void check_indices(std::span<const uint32_t> indices, size_t vertex_count, const char* what) {
  if (indices.size() % 3) throw_usage(std::string(what) + ": the index count is not a multiple of 3");
  for (const uint32_t i : indices)
    if (i >= vertex_count) throw_usage(std::string(what) + ": index " + std::to_string(i) + " out of range");
}

// Calls miss(v) for every index that misses the cache, in order.
template <class Miss>
void simulate_cache(std::span<const uint32_t> indices, size_t vertex_count, const VertexCacheOptions& o, Miss&& miss) {
  if (o.cache_size < 3) throw_usage("vertex cache size must be at least 3");
  if (o.policy == CachePolicy::fifo) {
    // A FIFO hit needs the vertex to have entered fewer than cache_size misses ago.
    std::vector<uint64_t> entered(vertex_count, 0);  // miss counter after the vertex entered; 0: never
    uint64_t misses = 0;
    for (const uint32_t v : indices) {
      if (entered[v] && misses - entered[v] < o.cache_size) continue;
      entered[v] = ++misses;
      miss(v);
    }
    return;
  }
  // LRU: the cache as a small array, most recent first.
  std::vector<uint32_t> cache;
  cache.reserve(o.cache_size + 1);
  for (const uint32_t v : indices) {
    auto it = std::find(cache.begin(), cache.end(), v);
    if (it == cache.end()) {
      miss(v);
      if (cache.size() < o.cache_size) cache.push_back(v);
      it = cache.end() - 1;
      *it = v;
    }
    std::rotate(cache.begin(), it, it + 1);
  }
}

}  // namespace

VertexCacheStats analyze_vertex_cache(std::span<const uint32_t> indices, size_t vertex_count, const VertexCacheOptions& options) {
  check_indices(indices, vertex_count, "analyze_vertex_cache");
  VertexCacheStats s;
  s.triangles = indices.size() / 3;
  simulate_cache(indices, vertex_count, options, [&](uint32_t) { ++s.misses; });
  std::vector<uint8_t> used(vertex_count, 0);
  for (const uint32_t v : indices) s.referenced_vertices += !used[v], used[v] = 1;
  s.acmr = s.triangles ? double(s.misses) / double(s.triangles) : 0;
  s.atvr = s.referenced_vertices ? double(s.misses) / double(s.referenced_vertices) : 0;
  return s;
}

VertexFetchStats analyze_vertex_fetch(std::span<const uint32_t> indices, size_t vertex_count, const VertexFetchOptions& options) {
  check_indices(indices, vertex_count, "analyze_vertex_fetch");
  if (options.vertex_size == 0 || options.line_size == 0 || options.cache_lines == 0)
    throw_usage("analyze_vertex_fetch: vertex size, line size and cache lines must be positive");
  VertexFetchStats s;
  // Direct-mapped line cache: tag + 1 per slot, 0 for empty.
  std::vector<uint64_t> tags(options.cache_lines, 0);
  simulate_cache(indices, vertex_count, {.cache_size = options.vertex_cache_size, .policy = CachePolicy::fifo}, [&](uint32_t v) {
    const uint64_t first = uint64_t(v) * options.vertex_size / options.line_size;
    const uint64_t last = (uint64_t(v) * options.vertex_size + options.vertex_size - 1) / options.line_size;
    for (uint64_t line = first; line <= last; ++line) {
      uint64_t& tag = tags[line % options.cache_lines];
      if (tag != line + 1) {
        tag = line + 1;
        s.bytes_fetched += options.line_size;
      }
    }
  });
  std::vector<uint8_t> used(vertex_count, 0);
  uint64_t referenced = 0;
  for (const uint32_t v : indices) referenced += !used[v], used[v] = 1;
  s.overfetch = referenced ? double(s.bytes_fetched) / (double(referenced) * options.vertex_size) : 0;
  return s;
}

StripStats analyze_strips(std::span<const uint32_t> strip, bool use_restart, uint32_t restart_index) {
  StripStats s;
  s.indices = strip.size();
  // A strip is a run between restart indices; without restarts, a run of triangles each sharing an
  // edge with the one before (a swap keeps the run, a degenerate join between strips ends it).
  size_t begin = 0;
  while (begin < strip.size()) {
    size_t end = begin;
    if (use_restart)
      while (end < strip.size() && strip[end] != restart_index) ++end;
    else
      end = strip.size();
    bool have_previous = false;
    uint32_t prev[3] = {};
    bool run_open = false;
    for (size_t k = begin; k + 2 < end; ++k) {
      const uint32_t a = strip[k], b = strip[k + 1], c = strip[k + 2];
      if (a == b || b == c || a == c) {
        ++s.degenerate_triangles;
        continue;
      }
      ++s.triangles;
      int shared = 0;
      if (have_previous)
        for (const uint32_t v : {a, b, c}) shared += v == prev[0] || v == prev[1] || v == prev[2];
      if (!run_open || (!use_restart && shared < 2)) ++s.strips;
      run_open = true;
      have_previous = true;
      prev[0] = a, prev[1] = b, prev[2] = c;
    }
    begin = end + 1;
  }
  s.indices_per_triangle = s.triangles ? double(s.indices) / double(s.triangles) : 0;
  return s;
}

}  // namespace lod
