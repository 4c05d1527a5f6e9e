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
// orderer also runs from the input's own first vertex (the first fan sets the sweep that follows),
// in Tipsify's place.
// One call shares its vertex -> triangle lists and scratch memory between the candidates, and stops
// a candidate as soon as a lower bound on its misses shows it cannot win (see choose_order).
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <memory>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <meshoptimizer.h>

#include "core/buckets.h"
#include "lodkit/error.h"
#include "lodkit/optimize.h"
#include "optimize/vertex_cache.h"

namespace lod {

namespace detail {

namespace {
constexpr uint32_t none = 0xFFFFFFFFu;
}  // namespace

CacheScoring default_scoring(uint32_t cache_size, bool index_codec) {
  // Forsyth's published shape: the last triangle's own vertices score a little less than the next
  // ones (so the walk does not run off in a thin strip), then the score falls with age; a vertex with
  // few triangles left scores high (finishing it frees a slot for good). For the index codec the
  // other way round: a triangle on an edge of the last one codes in a few bits, so they score more
  // (1.25; 1.2 to 1.5 code within 0.1% of each other on the compress bench's meshes, 0.75 takes 4.9%
  // more bytes), and the walk runs in strips.
  CacheScoring s;
  s.cache_size = cache_size;
  s.model = CachePolicy::lru;
  for (uint32_t p = 0; p < cache_size; ++p)
    s.cache[p] = p < 3 ? (index_codec ? 1.25f : 0.75f) : std::pow(1.0f - float(p - 3) / float(cache_size - 3), 1.5f);
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
  core::Buckets<uint32_t> around = core::bucket<uint32_t>(V, [&](auto&& emit) {
    for (uint32_t c = 0; c < indices.size(); ++c) emit(indices[c], c / 3);
  });
  const std::vector<uint32_t>& offset = around.first;
  std::vector<uint32_t>& triangles = around.items;
  std::vector<uint32_t> live(V);
  for (uint32_t v = 0; v < V; ++v) live[v] = offset[v + 1] - offset[v];

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

namespace {

constexpr uint64_t stopped = ~uint64_t(0);  // a bounded run that stopped: it could not beat its limit

// Scratch memory for one call, handed out in order and freed when the call ends: the first 4 KiB
// on the stack (a small input needs no allocation), then heap blocks, one per reserve() that does
// not fit.
class Workspace {
 public:
  Workspace() = default;
  Workspace(const Workspace&) = delete;
  Workspace& operator=(const Workspace&) = delete;
  // The next `words` of take() come from one block.
  void reserve(size_t words) {
    if (size_ - used_ >= words) return;
    blocks_.push_back(std::make_unique_for_overwrite<uint32_t[]>(words));
    base_ = blocks_.back().get(), size_ = words, used_ = 0;
  }
  uint32_t* take(size_t words) {
    reserve(words);
    uint32_t* p = base_ + used_;
    used_ += words;
    return p;
  }

 private:
  static constexpr size_t stack_words = 1024;
  uint32_t stack_[stack_words];
  std::vector<std::unique_ptr<uint32_t[]>> blocks_;
  uint32_t* base_ = stack_;
  size_t size_ = stack_words, used_ = 0;
};

// Vertex -> triangles (CSR). Every orderer starts from each vertex's triangles in ascending order
// (the fan orderer reorders them as it removes triangles, so they are filled again before the next).
struct Adjacency {
  uint32_t* offset = nullptr;     // V + 1
  uint32_t* triangles = nullptr;  // 3F
  uint32_t max_triangles = 0;     // the most triangles around one vertex
};

void fill_triangles(std::span<const uint32_t> indices, uint32_t V, const Adjacency& a, uint32_t* cursor) {
  std::fill_n(cursor, V, 0u);
  const uint32_t F = uint32_t(indices.size() / 3);
  for (uint32_t t = 0; t < F; ++t)
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t v = indices[3 * size_t(t) + k];
      a.triangles[a.offset[v] + cursor[v]++] = t;
    }
}

// offset[v + 1] must hold v's triangle count; makes the offsets.
void make_offsets(uint32_t V, Adjacency& a) {
  a.offset[0] = 0;
  for (uint32_t v = 0; v < V; ++v) {
    a.max_triangles = std::max(a.max_triangles, a.offset[v + 1]);
    a.offset[v + 1] += a.offset[v];
  }
}

Adjacency build_adjacency(std::span<const uint32_t> indices, uint32_t V, Workspace& ws) {
  Adjacency a;
  a.offset = ws.take(size_t(V) + 1);
  a.triangles = ws.take(indices.size());
  std::fill_n(a.offset, size_t(V) + 1, 0u);
  for (const uint32_t i : indices) ++a.offset[i + 1];
  make_offsets(V, a);
  fill_triangles(indices, V, a, ws.take(V));
  return a;
}

// The first centre by default: the vertex with the fewest triangles (a border or a corner).
uint32_t fewest_triangles_vertex(const uint32_t* offset, uint32_t V) {
  uint32_t best = none, best_count = 0;
  for (uint32_t v = 0; v < V; ++v) {
    const uint32_t count = offset[v + 1] - offset[v];
    if (count && (best == none || count < best_count)) best = v, best_count = count;
  }
  return best;
}

// Lower bound used to stop a run early: a run that has made `misses` misses, with `pending` vertices
// that still have triangles but are not cached, ends with at least misses + pending misses (each of
// those vertices is loaded again). Once that reaches `limit` (the best order so far, which a later
// candidate must beat strictly), the run cannot win and stops.

// Set bits per byte value (std::popcount is a library call without the popcnt instruction, which is
// not in the x86-64 baseline).
constexpr auto byte_bit_count = [] {
  std::array<uint8_t, 256> table{};
  for (uint32_t b = 1; b < 256; ++b) table[b] = uint8_t((b & 1) + table[b >> 1]);
  return table;
}();

// The fan orderer's state of one vertex, kept together: the orderer reads them together.
struct FanVertex {
  uint32_t entered;        // the miss count when it entered the FIFO; 0 when not cached
  uint32_t live;           // triangles left: the first `live` of its list
  uint32_t corner_misses;  // over its live triangles, the corners not cached
  uint32_t first;          // its list's offset
};

struct FanBuffers {
  FanVertex* vertices;  // V
  uint32_t *dead_end, *ring;  // 3F, K
};

// The fan orderer (see fan_cache_order) from `focus`, on fresh lists. Writes the order and returns
// its FIFO misses (its simulated cache is the caller's), or `stopped`.
uint64_t fan_run(std::span<const uint32_t> indices, uint32_t V, const Adjacency& adjacency, const FanScoring& scoring, uint32_t focus,
                 const FanBuffers& b, uint64_t limit, uint32_t* order) {
  const uint32_t K = scoring.cache_size;
  uint32_t* const triangles = adjacency.triangles;
  FanVertex* const vx = b.vertices;
  uint32_t* const dead_end = b.dead_end;
  // The ring twice over (entry s also at s + K), so the q-th oldest is ring[head + q] without a wrap.
  uint32_t ring[2 * max_cache_size];
  // The FIFO: a ring of K entries (ring[head] is the oldest, overwritten by the next miss) and the
  // miss count at which each cached vertex entered (0 when it is not cached: eviction clears it).
  // Per vertex, the corner misses of its fan: over its live triangles, the corners not cached (a
  // corner shared by two of them counts twice). Kept up to date as triangles leave and vertices enter
  // or leave the cache. A centre's fan costs about that many misses, fewer where corners are shared;
  // counting them all favours fans whose new corners are also needed by their neighbours' fans.
  uint32_t pending = 0;
  for (uint32_t v = 0; v < V; ++v) {
    const uint32_t first = adjacency.offset[v], live = adjacency.offset[v + 1] - first;
    vx[v] = {0, live, 3 * live, first};
    pending += live != 0;
  }
  std::fill_n(ring, 2 * K, none);
  // Bit s: ring[s] holds a vertex with triangles left.
  uint64_t working = 0;
  auto low_bits = [](uint32_t count) { return count >= 64 ? ~uint64_t(0) : (uint64_t(1) << count) - 1; };
  uint32_t head = 0, time = 0, emitted = 0, dead_end_size = 0, cursor = 0;
  auto slot_bit = [&](uint32_t v) {  // v is cached: it entered time - entered misses before the newest entry
    const uint32_t back = time - vx[v].entered + 1;
    return uint64_t(1) << (head >= back ? head - back : head + K - back);
  };
  if (uint64_t(time) + pending >= limit) return stopped;
  // The next centre's candidates (the cached entries with triangles left).
  uint32_t candidate_vertex[max_cache_size];
  int32_t candidate_misses[max_cache_size + 3], candidate_live[max_cache_size + 3], candidate_pushed[max_cache_size + 3];
  float candidate_cost[max_cache_size + 3];
  auto cached = [&](uint32_t v) { return vx[v].entered != 0; };
  auto add_to_corners = [&](const FanVertex& w, int32_t delta) {  // w entered (-1) or left (+1) the cache
    for (uint32_t i = w.first, e = w.first + w.live; i < e; ++i) {
      const uint32_t* c = &indices[3 * size_t(triangles[i])];
      vx[c[0]].corner_misses += delta, vx[c[1]].corner_misses += delta, vx[c[2]].corner_misses += delta;
    }
  };
  auto emit = [&](uint32_t t) {
    order[emitted++] = t;
    const uint32_t* c = &indices[3 * size_t(t)];
    const uint32_t uncached = uint32_t(!cached(c[0])) + !cached(c[1]) + !cached(c[2]);
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t v = c[k];
      FanVertex& x = vx[v];
      x.corner_misses -= uncached;
      uint32_t* list = triangles + x.first;
      const uint32_t n = x.live;
      uint32_t j = 0;
      while (list[j] != t) ++j;  // t is live around each of its corners
      list[j] = list[n - 1], list[n - 1] = t;
      x.live = n - 1;
      if (n == 1) {
        if (x.entered) working &= ~slot_bit(v);
        else --pending;
      }
    }
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t v = c[k];
      dead_end[dead_end_size++] = v;
      FanVertex& x = vx[v];
      if (x.entered) continue;
      const uint32_t evicted = ring[head];
      if (evicted != none) {
        FanVertex& y = vx[evicted];
        y.entered = 0;
        add_to_corners(y, +1);
        pending += y.live != 0;
      }
      ring[head] = ring[head + K] = v;
      working = x.live ? working | uint64_t(1) << head : working & ~(uint64_t(1) << head);
      head = head + 1 == K ? 0 : head + 1;
      x.entered = ++time;
      add_to_corners(x, -1);
      pending -= x.live != 0;
    }
  };
  auto misses_of = [&](const uint32_t* c) { return uint32_t(!cached(c[0])) + !cached(c[1]) + !cached(c[2]); };

  while (focus != none) {
    // The fan, cheapest triangle first; on a tie, the one holding the oldest cached corner besides
    // the centre (use it before it leaves).
    while (vx[focus].live) {
      const uint32_t* list = triangles + vx[focus].first;
      const uint32_t live = vx[focus].live;
      auto oldest_corner = [&](const uint32_t* c) {
        uint32_t oldest = 0xFFFFFFFFu;
        for (uint32_t k = 0; k < 3; ++k) {
          const uint32_t w = c[k];
          if (w != focus && cached(w)) oldest = std::min(oldest, vx[w].entered);
        }
        return oldest;
      };
      uint32_t best = list[0];
      if (live > 1) {  // (the last triangle of a fan, the common case, needs no choice)
        const uint32_t* c = &indices[3 * size_t(best)];
        uint32_t best_misses = misses_of(c), best_oldest = oldest_corner(c);
        for (uint32_t j = 1; j < live; ++j) {
          c = &indices[3 * size_t(list[j])];
          const uint32_t m = misses_of(c);
          if (m > best_misses) continue;
          const uint32_t oldest = oldest_corner(c);
          if (m < best_misses || oldest < best_oldest) best = list[j], best_misses = m, best_oldest = oldest;
        }
      }
      emit(best);
      if (uint64_t(time) + pending >= limit) return stopped;
    }
    // The next centre: the cached vertex whose fan costs least, the oldest on ties. Its cost: corner
    // misses per triangle, plus a weight per entry the fan would push out that still has triangles
    // (not counting the centre), plus a weight per triangle.
    // Only the entries with triangles left, oldest first: bit q of `by_age` is the q-th oldest entry.
    const uint64_t by_age = head == 0 ? working : (working >> head | working << (K - head)) & low_bits(K);
    // The entries with triangles among the e oldest: whole bytes of by_age counted once per fan, the
    // last partial byte by table.
    uint32_t before_byte[max_cache_size / 8 + 1];
    before_byte[0] = 0;
    for (uint32_t i = 0; 8 * i < K; ++i) before_byte[i + 1] = before_byte[i] + byte_bit_count[by_age >> 8 * i & 0xFF];
    auto older_working = [&](uint32_t e) {
      const uint32_t partial = e & 7;
      return before_byte[e >> 3] + (partial ? byte_bit_count[by_age >> (e - partial) & ((1u << partial) - 1)] : 0u);
    };
    // The entries' counts first, then their costs in one loop the compiler vectorises, then the
    // first (oldest) of the cheapest.
    uint32_t candidate_count = 0;
    for (uint64_t bits = by_age; bits; bits &= bits - 1) {
      const uint32_t q = uint32_t(std::countr_zero(bits));
      const uint32_t v = ring[head + q];
      const uint32_t n = vx[v].corner_misses;
      // About n / 2 distinct vertices enter (inner corners are shared by two triangles of the fan).
      const uint32_t entering = std::min(n / 2, K);
      candidate_vertex[candidate_count] = v;
      candidate_misses[candidate_count] = int32_t(n);
      candidate_live[candidate_count] = int32_t(vx[v].live);
      candidate_pushed[candidate_count] = int32_t(older_working(entering) - (q < entering ? 1u : 0u));
      ++candidate_count;
    }
#if defined(__SSE2__)
    // Four at a time, the same operations in the same order as the scalar form (so the same costs);
    // the last group is padded with harmless values.
    for (uint32_t i = candidate_count; i % 4; ++i) candidate_misses[i] = 0, candidate_live[i] = 1, candidate_pushed[i] = 0;
    const __m128 eviction_weight = _mm_set1_ps(scoring.eviction_weight), live_weight = _mm_set1_ps(scoring.live_weight);
    for (uint32_t i = 0; i < candidate_count; i += 4) {
      const __m128 n = _mm_cvtepi32_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(candidate_misses + i)));
      const __m128 live = _mm_cvtepi32_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(candidate_live + i)));
      const __m128 pushed = _mm_cvtepi32_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(candidate_pushed + i)));
      const __m128 cost = _mm_add_ps(_mm_div_ps(_mm_add_ps(n, _mm_mul_ps(eviction_weight, pushed)), live), _mm_mul_ps(live_weight, live));
      _mm_storeu_ps(candidate_cost + i, cost);
    }
#else
    for (uint32_t i = 0; i < candidate_count; ++i)
      candidate_cost[i] = (float(candidate_misses[i]) + scoring.eviction_weight * float(candidate_pushed[i])) / float(candidate_live[i]) +
                          scoring.live_weight * float(candidate_live[i]);
#endif
    focus = none;
    float best_cost = INFINITY;  // every cost is finite (live >= 1): the first entry always beats it
    for (uint32_t i = 0; i < candidate_count; ++i) {
      const bool better = candidate_cost[i] < best_cost;
      best_cost = better ? candidate_cost[i] : best_cost;
      focus = better ? candidate_vertex[i] : focus;
    }
    if (focus != none) continue;
    // Dead end: the most recently used vertex with triangles left, else the next in input order.
    while (dead_end_size && focus == none) {
      const uint32_t v = dead_end[--dead_end_size];
      if (vx[v].live) focus = v;
    }
    while (focus == none && cursor < V) {
      if (vx[cursor].live) focus = cursor;
      ++cursor;
    }
  }
  return time;
}

struct TipsifyBuffers {
  uint32_t *live, *entered, *dead_end, *candidates, *ring;  // V, V, 3F, 3 * max_triangles, K
  uint8_t* emitted;                                         // F
};

// Tipsify (Sander, Nehab and Barczak, 2007) on fresh lists: fan around one vertex at a time (emit
// all its remaining triangles), then move to the neighbour that will still be cached after its own
// fan, the oldest such first; at a dead end, back to the most recently used vertex with triangles
// left. Writes the order and returns its FIFO misses, or `stopped`.
uint64_t tipsify_run(std::span<const uint32_t> indices, uint32_t V, const Adjacency& adjacency, uint32_t cache_size,
                     const TipsifyBuffers& b, uint64_t limit, uint32_t* order) {
  const uint32_t F = uint32_t(indices.size() / 3);
  const uint32_t* offset = adjacency.offset;
  const uint32_t* triangles = adjacency.triangles;
  uint32_t *const live = b.live, *const entered = b.entered, *const dead_end = b.dead_end, *const candidates = b.candidates;
  uint32_t* const ring = b.ring;  // the last cache_size vertices to enter, for the bound (ring[slot] leaves next)
  uint8_t* const emitted = b.emitted;
  uint32_t pending = 0;
  for (uint32_t v = 0; v < V; ++v) {
    live[v] = offset[v + 1] - offset[v];
    entered[v] = 0;  // the clock when the vertex entered the FIFO (0: never)
    pending += live[v] != 0;
  }
  std::fill_n(emitted, F, uint8_t(0));
  std::fill_n(ring, cache_size, none);
  // The clock counts misses from cache_size + 1, so a vertex that never entered is never cached.
  // (32 bits: enough for inputs of up to 1.4 billion triangles.)
  const uint32_t clock_start = cache_size + 1;
  uint32_t time = clock_start, slot = 0, order_size = 0, dead_end_size = 0, cursor = 0;
  if (uint64_t(time - clock_start) + pending >= limit) return stopped;
  uint32_t fan = F ? indices[0] : none;
  while (fan != none) {
    uint32_t candidate_count = 0;
    for (uint32_t j = offset[fan]; j < offset[fan + 1]; ++j) {
      const uint32_t t = triangles[j];
      if (emitted[t]) continue;
      emitted[t] = 1;
      order[order_size++] = t;
      for (uint32_t k = 0; k < 3; ++k) {
        const uint32_t v = indices[3 * size_t(t) + k];
        dead_end[dead_end_size++] = v;
        candidates[candidate_count++] = v;
        --live[v];
        if (time - entered[v] > cache_size) {
          const uint32_t evicted = ring[slot];
          if (evicted != none) pending += live[evicted] != 0;
          ring[slot] = v;
          slot = slot + 1 == cache_size ? 0 : slot + 1;
          --pending;  // v had this triangle left and was not cached
          entered[v] = time++;
        }
      }
      if (uint64_t(time - clock_start) + pending >= limit) return stopped;
    }
    // The next fan: a candidate that stays cached through its own fan (about two misses per
    // triangle), the oldest in the cache first.
    fan = none;
    uint32_t best = 0;
    for (uint32_t i = 0; i < candidate_count; ++i) {
      const uint32_t v = candidates[i];
      if (!live[v]) continue;
      const uint32_t age = time - entered[v];
      if (uint64_t(age) + 2 * uint64_t(live[v]) <= cache_size && age > best) best = age, fan = v;
    }
    if (fan != none) continue;
    while (dead_end_size && fan == none) {
      const uint32_t v = dead_end[--dead_end_size];
      if (live[v]) fan = v;
    }
    while (fan == none && cursor < V) {
      if (live[cursor]) fan = cursor;
      ++cursor;
    }
  }
  return time - clock_start;
}

}  // namespace

std::vector<uint32_t> tipsify_order(std::span<const uint32_t> indices, size_t vertex_count, uint32_t cache_size) {
  const uint32_t F = uint32_t(indices.size() / 3), V = uint32_t(vertex_count);
  Workspace ws;
  ws.reserve(4 * size_t(V) + 1 + 6 * size_t(F) + cache_size + (size_t(F) + 3) / 4);
  const Adjacency a = build_adjacency(indices, V, ws);
  TipsifyBuffers b{ws.take(V), ws.take(V), ws.take(3 * size_t(F)), nullptr, ws.take(cache_size),
                   reinterpret_cast<uint8_t*>(ws.take((size_t(F) + 3) / 4))};
  b.candidates = ws.take(3 * size_t(a.max_triangles));
  std::vector<uint32_t> order(F);
  tipsify_run(indices, V, a, cache_size, b, stopped, order.data());
  return order;
}

std::vector<uint32_t> fan_cache_order(std::span<const uint32_t> indices, size_t vertex_count, const FanScoring& scoring) {
  const uint32_t F = uint32_t(indices.size() / 3), V = uint32_t(vertex_count), K = scoring.cache_size;
  Workspace ws;
  ws.reserve(6 * size_t(V) + 1 + 6 * size_t(F) + K);
  const Adjacency a = build_adjacency(indices, V, ws);
  const FanBuffers b{reinterpret_cast<FanVertex*>(ws.take(4 * size_t(V))), ws.take(3 * size_t(F)), ws.take(K)};
  // Start around the given vertex, else the vertex with the fewest triangles.
  const uint32_t focus = scoring.start < V && a.offset[scoring.start + 1] > a.offset[scoring.start] ? scoring.start
                                                                                                    : fewest_triangles_vertex(a.offset, V);
  std::vector<uint32_t> order(F);
  fan_run(indices, V, a, scoring, focus, b, stopped, order.data());
  return order;
}

}  // namespace detail

namespace {
constexpr uint32_t max_cache = detail::max_cache_size;
using detail::extra_start_triangles;
using detail::max_extra_starts;

// The chosen order, kept in the workspace; nullptr when it is the input order.
//
// Every candidate is scored by its misses on the caller's cache, and the first with the fewest
// wins: the input order, then for a FIFO the fan orderer and its extra starts (small inputs) or
// else Tipsify; for an LRU the Forsyth-style walk and Tipsify (for the index codec: the strip walk,
// kept only where its indices code in fewer bytes than the input's). For a FIFO the orderers' own
// simulated caches are the caller's, so their miss counts need no separate simulation, and a run
// stops as soon as its lower bound (detail::fan_run) shows it cannot beat the best so far; when the
// best needs one miss per referenced vertex nothing can beat it and no orderer runs. None of this
// changes which order wins.
const uint32_t* choose_order(std::span<const uint32_t> indices, size_t vertex_count, const VertexCacheOptions& options,
                             detail::Workspace& ws, std::vector<uint32_t>& lru_order) {
  if (indices.size() % 3) throw_usage("optimize_vertex_cache: the index count is not a multiple of 3");
  if (options.cache_size < 3 || options.cache_size > max_cache)
    throw_usage("optimize_vertex_cache: cache size must be in [3, " + std::to_string(max_cache) + "]");
  const uint32_t F = uint32_t(indices.size() / 3), K = options.cache_size;
  auto check_index = [&](uint32_t i) {
    if (i >= vertex_count) throw_usage("optimize_vertex_cache: index " + std::to_string(i) + " out of range");
  };

  if (options.policy == CachePolicy::lru)
    for (const uint32_t i : indices) check_index(i);
  if (options.policy == CachePolicy::lru && options.index_codec) {
    // For the index codec the order whose indices code in the fewest bytes (numbered by first use, as
    // the fetch order then numbers them): the input's, or the walk's in strips. Not the fewer misses:
    // a FIFO-ordered input (a LOD chain's levels) often has fewer LRU misses than the strips and
    // codes 23-30% larger (bunny00's chain).
    std::vector<uint32_t> list(indices.size()), first_use(vertex_count);
    std::vector<unsigned char> buffer;
    auto bytes_of = [&](const std::vector<uint32_t>* order) {
      std::fill(first_use.begin(), first_use.end(), detail::none);
      uint32_t next = 0;
      for (size_t k = 0; k < F; ++k)
        for (uint32_t c = 0; c < 3; ++c) {
          const uint32_t v = indices[3 * size_t(order ? (*order)[k] : uint32_t(k)) + c];
          if (first_use[v] == detail::none) first_use[v] = next++;
          list[3 * k + c] = first_use[v];
        }
      meshopt_encodeIndexVersion(1);  // (EXT_meshopt_compression's; the writer sets it again)
      buffer.resize(meshopt_encodeIndexBufferBound(list.size(), next));
      return meshopt_encodeIndexBuffer(buffer.data(), buffer.size(), list.data(), list.size());
    };
    const size_t input_bytes = bytes_of(nullptr);
    lru_order = detail::greedy_cache_order(indices, vertex_count, detail::default_scoring(K, true));
    return bytes_of(&lru_order) < input_bytes ? lru_order.data() : nullptr;
  }
  if (options.policy == CachePolicy::lru) {
    auto misses_of = [&](const std::vector<uint32_t>& order) {
      std::vector<uint32_t> list(indices.size());
      for (size_t k = 0; k < order.size(); ++k)
        for (uint32_t c = 0; c < 3; ++c) list[3 * k + c] = indices[3 * size_t(order[k]) + c];
      return analyze_vertex_cache(list, vertex_count, options).misses;
    };
    const VertexCacheStats input = analyze_vertex_cache(indices, vertex_count, options);
    uint64_t best_misses = input.misses;
    if (best_misses == input.referenced_vertices) return nullptr;  // one miss per vertex: nothing does better
    bool input_best = true;
    auto consider = [&](std::vector<uint32_t> order) {
      const uint64_t misses = misses_of(order);
      if (misses < best_misses) best_misses = misses, lru_order = std::move(order), input_best = false;
    };
    consider(detail::greedy_cache_order(indices, vertex_count, detail::default_scoring(K)));
    consider(detail::tipsify_order(indices, vertex_count, K));
    return input_best ? nullptr : lru_order.data();
  }

  // FIFO. One pass checks the indices, counts each vertex's triangles and simulates the input order.
  const uint32_t V = uint32_t(vertex_count);
  ws.reserve(2 * size_t(V) + 1);
  detail::Adjacency a;
  a.offset = ws.take(size_t(V) + 1);
  uint32_t* const stamp = ws.take(V);  // the input simulation's entry stamps, then scratch
  std::fill_n(a.offset, size_t(V) + 1, 0u);
  std::fill_n(stamp, V, 0u);
  uint32_t misses = 0, referenced = 0;
  for (const uint32_t v : indices) {
    check_index(v);
    ++a.offset[v + 1];
    if (stamp[v] && misses - stamp[v] < K) continue;
    referenced += stamp[v] == 0;
    stamp[v] = ++misses;
  }
  uint64_t best_misses = misses;
  if (best_misses == referenced) return nullptr;  // one miss per vertex: no order does better

  detail::make_offsets(V, a);
  // The lists (and a spare copy on small inputs), two orders, the fan orderer's and Tipsify's buffers.
  ws.reserve(3 * size_t(F) + (F <= extra_start_triangles ? 3 * size_t(F) : 0) + 2 * size_t(F) + 4 * size_t(V) + 3 * size_t(F) + K + V +
             3 * size_t(a.max_triangles) + (size_t(F) + 3) / 4);
  a.triangles = ws.take(indices.size());
  detail::fill_triangles(indices, V, a, stamp);
  uint32_t* buffers[2] = {ws.take(F), ws.take(F)};
  int best = -1;  // index into buffers, -1: the input order
  const detail::FanBuffers fan{reinterpret_cast<detail::FanVertex*>(ws.take(4 * size_t(V))), ws.take(3 * size_t(F)), ws.take(K)};
  const detail::TipsifyBuffers tipsify{ws.take(V), stamp, fan.dead_end, ws.take(3 * size_t(a.max_triangles)), fan.ring,
                                       reinterpret_cast<uint8_t*>(ws.take((size_t(F) + 3) / 4))};
  // Each orderer starts from the lists in ascending order, which the fan orderer reorders: with the
  // extra starts (small inputs) they are copied back from a spare copy, else filled again.
  const uint32_t extra_starts = std::min(max_extra_starts, extra_start_triangles / F);
  uint32_t* const pristine = extra_starts ? ws.take(indices.size()) : nullptr;
  if (pristine) std::copy_n(a.triangles, indices.size(), pristine);
  bool fresh = true;
  auto run = [&](auto&& orderer) {
    if (!fresh) {
      if (pristine) std::copy_n(pristine, indices.size(), a.triangles);
      else detail::fill_triangles(indices, V, a, tipsify.live);
    }
    fresh = false;
    uint32_t* const candidate = buffers[best == 0 ? 1 : 0];
    const uint64_t m = orderer(candidate);
    if (m < best_misses) best_misses = m, best = candidate == buffers[0] ? 0 : 1;
  };
  const detail::FanScoring scoring{.cache_size = K};
  const uint32_t first_start = detail::fewest_triangles_vertex(a.offset, V);
  run([&](uint32_t* order) { return detail::fan_run(indices, V, a, scoring, first_start, fan, best_misses, order); });
  // On a small mesh the first fan decides the sweep that follows, and the fewest-triangle start is
  // sometimes a poor one: the fan orderer also starts at the first corner of input triangles
  // 0, F/n, ... (the input's own start first), as many runs as fit in extra_start_triangles (one run,
  // from the input's start, on inputs of at most 1,024 triangles: more starts gained 0.7% fewer
  // misses on the corpus and cost up to twice meshoptimizer's whole time). A start already tried
  // gives the same order again, which cannot win, and is skipped. The extra starts take Tipsify's
  // place (with one, Tipsify never gave the fewest misses on a corpus mesh), so Tipsify runs only
  // when no extra start did.
  uint32_t tried[max_extra_starts + 1] = {first_start};
  uint32_t tried_count = 1;
  for (uint32_t i = 0; i < extra_starts; ++i) {
    const uint32_t start = indices[3 * (size_t(i) * F / extra_starts)];
    if (std::find(tried, tried + tried_count, start) != tried + tried_count) continue;
    tried[tried_count++] = start;
    run([&](uint32_t* order) { return detail::fan_run(indices, V, a, scoring, start, fan, best_misses, order); });
  }
  if (tried_count == 1) run([&](uint32_t* order) { return detail::tipsify_run(indices, V, a, K, tipsify, best_misses, order); });
  return best < 0 ? nullptr : buffers[best];
}
}  // namespace

std::vector<uint32_t> vertex_cache_order(std::span<const uint32_t> indices, size_t vertex_count, const VertexCacheOptions& options) {
  detail::Workspace ws;
  std::vector<uint32_t> lru_order;
  const uint32_t* chosen = choose_order(indices, vertex_count, options, ws, lru_order);
  const uint32_t F = uint32_t(indices.size() / 3);
  std::vector<uint32_t> order(F);
  for (uint32_t t = 0; t < F; ++t) order[t] = chosen ? chosen[t] : t;
  return order;
}

std::vector<uint32_t> optimize_vertex_cache(std::span<const uint32_t> indices, size_t vertex_count, const VertexCacheOptions& options) {
  detail::Workspace ws;
  std::vector<uint32_t> lru_order;
  const uint32_t* chosen = choose_order(indices, vertex_count, options, ws, lru_order);
  if (!chosen) return std::vector<uint32_t>(indices.begin(), indices.end());
  std::vector<uint32_t> out(indices.size());
  for (size_t k = 0; k < out.size() / 3; ++k)
    for (uint32_t c = 0; c < 3; ++c) out[3 * k + c] = indices[3 * size_t(chosen[k]) + c];
  return out;
}

}  // namespace lod
