#include "measure/bvh.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/heap.h"
#include "core/parallel.h"
#include "lodkit/error.h"

// Eight-lane vectors are passed only to inlined functions: no ABI concerns (GCC warns at the end of
// the file, so this cannot be scoped).
#pragma GCC diagnostic ignored "-Wpsabi"

namespace lod::measure {

namespace {

constexpr float inf = std::numeric_limits<float>::infinity();
constexpr int bin_count = 16;
constexpr uint32_t max_leaf = 8;  // triangles per leaf (a node's leaf link can count up to 16)
// SAH's cost of visiting a node, against 1 for a triangle: a group's node visit sorts and pushes its
// children, and a leaf's triangles are tested a batch of points at a time with a box test first, so
// leaves of a few triangles (rather than SAH's usual one or two) save visits (3% of the instructions).
constexpr float traversal_cost = 4;
constexpr uint32_t max_binned_depth = 64;  // deeper than this, split at the median: depth stays bounded
constexpr uint32_t max_depth = 128;        // traversal stack: 3 entries per level plus one
// Pruning compares a box's float distance with a triangle's float distance; both round. Boxes are
// grown by a few ulps of the scene's extent and the comparison has a relative slack, so a box that
// holds the closest triangle is never skipped (the result must equal a brute-force scan).
constexpr float prune_slack = 1.0f + 1.0f / (1 << 18);
// closest_group gives up on a group after scanning this many triangles (the points are too far apart).
constexpr size_t max_group_scanned = 128;

// A binary node's bounds: six floats.
struct Bounds {
  float lo[3], hi[3];
  // Half the surface area, which is all SAH needs (ratios).
  float half_area() const {
    const float x = hi[0] - lo[0], y = hi[1] - lo[1], z = hi[2] - lo[2];
    return x < 0 ? 0 : x * y + y * z + z * x;
  }
};

// Four floats per corner (the fourth is ignored), so the build grows boxes with one SSE min and max.
struct alignas(16) Box {
  float lo[4] = {inf, inf, inf, inf}, hi[4] = {-inf, -inf, -inf, -inf};
  void grow(const Box& b) { grow(b.lo, b.hi); }
  void grow(const vec3f& p) { grow(&p.x, &p.x); }
  void grow(const float* blo, const float* bhi) {
#if defined(__SSE2__)
    _mm_store_ps(lo, _mm_min_ps(_mm_load_ps(lo), _mm_loadu_ps(blo)));
    _mm_store_ps(hi, _mm_max_ps(_mm_load_ps(hi), _mm_loadu_ps(bhi)));
#else
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], blo[k]), hi[k] = std::max(hi[k], bhi[k]);
#endif
  }
  void grow_point(const float* p) {
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  }
  Bounds bounds() const { return {{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}}; }
  float half_area() const { return bounds().half_area(); }
};

// A box [lo, hi] (a point when lo == hi) measured against four boxes at once.
class Probe {
 public:
  Probe(const float* lo, const float* hi) {
    for (int k = 0; k < 3; ++k) {
      lo_[k] = lo[k], hi_[k] = hi[k];
#if defined(__SSE2__)
      vlo_[k] = _mm_set1_ps(lo[k]), vhi_[k] = _mm_set1_ps(hi[k]);
#endif
    }
  }
  explicit Probe(const vec3f& p) : Probe(&p.x, &p.x) {}

  // Squared distances to four boxes stored as 24 floats (min x, y, z, max x, y, z; four lanes each),
  // into d when given; returns the lanes within `limit` as a bit mask. A box-to-box distance is never
  // more than any one point's distance.
  int within(const float* b, float limit, float* d = nullptr) const {
#if defined(__SSE2__)
    const __m128 zero = _mm_setzero_ps();
    __m128 d2 = zero;
    for (int k = 0; k < 3; ++k) {
      const __m128 gap = _mm_max_ps(_mm_max_ps(_mm_sub_ps(_mm_loadu_ps(b + 4 * k), vhi_[k]),
                                               _mm_sub_ps(vlo_[k], _mm_loadu_ps(b + 4 * (k + 3)))),
                                    zero);
      d2 = _mm_add_ps(d2, _mm_mul_ps(gap, gap));
    }
    if (d) _mm_storeu_ps(d, d2);
    return _mm_movemask_ps(_mm_cmple_ps(d2, _mm_set1_ps(limit)));
#else
    int mask = 0;
    for (int lane = 0; lane < 4; ++lane) {
      float d2 = 0;
      for (int k = 0; k < 3; ++k) {
        const float gap = std::max({b[4 * k + lane] - hi_[k], lo_[k] - b[4 * (k + 3) + lane], 0.0f});
        d2 += gap * gap;
      }
      if (d) d[lane] = d2;
      if (d2 <= limit) mask |= 1 << lane;
    }
    return mask;
#endif
  }

  // For a point probe: the lanes whose planes (unit normal x, y, z, offset; four lanes each) lie
  // within sqrt(limit) of the point, less `slack` for rounding. A triangle is never nearer than its
  // plane, so this prunes candidates whose boxes the point is inside (large or tilted triangles).
  int planes_within(const float* plane, float slack, float limit) const {
#if defined(__SSE2__)
    const __m128 dot = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_loadu_ps(plane), vlo_[0]), _mm_mul_ps(_mm_loadu_ps(plane + 4), vlo_[1])),
                                  _mm_mul_ps(_mm_loadu_ps(plane + 8), vlo_[2]));
    const __m128 diff = _mm_sub_ps(dot, _mm_loadu_ps(plane + 12));
    const __m128 abs = _mm_max_ps(diff, _mm_sub_ps(_mm_setzero_ps(), diff));
    const __m128 gap = _mm_max_ps(_mm_sub_ps(abs, _mm_set1_ps(slack)), _mm_setzero_ps());
    return _mm_movemask_ps(_mm_cmple_ps(_mm_mul_ps(gap, gap), _mm_set1_ps(limit)));
#else
    int mask = 0;
    for (int lane = 0; lane < 4; ++lane) {
      const float dot = plane[lane] * lo_[0] + plane[4 + lane] * lo_[1] + plane[8 + lane] * lo_[2];
      const float gap = std::max(std::fabs(dot - plane[12 + lane]) - slack, 0.0f);
      if (gap * gap <= limit) mask |= 1 << lane;
    }
    return mask;
#endif
  }

 private:
  float lo_[3], hi_[3];
#if defined(__SSE2__)
  __m128 vlo_[3], vhi_[3];
#endif
};

struct BinaryNode {
  Bounds box;
  uint32_t left = 0;          // inner: children at left and left + 1
  uint32_t begin = 0, count = 0;  // leaf: range of the triangle order (count > 0)
};

// A triangle as the build files it: its bounds and its mesh index, 32 bytes. The build moves these
// with its partitions, so each pass over a node's range reads them in sequence (an index array into
// per-triangle boxes made every pass a gather: most of the build's cache misses). Box::grow reads lo
// and hi as four floats each; the fourth (the index's bits, the padding) is ignored.
struct alignas(16) Ref {
  float lo[3];
  uint32_t triangle;
  float hi[3];
  float unused = 0;
  float centroid(int axis) const { return (lo[axis] + hi[axis]) * 0.5f; }
};

struct Bin {
  Box box, centroids;
  uint32_t count = 0;
};

// A node to build over refs[begin, end), with its triangles' box and their centroids' box (known
// from the parent's bins, so no pass over the range is needed for them).
struct BuildTask {
  uint32_t node, begin, end, depth;
  Box box, centroids;
};

// The boxes of refs[begin, end) and of their centroids.
void bound_range(const std::vector<Ref>& refs, uint32_t begin, uint32_t end, Box& box, Box& centroids) {
  for (uint32_t i = begin; i < end; ++i) {
    const Ref& r = refs[i];
    box.grow(r.lo, r.hi);
    const float c[3] = {r.centroid(0), r.centroid(1), r.centroid(2)};
    centroids.grow_point(c);
  }
}

// Binned SAH over triangle centroids, building a binary tree (root at index 0) whose leaves are ranges
// of `refs`, over refs[task.begin, task.end). Nodes at `defer_depth` are left empty and listed in
// `deferred`.
std::vector<BinaryNode> build_binary(std::vector<Ref>& refs, const BuildTask& root, uint32_t defer_depth,
                                     std::vector<BuildTask>& deferred) {
  std::vector<BinaryNode> nodes;
  // At most a node per triangle (leaves of a few); a call that defers stops after a few levels.
  const uint32_t size = root.end - root.begin;
  nodes.reserve(defer_depth < 32 ? std::min<size_t>(size, size_t(2) << (defer_depth - root.depth)) : size);
  nodes.emplace_back();
  std::vector<BuildTask> tasks{root};
  tasks.back().node = 0;
  while (!tasks.empty()) {
    const BuildTask task = tasks.back();
    tasks.pop_back();
    if (task.depth == defer_depth && task.end - task.begin > max_leaf) {
      deferred.push_back(task);
      continue;
    }
    const uint32_t n = task.end - task.begin;
    const Box& centroid_box = task.centroids;
    nodes[task.node].box = task.box.bounds();
    auto make_leaf = [&] {
      nodes[task.node].begin = task.begin;
      nodes[task.node].count = n;
    };
    // A split costs at least a node visit, so a node of no more triangles than that is a leaf.
    if (float(n) <= traversal_cost) {
      make_leaf();
      continue;
    }

    // Binned along the centroids' longest axis only: a third of the work of binning all three, and
    // the split it misses rarely matters for closest-point queries.
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (centroid_box.hi[a] - centroid_box.lo[a] > centroid_box.hi[axis] - centroid_box.lo[axis]) axis = a;
    const float extent = centroid_box.hi[axis] - centroid_box.lo[axis];
    const float scale = extent > 0 ? float(bin_count) / extent : 0.0f;
    auto bin_of = [&](const Ref& r) {
      const float t = (r.centroid(axis) - centroid_box.lo[axis]) * scale;
      return std::min(bin_count - 1, std::max(0, int(t)));
    };
    float best_cost = inf;
    int best_split = 0;  // left side: bins [0, best_split)
    Bin bins[bin_count];
    if (scale > 0) {
      for (uint32_t i = task.begin; i < task.end; ++i) {
        const Ref& r = refs[i];
        Bin& b = bins[bin_of(r)];
        b.box.grow(r.lo, r.hi);
        const float c[3] = {r.centroid(0), r.centroid(1), r.centroid(2)};
        b.centroids.grow_point(c);
        ++b.count;
      }
      float right_area[bin_count];
      uint32_t right_count[bin_count];
      Box acc;
      uint32_t count = 0;
      for (int k = bin_count - 1; k > 0; --k) {
        acc.grow(bins[k].box);
        count += bins[k].count;
        right_area[k] = acc.half_area(), right_count[k] = count;
      }
      acc = Box{};
      count = 0;
      for (int k = 1; k < bin_count; ++k) {
        acc.grow(bins[k - 1].box);
        count += bins[k - 1].count;
        if (count == 0 || right_count[k] == 0) continue;
        const float cost = acc.half_area() * float(count) + right_area[k] * float(right_count[k]);
        if (cost < best_cost) best_cost = cost, best_split = k;
      }
    }
    const int best_axis = best_cost < inf ? axis : -1;
    // SAH in units of one triangle test, relative to this node's area.
    const float area = task.box.half_area();
    const float split_cost = traversal_cost + (area > 0 ? best_cost / area : float(n));
    if (n <= max_leaf && (best_axis < 0 || float(n) <= split_cost)) {
      make_leaf();
      continue;
    }
    uint32_t mid;
    BuildTask left_task{0, task.begin, 0, task.depth + 1, {}, {}}, right_task{0, 0, task.end, task.depth + 1, {}, {}};
    if (best_axis < 0 || task.depth >= max_binned_depth) {
      // Coincident centroids (or a pathological chain of thin splits): halve the range.
      mid = task.begin + n / 2;
      bound_range(refs, task.begin, mid, left_task.box, left_task.centroids);
      bound_range(refs, mid, task.end, right_task.box, right_task.centroids);
    } else {
      Ref* first = refs.data() + task.begin;
      mid = uint32_t(std::partition(first, refs.data() + task.end, [&](const Ref& r) { return bin_of(r) < best_split; }) -
                     refs.data());
      for (int k = 0; k < bin_count; ++k) {
        BuildTask& side = k < best_split ? left_task : right_task;
        side.box.grow(bins[k].box), side.centroids.grow(bins[k].centroids);
      }
    }
    const uint32_t left = uint32_t(nodes.size());
    nodes[task.node].left = left;
    nodes.emplace_back();
    nodes.emplace_back();
    left_task.node = left, left_task.end = mid;
    right_task.node = left + 1, right_task.begin = mid;
    // Right pushed first so the left subtree is built (and numbered) first.
    tasks.push_back(right_task);
    tasks.push_back(left_task);
  }
  return nodes;
}

// The same tree built in parts: the top levels first, then the subtrees below `split_depth` side by
// side (they own disjoint ranges of `refs`), spliced in list order. The split depth is fixed, so the
// layout does not depend on the thread count.
std::vector<BinaryNode> build_binary(std::vector<Ref>& refs, unsigned threads) {
  constexpr uint32_t split_depth = 3;  // up to 8 subtrees
  BuildTask root{0, 0, uint32_t(refs.size()), 0, {}, {}};
  bound_range(refs, root.begin, root.end, root.box, root.centroids);
  std::vector<BuildTask> deferred, none;
  std::vector<BinaryNode> nodes = build_binary(refs, root, split_depth, deferred);
  std::vector<std::vector<BinaryNode>> parts(deferred.size());
  core::parallel_blocks(deferred.size(), 1, threads, [&](size_t k, size_t, size_t) {
    parts[k] = build_binary(refs, deferred[k], UINT32_MAX, none);
  });
  size_t total = nodes.size();
  for (const std::vector<BinaryNode>& part : parts) total += part.size() - 1;
  nodes.reserve(total);
  for (size_t k = 0; k < deferred.size(); ++k) {
    // The part's root takes the deferred node's place; its other nodes follow, their child links moved.
    const uint32_t offset = uint32_t(nodes.size()) - 1;
    auto moved = [&](BinaryNode n) {
      if (n.count == 0) n.left += offset;
      return n;
    };
    nodes[deferred[k].node] = moved(parts[k][0]);
    for (size_t i = 1; i < parts[k].size(); ++i) nodes.push_back(moved(parts[k][i]));
    std::vector<BinaryNode>().swap(parts[k]);  // freed as it is copied: the peak stays near one tree
  }
  return nodes;
}

// The tree over refs in their given order: each node halves its range, down to leaves of at most
// max_leaf triangles; boxes come back up from the leaves. One pass over the refs, no binning.
Box build_in_order(const std::vector<Ref>& refs, uint32_t begin, uint32_t end, uint32_t node,
                   std::vector<BinaryNode>& nodes) {
  Box box;
  if (end - begin <= max_leaf) {
    for (uint32_t i = begin; i < end; ++i) box.grow(refs[i].lo, refs[i].hi);
    nodes[node].begin = begin, nodes[node].count = end - begin;
  } else {
    const uint32_t left = uint32_t(nodes.size()), mid = begin + (end - begin) / 2;
    nodes[node].left = left;
    nodes.emplace_back();
    nodes.emplace_back();
    box = build_in_order(refs, begin, mid, left, nodes);
    box.grow(build_in_order(refs, mid, end, left + 1, nodes));
  }
  nodes[node].box = box.bounds();
  return box;
}

// closest_group's points in lanes: per point (padded to whole batches) x, y, z, the squared distance
// to its best triangle so far and that triangle's mesh index.
struct LaneArrays {
  float* floats;
  int32_t* ints;
  uint32_t n;
  float* x() const { return floats; }
  float* y() const { return floats + n; }
  float* z() const { return floats + 2 * size_t(n); }
  float* distance_squared() const { return floats + 3 * size_t(n); }
  int32_t* triangle() const { return ints; }
};

// closest_group's candidates (leaf order) and the tree's per-triangle arrays.
struct GroupCandidates {
  const uint32_t* slots;
  size_t count;
  const float* box;  // 6 per triangle
  const PreparedTriangle* triangles;
  const uint32_t* original;
  float plane_slack;
};

template <class V>
[[gnu::always_inline]] inline V load_lanes(const void* p) {
  V v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
template <class V>
[[gnu::always_inline]] inline void store_lanes(void* p, const V& v) {
  std::memcpy(p, &v, sizeof v);
}

// Each batch of points scans the candidates: box, then plane, then the exact distance of every lane.
// A lane takes a triangle when it is nearer, or as near with a lower index (as a brute-force scan
// would); a lane the box or the plane ruled out is never nearer, so taking it or not changes nothing.
template <int W>
struct Batch {
  typename Lanes<W>::F px, py, pz, best;
  typename Lanes<W>::I triangle;
  void load(const LaneArrays& l, uint32_t i) {
    using F = typename Lanes<W>::F;
    using I = typename Lanes<W>::I;
    px = load_lanes<F>(l.x() + i), py = load_lanes<F>(l.y() + i), pz = load_lanes<F>(l.z() + i);
    best = load_lanes<F>(l.distance_squared() + i);
    triangle = load_lanes<I>(l.triangle() + i);
  }
  void store(const LaneArrays& l, uint32_t i) const {
    store_lanes(l.distance_squared() + i, best);
    store_lanes(l.triangle() + i, triangle);
  }
  // The largest lane, by halving (distances are never NaN).
  float upper() const {
    typename Lanes<4>::F m;
    if constexpr (W == 8) {
      const typename Lanes<4>::F lo = __builtin_shufflevector(best, best, 0, 1, 2, 3);
      const typename Lanes<4>::F hi = __builtin_shufflevector(best, best, 4, 5, 6, 7);
      m = lo > hi ? lo : hi;
    } else {
      m = best;
    }
    const typename Lanes<4>::F q = __builtin_shufflevector(m, m, 2, 3, 0, 1);
    m = m > q ? m : q;
    return std::max(m[0], m[1]);
  }
};

// How far each lane lies outside [lo, hi]. A function, not a lambda: inlined, it takes an AVX2
// caller's target (a lambda left out of line would pass eight-lane vectors without AVX).
template <int W>
[[gnu::always_inline]] inline typename Lanes<W>::F box_gap(const typename Lanes<W>::F& q, float lo, float hi) {
  using F = typename Lanes<W>::F;
  const F below = lo - q, above = q - hi, zero{};
  const F g = below > above ? below : above;
  return g > zero ? g : zero;
}

template <int W>
[[gnu::always_inline]] inline void scan_batch(Batch<W>& p, const GroupCandidates& c) {
  using F = typename Lanes<W>::F;
  using I = typename Lanes<W>::I;
  const F zero{};
  F limit = p.best * prune_slack;
  for (size_t k = 0; k < c.count; ++k) {
    const uint32_t slot = c.slots[k];
    const float* b = c.box + 6 * size_t(slot);
    const F gx = box_gap<W>(p.px, b[0], b[3]), gy = box_gap<W>(p.py, b[1], b[4]), gz = box_gap<W>(p.pz, b[2], b[5]);
    const I near_box = gx * gx + gy * gy + gz * gz <= limit;
    if (!any_lane<W>(near_box)) continue;
    // The distance to the plane (h) bounds the triangle's, and is a face point's distance.
    const PreparedTriangle& tri = c.triangles[slot];
    const F apx = p.px - tri.a.x, apy = p.py - tri.a.y, apz = p.pz - tri.a.z;
    const F h = tri.normal.x * apx + tri.normal.y * apy + tri.normal.z * apz;
    const F size = (h < zero ? -h : h) - c.plane_slack;
    const F plane_gap = size > zero ? size : zero;
    if (!any_lane<W>(near_box & (plane_gap * plane_gap <= limit))) continue;
    const F d = closest_on_triangle_lanes<W>(apx, apy, apz, h, tri);
    const I index = I{} + int32_t(c.original[slot]);
    const I take = (d < p.best) | ((d == p.best) & (index < p.triangle));
    p.best = take ? d : p.best;
    p.triangle = take ? index : p.triangle;
    limit = p.best * prune_slack;
  }
}

// Every batch of points through scan_batch; returns the largest best distance.
template <int W>
[[gnu::always_inline]] inline float scan_lanes(const LaneArrays& l, const GroupCandidates& c) {
  float upper = 0;
  for (uint32_t i = 0; i < l.n; i += W) {
    Batch<W> p;
    p.load(l, i);
    scan_batch<W>(p, c);
    p.store(l, i);
    upper = std::max(upper, p.upper());
  }
  return upper;
}

// closest_group's search: one traversal for the whole group, nearest boxes (to the points' box)
// first, scanning each leaf's triangles in lanes as it is reached. The bound is the largest of the
// points' best distances so far, so it shrinks as leaves are scanned; a box farther from the points'
// box than that cannot hold any point's closest triangle. Every lane starts from the hint triangle.
// Returns false, leaving the lanes with their best so far, once more than `budget` triangles were
// scanned (the points are spread too far for one search).
struct GroupTree {
  const BvhNode* nodes;
  GroupCandidates leaves;  // slots unused: a leaf's triangles are a range of the leaf order
};

// scan(candidates) scans the points (one batch kept in registers, or all of them) and returns the
// largest best distance.
template <class Scan>
[[gnu::always_inline]] inline bool search_group(const GroupTree& tree, const float* lo, const float* hi,
                                                uint32_t hint_slot, uint32_t budget, Scan&& scan) {
  GroupCandidates c = tree.leaves;
  uint32_t slots[16];
  c.slots = slots;
  slots[0] = hint_slot;
  c.count = 1;
  float upper = scan(c);
  uint32_t stack[3 * max_depth + 4];
  float stack_distance[3 * max_depth + 4], stack_key[3 * max_depth + 4];
  int top = 0;
  stack[top] = 0, stack_distance[top] = 0, stack_key[top] = 0, ++top;
  const Probe probe(lo, hi);
  // Boxes are visited nearest to the group's centre first (many overlap the group's box, and the
  // triangles nearest its middle bound the most points); pruning uses the distance to the box.
  const vec3f centre{(lo[0] + hi[0]) * 0.5f, (lo[1] + hi[1]) * 0.5f, (lo[2] + hi[2]) * 0.5f};
  const Probe middle(centre);
  uint32_t scanned = 0;
  while (top > 0) {
    --top;
    float limit = upper * prune_slack;
    if (stack_distance[top] > limit) continue;
    const uint32_t ref = stack[top];
    if (ref & bvh_leaf_bit) {
      const uint32_t first = (ref & ~bvh_leaf_bit) >> 4, count = (ref & 15) + 1;
      c.count = 0;
      for (uint32_t s = first; s < first + count; ++s)
        if (s != hint_slot) slots[c.count++] = s;
      scanned += uint32_t(c.count);
      if (scanned > budget) return false;
      upper = scan(c);
      continue;
    }
    const BvhNode& n = tree.nodes[ref];
    float d[4], key[4];
    const int mask = probe.within(n.box, limit, d);
    if (!mask) continue;
    if (!(mask & (mask - 1))) {  // one child (the usual case deep in the tree): no order to find
      const int k = __builtin_ctz(unsigned(mask));
      if (n.child[k] != bvh_empty_child) stack[top] = n.child[k], stack_distance[top] = d[k], stack_key[top] = 0, ++top;
      continue;
    }
    middle.within(n.box, inf, key);
    // Push the hits farthest first, so the nearest is popped next (sorted in place on the stack).
    const int base = top;
    for (unsigned m = unsigned(mask); m; m &= m - 1) {
      const int k = __builtin_ctz(m);
      if (n.child[k] == bvh_empty_child) continue;
      int j = top++;
      for (; j > base && stack_key[j - 1] < key[k]; --j)
        stack[j] = stack[j - 1], stack_distance[j] = stack_distance[j - 1], stack_key[j] = stack_key[j - 1];
      stack[j] = n.child[k], stack_distance[j] = d[k], stack_key[j] = key[k];
    }
  }
  return true;
}

// Four lanes (SSE2, NEON), or eight with AVX2 when the CPU has it (chosen at run time, so a default
// build uses it too). Both give the same bits: AVX2 alone has no fused multiply-add to contract to.
// One batch (the usual patch of 8 with 8 lanes) stays in registers through the whole search.
template <int W>
[[gnu::always_inline]] inline bool search_group_lanes(const LaneArrays& l, const GroupTree& t, const float* lo,
                                                      const float* hi, uint32_t hint_slot, uint32_t budget) {
  // Functors, not lambdas: a lambda would not take the caller's avx2 target.
  struct One {
    Batch<W>& p;
    [[gnu::always_inline]] float operator()(const GroupCandidates& c) const {
      scan_batch<W>(p, c);
      return p.upper();
    }
  };
  struct All {
    const LaneArrays& l;
    [[gnu::always_inline]] float operator()(const GroupCandidates& c) const { return scan_lanes<W>(l, c); }
  };
  if (l.n == W) {
    Batch<W> p;
    p.load(l, 0);
    const bool done = search_group(t, lo, hi, hint_slot, budget, One{p});
    p.store(l, 0);
    return done;
  }
  return search_group(t, lo, hi, hint_slot, budget, All{l});
}
[[gnu::noinline]] bool search_group_narrow(const LaneArrays& l, const GroupTree& t, const float* lo, const float* hi,
                                           uint32_t hint_slot, uint32_t budget) {
  return search_group_lanes<4>(l, t, lo, hi, hint_slot, budget);
}
#if defined(__x86_64__) && defined(__GNUC__)
[[gnu::noinline, gnu::target("avx2")]] bool search_group_wide(const LaneArrays& l, const GroupTree& t, const float* lo,
                                                              const float* hi, uint32_t hint_slot, uint32_t budget) {
  return search_group_lanes<8>(l, t, lo, hi, hint_slot, budget);
}
std::atomic<unsigned> lane_width{0};
bool use_wide_lanes() {
  static const bool avx2 = __builtin_cpu_supports("avx2");
  const unsigned w = lane_width.load(std::memory_order_relaxed);
  return w ? w == 8 && avx2 : avx2;
}
#else
bool search_group_wide(const LaneArrays& l, const GroupTree& t, const float* lo, const float* hi, uint32_t hint_slot,
                       uint32_t budget) {
  return search_group_narrow(l, t, lo, hi, hint_slot, budget);
}
std::atomic<unsigned> lane_width{0};
bool use_wide_lanes() { return false; }
#endif

}  // namespace

TriangleBvh::TriangleBvh(const Mesh& mesh, unsigned threads) : TriangleBvh(mesh, {}, threads) {}

TriangleBvh::TriangleBvh(const Mesh& mesh, std::span<const uint32_t> coherent_order, unsigned threads) {
  const size_t triangles = mesh.triangle_count();
  if (triangles == 0) throw_internal("TriangleBvh: no triangles");
  if (triangles >= (size_t(1) << 27)) throw_bad_input("mesh", "more than 2^27 triangles to measure");
  const bool in_order = !coherent_order.empty();
  if (in_order) {
    std::vector<uint8_t> seen(triangles, 0);
    for (const uint32_t t : coherent_order)
      if (t >= triangles || seen[t]++) throw_internal("TriangleBvh: the coherent order is not a permutation of the triangles");
    if (coherent_order.size() != triangles) throw_internal("TriangleBvh: the coherent order misses triangles");
  }

  std::vector<Ref> refs = core::make_huge<Ref>(triangles);
  core::parallel_for(triangles, threads, [&](size_t i) {
    const uint32_t t = in_order ? coherent_order[i] : uint32_t(i);
    Box b;
    for (int k = 0; k < 3; ++k) b.grow_point(&mesh.positions[mesh.indices[3 * size_t(t) + k]].x);
    Ref& r = refs[i];
    for (int k = 0; k < 3; ++k) r.lo[k] = b.lo[k], r.hi[k] = b.hi[k];
    r.triangle = t;
  });
  std::vector<BinaryNode> binary;
  if (in_order) {
    binary.reserve(4 * (triangles / max_leaf + 1));
    binary.emplace_back();
    build_in_order(refs, 0, uint32_t(triangles), 0, binary);
  } else {
    binary = build_binary(refs, threads);
  }
  std::vector<uint32_t> order = core::make_huge<uint32_t>(triangles);
  for (size_t s = 0; s < triangles; ++s) order[s] = refs[s].triangle;
  // Freed before the per-triangle arrays are made: less peak memory on large meshes.
  std::vector<Ref>().swap(refs);

  core::copy_huge(original_, order);
  core::resize_huge(slot_, triangles);
  for (size_t s = 0; s < triangles; ++s) slot_[order[s]] = uint32_t(s);
  const float grow = place_triangles(mesh, threads);

  // Collapse: each 4-wide node takes a binary node's children and opens the largest inner ones until
  // it has four.
  auto is_leaf = [&](uint32_t b) { return binary[b].count > 0; };
  nodes_.emplace_back();
  struct Job {
    uint32_t binary, node, depth;
  };
  std::vector<Job> jobs;
  auto fill = [&](uint32_t node, const uint32_t* children, int count, uint32_t depth) {
    for (int lane = 0; lane < 4; ++lane) {
      Node& n = nodes_[node];
      if (lane >= count) {
        for (int k = 0; k < 3; ++k) n.box[4 * k + lane] = inf, n.box[4 * (k + 3) + lane] = -inf;
        n.child[lane] = empty_child;
        continue;
      }
      const BinaryNode& b = binary[children[lane]];
      for (int k = 0; k < 3; ++k)
        n.box[4 * k + lane] = b.box.lo[k] - grow, n.box[4 * (k + 3) + lane] = b.box.hi[k] + grow;
      if (b.count > 0) {
        n.child[lane] = leaf_bit | b.begin << 4 | (b.count - 1);
      } else {
        const uint32_t index = uint32_t(nodes_.size());
        nodes_[node].child[lane] = index;  // `n` may dangle after the push below
        nodes_.emplace_back();
        jobs.push_back({children[lane], index, depth + 1});
      }
    }
  };
  if (is_leaf(0)) {
    const uint32_t root_child = 0;
    fill(0, &root_child, 1, 1);
    depth_ = 1;
  } else {
    jobs.push_back({0, 0, 1});
  }
  while (!jobs.empty()) {
    const Job job = jobs.back();
    jobs.pop_back();
    depth_ = std::max(depth_, job.depth);
    uint32_t children[4] = {binary[job.binary].left, binary[job.binary].left + 1};
    int count = 2;
    while (count < 4) {
      int open = -1;
      float largest = -1;
      for (int k = 0; k < count; ++k)
        if (!is_leaf(children[k]) && binary[children[k]].box.half_area() > largest)
          largest = binary[children[k]].box.half_area(), open = k;
      if (open < 0) break;
      const uint32_t left = binary[children[open]].left;
      for (int k = count; k > open + 1; --k) children[k] = children[k - 1];
      children[open] = left;
      children[open + 1] = left + 1;
      ++count;
    }
    fill(job.node, children, count, job.depth);
  }
  if (depth_ > max_depth) throw_internal("TriangleBvh: tree deeper than the traversal stack");
}

float TriangleBvh::place_triangles(const Mesh& mesh, unsigned threads) {
  const size_t triangles = original_.size();
  core::resize_huge(triangles_, triangles);
  // Growth of every box: a few ulps of the largest coordinate.
  float magnitude = 0;
  for (const float3& p : mesh.positions)
    magnitude = std::max({magnitude, std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)});
  const float grow = magnitude * 1e-6f + std::numeric_limits<float>::min();
  plane_slack_ = 4 * grow;
  triangle_box_.resize(6 * triangles);
  // Per leaf-order triangle, each slot written by its own item: the prepared triangle and its grown box.
  core::parallel_for(triangles, threads, [&](size_t s) {
    const uint32_t* corner = &mesh.indices[3 * size_t(original_[s])];
    const vec3f c[3] = {mesh.positions[corner[0]], mesh.positions[corner[1]], mesh.positions[corner[2]]};
    triangles_[s] = prepare_triangle(c[0], c[1], c[2]);
    Box b;
    for (int k = 0; k < 3; ++k) b.grow_point(&c[k].x);
    for (int k = 0; k < 3; ++k) triangle_box_[6 * s + k] = b.lo[k] - grow, triangle_box_[6 * s + 3 + k] = b.hi[k] + grow;
  });
  return grow;
}

void TriangleBvh::refit(const Mesh& mesh, unsigned threads) {
  if (mesh.triangle_count() != original_.size())
    throw_internal("TriangleBvh::refit: the mesh has other triangles than the tree was built over");
  place_triangles(mesh, threads);
  // Bottom-up: a node's children come after it in nodes_ (the build appends them as it fills it).
  // Each lane's box is the union of its grown triangle boxes or of its child's lanes, which is the
  // build's box of that subtree minus and plus the same growth, to the bit (rounding is monotonic).
  for (size_t i = nodes_.size(); i-- > 0;) {
    Node& n = nodes_[i];
    for (int lane = 0; lane < 4; ++lane) {
      const uint32_t child = n.child[lane];
      if (child == empty_child) continue;
      float lo[3] = {inf, inf, inf}, hi[3] = {-inf, -inf, -inf};
      if (child & leaf_bit) {
        const uint32_t first = (child & ~leaf_bit) >> 4, count = (child & 15) + 1;
        for (uint32_t s = first; s < first + count; ++s)
          for (int k = 0; k < 3; ++k)
            lo[k] = std::min(lo[k], triangle_box_[6 * size_t(s) + k]), hi[k] = std::max(hi[k], triangle_box_[6 * size_t(s) + 3 + k]);
      } else {
        const Node& c = nodes_[child];  // its empty lanes are +inf to -inf: no part of the union
        for (int l = 0; l < 4; ++l)
          for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], c.box[4 * k + l]), hi[k] = std::max(hi[k], c.box[4 * (k + 3) + l]);
      }
      for (int k = 0; k < 3; ++k) n.box[4 * k + lane] = lo[k], n.box[4 * (k + 3) + lane] = hi[k];
    }
  }
}

void TriangleBvh::set_lane_width(unsigned width) { lane_width.store(width, std::memory_order_relaxed); }

bool TriangleBvh::consider(const vec3f& p, uint32_t slot, ClosestHit& best) const {
  const float d = closest_distance_squared(p, triangles_[slot]);
  if (d > best.distance_squared) return false;
  const uint32_t triangle = original_[slot];
  if (d == best.distance_squared && triangle >= best.triangle) return false;
  best.distance_squared = d;
  best.triangle = triangle;
  best.resolved = false;  // the point is found once, for the answer
  return true;
}

ClosestHit TriangleBvh::closest(const vec3f& p, uint32_t hint, float bound) const {
  ClosestHit best;
  best.distance_squared = bound;  // no triangle yet: consider() takes any within the bound
  consider(p, slot_[hint < original_.size() ? hint : 0], best);
  float limit = best.distance_squared * prune_slack;
  uint32_t stack[3 * max_depth + 4];
  float stack_distance[3 * max_depth + 4];
  int top = 0;
  stack[top] = 0, stack_distance[top] = 0, ++top;
  const Probe probe(p);
  while (top > 0) {
    --top;
    if (stack_distance[top] > limit) continue;
    const uint32_t ref = stack[top];
    if (ref & leaf_bit) {
      const uint32_t first = (ref & ~leaf_bit) >> 4, count = (ref & 15) + 1;
      for (uint32_t s = first; s < first + count; ++s) {
        // A triangle is never nearer than its plane: a cheap test before the exact one.
        const PreparedTriangle& t = triangles_[s];
        const float gap = std::max(std::fabs(dot(t.normal, p - t.a)) - plane_slack_, 0.0f);
        if (gap * gap > limit) continue;
        if (consider(p, s, best)) limit = best.distance_squared * prune_slack;
      }
      continue;
    }
    const Node& n = nodes_[ref];
    float d[4];
    const int mask = probe.within(n.box, limit, d);
    if (!mask) continue;
    // Push the hits farthest first, so the nearest is popped next (sorted in place on the stack).
    const int base = top;
    for (unsigned m = unsigned(mask); m; m &= m - 1) {
      const int k = __builtin_ctz(m);
      if (n.child[k] == empty_child) continue;
      int j = top++;
      for (; j > base && stack_distance[j - 1] < d[k]; --j) stack[j] = stack[j - 1], stack_distance[j] = stack_distance[j - 1];
      stack[j] = n.child[k], stack_distance[j] = d[k];
    }
  }
  resolve(best, p);
  return best;
}

void TriangleBvh::closest_group(const vec3f* points, uint32_t count, uint32_t hint, ClosestHit* out,
                                GroupScratch& scratch, const float* bounds) const {
  if (count == 0) return;
  const auto bound = [&](uint32_t i) { return bounds ? bounds[i] : inf; };
  if (count == 1) {
    out[0] = closest(points[0], hint, bound(0));
    return;
  }
  float lo[3] = {points[0].x, points[0].y, points[0].z}, hi[3] = {lo[0], lo[1], lo[2]};
  for (uint32_t i = 1; i < count; ++i) {
    const float* p = &points[i].x;
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  }
  // The points a lane each, in batches (the last padded with copies of the last point), with no
  // triangle yet.
  const bool wide = use_wide_lanes();
  const uint32_t width = wide ? 8 : 4;
  const uint32_t padded = (count + width - 1) / width * width;
  scratch.lane_floats.resize(4 * size_t(padded));
  scratch.lane_ints.resize(size_t(padded));
  LaneArrays lanes{scratch.lane_floats.data(), scratch.lane_ints.data(), padded};
  for (uint32_t i = 0; i < padded; ++i) {
    const vec3f& p = points[std::min(i, count - 1)];
    lanes.x()[i] = p.x, lanes.y()[i] = p.y, lanes.z()[i] = p.z;
    lanes.distance_squared()[i] = bound(std::min(i, count - 1));  // a lane keeps INT32_MAX if none is within
    lanes.triangle()[i] = INT32_MAX;
  }
  const GroupTree tree{nodes_.data(),
                       {nullptr, 0, triangle_box_.data(), triangles_.data(), original_.data(), plane_slack_}};
  const uint32_t hint_slot = slot_[hint < original_.size() ? hint : 0];
  const bool done = wide ? search_group_wide(lanes, tree, lo, hi, hint_slot, max_group_scanned)
                         : search_group_narrow(lanes, tree, lo, hi, hint_slot, max_group_scanned);
  if (!done) {
    // Too spread out: each point on its own, from its best triangle so far.
    for (uint32_t i = 0; i < count; ++i) out[i] = closest(points[i], uint32_t(lanes.triangle()[i]), bound(i));
    return;
  }
  for (uint32_t i = 0; i < count; ++i) {
    ClosestHit& h = out[i];
    h.distance_squared = lanes.distance_squared()[i];
    const bool found = lanes.triangle()[i] != INT32_MAX;
    h.triangle = found ? uint32_t(lanes.triangle()[i]) : UINT32_MAX;
    h.resolved = !found;  // nothing to resolve without a triangle
  }
}

}  // namespace lod::measure
