// The collapse engine: passes of independent edge collapses, cheapest first.
//
// Each pass rebuilds the position -> triangles table, lets the metric refresh (memoryless rebuilds
// its quadrics), evaluates every edge in parallel (each position keeps its cheapest edge to a
// higher position), then applies the cheapest candidates in cost order. A collapse locks every
// position around it for the rest of the pass, so the candidates applied later were evaluated on
// exactly the neighbourhood they change: the result is the same on any number of threads, and no
// adjacency is updated (or allocated) per collapse. With qem and cqem, a distance guard holds back
// collapses that would leave an end's input point far from the result (distance_excess).
#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <tuple>
#include <thread>
#include <type_traits>

#include "core/heap.h"
#include "core/parallel.h"
#include "core/union_find.h"
#include "lodkit/error.h"
#include "lodkit/measure.h"
#include "measure/triangle_distance.h"
#include "simplify/edge_length.h"
#include "simplify/fit.h"
#include "simplify/multipose_metric.h"
#include "simplify/quadric_metric.h"
#include "simplify/record.h"

namespace lod {

const char* metric_name(Metric metric) {
  switch (metric) {
    case Metric::edge_length: return "edge";
    case Metric::qem: return "qem";
    case Metric::constrained_qem: return "cqem";
    case Metric::memoryless: return "memoryless";
    case Metric::constrained_memoryless: return "cmemoryless";
  }
  return "?";
}

namespace collapse {
namespace {

using clock = std::chrono::steady_clock;
constexpr uint32_t none = ~0u;

double seconds(clock::time_point a, clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

// Per-thread scratch for evaluating one edge; reused so evaluation allocates nothing in steady state.
struct Scratch {
  std::vector<uint32_t> removed_faces, neighbours_u, neighbours_v, kept_wedges, candidates, extra;
  std::vector<uint64_t> keys;  // best_checked: edges by cost
  std::vector<WedgePair> pairs[2];
  std::vector<measure::vec3f> fan;  // distance_excess: the fan's far corners
  // The removed faces of the edge being evaluated (at most two get that far) and per face its
  // corner that is neither end.
  uint32_t face[2] = {}, face_count = 0, opposite[2] = {};
  std::span<const uint32_t> faces() const { return {face, face_count}; }
};

// What the engine decided for one edge.
struct Decision {
  uint32_t kept = none, removed = none;
  bool fixed = false;
  Placement placement;
  int direction = 0;  // index of the pairs in Scratch
};

enum class Reject { ok, topology, seam, flip, shape, distance };

template <class MetricT>
class Engine {
 public:
  Engine(State& state, MetricT& metric, SimplifyResult& result) : s_(state), metric_(metric), result_(result) {}

  void run(uint64_t target_triangles, double cost_limit) {
    const uint64_t start_triangles = s_.live_triangles;
    core::reserve_huge(s_.live, s_.live_triangles);
    for (uint32_t t = 0; t < s_.alive.size(); ++t)
      if (s_.alive[t]) s_.live.push_back(t);
    bool first = true;
    SimplifyResult::CollapseSteps& steps = result_.seconds_steps;
    while (s_.live_triangles > target_triangles) {
      clock::time_point mark = clock::now();
      // Adds the time since the last step's end to `step`.
      const auto lap = [&](double& step) {
        const clock::time_point now = clock::now();
        step += seconds(mark, now);
        mark = now;
      };
      build_star();
      lap(steps.stars);
      roll_flags(first);
      if (first) classify();
      if (aggregate_) {
        if (first) find_virtual_pairs();
        update_virtual_pairs();
      }
      if (first) metric_.initialize(s_);
      else metric_.begin_pass(s_);
      ++result_.passes;
      evaluate_all(first);
      lap(steps.ranking);
      first = false;
      // Candidates as (cost, position) keys: sorting the integers orders them by cost, then position,
      // without an indirection per comparison (NaN costs never pass the limit test).
      std::vector<uint64_t>& order = order_;
      order.clear();
      core::reserve_huge(order, s_.position_count);
      for (uint32_t u = 0; u < s_.position_count; ++u)
        if (best_[u].other != none && best_[u].cost <= cost_limit) order.push_back(sort_key(best_[u].cost, u));
      if (order.empty() && guard_ > 0 && release_held()) continue;
      if (order.empty()) break;

      // This pass applies at most a third of the live positions' worth of collapses, fewer as the
      // mesh nears its target (a thirty-third there), and never more than are still needed. A pass
      // applies candidates ranked before its earlier collapses changed the costs around them; finer
      // passes track the greedy order more closely, which matters most for the last, coarse
      // collapses (corpus at 1%: Hausdorff distance -5% in geometric mean, at 1.5-2x the passes).
      const uint64_t needed = (s_.live_triangles - target_triangles + 1) / 2;
      const uint64_t live_positions = std::max<uint64_t>(1, s_.live_triangles / 2);
      const double share = 3 + 30 * double(target_triangles) / double(s_.live_triangles);
      const size_t goal = size_t(std::clamp<uint64_t>(std::min(needed, uint64_t(double(live_positions) / share)), 1, order.size()));
      const size_t considered = std::min(order.size(), goal * 2);
      if (considered < order.size()) std::nth_element(order.begin(), order.begin() + considered, order.end());
      order.resize(considered);
      core::parallel_sort(order.begin(), order.end(), s_.threads);  // distinct keys: any thread count
      if (guard_ > 0) {
        // The guard's level: the cost this pass's collapses reach, never lower than an earlier
        // pass's; a pass that applied nothing lets the least held-back collapse through next.
        const uint32_t at_goal = uint32_t(order[std::min(order.size(), goal) - 1]);
        level_ = std::max(level_, double(best_[at_goal].cost));
        if (stalled_ && least_excess_ < std::numeric_limits<double>::infinity()) level_ = std::max(level_, least_excess_);
        least_excess_ = std::numeric_limits<double>::infinity();
      }

      // Chunks of the candidates still free are checked and then applied in cost order. A candidate
      // is applied only if none of its positions was locked by an earlier collapse, and then
      // everything its own checks read (its two stars and their corners) is as the chunk found it.
      // The candidates whose neighbourhoods (both stars and their rings) are disjoint from those of
      // all before them in the chunk are "taken" and checked in parallel first; any other, held
      // back by an earlier one's neighbourhood, is checked when the applying loop reaches it
      // unlocked (the earlier ones failed their checks; if it fails too, its fallback edge may lead
      // around the collapses applied before it, and is checked on them). So no check is wasted on a
      // candidate that ends locked, and none waits on verdicts to know whether it will be reached:
      // checks in rounds did, and on two threads took as long as on one (armadillo-s2 -> 83,200:
      // 0.85 s of checks, 562k of them for 448k needed). Same result on any number of threads.
      lap(steps.ordering);
      size_t applied = 0, deferred = 0;
      // Chunks: big enough to keep the workers busy, small enough that few of a chunk's candidates
      // are held back by earlier ones in it (their checks run on one thread).
      const size_t chunk = std::clamp<size_t>(order.size() / 64, 256, 4096);
      std::vector<uint32_t>& batch = batch_;
      for (size_t next = 0; next < order.size() && s_.live_triangles > target_triangles;) {
        batch.clear();
        for (; next < order.size() && batch.size() < chunk; ++next) {
          const uint32_t u = uint32_t(order[next]), v = best_[u].other;  // none: u died in this pass
          if (v != none && !((s_.flags[u] | s_.flags[v]) & flag_pass_locked)) batch.push_back(u);
        }
        const uint32_t stamp = ++chunk_;  // claimed_[x] == stamp: x is around a taken candidate
        taken_.clear();
        for (uint32_t i = 0; i < batch.size(); ++i) {
          const uint32_t u = batch[i], v = best_[u].other;
          if (claimed_[u] == stamp || claimed_[v] == stamp) continue;
          taken_.push_back(i);
          around(u, v, [&](uint32_t x) { claimed_[x] = stamp; });
        }
        decisions_.resize(batch.size());
        verdicts_.resize(batch.size());
        fallback_.resize(batch.size());
        excess_.resize(batch.size());
        checked_.assign(batch.size(), 0);
        core::parallel_blocks(taken_.size(), 32, s_.threads, [&](size_t, size_t begin, size_t end) {
          Scratch& scratch = block_scratch();
          for (size_t j = begin; j < end; ++j) check_candidate(batch, taken_[j], scratch);
        });
        lap(steps.checks);
        for (size_t i = 0; i < batch.size(); ++i) {
          if (s_.live_triangles <= target_triangles) break;
          const uint32_t u = batch[i], v = best_[u].other;
          if (v == none || ((s_.flags[u] | s_.flags[v]) & flag_pass_locked)) continue;  // none: u died
          if (!checked_[i]) check_candidate(batch, i, scratch_);
          if (verdicts_[i] != Reject::ok) {
            rejected_[int(verdicts_[i])] += 1;
            best_[u] = fallback_[i];
            mark_[u] |= mark_fallback;
            if (verdicts_[i] == Reject::distance) {
              // Like any rejected candidate, u waits with its next allowed edge until something
              // around it changes; release_held() ranks it again if the engine runs out first.
              least_excess_ = std::min(least_excess_, excess_[i]);
              held_[u] = excess_[i];
            }
            ++deferred;
            continue;
          }
          apply(decisions_[i], scratch_);
          ++applied;
        }
        lap(steps.applying);
      }
      stalled_ = applied == 0;
      if (applied == 0 && deferred == 0) break;
      std::erase_if(s_.live, [&](uint32_t t) { return !s_.alive[t]; });
      lap(steps.stars);
      if (s_.options.progress && start_triangles > target_triangles)
        // A collapse removes up to two triangles: the last may pass the target by one.
        s_.options.progress(std::min(1.0, double(start_triangles - s_.live_triangles) / double(start_triangles - target_triangles)));
    }
  }

 private:
  struct Best {
    float cost = std::numeric_limits<float>::infinity();
    uint32_t other = none;
  };

  // A position's cheapest edges (to higher positions), by (cost, other): the `count` first of
  // them, or all if `complete`. Every edge cheaper than the last listed one is listed, so after
  // dropping changed edges the first left is the cheapest of the unchanged ones.
  struct EdgeList {
    static constexpr uint32_t capacity = 4;
    Best edge[capacity];
    uint8_t count = 0;
    bool complete = true;

    static bool before(const Best& a, const Best& b) {
      return a.cost < b.cost || (a.cost == b.cost && a.other < b.other);
    }
    void insert(const Best& e) {
      uint32_t n = count;
      if (!complete && (n == 0 || !before(e, edge[n - 1]))) return;  // past the listed range
      if (n == capacity) {
        complete = false;  // e or the last one drops out
        if (!before(e, edge[n - 1])) return;
        --n;
      }
      uint32_t i = n;
      for (; i > 0 && before(e, edge[i - 1]); --i) edge[i] = edge[i - 1];
      edge[i] = e;
      count = uint8_t(n + 1);
    }
    template <class Changed>
    void remove_if(Changed changed) {
      uint32_t n = 0;
      for (uint32_t i = 0; i < count; ++i)
        if (!changed(edge[i].other)) edge[n++] = edge[i];
      count = uint8_t(n);
    }
  };

  // Orders like (cost, u) compared as (float, uint32), for any cost but NaN (-0 counts as 0).
  static uint64_t sort_key(float cost, uint32_t u) {
    const uint32_t bits = std::bit_cast<uint32_t>(cost + 0.0f);
    return uint64_t(bits & 0x80000000u ? ~bits : bits | 0x80000000u) << 32 | u;
  }

  void build_star() {
    const size_t live = s_.live.size();
    const size_t workers = core::parallel_workers(live, size_t(1) << 16, s_.threads);
    if (workers > 1) return build_star_parallel(workers);
    core::assign_huge(s_.first, s_.position_count + 1, 0);
    for (const uint32_t t : s_.live)
      for (uint32_t k = 0; k < 3; ++k) ++s_.first[s_.corner_position(t, k) + 1];
    for (uint32_t p = 0; p < s_.position_count; ++p) s_.first[p + 1] += s_.first[p];
    core::resize_huge(s_.wings, s_.first[s_.position_count]);
    core::reserve_huge(fill_, s_.position_count);
    fill_.assign(s_.first.begin(), s_.first.end() - 1);
    for (const uint32_t t : s_.live) {
      const uint32_t* c = &s_.corner_pos[3 * size_t(t)];
      for (uint32_t k = 0; k < 3; ++k) {
        const uint32_t slot = fill_[c[k]]++;
        s_.wings[slot] = {c[(k + 1) % 3], c[(k + 2) % 3], s_.corners[3 * size_t(t) + k], t};
      }
    }
  }

  // build_star on several threads, with the same result: each worker counts and then files one
  // range of the live triangles, its slots in a star following those of the ranges before it.
  void build_star_parallel(size_t workers) {
    const size_t live = s_.live.size(), block = (live + workers - 1) / workers;
    const size_t blocks = (live + block - 1) / block;
    const uint32_t positions = s_.position_count;
    star_slots_.resize(blocks);
    core::parallel_blocks(live, block, s_.threads, [&](size_t b, size_t begin, size_t end) {
      std::vector<uint32_t>& count = star_slots_[b];
      core::assign_huge(count, positions, 0);
      for (size_t i = begin; i < end; ++i)
        for (uint32_t k = 0; k < 3; ++k) ++count[s_.corner_position(s_.live[i], k)];
    });
    core::resize_huge(s_.first, size_t(positions) + 1);
    uint32_t slot = 0;
    for (uint32_t p = 0; p < positions; ++p) {
      s_.first[p] = slot;
      for (std::vector<uint32_t>& count : star_slots_) {
        const uint32_t c = count[p];
        count[p] = slot;  // where the block's first triangle at p goes
        slot += c;
      }
    }
    s_.first[positions] = slot;
    core::resize_huge(s_.wings, slot);
    core::parallel_blocks(live, block, s_.threads, [&](size_t b, size_t begin, size_t end) {
      std::vector<uint32_t>& fill = star_slots_[b];
      for (size_t i = begin; i < end; ++i) {
        const uint32_t t = s_.live[i];
        const uint32_t* c = &s_.corner_pos[3 * size_t(t)];
        for (uint32_t k = 0; k < 3; ++k) {
          const uint32_t at = fill[c[k]]++;
          s_.wings[at] = {c[(k + 1) % 3], c[(k + 2) % 3], s_.corners[3 * size_t(t) + k], t};
        }
      }
    });
  }

  // fn(x) for u, v and every position of their stars' rings (some more than once): the
  // neighbourhood a collapse of edge (u, v) changes, which a chunk's candidate claims and an applied
  // collapse locks (see run).
  template <class Fn>
  void around(uint32_t u, uint32_t v, Fn&& fn) const {
    for (const uint32_t x : {u, v}) {
      fn(x);
      for (const Wing& w : s_.wings_of(x)) fn(w.next), fn(w.prev);
    }
  }

  // Checks candidate i of the chunk (see run) and, if it fails, finds u's fallback edge.
  void check_candidate(const std::vector<uint32_t>& batch, uint32_t i, Scratch& scratch) {
    const uint32_t u = batch[i];
    verdicts_[i] = evaluate(u, best_[u].other, scratch, decisions_[i], true);
    if (verdicts_[i] == Reject::ok && guard_ > 0 && (excess_[i] = distance_excess(decisions_[i], scratch)) > 0)
      verdicts_[i] = Reject::distance;
    // Ranked but not allowed: u waits for the next pass with its cheapest allowed edge.
    if (verdicts_[i] != Reject::ok) fallback_[i] = best_checked(u, scratch);
    checked_[i] = 1;
  }

  // No candidate left, but the distance guard held some back: rank their positions again and raise
  // the level to the least excess, so the target is still reached. False if none was held.
  bool release_held() {
    double least = std::numeric_limits<double>::infinity();
    for (uint32_t u = 0; u < s_.position_count; ++u)
      if (held_[u] > 0 && !(s_.flags[u] & flag_dead)) least = std::min(least, held_[u]), mark_[u] |= mark_full;
    std::fill(held_.begin(), held_.end(), 0.0);
    if (least == std::numeric_limits<double>::infinity()) return false;
    level_ = std::max(level_, least);
    return true;
  }

  // The distance guard (SimplifyOptions::distance_guard): 0 if the input points of both ends stay
  // within sqrt(guard * max(level, cost)) of the faces around the kept position after the collapse,
  // else the level at which they would (their distance squared over the guard).
  double distance_excess(const Decision& d, Scratch& scratch) const {
    // Below this (squared, normalised frame) a distance is float noise: flat collapses pass.
    constexpr double noise = 1e-12;
    // Judged in the level's units, as the excess is returned: once the level has risen to an
    // excess, that distance passes exactly (guard * (d / guard) can round below d, and a collapse
    // held back at every level it raised would stall the engine).
    const double allowed = std::max(level_, d.placement.cost);
    const auto over = [&](double distance_squared) { return distance_squared > noise && distance_squared / guard_ > allowed; };
    const auto point = [](const vec3d& v) { return measure::vec3f(float(v.x), float(v.y), float(v.z)); };
    const measure::vec3f to = point(d.placement.position);
    // The fan after the collapse, as the two far corners of each face (the kept position is `to`):
    // the kept star's faces, then the removed star's from `split` on.
    std::vector<measure::vec3f>& fan = scratch.fan;
    fan.clear();
    size_t split = 0;
    for (const uint32_t y : {d.kept, d.removed}) {
      const uint32_t other = y == d.kept ? d.removed : d.kept;
      for (const Wing& w : s_.wings_of(y))
        if (w.next != other && w.prev != other)  // else removed by the collapse
          fan.push_back(point(s_.normalized(w.next))), fan.push_back(point(s_.normalized(w.prev)));
      if (y == d.kept) split = fan.size();
    }
    double excess = 0;
    for (const uint32_t x : {d.kept, d.removed}) {
      const measure::vec3f q = point(s_.normalized_input(origin_[x]));
      // Only whether some face is within the bound matters; the point's own star is likelier to be.
      const size_t start = x == d.kept ? 0 : split;
      double nearest = std::numeric_limits<double>::infinity();
      for (size_t k = 0; k < fan.size() && over(nearest); k += 2) {
        const size_t i = (start + k) % fan.size();
        const measure::TrianglePoint hit = measure::closest_on_triangle(q, to, fan[i], fan[i + 1]);
        nearest = std::min(nearest, double(measure::length_squared(q - hit.point)));
      }
      if (over(nearest) && nearest < std::numeric_limits<double>::infinity()) excess = std::max(excess, nearest / guard_);
    }
    return excess;
  }

  // A position whose star a collapse touched (it was locked) needs its edges ranked again; the pass
  // locks are lifted. On the first pass everything is new.
  void roll_flags(bool first) {
    for (uint8_t& f : s_.flags) {
      const bool touched = first || (f & flag_pass_locked);
      f = uint8_t((f & ~(flag_dirty | flag_pass_locked)) | (touched ? flag_dirty : 0));
    }
  }

  // Border, seam and non-manifold flags of every position, from its star, on the first pass. Later
  // collapses update them directly (apply): the link condition keeps stars manifold.
  void classify() {
    core::parallel_blocks(s_.position_count, 4096, s_.threads, [&](size_t, size_t begin, size_t end) {
     std::vector<uint32_t> next, prev;  // per block: thread_local costs a TLS lookup per use here
     // Counts and first occurrences in next and prev: by scanning a small star, and in a large one
     // (a fan's centre, thousands of triangles) by binary search over (value, index) pairs, sorted,
     // so that it costs n log n, not n^2.
     std::vector<uint64_t> next_sorted, prev_sorted;
     bool small = true;
     const auto sorted = [](const std::vector<uint32_t>& values, std::vector<uint64_t>& out) {
       out.resize(values.size());
       for (size_t i = 0; i < values.size(); ++i) out[i] = uint64_t(values[i]) << 32 | i;
       std::sort(out.begin(), out.end());
     };
     const auto range = [](const std::vector<uint64_t>& in, uint32_t value) {
       const auto lo = std::lower_bound(in.begin(), in.end(), uint64_t(value) << 32);
       return std::pair{lo, std::lower_bound(lo, in.end(), (uint64_t(value) + 1) << 32)};
     };
     const auto count = [&](const std::vector<uint32_t>& values, const std::vector<uint64_t>& in, uint32_t value) {
       if (small) return uint32_t(std::count(values.begin(), values.end(), value));
       const auto [lo, hi] = range(in, value);
       return uint32_t(hi - lo);
     };
     const auto first_index = [&](const std::vector<uint32_t>& values, const std::vector<uint64_t>& in, uint32_t value) {
       if (small) return size_t(std::find(values.begin(), values.end(), value) - values.begin());
       const auto [lo, hi] = range(in, value);
       return lo == hi ? values.size() : size_t(uint32_t(*lo));
     };
     for (size_t u = begin; u < end; ++u) {
      uint8_t& f = s_.flags[u];
      f &= uint8_t(~(flag_border | flag_complex | flag_seam));
      if (f & flag_dead) continue;
      const auto star = s_.triangles_of(uint32_t(u));
      const auto wings = s_.wings_of(uint32_t(u));
      if (star.empty()) continue;
      next.clear(), prev.clear();
      bool complex = false, seam = false;
      uint32_t wedge = none, material = none;
      for (size_t i = 0; i < star.size(); ++i) {
        const Wing& w = wings[i];
        const uint32_t m = s_.material(star[i]);
        seam |= wedge != none && (w.wedge != wedge || m != material);
        wedge = w.wedge, material = m;
        complex |= w.next == u || w.prev == u || w.next == w.prev;  // degenerate triangle
        next.push_back(w.next), prev.push_back(w.prev);
      }
      small = star.size() <= 16;
      if (!small) sorted(next, next_sorted), sorted(prev, prev_sorted);
      // A manifold star: each neighbour is `next` at most once and `prev` at most once, and the
      // triangles form one fan, open (border) or closed.
      uint32_t starts = 0, start = 0;
      bool border = false;
      for (size_t i = 0; i < star.size() && !complex; ++i) {
        complex |= count(next, next_sorted, next[i]) > 1 || count(prev, prev_sorted, prev[i]) > 1;
        if (count(prev, prev_sorted, next[i]) == 0) border = true;  // edge u-next[i] has one triangle
        // Triangle i starts a fan if no triangle continues into it (its prev is nobody's next).
        if (count(next, next_sorted, prev[i]) == 0) ++starts, start = uint32_t(i);
      }
      if (!complex) {
        if (starts > 1) complex = true;
        else {
          // Walk the fan from its start (or anywhere if closed); it must visit every triangle.
          size_t visited = 1, i = start;
          for (; visited <= star.size(); ++visited) {
            const size_t j = first_index(prev, prev_sorted, next[i]);  // the first j with prev[j] == next[i]
            if (j == star.size() || j == start) break;
            i = j;
          }
          complex = visited != star.size();
        }
      }
      if (complex) f |= flag_complex;
      if (border) f |= flag_border;
      if (seam) f |= flag_seam;
      if (border && s_.options.lock_border) f |= flag_locked;
     }
    });
  }

  // Each live position's cheapest edge to a higher position, by cost alone (no checks).
  void evaluate_all(bool first) {
    core::resize_huge(best_, s_.position_count);
    mark_.resize(s_.position_count);
    core::resize_huge(claimed_, s_.position_count);
    core::resize_huge(locked_in_, s_.position_count);
    const bool wide = first || metric_.reads_neighbourhood();
    // Cheapest-edge lists are kept where a collapse changes only the edges at its kept position.
    const bool lists = lists_ = !aggregate_ && !metric_.reads_neighbourhood();
    if (lists) core::resize_huge(edges_, s_.position_count);
    core::parallel_blocks(s_.position_count, 4096, s_.threads, [&](size_t, size_t begin, size_t end) {
     Scratch& scratch = block_scratch();
     for (size_t i = begin; i < end; ++i) {
      const uint32_t u = uint32_t(i);
      // Virtual pairs follow merged positions around: rank everything again (an opt-in mode), unless
      // the last pass applied nothing. The state is then unchanged, and ranking again would bring
      // back the very candidates the checks just rejected, pass after pass (an endless loop on a
      // pinched soup, found by SimplifyRobustness); their fallbacks, the cheapest allowed edges, go.
      bool full = aggregate_ && !stalled_, partial = false;
      if (aggregate_) {
      } else if (wide) {
        // Memoryless costs read the faces around both ends: a collapse changes the costs of every
        // edge with an end in its locked ring.
        full = s_.flags[u] & flag_dirty;
        for (const Wing& w : s_.wings_of(u)) full = full || ((s_.flags[w.next] | s_.flags[w.prev]) & flag_dirty);
      } else {
        // Other costs read only the edge's two ends, so a collapse changes only the edges at its
        // kept position (see mark_changed_edges).
        full = mark_[u] & mark_full;
        partial = mark_[u] & mark_partial;
      }
      if (!full && !partial) continue;
      if (full) best_[u] = Best{}, mark_[u] &= uint8_t(~mark_fallback);
      // Non-manifold positions never collapse an edge, but may still join a virtual pair.
      if ((s_.flags[u] & flag_dead) || ((s_.flags[u] & flag_complex) && !aggregate_)) {
        best_[u] = Best{};
        continue;
      }
      // u's neighbours, as neighbours() lists them: in a manifold interior fan, each wing's next
      // once, read in place (no copy).
      const bool simple = !(s_.flags[u] & (flag_complex | flag_border));
      const std::span<const uint32_t> listed = simple ? std::span<const uint32_t>{} : neighbours(u, none, scratch.candidates);
      const auto each_neighbour = [&](auto&& fn) {
        if (simple)
          for (const Wing& w : s_.wings_of(u)) fn(w.next);
        else
          for (const uint32_t v : listed) fn(v);
      };
      // The prefetch loops are written out: through each_neighbour, GCC dropped the prefetches.
      if constexpr (requires { metric_.prefetch(u); }) {
        if (simple) {
          for (const Wing& w : s_.wings_of(u))
            if (w.next > u) metric_.prefetch(w.next), __builtin_prefetch(&s_.position[w.next]);
        } else {
          for (const uint32_t v : listed)
            if (v > u) metric_.prefetch(v), __builtin_prefetch(&s_.position[v]);
        }
      }
      if (lists && !wide && !(mark_[u] & mark_kept)) {
        // Only u's edges to kept positions changed (or vanished): update its cheapest edges. A full
        // ranking (best pointed at a changed edge) is needed only if none of those are left.
        EdgeList& list = edges_[u];
        list.remove_if([&](uint32_t v) { return (s_.flags[v] & (flag_dead | flag_complex)) || (mark_[v] & mark_kept); });
        each_neighbour([&](uint32_t v) {
          if (v <= u || (s_.flags[v] & (flag_dead | flag_complex)) || !(mark_[v] & mark_kept)) return;
          Decision decision;
          if (evaluate(u, v, scratch, decision, false) != Reject::ok) return;
          const float cost = float(decision.placement.cost);
          list.insert({cost, v});
          if (cost < best_[u].cost || (cost == best_[u].cost && v < best_[u].other)) best_[u] = {cost, v};
        });
        if (!full) continue;
        if (list.count > 0 || list.complete) {
          best_[u] = list.count > 0 ? list.edge[0] : Best{};
          continue;
        }
      }
      EdgeList ranked;
      each_neighbour([&](uint32_t v) {
        if (v <= u || (s_.flags[v] & (flag_dead | flag_complex))) return;
        if (!full && !(mark_[v] & mark_kept)) return;
        Decision decision;
        if (evaluate(u, v, scratch, decision, false) != Reject::ok) return;
        const float cost = float(decision.placement.cost);
        if (cost < best_[u].cost || (cost == best_[u].cost && v < best_[u].other)) best_[u] = {cost, v};
        ranked.insert({cost, v});
      });
      if (lists && full) edges_[u] = ranked;
      if (aggregate_)
        for (uint32_t j = virtual_first_[u]; j < virtual_first_[u + 1]; ++j) {
          const uint32_t v = virtual_partner_[j];
          Decision decision;
          if (evaluate(u, v, scratch, decision, false) != Reject::ok) continue;
          const float cost = float(decision.placement.cost);
          if (cost < best_[u].cost || (cost == best_[u].cost && v < best_[u].other)) best_[u] = {cost, v};
        }
     }
    });
    for (uint8_t& m : mark_) m &= mark_fallback;
  }

  // Virtual pairs: for each live position, up to aggregate_neighbours nearest positions within the
  // aggregation distance that are not its neighbours, found in a uniform grid of that cell size (a
  // sorted cell list, so the result does not depend on hashing or threads).
  void find_virtual_pairs() {
    const double tau = double(s_.options.aggregate_distance) * s_.scale;
    const uint32_t k_nearest = std::max<uint32_t>(1, s_.options.aggregate_neighbours);
    merged_into_.resize(s_.position_count);
    std::iota(merged_into_.begin(), merged_into_.end(), 0u);
    struct Entry {
      int64_t x, y, z;
      uint32_t p;
      bool operator<(const Entry& o) const { return std::tie(x, y, z, p) < std::tie(o.x, o.y, o.z, o.p); }
    };
    const auto cell = [&](double c) { return int64_t(std::floor(std::clamp(c / tau, -1e15, 1e15))); };
    std::vector<Entry> grid;
    for (uint32_t p = 0; p < s_.position_count; ++p) {
      if (s_.first[p] == s_.first[p + 1]) continue;  // unused
      const vec3d q = s_.normalized(p);
      grid.push_back({cell(q.x), cell(q.y), cell(q.z), p});
    }
    std::sort(grid.begin(), grid.end());
    // A crowded cell (tau much larger than the spacing) is scanned only this far: pairs are then
    // found among the first positions of the cell, which keeps the search linear.
    constexpr size_t max_scan = 256;
    const size_t block = 1024;
    std::vector<std::vector<std::pair<uint32_t, uint32_t>>> found((grid.size() + block - 1) / block);
    core::parallel_blocks(grid.size(), block, s_.threads, [&](size_t b, size_t begin, size_t end) {
      std::vector<std::pair<double, uint32_t>> near;
      std::vector<uint32_t> ring;
      for (size_t i = begin; i < end; ++i) {
        const Entry& e = grid[i];
        const vec3d q = s_.normalized(e.p);
        near.clear();
        for (int64_t dx = -1; dx <= 1; ++dx)
          for (int64_t dy = -1; dy <= 1; ++dy)
            for (int64_t dz = -1; dz <= 1; ++dz) {
              const Entry key{e.x + dx, e.y + dy, e.z + dz, 0};
              auto it = std::lower_bound(grid.begin(), grid.end(), key);
              for (size_t n = 0; it != grid.end() && it->x == key.x && it->y == key.y && it->z == key.z && n < max_scan;
                   ++it, ++n) {
                if (it->p == e.p) continue;
                const double d2 = length_squared(s_.normalized(it->p) - q);
                if (d2 <= tau * tau) near.push_back({d2, it->p});
              }
            }
        std::sort(near.begin(), near.end());
        const auto around = neighbours(e.p, none, ring);
        uint32_t kept = 0;
        for (const auto& [d2, other] : near) {
          if (kept == k_nearest) break;
          if (std::find(around.begin(), around.end(), other) != around.end()) continue;  // an edge already
          found[b].push_back({std::min(e.p, other), std::max(e.p, other)});
          ++kept;
        }
      }
    });
    for (const auto& f : found) virtual_pairs_.insert(virtual_pairs_.end(), f.begin(), f.end());
    std::sort(virtual_pairs_.begin(), virtual_pairs_.end());
    virtual_pairs_.erase(std::unique(virtual_pairs_.begin(), virtual_pairs_.end()), virtual_pairs_.end());
  }

  uint32_t representative(uint32_t p) const {
    while (merged_into_[p] != p) p = merged_into_[p];
    return p;
  }

  // The virtual pairs between current positions, without self pairs and pairs that became edges.
  void update_virtual_pairs() {
    for (auto& [a, b] : virtual_pairs_) {
      const uint32_t ra = representative(a), rb = representative(b);
      a = std::min(ra, rb), b = std::max(ra, rb);
    }
    std::sort(virtual_pairs_.begin(), virtual_pairs_.end());
    virtual_pairs_.erase(std::unique(virtual_pairs_.begin(), virtual_pairs_.end()), virtual_pairs_.end());
    std::erase_if(virtual_pairs_, [&](const std::pair<uint32_t, uint32_t>& pair) {
      return pair.first == pair.second || shared_triangles(s_, pair.first, pair.second) > 0;
    });
    virtual_first_.assign(s_.position_count + 1, 0);
    for (const auto& pair : virtual_pairs_) ++virtual_first_[pair.first + 1];
    for (uint32_t p = 0; p < s_.position_count; ++p) virtual_first_[p + 1] += virtual_first_[p];
    virtual_partner_.resize(virtual_pairs_.size());
    for (size_t i = 0; i < virtual_pairs_.size(); ++i) virtual_partner_[i] = virtual_pairs_[i].second;  // sorted
  }

  // After a collapse, the edges that changed are those at the kept position (its quadric and place
  // moved, and it took over the removed position's edges). A neighbour whose best edge was one of
  // them, or whose best is a fallback chosen under checks, ranks all its edges again; any other
  // only needs to weigh its edge to the kept position against its unchanged best.
  void mark_changed_edges(const Decision& d) {
    mark_[d.kept] |= mark_full | mark_kept;
    // The geometry around these positions changed: a collapse the guard held back is weighed afresh.
    if (guard_ > 0) held_[d.kept] = 0;
    for (const uint32_t x : {d.kept, d.removed})
      for (const Wing& w : s_.wings_of(x))
        for (const uint32_t p : {w.next, w.prev}) {
          const uint32_t other = best_[p].other;
          if (p == d.kept || p == d.removed) continue;
          const bool stale = other == d.kept || other == d.removed || (mark_[p] & mark_fallback);
          mark_[p] |= stale ? mark_full : mark_partial;
          if (guard_ > 0) held_[p] = 0;
        }
  }

  // The distinct positions around x, except `skip`.
  // `storage` only holds them: written in place, since appending one by one costs a call each.
  std::span<const uint32_t> neighbours(uint32_t x, uint32_t skip, std::vector<uint32_t>& storage) const {
    const auto wings = s_.wings_of(x);
    if (storage.size() < 2 * wings.size()) storage.resize(4 * wings.size());
    uint32_t* const begin = storage.data();
    uint32_t* end = begin;
    // In a manifold fan every neighbour follows the centre in exactly one triangle, and only a
    // border fan's last neighbour does not: `next` needs no de-duplication there.
    const bool simple = !(s_.flags[x] & (flag_complex | flag_border));
    if (!simple && wings.size() > 64) {
      // A large border or non-manifold star: de-duplicating by search would take the square of its
      // size. Sorted instead (callers treat the list as a set).
      for (const Wing& w : wings) {
        if (w.next != skip) *end++ = w.next;
        if (w.prev != skip) *end++ = w.prev;
      }
      std::sort(begin, end);
      return {begin, std::unique(begin, end)};
    }
    for (const Wing& w : wings)
      if (w.next != skip && (simple || std::find(begin, end, w.next) == end)) *end++ = w.next;
    if (!simple)
      for (const Wing& w : wings)
        if (w.prev != skip && std::find(begin, end, w.prev) == end) *end++ = w.prev;
    return {begin, end};
  }

  // Wedge pairs for collapsing `removed` into `kept`: every (wedge, material) of removed must meet
  // one of kept's in a removed face, consistently, and distinct wedges must stay distinct. This is
  // what keeps seams and material borders: they can only collapse along themselves.
  bool map_wedges(uint32_t kept, uint32_t removed, std::span<const uint32_t> faces,
                  std::vector<WedgePair>& pairs) const {
    pairs.clear();
    if (!((s_.flags[kept] | s_.flags[removed]) & flag_seam)) {
      // One wedge and material at each end (every corner of its star has it): they pair up.
      pairs.push_back({s_.wings[s_.first[removed]].wedge, s_.wings[s_.first[kept]].wedge, s_.material(faces[0])});
      return true;
    }
    for (const uint32_t t : faces) {
      uint32_t from = none, to = none;
      for (uint32_t k = 0; k < 3; ++k) {
        const uint32_t p = s_.corner_position(t, k);
        if (p == removed) from = s_.corners[3 * t + k];
        if (p == kept) to = s_.corners[3 * t + k];
      }
      const uint32_t m = s_.material(t);
      bool known = false;
      for (const WedgePair& pair : pairs) {
        if (pair.from == from && pair.material == m) {
          if (pair.to != to) return false;
          known = true;
        } else if ((pair.from == from) != (pair.to == to)) {
          return false;  // two wedges would merge, or one would split
        }
      }
      if (!known) pairs.push_back({from, to, m});
    }
    const auto star = s_.triangles_of(removed);
    const auto wings = s_.wings_of(removed);
    for (size_t i = 0; i < star.size(); ++i) {
      const uint32_t w = wings[i].wedge, m = s_.material(star[i]);
      bool found = false;
      for (const WedgePair& pair : pairs) found |= pair.from == w && pair.material == m;
      if (!found) return false;
    }
    return true;
  }

  void wedges_of(uint32_t x, std::vector<uint32_t>& out) const {
    out.clear();
    for (const Wing& w : s_.wings_of(x))
      if (std::find(out.begin(), out.end(), w.wedge) == out.end()) out.push_back(w.wedge);
  }

  // Would any surviving face around the edge flip, degenerate or get too thin with `kept` and
  // `removed` both at p?
  Reject check_faces(uint32_t kept, uint32_t removed, const vec3d& p) const {
    const double min_dot = s_.options.min_normal_dot, max_aspect = s_.options.max_aspect_ratio;
    for (const uint32_t x : {kept, removed}) {
      const uint32_t other = x == kept ? removed : kept;
      const vec3d px = s_.normalized(x);
      for (const Wing& w : s_.wings_of(x)) {
        if (w.next == other || w.prev == other) continue;  // removed by the collapse
        // The triangle as (x, next, prev), its own winding.
        const vec3d before[3] = {px, s_.normalized(w.next), s_.normalized(w.prev)};
        const vec3d after[3] = {p, before[1], before[2]};
        const FaceChange change = face_change(before, after, min_dot);
        if (change.degenerate) return Reject::shape;
        if (change.flipped) return Reject::flip;
        // Aspect ratio: longest edge over its altitude, L / (2 area / L) = L^2 / |n|.
        if (max_aspect > 0 && change.longest / change.normal_length > max_aspect) return Reject::shape;
      }
    }
    return Reject::ok;
  }

 public:
  // Decides the collapse of edge (u, v): direction, placement, cost. `count` tallies rejections.
  // With `checked` false only what the cost depends on is done (used to rank every edge each pass);
  // the link condition, wedge consistency and face checks then run only for the collapses about to
  // be applied, in cost order.
  Reject evaluate(uint32_t u, uint32_t v, Scratch& scratch, Decision& decision, bool checked) {
    const uint8_t fu = s_.flags[u], fv = s_.flags[v];
    if ((fu | fv) & flag_dead) return Reject::topology;
    if ((fu & flag_locked) && (fv & flag_locked)) return Reject::topology;
    if (!aggregate_ && ((fu | fv) & flag_complex)) return Reject::topology;

    uint32_t shared = 0;
    if (!checked && !aggregate_ && !channel_floats_ && !(fu & (flag_border | flag_complex)) && !((fu | fv) & flag_seam)) {
      // Ranking an edge of a manifold interior position (v is one of its neighbours), without seams
      // or attributes: only the number of removed faces matters (no wedges are mapped), and it is
      // two, v following u in one triangle of the closed fan and preceding it in another.
      shared = 2;
    } else {
      // The faces on edge (u, v) are in both stars, in the same (triangle id) order: scan the smaller,
      // so that a position with thousands of faces (a fan's centre) costs its neighbours nothing.
      const bool from_u = s_.triangles_of(u).size() <= s_.triangles_of(v).size();
      const uint32_t other = from_u ? v : u;
      for (const Wing& w : s_.wings_of(from_u ? u : v))
        if (w.next == other || w.prev == other) {
          if (shared < 2) scratch.face[shared] = w.triangle, scratch.opposite[shared] = w.next == other ? w.prev : w.next;
          ++shared;
        }
    }
    scratch.face_count = std::min<uint32_t>(shared, 2);
    // No shared face: a virtual pair (only ranked when aggregating).
    if (shared == 0) return aggregate_ ? evaluate_virtual(u, v, scratch, decision, checked) : Reject::topology;
    if ((fu | fv) & flag_complex) return Reject::topology;
    if (shared > 2) return Reject::topology;
    // An interior edge between two border positions would pinch the surface.
    if ((fu & flag_border) && (fv & flag_border) && shared != 1) return Reject::topology;
    if (checked) {
      const Reject link = link_condition(u, v, scratch);
      if (link != Reject::ok) return link;
    }
    return place(u, v, scratch, decision, checked);
  }

  // A virtual pair joins two parts at one position. No face disappears and no corner changes wedge;
  // the removed position's wedges move to the kept one. Refused when u and v have a common
  // neighbour: a face would be doubled or an edge get a third face.
  Reject evaluate_virtual(uint32_t u, uint32_t v, Scratch& scratch, Decision& decision, bool checked) {
    const uint8_t fu = s_.flags[u], fv = s_.flags[v];
    if (checked) {
      const auto around_u = neighbours(u, none, scratch.neighbours_u);
      const auto around_v = neighbours(v, none, scratch.neighbours_v);
      for (const uint32_t a : around_u)
        if (std::find(around_v.begin(), around_v.end(), a) != around_v.end())
          return Reject::topology;
    }
    const bool fixed = s_.options.keep_vertices || ((fu | fv) & flag_locked);
    scratch.pairs[0].clear(), scratch.pairs[1].clear();
    decision = {};
    for (int d = 0; d < 2; ++d) {
      const uint32_t kept = d == 0 ? u : v, removed = d == 0 ? v : u;
      if (s_.flags[removed] & flag_locked) continue;
      if (!fixed && decision.kept != none) break;
      virtual_wedges(kept, removed, scratch);
      const EdgeQuery query{kept, removed, fixed, scratch.pairs[d], scratch.kept_wedges, scratch.faces()};
      const Placement placement = metric_.place(s_, query);
      if (decision.kept == none || placement.cost < decision.placement.cost)
        decision = {kept, removed, fixed, placement, d};
    }
    if (decision.kept == none) return Reject::seam;
    if (checked) return check_faces(decision.kept, decision.removed, decision.placement.position);
    return Reject::ok;
  }

  // The wedges at the kept position after a virtual pair: its own and the removed position's.
  void virtual_wedges(uint32_t kept, uint32_t removed, Scratch& scratch) const {
    scratch.kept_wedges.clear();
    if (!channel_floats_) return;
    wedges_of(kept, scratch.kept_wedges);
    wedges_of(removed, scratch.extra);
    scratch.kept_wedges.insert(scratch.kept_wedges.end(), scratch.extra.begin(), scratch.extra.end());
  }

  Reject link_condition(uint32_t u, uint32_t v, Scratch& scratch) const {
    const auto faces = scratch.faces();
    // Link condition: the positions next to both u and v are exactly the opposite corners (of
    // non-degenerate faces: complex positions never get here).
    const uint32_t opposite[2] = {scratch.opposite[0], faces.size() == 2 ? scratch.opposite[1] : none};
    if (faces.size() == 2 && opposite[0] == opposite[1]) return Reject::topology;
    const auto around_u = neighbours(u, v, scratch.neighbours_u);
    const auto around_v = neighbours(v, u, scratch.neighbours_v);
    size_t common = 0;
    for (const uint32_t a : around_u)
      if (std::find(around_v.begin(), around_v.end(), a) != around_v.end()) {
        if (a != opposite[0] && a != opposite[1]) return Reject::topology;
        ++common;
      }
    if (common != faces.size()) return Reject::topology;
    if (faces.size() == 2) {
      // The edge between the opposite corners is in both links when triangles (u, a, b) and
      // (v, a, b) both exist (a tetrahedron): the collapse would make them one doubled face.
      bool in_link[2] = {false, false};
      for (int i = 0; i < 2; ++i)
        for (const Wing& w : s_.wings_of(i == 0 ? u : v)) {
          const uint32_t hits = (w.next == opposite[0] || w.next == opposite[1]) + (w.prev == opposite[0] || w.prev == opposite[1]);
          in_link[i] |= hits == 2;
        }
      if (in_link[0] && in_link[1]) return Reject::topology;
    } else if (is_border_edge(s_, u, opposite[0]) && is_border_edge(s_, v, opposite[0])) {
      return Reject::topology;  // a lone triangle would vanish
    }

    return Reject::ok;
  }

  Reject place(uint32_t u, uint32_t v, Scratch& scratch, Decision& decision, bool checked) {
    const uint8_t fu = s_.flags[u], fv = s_.flags[v];
    const auto faces = scratch.faces();
    // Directions allowed by locks and wedges. Without seams, attributes or checks, wedges do not
    // matter: each side has one wedge.
    const bool wedges = checked || channel_floats_ || ((fu | fv) & flag_seam);
    // can[d]: direction d (0: keep u, remove v) is allowed; the second is worked out only if needed.
    const bool fixed = s_.options.keep_vertices || ((fu | fv) & flag_locked);
    const bool seam = (fu | fv) & flag_seam;
    bool can[2];
    // Metrics without border terms keep borders topologically, as seams: a border position only
    // collapses along a border edge into another border position, and an interior position
    // collapsing into a border one leaves it where it is.
    const bool border_edge = faces.size() == 1;
    const auto border_allows = [&](uint8_t fkept, uint8_t fremoved) {
      return !keep_borders_ || !(fremoved & flag_border) || ((fkept & flag_border) && border_edge);
    };
    can[0] = !(fv & flag_locked) && border_allows(fu, fv) && (!wedges || map_wedges(u, v, faces, scratch.pairs[0]));
    const bool need_second = !can[0] || fixed || seam || (keep_borders_ && ((fu | fv) & flag_border));
    can[1] = need_second && !(fu & flag_locked) && border_allows(fv, fu) &&
             (!wedges || map_wedges(v, u, faces, scratch.pairs[1]));
    if (!can[0] && !can[1]) return Reject::seam;

    decision = {};
    for (int d = 0; d < 2; ++d) {
      if (!can[d]) continue;
      const uint32_t kept = d == 0 ? u : v, removed = d == 0 ? v : u;
      // Free placement: one direction is enough (both give the same optimum), unless border rules
      // make them differ.
      if (!fixed && decision.kept != none && !(keep_borders_ && ((fu | fv) & flag_border))) break;
      if (!fixed && d == 0 && can[1] && seam) {
        // Both directions work: keep the position with more wedges (seam ends stay put), else u.
        wedges_of(u, scratch.kept_wedges);
        const size_t wu = scratch.kept_wedges.size();
        wedges_of(v, scratch.kept_wedges);
        if (scratch.kept_wedges.size() > wu) continue;
      }
      if (channel_floats_) wedges_of(kept, scratch.kept_wedges);
      else scratch.kept_wedges.clear();
      const uint8_t fk = s_.flags[kept], fr = s_.flags[removed];
      const bool pinned = keep_borders_ && (fk & flag_border) && !(fr & flag_border);
      EdgeQuery query{kept, removed, fixed || pinned, scratch.pairs[d], scratch.kept_wedges, faces};
      query.on_edge = keep_borders_ && (fk & fr & flag_border);
      const Placement placement = metric_.place(s_, query);
      if (decision.kept == none || placement.cost < decision.placement.cost)
        decision = {kept, removed, fixed || pinned, placement, d};
    }
    if (decision.kept == none) return Reject::seam;
    if (checked) return check_faces(decision.kept, decision.removed, decision.placement.position);
    return Reject::ok;
  }

  // Locked by a collapse applied in the pass before the current chunk. A fallback edge must not lead
  // there, by the same rule whether its check runs in parallel before the chunk's collapses or
  // after some of them (see run).
  bool locked_before_chunk(uint32_t v) const { return (s_.flags[v] & flag_pass_locked) && locked_in_[v] != chunk_; }

  // u's cheapest edge (to a higher position) that passes every check now, or none.
  Best best_checked(uint32_t u, Scratch& scratch) {
    Best best;
    Decision decision;
    if (lists_) {
      // Checks only add rejections to the ranking's (with the same costs): the first of u's
      // cheapest edges that passes them is the answer, if the list has one. best_[u] just failed
      // on this state.
      const EdgeList& list = edges_[u];
      for (uint32_t i = 0; i < list.count; ++i) {
        const uint32_t v = list.edge[i].other;
        if (v == best_[u].other || (s_.flags[v] & (flag_dead | flag_complex)) || locked_before_chunk(v)) continue;
        if (evaluate(u, v, scratch, decision, true) == Reject::ok) return {float(decision.placement.cost), v};
      }
      if (list.complete) return best;
    }
    // Every edge ranked by cost alone, then checked cheapest first (by cost, then position, as
    // above): the first that passes is the answer. Checking all of them would cost a position with
    // thousands of edges (a fan's centre) the square of that, since each check walks its star.
    std::vector<uint64_t>& keys = scratch.keys;
    keys.clear();
    for (const uint32_t v : neighbours(u, none, scratch.candidates)) {
      // Stars of positions locked in this pass are stale until the next rebuild.
      if (v <= u || (s_.flags[v] & (flag_dead | flag_complex)) || locked_before_chunk(v)) continue;
      if (evaluate(u, v, scratch, decision, false) != Reject::ok) continue;
      const float cost = float(decision.placement.cost);
      if (!std::isnan(cost)) keys.push_back(sort_key(cost, v));
    }
    std::sort(keys.begin(), keys.end());
    for (const uint64_t key : keys) {
      const uint32_t v = uint32_t(key);
      if (evaluate(u, v, scratch, decision, true) == Reject::ok) return {float(decision.placement.cost), v};
    }
    return best;
  }

 private:
  void apply(const Decision& d, Scratch& scratch) {
    // The removed faces, wedge pairs and kept wedges, as the (parallel) checks found them.
    auto& faces = scratch.removed_faces;
    faces.clear();
    const auto kept_star = s_.triangles_of(d.kept);
    const auto kept_wings = s_.wings_of(d.kept);
    for (size_t i = 0; i < kept_star.size(); ++i)
      if (kept_wings[i].next == d.removed || kept_wings[i].prev == d.removed) faces.push_back(kept_star[i]);
    auto& pairs = scratch.pairs[0];
    const bool virtual_pair = faces.empty();
    if (virtual_pair) {
      pairs.clear();
      virtual_wedges(d.kept, d.removed, scratch);
    } else {
      map_wedges(d.kept, d.removed, faces, pairs);
      wedges_of(d.kept, scratch.kept_wedges);
    }
    const EdgeQuery query{d.kept, d.removed, d.fixed, pairs, scratch.kept_wedges, scratch.removed_faces};
    // A metric that chooses the survivor's joints and weights (multi-pose) records them per collapse.
    constexpr bool chooses_influences = requires { metric_.chose(0u); };
    InfluenceChange influence_change;
    if constexpr (chooses_influences)
      if (metric_.chose(d.kept)) influence_change.old_value = metric_.influences(d.kept);
    metric_.collapsed(s_, query, d.placement.position);
    if constexpr (chooses_influences) {
      influence_change.new_value = metric_.influences(d.kept);
      if (s_.options.record) result_.record.influences.push_back(influence_change);
    }

    const vec3d old_kept = s_.normalized(d.kept);
    Collapse c;
    c.kept = s_.external[d.kept], c.removed = s_.external[d.removed];
    c.old_position = s_.position[d.kept];
    c.new_position = d.fixed ? c.old_position : s_.object(d.placement.position);
    c.error = float(std::sqrt(std::max(0.0, d.placement.cost)) / s_.scale);
    max_cost_ = std::max(max_cost_, d.placement.cost);
    SimplifyRecord& record = result_.record;
    const bool keep_record = s_.options.record;
    c.faces_begin = uint32_t(record.removed_faces.size());
    c.relinks_begin = uint32_t(record.relinks.size());
    c.wedges_begin = uint32_t(record.wedges.size());
    c.moved_begin = uint32_t(record.moved_wedges.size());
    if (!s_.degenerate.empty()) {  // the first collapse: the degenerate input triangles go with it
      if (keep_record) record.removed_faces.insert(record.removed_faces.end(), s_.degenerate.begin(), s_.degenerate.end());
      s_.live_triangles -= s_.degenerate.size();
      s_.degenerate.clear();
    }
    if (virtual_pair) {
      wedges_of(d.removed, scratch.extra);
      for (const uint32_t w : scratch.extra) {
        s_.position_of[w] = d.kept;
        if (keep_record) record.moved_wedges.push_back(w);
      }
      c.moved_count = uint32_t(record.moved_wedges.size()) - c.moved_begin;
      merged_into_[d.removed] = d.kept;
      ++result_.virtual_pairs;
    }

    for (const uint32_t t : s_.triangles_of(d.removed)) {
      uint32_t k = 0;
      while (s_.corner_position(t, k) != d.removed) ++k;
      if (std::find(scratch.removed_faces.begin(), scratch.removed_faces.end(), t) != scratch.removed_faces.end()) {
        s_.alive[t] = 0;
        --s_.live_triangles;
        if (keep_record) record.removed_faces.push_back(t);
        continue;
      }
      s_.corner_pos[3 * t + k] = d.kept;
      uint32_t& corner = s_.corners[3 * t + k];
      const uint32_t m = s_.material(t);
      for (const WedgePair& pair : pairs)
        if (pair.from == corner && pair.material == m) {
          if (keep_record) record.relinks.push_back({t, k, corner, pair.to});
          s_.wedge_successor[corner] = pair.to;
          corner = pair.to;
          break;
        }
    }
    if (virtual_pair) {
      // The moved wedges sit at kept's position from now on, even if it stays put (see Replay).
      s_.flags[d.kept] |= flag_complex | flag_seam;  // two fans and both sets of wedges
      s_.position[d.kept] = c.new_position;
      ++s_.moves[d.kept];
    } else if (!d.fixed && !(c.new_position == c.old_position)) {
      s_.position[d.kept] = c.new_position;
      ++s_.moves[d.kept];
    }
    s_.flags[d.removed] |= flag_dead;
    s_.successor[d.removed] = d.kept;
    // An edge collapse that passed the link condition keeps the surface manifold: the kept position
    // is on a border or seam if either end was (a seam that closes up is kept conservatively).
    if (!virtual_pair) s_.flags[d.kept] |= s_.flags[d.removed] & (flag_border | flag_seam);
    best_[d.removed] = Best{};  // a dead position ranks nothing
    if (s_.layout.stride) update_attributes(d, pairs, scratch.kept_wedges, old_kept, keep_record);

    mark_changed_edges(d);
    // Lock the neighbourhood for the rest of the pass.
    around(d.kept, d.removed, [&](uint32_t x) {
      if (!(s_.flags[x] & flag_pass_locked)) s_.flags[x] |= flag_pass_locked, locked_in_[x] = chunk_;
    });

    c.removed_face_count = uint32_t(record.removed_faces.size()) - c.faces_begin;
    c.relink_count = uint32_t(record.relinks.size()) - c.relinks_begin;
    c.wedge_count = uint32_t(record.wedges.size()) - c.wedges_begin;
    if (keep_record) record.collapses.push_back(c);
    ++result_.collapses;
  }

  // New attribute values at the kept wedges: optimised channels from the attribute quadrics, the
  // others interpolated along the edge with the wedge they merged with.
  void update_attributes(const Decision& d, std::span<const WedgePair> pairs, std::span<const uint32_t> kept_wedges,
                         const vec3d& from, bool keep_record) {
    const AttributeLayout& layout = s_.layout;
    const vec3d to = s_.normalized(d.removed), p = d.fixed ? from : d.placement.position;
    const vec3d edge = to - from;
    const double len2 = length_squared(edge);
    const double t = len2 > 0 ? std::clamp(dot(p - from, edge) / len2, 0.0, 1.0) : 0.0;
    thread_local std::vector<float> values, optimal;
    for (const uint32_t w : kept_wedges) {
      float* current = s_.attributes.data() + size_t(w) * layout.stride;
      values.assign(current, current + layout.stride);
      uint32_t partner = none;
      for (const WedgePair& pair : pairs)
        if (pair.to == w) { partner = pair.from; break; }
      if (partner != none) {
        const float* other = s_.attributes.data() + size_t(partner) * layout.stride;
        for (uint32_t i = 0; i < layout.stride; ++i) values[i] = float((1 - t) * values[i] + t * other[i]);
      }
      optimal.assign(channel_floats_, 0.0f);
      if (channel_floats_) {
        uint32_t f = 0;
        for (const Channel& c : channels_)
          for (uint32_t i = 0; i < c.size; ++i) optimal[f++] = values[c.offset + i];
        metric_.attributes_at(s_, w, p, optimal.data());
        f = 0;
        for (const Channel& c : channels_) {
          for (uint32_t i = 0; i < c.size; ++i, ++f) {
            float value = optimal[f];
            if (c.kind == Channel::uv && partner != none) {
              // Keep UVs inside the chart: between the two merged wedges' values.
              const float lo = std::min(current[c.offset + i], s_.attributes[size_t(partner) * layout.stride + c.offset + i]);
              const float hi = std::max(current[c.offset + i], s_.attributes[size_t(partner) * layout.stride + c.offset + i]);
              value = std::clamp(value, lo, hi);
            }
            if (c.kind == Channel::color) value = std::clamp(value, 0.0f, 1.0f);
            values[c.offset + i] = value;
          }
        }
      }
      if (layout.normal >= 0) {
        float* n = values.data() + layout.normal;
        const double l = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
        if (l > 0) n[0] = float(n[0] / l), n[1] = float(n[1] / l), n[2] = float(n[2] / l);
        else std::copy_n(current + layout.normal, 3, n);
      }
      if (std::equal(values.begin(), values.end(), current)) continue;
      if (keep_record) {
        SimplifyRecord& record = result_.record;
        record.wedges.push_back({w, uint32_t(record.old_values.size())});
        record.old_values.insert(record.old_values.end(), current, current + layout.stride);
        record.new_values.insert(record.new_values.end(), values.begin(), values.end());
      }
      std::copy(values.begin(), values.end(), current);
    }
  }

 public:
  std::vector<Channel> channels_;
  uint32_t channel_floats_ = 0;
  bool aggregate_ = false;  // rank virtual pairs too
  bool keep_borders_ = false;  // the metric has no border term: keep borders by the rules in place()
  double max_cost_ = 0;
  uint64_t rejected_[6] = {};
  // The distance guard: its factor (0: off), the input positions (by position id), and its level.
  double guard_ = 0;
  std::vector<float3> origin_;
  std::vector<double> held_;  // per position: the level its held-back collapse needs (0: none)

 private:
  State& s_;
  MetricT& metric_;
  SimplifyResult& result_;
  std::vector<Best> best_;
  // Per position: which of its edges to rank again next pass (mark_changed_edges).
  enum : uint8_t { mark_full = 1, mark_partial = 2, mark_kept = 4, mark_fallback = 8 };
  std::vector<uint8_t> mark_;
  std::vector<EdgeList> edges_;  // per position, when the metric allows (evaluate_all)
  bool lists_ = false;

  // Aggregation: virtual pairs, as found at the start, and per pass the pairs between the positions
  // they have become (merged_into_), at the lower position (CSR, like the star).
  std::vector<std::pair<uint32_t, uint32_t>> virtual_pairs_;
  std::vector<uint32_t> merged_into_, virtual_first_, virtual_partner_;
  Scratch scratch_;  // the sequential part's

  // Scratch for the worker running a parallel block; allocated once per thread.
  static Scratch& block_scratch() {
    thread_local Scratch scratch;
    return scratch;
  }
  std::vector<uint32_t> fill_;
  std::vector<std::vector<uint32_t>> star_slots_;  // build_star_parallel: per block, per position
  std::vector<uint64_t> order_;  // the pass's candidates, cheapest first (sort_key)
  std::vector<Decision> decisions_;  // per candidate of the pass
  std::vector<Reject> verdicts_;
  std::vector<Best> fallback_;
  std::vector<double> excess_;  // per candidate: distance_excess when the guard held it back
  double level_ = 0, least_excess_ = std::numeric_limits<double>::infinity();
  bool stalled_ = false;  // the last pass applied nothing
  // The chunk's candidates, which of them are checked (in parallel: taken_, by index), and per
  // position the chunk whose taken candidates' neighbourhoods hold it (claimed_) or whose collapse
  // locked it (locked_in_). chunk_ numbers the current chunk, counting on across passes.
  std::vector<uint32_t> batch_, taken_, claimed_, locked_in_;
  std::vector<uint8_t> checked_;
  uint32_t chunk_ = 0;
};

template <class MetricT>
void run(State& state, MetricT& metric, const std::vector<Channel>& channels, uint64_t target, double cost_limit,
         SimplifyResult& result) {
  Engine<MetricT> engine(state, metric, result);
  engine.channels_ = channels;
  // The guard applies to qem and cqem: release_held() ranks held-back positions again through
  // evaluate_all's marks, which memoryless metrics do not use (they re-rank by dirty flags), and
  // there its deferrals churned (245 passes instead of 37 on mech-holes-shark at 1%).
  if constexpr (std::is_same_v<MetricT, QuadricMetric>) {
    const Metric m = state.options.metric;
    if (m == Metric::qem || m == Metric::constrained_qem) engine.guard_ = state.options.distance_guard;
    if (engine.guard_ > 0) {
      core::copy_huge(engine.origin_, state.position);
      core::assign_huge(engine.held_, state.position_count, 0.0);
    }
  }
  result.distance_guard = float(engine.guard_);
  engine.aggregate_ = state.options.aggregate_distance > 0;
  engine.keep_borders_ = state.options.metric == Metric::qem || state.options.metric == Metric::edge_length;
  for (const Channel& c : channels) engine.channel_floats_ += c.size;
  engine.run(target, cost_limit);
  result.error = float(std::sqrt(engine.max_cost_) / state.scale);
  result.rejected_topology = engine.rejected_[int(Reject::topology)];
  result.rejected_seam = engine.rejected_[int(Reject::seam)];
  result.rejected_flip = engine.rejected_[int(Reject::flip)];
  result.rejected_shape = engine.rejected_[int(Reject::shape)];
  result.deferred_distance = engine.rejected_[int(Reject::distance)];
}

// Drops the live triangles of every connected component whose bounding-box diagonal is below `size`.
uint64_t prune_components(State& state, double size) {
  const size_t triangles = state.corners.size() / 3;
  core::UnionFind sets(state.position_count);
  for (size_t t = 0; t < triangles; ++t)
    if (state.alive[t]) {
      sets.unite(state.corner_position(uint32_t(t), 0), state.corner_position(uint32_t(t), 1));
      sets.unite(state.corner_position(uint32_t(t), 0), state.corner_position(uint32_t(t), 2));
    }
  constexpr float inf = std::numeric_limits<float>::infinity();
  std::vector<float3> lo(state.position_count, {inf, inf, inf}), hi(state.position_count, {-inf, -inf, -inf});
  for (size_t t = 0; t < triangles; ++t)
    if (state.alive[t])
      for (uint32_t k = 0; k < 3; ++k) {
        const uint32_t p = state.corner_position(uint32_t(t), k), root = sets.find(p);
        const float3& x = state.position[p];
        lo[root] = {std::min(lo[root].x, x.x), std::min(lo[root].y, x.y), std::min(lo[root].z, x.z)};
        hi[root] = {std::max(hi[root].x, x.x), std::max(hi[root].y, x.y), std::max(hi[root].z, x.z)};
      }
  uint64_t pruned = 0;
  for (size_t t = 0; t < triangles; ++t) {
    if (!state.alive[t]) continue;
    const uint32_t root = sets.find(state.corner_position(uint32_t(t), 0));
    const vec3d d{double(hi[root].x) - lo[root].x, double(hi[root].y) - lo[root].y, double(hi[root].z) - lo[root].z};
    if (length(d) < size) state.alive[t] = 0, --state.live_triangles, ++pruned;
  }
  return pruned;
}

// Internal position ids in Morton order of the positions (ties by public id): the engine's random
// accesses (positions, quadrics, flags of neighbours) then mostly hit the cache.
std::vector<uint32_t> spatial_order(const Mesh& mesh, const PositionIds& ids, const State& state) {
  std::vector<uint64_t> key;
  core::resize_huge(key, ids.count);
  const auto spread = [](uint64_t x) {  // 21 bits -> every third bit of 63
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffull;
    x = (x | x << 16) & 0x1f0000ff0000ffull;
    x = (x | x << 8) & 0x100f00f00f00f00full;
    x = (x | x << 4) & 0x10c30c30c30c30c3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
  };
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    const vec3d q = state.normalized_input(mesh.positions[v]);  // each axis within [-0.5, 0.5]
    const auto cell = [](double x) { return uint64_t(std::clamp((x + 0.5) * 2097151.0, 0.0, 2097151.0)); };
    key[ids.id[v]] = spread(cell(q.x)) | spread(cell(q.y)) << 1 | spread(cell(q.z)) << 2;
  }
  std::vector<uint32_t> order;
  core::resize_huge(order, ids.count);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key[a] < key[b] || (key[a] == key[b] && a < b); });
  std::vector<uint32_t> internal;
  core::resize_huge(internal, ids.count);
  for (uint32_t i = 0; i < ids.count; ++i) internal[order[i]] = i;
  return internal;
}

// The final fit's pull of each position towards its closest input point, against the input
// vertices' pull on the result (fit.h); chosen on the corpus at 10% and 1% among 0.05 to 1.
constexpr double fit_weight = 0.2;

uint64_t target_triangles(const Mesh& mesh, const SimplifyOptions& o) {
  const uint64_t triangles = mesh.triangle_count();
  return o.target_triangles ? std::min<uint64_t>(o.target_triangles, triangles)
                            : uint64_t(std::llround(double(o.target_ratio) * double(triangles)));
}

void check_options(const Mesh& mesh, const SimplifyOptions& o) {
  if (!(o.target_ratio >= 0 && o.target_ratio <= 1)) throw_usage("simplify: target_ratio must be in [0, 1]");
  if (!o.locked.empty() && o.locked.size() != mesh.vertex_count())
    throw_usage("simplify: `locked` must have one entry per vertex");
  if (!o.importance.empty() && o.importance.size() != mesh.vertex_count())
    throw_usage("simplify: `importance` must have one entry per vertex");
  for (const float w : o.importance)
    if (!(w >= 0) || !std::isfinite(w)) throw_usage("simplify: importance weights must be finite and >= 0");
  if (!(o.min_normal_dot >= -1 && o.min_normal_dot <= 1)) throw_usage("simplify: min_normal_dot must be in [-1, 1]");
  for (const float w : {o.normal_weight, o.uv_weight, o.color_weight, o.border_weight, o.max_aspect_ratio, o.distance_guard,
                        o.fit_edge_weight})
    if (!(w >= 0) || !std::isfinite(w))
      throw_usage("simplify: weights, max_aspect_ratio, distance_guard and fit_edge_weight must be finite and >= 0");
  if (!(o.aggregate_distance >= 0)) throw_usage("simplify: aggregate_distance must be >= 0");  // infinity: any pair
  // Negative means no limit; NaN is a mistake, not "no limit".
  if (std::isnan(o.max_error) || std::isnan(o.max_relative_error))
    throw_usage("simplify: max_error and max_relative_error must be numbers (negative: no limit)");
}

}  // namespace
}  // namespace collapse

namespace collapse {

namespace {

// Inputs from this size up return the heap's free pages after the call (core::release_free_memory):
// their arrays (a few MB) are above glibc's mmap threshold.
constexpr size_t trim_triangles = size_t(1) << 16;

// The engine around any metric: the quadric family, or (with `multipose`) the multi-pose metric of
// skinned meshes, whose chosen influences then replace the output's joints and weights.
SimplifyResult simplify_once(const Mesh& mesh, const SimplifyOptions& options, const MultiposeInput* multipose) {
  const auto start = clock::now();
  check_options(mesh, options);
  SimplifyResult result;
  State state(mesh, options);
  state.threads = core::thread_count(options.threads);

  float3 lo, hi;
  bounding_box(mesh, lo, hi);
  state.center = {0.5 * (double(lo.x) + hi.x), 0.5 * (double(lo.y) + hi.y), 0.5 * (double(lo.z) + hi.z)};
  const double extent = std::max({double(hi.x) - lo.x, double(hi.y) - lo.y, double(hi.z) - lo.z});
  state.scale = extent > 0 ? 1.0 / extent : 1.0;
  const vec3d diagonal{double(hi.x) - lo.x, double(hi.y) - lo.y, double(hi.z) - lo.z};
  result.diagonal = float(length(diagonal));

  const PositionIds ids = position_ids(mesh);
  state.position_count = ids.count;
  const std::vector<uint32_t> internal = spatial_order(mesh, ids, state);
  // The working arrays of a large input ask for huge pages before their first touch (core/heap.h).
  core::resize_huge(state.external, ids.count);
  for (uint32_t p = 0; p < ids.count; ++p) state.external[internal[p]] = p;
  core::resize_huge(state.position_of, mesh.vertex_count());
  for (size_t v = 0; v < mesh.vertex_count(); ++v) state.position_of[v] = internal[ids.id[v]];
  core::resize_huge(state.position, ids.count);
  for (size_t v = mesh.vertex_count(); v-- > 0;) state.position[state.position_of[v]] = mesh.positions[v];
  core::assign_huge(state.moves, ids.count, 0);
  core::assign_huge(state.successor, ids.count, none);
  core::assign_huge(state.wedge_successor, mesh.vertex_count(), none);
  state.flags.assign(ids.count, 0);
  for (size_t v = 0; v < options.locked.size(); ++v)
    if (options.locked[v]) state.flags[state.position_of[v]] |= flag_locked;
  if (!options.importance.empty()) {
    state.importance.assign(ids.count, 0.0f);
    for (size_t v = 0; v < mesh.vertex_count(); ++v) {
      float& w = state.importance[state.position_of[v]];
      w = std::max(w, options.importance[v]);
    }
  }
  core::copy_huge(state.corners, mesh.indices);
  core::resize_huge(state.corner_pos, state.corners.size());
  for (size_t i = 0; i < state.corners.size(); ++i) state.corner_pos[i] = state.position_of[state.corners[i]];
  state.alive.assign(mesh.triangle_count(), 1);
  state.live_triangles = mesh.triangle_count();
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    const uint32_t* p = &state.corner_pos[3 * size_t(t)];
    if (p[0] == p[1] || p[1] == p[2] || p[2] == p[0]) state.degenerate.push_back(t), state.alive[t] = 0;
  }
  state.layout = attribute_layout(mesh);
  state.attributes = gather_attributes(mesh, state.layout);

  const uint64_t triangles = mesh.triangle_count();
  const uint64_t target = target_triangles(mesh, options);
  double limit = std::numeric_limits<double>::infinity();
  if (options.max_error >= 0) limit = std::min(limit, double(options.max_error) * state.scale);
  if (options.max_relative_error >= 0)
    limit = std::min(limit, double(options.max_relative_error) * result.diagonal * state.scale);
  const double cost_limit = limit * limit;

  std::vector<Channel> channels;
  if (options.normal_weight > 0 && state.layout.normal >= 0)
    channels.push_back({uint32_t(state.layout.normal), 3, options.normal_weight, Channel::normal});
  if (options.uv_weight > 0)
    for (uint32_t k = 0; k < state.layout.uv_sets; ++k)
      channels.push_back({uint32_t(state.layout.uv[k]), 2, options.uv_weight, Channel::uv});
  if (options.color_weight > 0 && state.layout.color >= 0)
    channels.push_back({uint32_t(state.layout.color), 4, options.color_weight, Channel::color});

  result.record.stride = state.layout.stride;
  const auto engine_start = clock::now();
  result.seconds_setup = seconds(start, engine_start);
  // multipose: per input vertex, its position's influences where a collapse chose them, else
  // weightless (the vertex keeps its own, as a replay of the record does).
  std::vector<Influences> final_influences;
  if (multipose) {
    MultiposeMetric metric(*multipose);
    run(state, metric, {}, target, cost_limit, result);
    final_influences.resize(mesh.vertex_count());
    for (size_t v = 0; v < mesh.vertex_count(); ++v)
      if (metric.chose(state.position_of[v])) final_influences[v] = metric.influences(state.position_of[v]);
  } else if (options.metric == Metric::edge_length) {
    EdgeLengthMetric metric;
    run(state, metric, {}, target, cost_limit, result);
  } else {
    const bool constrained = options.metric == Metric::constrained_qem || options.metric == Metric::constrained_memoryless;
    const bool memoryless = options.metric == Metric::memoryless || options.metric == Metric::constrained_memoryless;
    QuadricMetric metric(constrained, memoryless, channels);
    run(state, metric, channels, target, cost_limit, result);
  }
  // No collapse took the degenerate triangles: the output is the input, they included.
  for (const uint32_t t : state.degenerate) state.alive[t] = 1;
  const auto fit_start = clock::now();
  result.seconds_collapse = seconds(engine_start, fit_start);
  result.fit_flips = options.fit_flips, result.fit_edge_weight = options.fit_edge_weight;
  // The fit moves positions only: keep_vertices promises input vertices, and the multi-pose metric
  // places positions for every pose, which a rest-pose fit would undo.
  const bool on_input = result.error < fit_skip_error * result.diagonal;
  if (options.fit_iterations > 0 && !options.keep_vertices && !multipose && !on_input) {
    std::vector<FittedPosition> fitted;
    std::vector<Relink> flipped;
    result.fit_iterations =
        fit_positions(state, options.fit_iterations, fit_weight, options.fit_edge_weight, options.fit_flips, &fitted, &flipped);
    result.fitted_positions = fitted.size();
    result.flipped_edges = flipped.size() / 2;
    if (options.record) result.record.fitted = std::move(fitted), result.record.flipped = std::move(flipped);
    result.seconds_fit = seconds(fit_start, clock::now());
  }

  // Pruning comes after the record: replaying the record gives the mesh before pruning.
  if (options.prune) result.pruned_triangles = prune_components(state, result.error);
  const Snapshot snapshot{state.position_of, state.position, state.moves, state.corners,
                          state.alive, &state.layout, state.attributes};
  result.mesh = compact(mesh, snapshot, &result.vertex_origin, &result.triangle_origin);
  // Each input vertex's output vertex: the wedge its relinks end at, if that is in the output.
  std::vector<uint32_t>& next = state.wedge_successor;
  core::assign_huge(result.vertex_successor, mesh.vertex_count(), none);
  std::vector<uint32_t> output_of = core::make_huge<uint32_t>(mesh.vertex_count(), none);
  for (uint32_t v = 0; v < result.vertex_origin.size(); ++v) output_of[result.vertex_origin[v]] = v;
  for (uint32_t w = 0; w < mesh.vertex_count(); ++w) result.vertex_successor[w] = output_of[core::chain_end(next, w)];
  if (multipose)
    for (size_t v = 0; v < result.mesh.vertex_count(); ++v) {
      const Influences& w = final_influences[result.vertex_origin[v]];
      if (!has_weight(w)) continue;
      result.mesh.joints[v] = {w.joint[0], w.joint[1], w.joint[2], w.joint[3]};
      result.mesh.weights[v] = {w.weight[0], w.weight[1], w.weight[2], w.weight[3]};
      if (!result.mesh.joints1.empty()) {
        result.mesh.joints1[v] = {w.joint[4], w.joint[5], w.joint[6], w.joint[7]};
        result.mesh.weights1[v] = {w.weight[4], w.weight[5], w.weight[6], w.weight[7]};
      }
    }
  result.relative_error = result.diagonal > 0 ? result.error / result.diagonal : 0;
  result.metric = options.metric;
  result.input_triangles = triangles;
  result.input_vertices = mesh.vertex_count();
  result.output_triangles = result.mesh.triangle_count();
  result.output_vertices = result.mesh.vertex_count();
  result.seconds_total = seconds(start, clock::now());
  return result;
}

// The ways the search (SimplifyOptions::search_input_triangles) tries: the options as set first.
// Its cost grows with the input, its gain with how far down the result is (one collapse's choice
// shows more among few triangles): at 10% on the corpus it won one case more, at 1% six.
std::vector<SimplifyOptions> search_ways(const Mesh& mesh, const SimplifyOptions& o) {
  std::vector<SimplifyOptions> ways{o};
  const bool quadric = o.metric == Metric::qem || o.metric == Metric::constrained_qem;
  // An error limit stops each way at a different count; aggregation merges parts, which the
  // Hausdorff distance does not reward.
  if (!quadric || mesh.triangle_count() > o.search_input_triangles || target_triangles(mesh, o) > o.search_output_triangles ||
      o.max_error >= 0 || o.max_relative_error >= 0 || o.aggregate_distance > 0)
    return ways;
  for (const float guard : {0.0f, 2.0f})
    if (guard != o.distance_guard) ways.push_back(o), ways.back().distance_guard = guard;
  ways.push_back(o);
  ways.back().metric = o.metric == Metric::qem ? Metric::memoryless : Metric::constrained_memoryless;
  // The fit's edge term and flips were chosen for the corpus as a whole; on some meshes a plain fit
  // comes nearer (ellipe0.003 at 1%: Hausdorff 0.0402 -> 0.0384 of the diagonal).
  if (o.fit_iterations > 0 && !o.keep_vertices && (o.fit_flips || o.fit_edge_weight != 0)) {
    ways.push_back(o);
    ways.back().fit_flips = false, ways.back().fit_edge_weight = 0;
  }
  return ways;
}

// The search's own samples: not the seed a caller's lod::compare uses by default, so that the choice
// is not tuned to the samples it is later judged by. Two per input triangle, at least 1,000 (not
// lod::compare's 10,000: on a tiny mesh that floor cost more than the four simplifications): the
// vertices and edges are sampled as well, where the largest distances mostly lie.
constexpr uint64_t search_seed = 0x5ea6c4;
constexpr uint64_t search_samples_per_triangle = 2, search_min_samples = 1'000;

SimplifyResult search(const Mesh& mesh, const std::vector<SimplifyOptions>& ways) {
  const auto start = clock::now();
  const SimplifyOptions& first = ways.front();
  const size_t n = ways.size();
  // With several threads the ways run side by side, one thread each (a small mesh keeps two threads
  // busy with one way each better than with one way at a time); each result is the same on any
  // thread count, so the choice is too.
  const unsigned threads = core::thread_count(first.threads);
  const unsigned each_threads = threads > 1 ? 1 : first.threads;
  const CompareOptions measure{.samples = std::max<uint64_t>(search_min_samples, search_samples_per_triangle * mesh.triangle_count()),
                               .seed = search_seed,
                               .attributes = false,
                               .threads = each_threads};
  std::vector<SimplifyResult> results(n);
  std::vector<double> distance(n, std::numeric_limits<double>::infinity());
  // Progress comes from the calling thread only: (ways finished + the current way's fraction) / n.
  const std::thread::id caller = std::this_thread::get_id();
  std::atomic<size_t> finished{0};
  double reported = 0;
  core::parallel_for(n, threads, [&](size_t i) {
    SimplifyOptions way = ways[i];
    way.threads = each_threads;
    way.progress = nullptr;
    if (first.progress)
      way.progress = [&](double f) {
        if (std::this_thread::get_id() != caller) return;
        reported = std::max(reported, std::min(1.0, (double(finished.load()) + f) / double(n)));
        first.progress(reported);
      };
    results[i] = simplify_once(mesh, way, nullptr);
    if (results[i].mesh.triangle_count()) distance[i] = compare(mesh, results[i].mesh, measure).relative_hausdorff;
    ++finished;
  }, 1);
  if (first.progress) first.progress(1.0);
  // A way that stopped shorter than the first (the topology held it) had an easier job.
  const uint64_t most_triangles = std::max(target_triangles(mesh, first), results[0].output_triangles);
  size_t best = 0;
  for (size_t i = 1; i < n; ++i)
    if (results[i].output_triangles <= most_triangles && distance[i] < distance[best]) best = i;
  SimplifyResult result = std::move(results[best]);
  result.search_ways = uint32_t(n);
  result.search_hausdorff = std::isfinite(distance[best]) ? distance[best] : 0;
  result.seconds_total = seconds(start, clock::now());
  return result;
}

}  // namespace

SimplifyResult simplify_with(const Mesh& mesh, const SimplifyOptions& options, const MultiposeInput* multipose) {
  const std::vector<SimplifyOptions> ways = multipose ? std::vector<SimplifyOptions>{options} : search_ways(mesh, options);
  SimplifyResult result = ways.size() > 1 ? search(mesh, ways) : simplify_once(mesh, options, multipose);
  // The working state is gone: a LOD chain's next call starts afresh. Only after large calls: a
  // small one's arrays stay below glibc's mmap threshold (and trimming scans the whole heap, which
  // in a host simplifying thousands of small meshes would cost more than it saves).
  if (mesh.triangle_count() >= trim_triangles) core::release_free_memory();
  return result;
}

SimplifyResult simplify_multipose(const Mesh& mesh, const SimplifyOptions& options, const MultiposeInput& input) {
  if (mesh.joints.empty() || mesh.weights.empty()) throw_usage("simplify: the multi-pose metric needs joints and weights");
  if (mesh.joints1.size() != mesh.weights1.size() || (!mesh.joints1.empty() && mesh.joints1.size() != mesh.vertex_count()))
    throw_usage("simplify: the second influence set needs one joint and one weight entry per vertex");
  if (input.poses.empty()) throw_usage("simplify: the multi-pose metric needs at least one pose");
  for (const auto& pose : input.poses)
    if (pose.size() != input.poses[0].size()) throw_usage("simplify: every pose needs the same joint count");
  if (!input.pose_weights.empty() && input.pose_weights.size() != input.poses.size())
    throw_usage("simplify: pose_weights needs one weight per pose");
  for (const float w : input.pose_weights)
    if (!(w >= 0) || !std::isfinite(w)) throw_usage("simplify: pose weights must be finite and >= 0");
  SimplifyOptions o = options;
  o.metric = Metric::constrained_qem;  // for the engine's border rules: the metric has border planes
  return simplify_with(mesh, o, &input);
}

}  // namespace collapse

SimplifyResult simplify(const Mesh& mesh, const SimplifyOptions& options) {
  return collapse::simplify_with(mesh, options, nullptr);
}

std::vector<SimplifyResult> simplify_batch(std::span<const Mesh* const> meshes, std::span<const SimplifyOptions> options,
                                           unsigned threads, const std::function<void(double)>& progress) {
  if (options.size() != meshes.size())
    throw_usage("simplify_batch: " + std::to_string(meshes.size()) + " meshes and " + std::to_string(options.size()) + " options");
  std::vector<SimplifyResult> results(meshes.size());
  core::parallel_meshes(meshes, "simplify_batch", threads, progress,
                        [&](size_t i, unsigned job_threads, const std::function<void(double)>& job_progress) {
                          SimplifyOptions one = options[i];
                          one.threads = job_threads, one.progress = job_progress;
                          results[i] = simplify(*meshes[i], one);
                        });
  return results;
}

}  // namespace lod
