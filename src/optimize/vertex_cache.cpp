// Vertex-cache order. Three orderers, the analyzer picking the best on the caller's cache:
// - the fan orderer (lodkit's, for FIFO caches): emits all remaining triangles around one vertex at a
//   time, like Tipsify, but chooses the next centre among all cached vertices by the cost of its fan
//   in the simulated FIFO (uncached corners per triangle, kept up to date incrementally, with small
//   terms for the entries it pushes out and for the triangles left around it);
// - Tipsify (Sander, Nehab and Barczak 2007): the next centre is the oldest neighbour that stays
//   cached through its own fan;
// - a greedy walk in the manner of Tom Forsyth's linear-speed optimiser (for LRU caches): a simulated
//   cache of the target size holds the vertices just used; each vertex scores by its place in that
//   cache and by how few triangles still need it; the next triangle is the best-scoring one among the
//   triangles of the cached vertices.
// At a dead end each restarts from the most recently used vertex that still has triangles (it keeps
// the walk local), and only then from the next triangle in input order. On small inputs the fan
// orderer also runs from a few other start vertices (the first fan sets the sweep that follows).
#include <algorithm>
#include <cmath>

#include "lodkit/error.h"
#include "lodkit/optimize.h"
#include "optimize/vertex_cache.h"

namespace lod {

namespace detail {

namespace {
constexpr uint32_t none = 0xFFFFFFFFu;
}  // namespace

CacheScoring default_scoring(uint32_t cache_size) {
  // Forsyth's published shape: the last triangle's own vertices score a little less than the next
  // ones (so the walk does not run off in a thin strip), then the score falls with age; a vertex with
  // few triangles left scores high (finishing it frees a slot for good).
  CacheScoring s;
  s.cache_size = cache_size;
  s.model = CachePolicy::lru;
  for (uint32_t p = 0; p < cache_size; ++p)
    s.cache[p] = p < 3 ? 0.75f : std::pow(1.0f - float(p - 3) / float(cache_size - 3), 1.5f);
  s.cache[cache_size] = 0;
  for (uint32_t l = 1; l < live_table_size; ++l) s.live[l] = 2.0f / std::sqrt(float(l));
  return s;
}

std::vector<uint32_t> greedy_cache_order(std::span<const uint32_t> indices, size_t vertex_count, const CacheScoring& scoring) {
  const uint32_t F = uint32_t(indices.size() / 3);
  const uint32_t V = uint32_t(vertex_count);
  const uint32_t K = scoring.cache_size;
  auto vertex_score = [&](uint32_t position, uint32_t live_count) {
    return live_count ? scoring.cache[position] + scoring.live[std::min(live_count, live_table_size - 1)] : 0.0f;
  };

  // Vertex -> triangles (CSR). The first live[v] entries of each list are the triangles not yet emitted.
  std::vector<uint32_t> offset(V + 1, 0), live(V, 0);
  for (const uint32_t i : indices) ++offset[i + 1];
  for (uint32_t v = 0; v < V; ++v) offset[v + 1] += offset[v];
  std::vector<uint32_t> triangles(indices.size());
  for (uint32_t t = 0; t < F; ++t)
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t v = indices[3 * t + k];
      triangles[offset[v] + live[v]++] = t;
    }

  std::vector<uint32_t> position(V, K);  // cache position, K when not cached
  std::vector<float> score(V);
  for (uint32_t v = 0; v < V; ++v) score[v] = vertex_score(K, live[v]);
  std::vector<uint8_t> emitted(F, 0);
  std::vector<uint32_t> order;
  order.reserve(F);

  uint32_t cache[max_cache_size + 3];
  uint32_t cache_count = 0;
  std::vector<uint32_t> recent;  // vertices in the order they entered the cache: dead-end restarts
  uint32_t cursor = 0;           // input order restarts

  auto best_triangle_of = [&](uint32_t v) {
    uint32_t best = none;
    float best_score = -1;
    for (uint32_t j = offset[v], e = offset[v] + live[v]; j < e; ++j) {
      const uint32_t t = triangles[j];
      const float s = score[indices[3 * t]] + score[indices[3 * t + 1]] + score[indices[3 * t + 2]];
      if (s > best_score) best_score = s, best = t;
    }
    return best;
  };

  // Start at the best-scoring triangle of the vertex with the fewest triangles (a border or corner).
  uint32_t next = none;
  {
    uint32_t start_vertex = none;
    for (uint32_t v = 0; v < V; ++v)
      if (live[v] && (start_vertex == none || live[v] < live[start_vertex])) start_vertex = v;
    if (start_vertex != none) next = best_triangle_of(start_vertex);
  }

  while (next != none) {
    const uint32_t t = next;
    emitted[t] = 1;
    order.push_back(t);
    const uint32_t tv[3] = {indices[3 * t], indices[3 * t + 1], indices[3 * t + 2]};
    for (const uint32_t v : tv) {
      // Drop t from v's live triangles (swap with the last live one).
      uint32_t* list = triangles.data() + offset[v];
      for (uint32_t j = 0; j < live[v]; ++j)
        if (list[j] == t) {
          std::swap(list[j], list[live[v] - 1]);
          --live[v];
          break;
        }
    }

    // Update the simulated cache. Old entries beyond K are evicted (kept in cache[K..] for rescoring).
    uint32_t fresh[3];
    uint32_t fresh_count = 0;
    if (scoring.model == CachePolicy::fifo) {
      for (const uint32_t v : tv)
        if (position[v] == K && std::find(fresh, fresh + fresh_count, v) == fresh + fresh_count) fresh[fresh_count++] = v;
      // Newest first: the last vertex pushed sits at position 0.
      std::move_backward(cache, cache + cache_count, cache + cache_count + fresh_count);
      for (uint32_t j = 0; j < fresh_count; ++j) cache[j] = fresh[fresh_count - 1 - j];
      cache_count += fresh_count;
    } else {
      // Accessing a, b, c moves each to the front in turn: c, b, a, then the others in their order.
      uint32_t front[3];
      uint32_t front_count = 0;
      for (int k = 2; k >= 0; --k)
        if (std::find(front, front + front_count, tv[k]) == front + front_count) front[front_count++] = tv[k];
      uint32_t rest[max_cache_size + 3];
      uint32_t rest_count = 0;
      for (uint32_t j = 0; j < cache_count; ++j)
        if (std::find(front, front + front_count, cache[j]) == front + front_count) rest[rest_count++] = cache[j];
      for (uint32_t j = 0; j < front_count; ++j) {
        if (position[front[j]] == K) fresh[fresh_count++] = front[j];
        cache[j] = front[j];
      }
      std::copy(rest, rest + rest_count, cache + front_count);
      cache_count = front_count + rest_count;
    }
    for (uint32_t j = 0; j < fresh_count; ++j) recent.push_back(fresh[j]);
    for (uint32_t j = 0; j < cache_count; ++j) {
      const uint32_t v = cache[j];
      position[v] = j < K ? j : K;
      score[v] = vertex_score(position[v], live[v]);
    }
    cache_count = std::min(cache_count, K);

    // The best triangle touching the cache.
    next = none;
    float best_score = -1;
    for (uint32_t j = 0; j < cache_count; ++j) {
      const uint32_t v = cache[j];
      for (uint32_t i = offset[v], e = offset[v] + live[v]; i < e; ++i) {
        const uint32_t c = triangles[i];
        const float s = score[indices[3 * c]] + score[indices[3 * c + 1]] + score[indices[3 * c + 2]];
        if (s > best_score) best_score = s, next = c;
      }
    }
    if (next != none) continue;
    // Dead end: the most recently cached vertex with triangles left, else the next in input order.
    while (!recent.empty() && next == none) {
      const uint32_t v = recent.back();
      recent.pop_back();
      if (live[v]) next = best_triangle_of(v);
    }
    while (next == none && cursor < F) {
      if (!emitted[cursor]) next = cursor;
      ++cursor;
    }
  }
  if (order.size() != F) throw_internal("optimize_vertex_cache: lost triangles");
  return order;
}

// Tipsify (Sander, Nehab and Barczak, 2007): fan around one vertex at a time (emit all its remaining
// triangles), then move to the neighbour that will still be cached after its own fan, the oldest such
// first; at a dead end, back to the most recently used vertex with triangles left.
std::vector<uint32_t> tipsify_order(std::span<const uint32_t> indices, size_t vertex_count, uint32_t cache_size) {
  const uint32_t F = uint32_t(indices.size() / 3);
  const uint32_t V = uint32_t(vertex_count);
  std::vector<uint32_t> offset(V + 1, 0), live(V, 0);
  for (const uint32_t i : indices) ++offset[i + 1];
  for (uint32_t v = 0; v < V; ++v) offset[v + 1] += offset[v];
  std::vector<uint32_t> triangles(indices.size());
  for (uint32_t t = 0; t < F; ++t)
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t v = indices[3 * t + k];
      triangles[offset[v] + live[v]++] = t;
    }
  std::vector<uint64_t> entered(V, 0);  // miss count when the vertex entered the FIFO (0: never)
  uint64_t time = cache_size + 1;
  std::vector<uint8_t> emitted(F, 0);
  std::vector<uint32_t> dead_end, candidates, order;
  dead_end.reserve(indices.size());
  order.reserve(F);
  uint32_t cursor = 0;
  uint32_t fan = F ? indices[0] : none;
  while (fan != none) {
    candidates.clear();
    for (uint32_t j = offset[fan]; j < offset[fan + 1]; ++j) {
      const uint32_t t = triangles[j];
      if (emitted[t]) continue;
      emitted[t] = 1;
      order.push_back(t);
      for (uint32_t k = 0; k < 3; ++k) {
        const uint32_t v = indices[3 * t + k];
        dead_end.push_back(v);
        candidates.push_back(v);
        --live[v];
        if (time - entered[v] > cache_size) entered[v] = time++;
      }
    }
    // The next fan: a candidate that stays cached through its own fan (about two misses per
    // triangle), the oldest in the cache first.
    fan = none;
    uint64_t best = 0;
    for (const uint32_t v : candidates) {
      if (!live[v]) continue;
      const uint64_t age = time - entered[v];
      if (age + 2 * uint64_t(live[v]) <= cache_size && age > best) best = age, fan = v;
    }
    if (fan != none) continue;
    while (!dead_end.empty() && fan == none) {
      const uint32_t v = dead_end.back();
      dead_end.pop_back();
      if (live[v]) fan = v;
    }
    while (fan == none && cursor < V) {
      if (live[cursor]) fan = cursor;
      ++cursor;
    }
  }
  return order;
}

std::vector<uint32_t> fan_cache_order(std::span<const uint32_t> indices, size_t vertex_count, const FanScoring& scoring) {
  const uint32_t F = uint32_t(indices.size() / 3);
  const uint32_t V = uint32_t(vertex_count);
  const uint32_t K = scoring.cache_size;
  std::vector<uint32_t> offset(V + 1, 0), live(V, 0);
  for (const uint32_t i : indices) ++offset[i + 1];
  for (uint32_t v = 0; v < V; ++v) offset[v + 1] += offset[v];
  std::vector<uint32_t> triangles(indices.size());
  for (uint32_t t = 0; t < F; ++t)
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t v = indices[3 * t + k];
      triangles[offset[v] + live[v]++] = t;
    }
  // The FIFO: a ring of K entries (ring[head] is the oldest, overwritten by the next miss) and the
  // miss count at which each cached vertex entered (0 when it is not cached: eviction clears it).
  std::vector<uint32_t> ring(K, none), entered(V, 0);
  uint32_t head = 0, time = 0;
  auto cached = [&](uint32_t v) { return entered[v] != 0; };
  // Per vertex, the corner misses of its fan: over its live triangles, the corners not cached (a
  // corner shared by two of them counts twice). Kept up to date as triangles leave and vertices enter
  // or leave the cache. A centre's fan costs about that many misses, fewer where corners are shared;
  // counting them all favours fans whose new corners are also needed by their neighbours' fans.
  std::vector<uint32_t> corner_misses(V, 0);
  for (uint32_t v = 0; v < V; ++v) corner_misses[v] = 3 * live[v];
  auto add_to_corners = [&](uint32_t w, int32_t delta) {  // w entered (-1) or left (+1) the cache
    for (uint32_t i = offset[w], e = offset[w] + live[w]; i < e; ++i) {
      const uint32_t* c = &indices[3 * size_t(triangles[i])];
      corner_misses[c[0]] += delta, corner_misses[c[1]] += delta, corner_misses[c[2]] += delta;
    }
  };
  std::vector<uint32_t> order, dead_end;
  order.reserve(F);
  dead_end.reserve(indices.size());
  uint32_t cursor = 0;

  auto emit = [&](uint32_t t) {
    order.push_back(t);
    const uint32_t* c = &indices[3 * size_t(t)];
    const uint32_t uncached = uint32_t(!cached(c[0])) + !cached(c[1]) + !cached(c[2]);
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t v = c[k];
      corner_misses[v] -= uncached;
      uint32_t* list = triangles.data() + offset[v];
      for (uint32_t j = 0; j < live[v]; ++j)
        if (list[j] == t) {
          std::swap(list[j], list[live[v] - 1]);
          --live[v];
          break;
        }
    }
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t v = c[k];
      dead_end.push_back(v);
      if (cached(v)) continue;
      const uint32_t evicted = ring[head];
      if (evicted != none) {
        entered[evicted] = 0;
        add_to_corners(evicted, +1);
      }
      ring[head] = v;
      head = head + 1 == K ? 0 : head + 1;
      entered[v] = ++time;
      add_to_corners(v, -1);
    }
  };
  auto misses_of = [&](uint32_t t) {
    return uint32_t(!cached(indices[3 * t])) + !cached(indices[3 * t + 1]) + !cached(indices[3 * t + 2]);
  };
  // with_work[q]: how many of the q oldest entries still have triangles (they would be loaded again).
  std::vector<uint32_t> with_work(K + 1, 0);

  // Start around the given vertex, else the vertex with the fewest triangles (a border or a corner).
  uint32_t focus = scoring.start < V && live[scoring.start] ? scoring.start : none;
  if (focus == none)
    for (uint32_t v = 0; v < V; ++v)
      if (live[v] && (focus == none || live[v] < live[focus])) focus = v;
  while (focus != none) {
    // The fan, cheapest triangle first; on a tie, the one holding the oldest cached corner besides
    // the centre (use it before it leaves).
    while (live[focus]) {
      const uint32_t* list = triangles.data() + offset[focus];
      auto oldest_corner = [&](uint32_t t) {
        uint32_t oldest = 0xFFFFFFFFu;
        for (uint32_t k = 0; k < 3; ++k) {
          const uint32_t w = indices[3 * size_t(t) + k];
          if (w != focus && cached(w)) oldest = std::min(oldest, entered[w]);
        }
        return oldest;
      };
      uint32_t best = list[0], best_misses = misses_of(list[0]), best_oldest = oldest_corner(list[0]);
      for (uint32_t j = 1; j < live[focus]; ++j) {
        const uint32_t m = misses_of(list[j]);
        if (m > best_misses) continue;
        const uint32_t oldest = oldest_corner(list[j]);
        if (m < best_misses || oldest < best_oldest) best = list[j], best_misses = m, best_oldest = oldest;
      }
      emit(best);
    }
    // The next centre: the cached vertex whose fan costs least, the oldest on ties. Its cost: corner
    // misses per triangle, plus a weight per entry the fan would push out that still has triangles
    // (not counting the centre), plus a weight per triangle.
    for (uint32_t q = 0, slot = head; q < K; ++q, slot = slot + 1 == K ? 0 : slot + 1) {
      const uint32_t u = ring[slot];
      with_work[q + 1] = with_work[q] + (u != none && live[u] > 0);
    }
    focus = none;
    float best_cost = 0;
    for (uint32_t q = 0, slot = head; q < K; ++q, slot = slot + 1 == K ? 0 : slot + 1) {
      const uint32_t v = ring[slot];
      if (v == none || !live[v]) continue;
      const uint32_t n = corner_misses[v];
      // About n / 2 distinct vertices enter (inner corners are shared by two triangles of the fan).
      const uint32_t entering = std::min(n / 2, K);
      const uint32_t pushed_out = with_work[entering] - (q < entering ? 1u : 0u);
      const float cost = (float(n) + scoring.eviction_weight * float(pushed_out)) / float(live[v]) + scoring.live_weight * float(live[v]);
      if (focus == none || cost < best_cost) best_cost = cost, focus = v;
    }
    if (focus != none) continue;
    // Dead end: the most recently used vertex with triangles left, else the next in input order.
    while (!dead_end.empty() && focus == none) {
      const uint32_t v = dead_end.back();
      dead_end.pop_back();
      if (live[v]) focus = v;
    }
    while (focus == none && cursor < V) {
      if (live[cursor]) focus = cursor;
      ++cursor;
    }
  }
  return order;
}

}  // namespace detail

namespace {
constexpr uint32_t max_cache = detail::max_cache_size;
// Extra starts of the fan orderer on small inputs: at most `max_extra_starts` runs and at most
// `extra_start_triangles` triangles of extra work in all, so the extra time is bounded by a constant
// (one fan-orderer run over 8,192 triangles) and inputs over 8,192 triangles run each orderer once.
constexpr uint32_t max_extra_starts = 3;
constexpr uint32_t extra_start_triangles = 8192;

// Cache misses of the triangles taken in `order` (the analyzer's simulation, without building the list).
uint64_t cache_misses(std::span<const uint32_t> indices, std::span<const uint32_t> order, size_t vertex_count, const VertexCacheOptions& o) {
  if (o.policy == CachePolicy::lru) {
    std::vector<uint32_t> list(indices.size());
    for (size_t k = 0; k < order.size(); ++k)
      for (uint32_t c = 0; c < 3; ++c) list[3 * k + c] = indices[3 * size_t(order[k]) + c];
    return analyze_vertex_cache(list, vertex_count, o).misses;
  }
  std::vector<uint32_t> entered(vertex_count, 0);
  uint32_t misses = 0;
  for (const uint32_t t : order)
    for (uint32_t c = 0; c < 3; ++c) {
      const uint32_t v = indices[3 * size_t(t) + c];
      if (entered[v] && misses - entered[v] < o.cache_size) continue;
      entered[v] = ++misses;
    }
  return misses;
}
}  // namespace

std::vector<uint32_t> vertex_cache_order(std::span<const uint32_t> indices, size_t vertex_count, const VertexCacheOptions& options) {
  if (indices.size() % 3) throw_usage("optimize_vertex_cache: the index count is not a multiple of 3");
  if (options.cache_size < 3 || options.cache_size > max_cache)
    throw_usage("optimize_vertex_cache: cache size must be in [3, " + std::to_string(max_cache) + "]");
  for (const uint32_t i : indices)
    if (i >= vertex_count) throw_usage("optimize_vertex_cache: index " + std::to_string(i) + " out of range");
  // Two orderers with different strengths, the analyzer deciding on the caller's cache: for a FIFO,
  // lodkit's fan orderer (exact fan costs) and Tipsify; for an LRU, the Forsyth-style walk (its cache
  // model is an LRU) and Tipsify. The input order is a candidate too, so the result is never worse.
  const uint32_t F = uint32_t(indices.size() / 3);
  std::vector<uint32_t> best(F);
  for (uint32_t t = 0; t < F; ++t) best[t] = t;
  uint64_t best_misses = cache_misses(indices, best, vertex_count, options);
  auto consider = [&](std::vector<uint32_t> order) {
    const uint64_t misses = cache_misses(indices, order, vertex_count, options);
    if (misses < best_misses) best_misses = misses, best = std::move(order);
  };
  const bool fifo = options.policy == CachePolicy::fifo;
  if (fifo) consider(detail::fan_cache_order(indices, vertex_count, {.cache_size = options.cache_size}));
  else consider(detail::greedy_cache_order(indices, vertex_count, detail::default_scoring(options.cache_size)));
  consider(detail::tipsify_order(indices, vertex_count, options.cache_size));
  // On a small mesh the first fan decides the sweep that follows, and the fewest-triangle start is
  // sometimes a poor one: the fan orderer also starts at the first corner of input triangles
  // 0, F/n, ... (the input's own start first), as many runs as fit in extra_start_triangles.
  const uint32_t extra_starts = fifo && F ? std::min(max_extra_starts, extra_start_triangles / F) : 0;
  for (uint32_t i = 0; i < extra_starts; ++i)
    consider(detail::fan_cache_order(indices, vertex_count,
                                     {.cache_size = options.cache_size, .start = indices[3 * (size_t(i) * F / extra_starts)]}));
  return best;
}

std::vector<uint32_t> optimize_vertex_cache(std::span<const uint32_t> indices, size_t vertex_count, const VertexCacheOptions& options) {
  const std::vector<uint32_t> order = vertex_cache_order(indices, vertex_count, options);
  std::vector<uint32_t> out(indices.size());
  for (size_t k = 0; k < order.size(); ++k)
    for (uint32_t c = 0; c < 3; ++c) out[3 * k + c] = indices[3 * size_t(order[k]) + c];
  return out;
}

}  // namespace lod
