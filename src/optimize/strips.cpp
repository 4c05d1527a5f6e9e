// Triangle strips. Both stripifiers walk the triangle connectivity graph (core/adjacency.h, keyed on
// the indices: a strip shares indices, not positions) across edges where the two triangles agree on
// winding, and never use a triangle twice.
//
// In a strip v0 v1 v2 v3 ..., triangle k is (v[k], v[k+1], v[k+2]), its winding reversed for odd k,
// and it leaves through the edge (v[k+1], v[k+2]): the walk has no choice of direction. A "swap"
// repeats v[k] between v[k+1] and v[k+2] (one extra index, one degenerate triangle), which makes the
// triangle leave through (v[k], v[k+2]) instead: the other edge of its newest vertex.
#include <algorithm>
#include <queue>

#include "core/adjacency.h"
#include "lodkit/error.h"
#include "lodkit/optimize.h"

namespace lod {

const char* strip_method_name(StripMethod method) { return method == StripMethod::sgi ? "sgi" : "best"; }

namespace {

constexpr uint32_t none = 0xFFFFFFFFu;

struct Graph {
  std::span<const uint32_t> indices;
  core::TriangleAdjacency adj;
  uint32_t corner(uint32_t t, uint32_t k) const { return indices[3 * t + k]; }
  // The neighbour across t's edge {a, b} that a strip may enter (winding agrees), or none.
  uint32_t across(uint32_t t, uint32_t a, uint32_t b, uint32_t* third) const {
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t p = corner(t, k), q = corner(t, (k + 1) % 3);
      if (!((p == a && q == b) || (p == b && q == a))) continue;
      const uint32_t h = adj.twin[3 * t + k];
      if (h == core::no_twin || adj.twin_same_direction[3 * t + k]) return none;
      *third = corner(h / 3, (h % 3 + 2) % 3);
      return h / 3;
    }
    return none;
  }
  uint32_t neighbour(uint32_t t, uint32_t k) const {
    const uint32_t h = adj.twin[3 * t + k];
    return h == core::no_twin || adj.twin_same_direction[3 * t + k] ? none : h / 3;
  }
};

// Appends one strip (made to start at even parity) and its triangles to the output with the requested
// join. Degenerate joins repeat the last index and the strip's first: ..., last, last, first, first,
// ... (four degenerate triangles). When that would put the strip at odd parity (every winding
// reversed), a strip of odd length goes in backwards instead, which reverses every winding once more;
// only a strip of even length then needs one more copy of its first index.
void append_strip(Strips& out, const uint32_t* seq, size_t length, const uint32_t* triangles, size_t triangle_count) {
  if (!length) return;
  std::vector<uint32_t>& b = out.indices;
  bool backwards = false;
  if (!b.empty()) {
    if (out.use_restart) {
      b.push_back(out.restart_index);
    } else {
      const bool odd_start = b.size() % 2 == 1;  // b.size() + 2 join indices, same parity
      backwards = odd_start && length % 2 == 1;
      const uint32_t first = backwards ? seq[length - 1] : seq[0];
      b.push_back(b.back());
      b.push_back(first);
      if (odd_start && !backwards) b.push_back(first);
    }
  }
  if (backwards) {
    b.insert(b.end(), std::reverse_iterator(seq + length), std::reverse_iterator(seq));
    out.triangle_order.insert(out.triangle_order.end(), std::reverse_iterator(triangles + triangle_count), std::reverse_iterator(triangles));
  } else {
    b.insert(b.end(), seq, seq + length);
    out.triangle_order.insert(out.triangle_order.end(), triangles, triangles + triangle_count);
  }
  ++out.strips;
}

// Joins strips as the stripifiers produce them. With degenerate joins the extra index is due only for
// an even-length strip at odd parity, and only odd-length strips change the parity: such a strip waits
// until an odd-length one has turned the parity even again, so the extra index is paid at most once.
class StripWriter {
 public:
  explicit StripWriter(Strips& out) : out_(out) {}
  void add(const std::vector<uint32_t>& seq, const std::vector<uint32_t>& triangles) {
    if (out_.use_restart || seq.size() % 2 == 1 || out_.indices.size() % 2 == 0) {
      append_strip(out_, seq.data(), seq.size(), triangles.data(), triangles.size());
      flush();
      return;
    }
    waiting_.push_back({seq_.size(), seq.size(), triangles_.size(), triangles.size()});
    seq_.insert(seq_.end(), seq.begin(), seq.end());
    triangles_.insert(triangles_.end(), triangles.begin(), triangles.end());
  }
  // Writes whatever still waits: at the front of the buffer, where the parity is even (the strips
  // waiting have even lengths, so what was written keeps its even start behind them).
  void finish() {
    if (waiting_.empty()) return;
    Strips front;
    front.use_restart = out_.use_restart;
    front.restart_index = out_.restart_index;
    for (const Waiting& w : waiting_)
      append_strip(front, seq_.data() + w.seq_begin, w.seq_size, triangles_.data() + w.triangles_begin, w.triangles_size);
    if (!out_.indices.empty()) {
      front.indices.push_back(front.indices.back());
      front.indices.push_back(out_.indices.front());
      front.indices.insert(front.indices.end(), out_.indices.begin(), out_.indices.end());
      front.triangle_order.insert(front.triangle_order.end(), out_.triangle_order.begin(), out_.triangle_order.end());
    }
    out_.indices = std::move(front.indices);
    out_.triangle_order = std::move(front.triangle_order);
    out_.strips += front.strips;
    waiting_.clear(), seq_.clear(), triangles_.clear();
  }

 private:
  struct Waiting {
    size_t seq_begin, seq_size, triangles_begin, triangles_size;
  };
  // After an odd-length strip the parity may be even again: the waiting strips go in free.
  void flush() {
    if (waiting_.empty() || out_.indices.size() % 2 == 1) return;
    for (const Waiting& w : waiting_)
      append_strip(out_, seq_.data() + w.seq_begin, w.seq_size, triangles_.data() + w.triangles_begin, w.triangles_size);
    waiting_.clear(), seq_.clear(), triangles_.clear();
  }
  Strips& out_;
  std::vector<Waiting> waiting_;
  std::vector<uint32_t> seq_, triangles_;
};

// The free-neighbour count of each triangle, with buckets to find a triangle of the fewest.
// Entries are lazy: one is valid while its triangle is unused and its count still matches.
struct FreeDegree {
  std::vector<uint8_t> degree;
  std::vector<uint8_t> used;
  // Per degree, a min-heap on the tie-break key (input order for SGI, cache order for best).
  std::priority_queue<std::pair<uint32_t, uint32_t>, std::vector<std::pair<uint32_t, uint32_t>>, std::greater<>> bucket[4];
  const std::vector<uint32_t>* key = nullptr;

  void init(const Graph& g, const std::vector<uint32_t>& tie_key) {
    key = &tie_key;
    const uint32_t F = uint32_t(g.adj.triangle_count());
    degree.assign(F, 0);
    used.assign(F, 0);
    for (uint32_t t = 0; t < F; ++t) {
      if (g.adj.degenerate[t]) {
        used[t] = 1;
        continue;
      }
      for (uint32_t k = 0; k < 3; ++k) degree[t] += g.neighbour(t, k) != none;
      bucket[degree[t]].push({tie_key[t], t});
    }
  }
  uint32_t pop_fewest() {
    for (auto& b : bucket)
      while (!b.empty()) {
        const auto [k, t] = b.top();
        b.pop();
        if (!used[t] && &b == &bucket[degree[t]]) return t;
      }
    return none;
  }
  void use(const Graph& g, uint32_t t) {
    used[t] = 1;
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t n = g.neighbour(t, k);
      if (n == none || used[n]) continue;
      --degree[n];
      bucket[degree[n]].push({(*key)[n], n});
    }
  }
};

// ---- SGI, as the course gives it ----------------------------------------------------------------
// 1. take a triangle with the fewest free neighbours; 2. start one strip through each of them;
// 3. extend each as far as it goes (a triangle is taken by one of these strips at most);
// 4. keep the longest, remove its triangles; 5. repeat while triangles are left.
void stripify_sgi(const Graph& g, Strips& out) {
  StripWriter writer(out);
  const uint32_t F = uint32_t(g.adj.triangle_count());
  std::vector<uint32_t> input_order(F);
  for (uint32_t t = 0; t < F; ++t) input_order[t] = t;
  FreeDegree free;
  free.init(g, input_order);
  std::vector<uint32_t> claimed(F, none);  // start triangle whose trial strips took the triangle
  std::vector<uint32_t> seq, tris, best_seq, best_tris;
  for (uint32_t start = free.pop_fewest(); start != none; start = free.pop_fewest()) {
    best_seq.clear(), best_tris.clear();
    claimed[start] = start;
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t first = g.neighbour(start, k);
      if (first == none || free.used[first] || claimed[first] == start) continue;
      // Order the start triangle so that it leaves through edge k, winding kept.
      seq = {g.corner(start, (k + 2) % 3), g.corner(start, k), g.corner(start, (k + 1) % 3)};
      tris = {start};
      uint32_t current = start;
      for (;;) {
        uint32_t third = none;
        const uint32_t n = g.across(current, seq[seq.size() - 2], seq.back(), &third);
        if (n == none || free.used[n] || claimed[n] == start) break;
        claimed[n] = start;
        seq.push_back(third);
        tris.push_back(n);
        current = n;
      }
      if (tris.size() > best_tris.size()) std::swap(seq, best_seq), std::swap(tris, best_tris);
    }
    if (best_tris.empty()) {
      best_seq = {g.corner(start, 0), g.corner(start, 1), g.corner(start, 2)};
      best_tris = {start};
    }
    for (const uint32_t t : best_tris) free.use(g, t);
    writer.add(best_seq, best_tris);
  }
  writer.finish();
}

// ---- best: lodkit's ------------------------------------------------------------------------------
// The greedy walk: starts, like SGI, at a triangle with the fewest free neighbours, ties going to the
// lowest rank (a vertex-cache order lays the strips down roughly in that order). From each triangle it can leave
// through its forced edge or, with a swap, through the other edge of its newest vertex; it takes the
// neighbour with fewer free neighbours of its own (a triangle left with none would become a strip of
// its own), the forced one on a tie.
void stripify_greedy(const Graph& g, const std::vector<uint32_t>& rank, Strips& out) {
  StripWriter writer(out);
  FreeDegree free;
  free.init(g, rank);
  std::vector<uint32_t> seq, tris;
  // Free neighbours of a candidate, not counting the current triangle (already marked used).
  auto free_degree_without = [&](uint32_t n) { return free.degree[n]; };
  for (uint32_t start = free.pop_fewest(); start != none; start = free.pop_fewest()) {
    free.use(g, start);
    // Leave through the edge whose neighbour has the fewest free neighbours (then the earliest).
    uint32_t exit = none, exit_neighbour = none;
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t n = g.neighbour(start, k);
      if (n == none || free.used[n]) continue;
      if (exit_neighbour == none || free_degree_without(n) < free_degree_without(exit_neighbour) ||
          (free_degree_without(n) == free_degree_without(exit_neighbour) && rank[n] < rank[exit_neighbour]))
        exit = k, exit_neighbour = n;
    }
    if (exit == none) exit = 0;
    seq = {g.corner(start, (exit + 2) % 3), g.corner(start, exit), g.corner(start, (exit + 1) % 3)};
    tris = {start};
    uint32_t current = start;
    for (;;) {
      const size_t n = seq.size();
      const uint32_t x = seq[n - 3], y = seq[n - 2], z = seq[n - 1];
      uint32_t forced_third = none, swap_third = none;
      uint32_t forced = g.across(current, y, z, &forced_third);
      uint32_t swapped = g.across(current, x, z, &swap_third);
      if (forced != none && free.used[forced]) forced = none;
      if (swapped != none && free.used[swapped]) swapped = none;
      if (forced == none && swapped == none) break;
      bool take_swap = forced == none;
      if (forced != none && swapped != none) take_swap = free_degree_without(swapped) < free_degree_without(forced);
      if (take_swap) {
        seq.insert(seq.end() - 1, x);
        seq.push_back(swap_third);
        current = swapped;
      } else {
        seq.push_back(forced_third);
        current = forced;
      }
      free.use(g, current);
      tris.push_back(current);
    }
    writer.add(seq, tris);
  }
  writer.finish();
}

}  // namespace

void append_strips(Strips& into, const Strips& more) {
  if (into.use_restart != more.use_restart || (into.use_restart && into.restart_index != more.restart_index))
    throw_usage("append_strips: the two buffers use different joins");
  if (more.indices.empty()) return;
  // `more` starts at even parity like any single strip: join it as one (backwards if that is cheaper;
  // then its triangle order is reversed too).
  const uint64_t strips = into.strips + more.strips;
  append_strip(into, more.indices.data(), more.indices.size(), more.triangle_order.data(), more.triangle_order.size());
  into.strips = strips;
  into.triangles += more.triangles;
  into.dropped_degenerate += more.dropped_degenerate;
}

Strips stripify(std::span<const uint32_t> indices, size_t vertex_count, const StripOptions& options) {
  if (indices.size() % 3) throw_usage("stripify: the index count is not a multiple of 3");
  for (const uint32_t i : indices) {
    if (i >= vertex_count) throw_usage("stripify: index " + std::to_string(i) + " out of range");
    if (options.use_restart && i == options.restart_index) throw_usage("stripify: an index equals the restart index");
  }
  Strips out;
  out.use_restart = options.use_restart;
  out.restart_index = options.restart_index;
  Graph g{indices, core::triangle_adjacency(indices, {}, vertex_count)};
  out.dropped_degenerate = g.adj.degenerate_triangles;
  out.indices.reserve(indices.size() / 2);
  out.triangle_order.reserve(indices.size() / 3);
  if (options.method == StripMethod::sgi) {
    stripify_sgi(g, out);
  } else {
    // The greedy walk with ties going to a vertex-cache order, then to the input order, and SGI: the
    // shortest buffer wins (all three are linear; on small or odd meshes each wins somewhere).
    const uint32_t F = uint32_t(indices.size() / 3);
    std::vector<uint32_t> rank(F);
    const std::vector<uint32_t> order =
        vertex_cache_order(indices, vertex_count, {.cache_size = options.cache_size, .policy = CachePolicy::fifo});
    for (uint32_t k = 0; k < F; ++k) rank[order[k]] = k;
    stripify_greedy(g, rank, out);
    // Small inputs also try random tie-breaks (a fixed seed: the result depends on the input only), as
    // many as keep the extra work near 20,000 triangle visits.
    const uint32_t random_tries = F ? std::min<uint32_t>(32, 20000 / F) : 0;
    uint64_t seed = 0x9E3779B97F4A7C15ull;
    for (uint32_t variant = 0; variant < 2 + random_tries; ++variant) {
      Strips other;
      other.use_restart = out.use_restart;
      other.restart_index = out.restart_index;
      other.dropped_degenerate = out.dropped_degenerate;
      if (variant == 0) {
        for (uint32_t t = 0; t < F; ++t) rank[t] = t;
        stripify_greedy(g, rank, other);
      } else if (variant == 1) {
        stripify_sgi(g, other);
      } else {
        for (uint32_t t = 0; t < F; ++t) {
          seed ^= seed >> 12, seed ^= seed << 25, seed ^= seed >> 27;  // xorshift64*
          rank[t] = uint32_t((seed * 0x2545F4914F6CDD1Dull) >> 32);
        }
        stripify_greedy(g, rank, other);
      }
      if (other.indices.size() < out.indices.size()) out = std::move(other);
    }
  }
  out.triangles = out.triangle_order.size();
  return out;
}

std::vector<uint32_t> unstripify(std::span<const uint32_t> strip, bool use_restart, uint32_t restart_index) {
  std::vector<uint32_t> out;
  out.reserve(strip.size() * 3);
  size_t begin = 0;  // the current strip's first index: parity counts from there
  for (size_t k = 0; k + 2 < strip.size(); ++k) {
    const uint32_t a = strip[k], b = strip[k + 1], c = strip[k + 2];
    if (use_restart && (a == restart_index || b == restart_index || c == restart_index)) {
      if (a == restart_index) begin = k + 1;
      continue;
    }
    if (a == b || b == c || a == c) continue;
    if ((k - begin) % 2 == 0) out.insert(out.end(), {a, b, c});
    else out.insert(out.end(), {b, a, c});
  }
  return out;
}

}  // namespace lod
