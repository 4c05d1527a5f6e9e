// lod::compare: Metro-style sampling of both surfaces, exact closest points through a BVH, optional
// certified refinement of the maximum. Every sample stream (vertices, edge points, area points) is
// indexed, cut into fixed blocks and reduced in block order, so the result is the same on any number
// of threads; a sample's random position depends only on the seed and its index.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <numbers>
#include <optional>

#include <tbb/enumerable_thread_specific.h>

#include "core/buckets.h"
#include "core/parallel.h"
#include "core/vec3d.h"
#include "lodkit/error.h"
#include "lodkit/measure.h"
#include "measure/bvh.h"
#include "measure/refine.h"

namespace lod {

namespace {

using measure::ClosestHit;
using measure::TriangleBvh;
using measure::vec3f;

constexpr size_t block_size = 1024;       // samples per block
constexpr size_t blocks_per_slice = 256;  // progress is reported between slices
constexpr uint32_t group_size = 32;       // samples per closest_group query
// A triangle with many area samples is queried in patches of this many consecutive samples along a
// serpentine through square cells of about one sample in the triangle's plane, in strips
// `patch_strip` cells high walked column by column: whole batches of 8 lanes, each patch a compact
// block of about 3 x 3 cells. The smaller a patch's box, the fewer triangles its search must rule out.
constexpr uint32_t patch_size = 8;
constexpr uint32_t patch_strip = 3;

uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Spreads the low 10 bits of x to every third bit (Morton code helper).
uint32_t spread_bits(uint32_t x) {
  x &= 0x3FF;
  x = (x | x << 16) & 0x030000FF;
  x = (x | x << 8) & 0x0300F00F;
  x = (x | x << 4) & 0x030C30C3;
  x = (x | x << 2) & 0x09249249;
  return x;
}

// One mesh, ready to be sampled.
struct Surface {
  const Mesh* mesh = nullptr;
  PositionIds ids;
  std::vector<uint32_t> position_vertex;    // per position id: its first vertex
  std::vector<uint32_t> position_triangle;  // per position id: first triangle using it, or UINT32_MAX
  // Position ids along a Z curve through their bounding box: neighbours in this order are mostly
  // neighbours in space, so the vertex and edge samples are queried in groups that share a search.
  std::vector<uint32_t> position_order;
  std::vector<double> area_before;          // per triangle + 1: total area of the triangles before it
  double area = 0;
  // Unique edges (position ids lo < hi) with a triangle holding them, grouped by lo in position_order,
  // each group in hi order.
  struct Edge {
    uint32_t lo, hi, triangle;
  };
  std::vector<Edge> edges;

  explicit Surface(const Mesh& m) : mesh(&m), ids(position_ids(m)) {
    position_vertex.assign(ids.count, UINT32_MAX);
    position_triangle.assign(ids.count, UINT32_MAX);
    for (uint32_t v = 0; v < m.vertex_count(); ++v)
      if (position_vertex[ids.id[v]] == UINT32_MAX) position_vertex[ids.id[v]] = v;
    const size_t triangles = m.triangle_count();
    for (size_t t = 0; t < triangles; ++t)
      for (int k = 0; k < 3; ++k) {
        uint32_t& first = position_triangle[ids.id[m.indices[3 * t + k]]];
        if (first == UINT32_MAX) first = uint32_t(t);
      }
    float3 lo, hi;
    bounding_box(m, lo, hi);
    std::vector<std::pair<uint32_t, uint32_t>> keyed(ids.count);  // (Morton code, id)
    for (uint32_t p = 0; p < ids.count; ++p) {
      const vec3f q = position(p);
      uint32_t code = 0;
      for (int k = 0; k < 3; ++k) {
        const float extent = (&hi.x)[k] - (&lo.x)[k];
        const float t = extent > 0 ? ((&q.x)[k] - (&lo.x)[k]) / extent : 0.0f;
        code |= spread_bits(uint32_t(std::clamp(t, 0.0f, 1.0f) * 1023.0f)) << k;
      }
      keyed[p] = {code, p};
    }
    std::sort(keyed.begin(), keyed.end());
    position_order.resize(ids.count);
    for (uint32_t i = 0; i < ids.count; ++i) position_order[i] = keyed[i].second;
    area_before.resize(triangles + 1);
    double sum = 0;
    for (size_t t = 0; t < triangles; ++t) {
      area_before[t] = sum;
      sum += core::triangle_area(*mesh, t);
    }
    area_before[triangles] = area = sum;
  }

  vec3f corner(size_t t, int k) const { return mesh->positions[mesh->indices[3 * t + k]]; }
  vec3f position(uint32_t id) const { return mesh->positions[position_vertex[id]]; }

  // Unique edges by a counting sort on the smaller position id (linear time, no hashing).
  void find_edges() {
    const Mesh& m = *mesh;
    const size_t triangles = m.triangle_count();
    // Each edge under its lower position id, as (higher id, triangle).
    core::Buckets<std::pair<uint32_t, uint32_t>> around = core::bucket<std::pair<uint32_t, uint32_t>>(ids.count, [&](auto&& emit) {
      for (size_t t = 0; t < triangles; ++t)
        for (int k = 0; k < 3; ++k) {
          const uint32_t p = ids.id[m.indices[3 * t + k]], q = ids.id[m.indices[3 * t + (k + 1) % 3]];
          if (p != q) emit(std::min(p, q), std::pair{std::max(p, q), uint32_t(t)});
        }
    });
    edges.clear();
    for (const uint32_t p : position_order) {
      const auto first = around[p].begin(), last = around[p].end();
      std::sort(first, last);  // a handful of entries; equal hi keep the lowest triangle first
      for (auto it = first; it != last; ++it)
        if (it == first || it->first != (it - 1)->first) edges.push_back({p, it->first, it->second});
    }
  }
};

// Per-block sums; merged in block order.
struct Accumulator {
  double sum = 0, sum_squares = 0;
  float max = -1;
  MaxLocation where;
  double normal_sum = 0, normal_max = 0, uv_sum = 0, uv_max = 0, color_sum = 0, color_max = 0;
  uint64_t normal_count = 0, uv_count = 0, color_count = 0;

  void take(float d, const MaxLocation& at) {
    if (d > max) max = d, where = at;
  }
  void merge(const Accumulator& o) {
    sum += o.sum, sum_squares += o.sum_squares;
    if (o.max > max) max = o.max, where = o.where;
    normal_sum += o.normal_sum, uv_sum += o.uv_sum, color_sum += o.color_sum;
    normal_max = std::max(normal_max, o.normal_max), uv_max = std::max(uv_max, o.uv_max);
    color_max = std::max(color_max, o.color_max);
    normal_count += o.normal_count, uv_count += o.uv_count, color_count += o.color_count;
  }
};

struct Progress {
  const std::function<void(double)>* callback = nullptr;
  uint64_t total = 1, done = 0;
  void add(uint64_t n) {
    done += n;
    if (callback && *callback) (*callback)(std::min(1.0, double(done) / double(std::max<uint64_t>(total, 1))));
  }
};

// fn(first, end, accumulator, hint) over fixed blocks of [0, count), a slice of blocks at a time;
// the accumulators are merged into `total` in block order.
template <class Fn>
void run_stream(uint64_t count, unsigned threads, Progress& progress, Accumulator& total, Fn&& fn) {
  const uint64_t slice = block_size * blocks_per_slice;
  for (uint64_t slice_begin = 0; slice_begin < count; slice_begin += slice) {
    const uint64_t n = std::min(slice, count - slice_begin);
    std::vector<Accumulator> acc((n + block_size - 1) / block_size);
    core::parallel_blocks(n, block_size, threads, [&](size_t b, size_t begin, size_t end) {
      uint32_t hint = 0;
      fn(slice_begin + begin, slice_begin + end, acc[b], hint);
    });
    for (const Accumulator& a : acc) total.merge(a);
    progress.add(n);
  }
}

// Records the largest distance seen in each position's region, as float bits (non-negative floats
// order like their bits), with an atomic max: the result does not depend on the order.
void raise(std::vector<uint32_t>& field, uint32_t position, float d) {
  uint32_t bits;
  std::memcpy(&bits, &d, 4);
  std::atomic_ref<uint32_t> slot(field[position]);
  uint32_t current = slot.load(std::memory_order_relaxed);
  while (current < bits && !slot.compare_exchange_weak(current, bits, std::memory_order_relaxed)) {
  }
}

// A sample's region: the corner of its triangle nearest to it (the first on ties).
int nearest_corner(const vec3f& c0, const vec3f& c1, const vec3f& c2, const vec3f& q) {
  const float l0 = length_squared(q - c0), l1 = length_squared(q - c1), l2 = length_squared(q - c2);
  return l0 <= l1 && l0 <= l2 ? 0 : (l1 <= l2 ? 1 : 2);
}
// The same as a position id.
uint32_t nearest_corner_position(const Surface& s, size_t triangle, const vec3f& q) {
  const int k = nearest_corner(s.corner(triangle, 0), s.corner(triangle, 1), s.corner(triangle, 2), q);
  return s.ids.id[s.mesh->indices[3 * triangle + k]];
}

template <class T>
T interpolate(const std::vector<T>& stream, const uint32_t* corners, float w0, float w1, float w2);
template <>
float3 interpolate(const std::vector<float3>& s, const uint32_t* c, float w0, float w1, float w2) {
  return {s[c[0]].x * w0 + s[c[1]].x * w1 + s[c[2]].x * w2, s[c[0]].y * w0 + s[c[1]].y * w1 + s[c[2]].y * w2,
          s[c[0]].z * w0 + s[c[1]].z * w1 + s[c[2]].z * w2};
}
template <>
float2 interpolate(const std::vector<float2>& s, const uint32_t* c, float w0, float w1, float w2) {
  return {s[c[0]].x * w0 + s[c[1]].x * w1 + s[c[2]].x * w2, s[c[0]].y * w0 + s[c[1]].y * w1 + s[c[2]].y * w2};
}
template <>
float4 interpolate(const std::vector<float4>& s, const uint32_t* c, float w0, float w1, float w2) {
  return {s[c[0]].x * w0 + s[c[1]].x * w1 + s[c[2]].x * w2, s[c[0]].y * w0 + s[c[1]].y * w1 + s[c[2]].y * w2,
          s[c[0]].z * w0 + s[c[1]].z * w1 + s[c[2]].z * w2, s[c[0]].w * w0 + s[c[1]].w * w1 + s[c[2]].w * w2};
}

// An area sample, uniform in its triangle: s = sqrt(r1) picks the distance from corner 0 with density ~ s.
struct AreaSample {
  float s, r2;
  float w1() const { return s * (1 - r2); }  // barycentric weights; w0 = 1 - s
  float w2() const { return s * r2; }
};

// Samples of one block, queried in groups of nearby points (TriangleBvh::closest_group); hit(o) is
// the answer for offset o in the block, so the caller reduces them in sample order. One per thread
// and direction, reused block after block (cleared, its memory kept).
struct BlockQueries;
// Owned by the measuring call, not thread_local: oneTBB's workers outlive the call and main(), and
// thread_local scratch would stay allocated with them (and, with LeakSanitizer's TLS scan off, as in
// the render tests, look leaked at exit).
using BlockScratch = tbb::enumerable_thread_specific<BlockQueries>;
struct BlockQueries {
  std::vector<vec3f> points;         // in query order
  std::vector<uint32_t> offset;      // query order -> offset in the block
  std::vector<uint32_t> query;       // offset in the block -> query order
  std::vector<uint32_t> group_end;   // query order positions where a group ends
  std::vector<ClosestHit> hits;      // in query order
  TriangleBvh::GroupScratch scratch;
  // The area stream's own: each sample's draw and point, and the patch sort.
  std::vector<AreaSample> drawn;
  std::vector<vec3f> at;
  std::vector<uint32_t> cell, cell_start, sorted;

  static BlockQueries& local(BlockScratch& per_thread) {
    BlockQueries& block = per_thread.local();
    block.points.clear(), block.offset.clear(), block.group_end.clear();
    return block;
  }
  void add(const vec3f& p, uint32_t block_offset) {
    points.push_back(p);
    offset.push_back(block_offset);
  }
  // Ends the current group (if it has any points).
  void cut() {
    if (points.size() > (group_end.empty() ? 0 : group_end.back())) group_end.push_back(uint32_t(points.size()));
  }
  // Groups not cut by the caller are runs of `size` consecutive points.
  void run(const TriangleBvh& bvh, uint32_t size, uint32_t& hint) {
    cut();
    if (hits.size() < points.size()) hits.resize(points.size());
    uint32_t first = 0;
    for (const uint32_t last : group_end) {
      for (uint32_t g = first; g < last; g += size) {
        const uint32_t n = std::min(size, last - g);
        bvh.closest_group(&points[g], n, hint, &hits[g], scratch);
        hint = hits[g + n - 1].triangle;
      }
      first = last;
    }
    query.resize(points.size());
    for (uint32_t q = 0; q < points.size(); ++q) query[offset[q]] = q;
  }
  ClosestHit& hit(uint32_t block_offset) { return hits[query[block_offset]]; }
};

struct Direction {
  OneSidedDeviation result;
  std::vector<float> position_distance;     // per position id of `from`
  std::vector<uint32_t> position_closest;   // per position id: closest triangle of `to`
  std::vector<uint32_t> field;              // per position id: vertex_error bits (when asked)
  std::vector<uint32_t> triangle_closest;   // per triangle: closest triangle of its first area sample (refine)
};

struct Plan {
  uint64_t area_samples = 0;
  std::vector<uint64_t> edge_start;  // per edge + 1: index of its first sample
  std::vector<uint64_t> area_start;  // per triangle + 1
  double phase = 0;                  // systematic sampling offset in [0, 1)
};

Plan plan_samples(Surface& from, uint64_t samples, bool edge_samples, uint64_t stream_seed) {
  Plan plan;
  // An area that overflowed (coordinates near float's limit) would make every share NaN.
  plan.area_samples = from.area > 0 && std::isfinite(from.area) ? samples : 0;
  const size_t triangles = from.mesh->triangle_count();
  plan.phase = double(splitmix64(stream_seed ^ 0x5bd1e995ull) >> 11) * 0x1p-53;
  plan.area_start.resize(triangles + 1);
  for (size_t t = 0; t <= triangles; ++t)
    plan.area_start[t] =
        plan.area_samples ? uint64_t(std::floor(double(samples) * from.area_before[t] / from.area + plan.phase)) : 0;
  const uint64_t base = plan.area_start[0];
  for (uint64_t& s : plan.area_start) s -= base;
  plan.area_samples = plan.area_start.back();

  plan.edge_start.assign(1, 0);
  if (!edge_samples || samples == 0) return plan;
  from.find_edges();
  double total_length = 0;
  for (const Surface::Edge& e : from.edges) total_length += distance(from.position(e.lo), from.position(e.hi));
  // As far apart as the area samples, and at most half as many.
  const double spacing = std::max(std::sqrt(from.area / double(samples)), total_length / (0.5 * double(samples)));
  plan.edge_start.resize(from.edges.size() + 1);
  uint64_t sum = 0;
  for (size_t i = 0; i < from.edges.size(); ++i) {
    plan.edge_start[i] = sum;
    const double length = distance(from.position(from.edges[i].lo), from.position(from.edges[i].hi));
    // NaN (an overflowed length over an overflowed spacing) is skipped, not converted.
    if (const double n = length / spacing; spacing > 0 && n > 0) sum += uint64_t(std::min(n, double(samples)));
  }
  plan.edge_start.back() = sum;
  return plan;
}

Direction measure_direction(const Surface& from, const Surface& to, const TriangleBvh& bvh, const Plan& plan,
                            uint64_t stream_seed, bool want_field, const CompareOptions& options,
                            Progress& progress) {
  Direction out;
  OneSidedDeviation& r = out.result;
  const Mesh& fm = *from.mesh;
  const Mesh& tm = *to.mesh;
  const uint32_t positions = from.ids.count;
  out.position_distance.resize(positions);
  out.position_closest.resize(positions);
  if (want_field) out.field.assign(positions, 0);
  if (options.refine) out.triangle_closest.assign(fm.triangle_count(), UINT32_MAX);
  Accumulator total;
  BlockScratch per_thread;

  // Vertices: every position (a vertex used by no triangle is measured for the field but is not a sample).
  run_stream(positions, options.threads, progress, total, [&](uint64_t begin, uint64_t end, Accumulator& acc, uint32_t& hint) {
    BlockQueries& block = BlockQueries::local(per_thread);
    for (uint64_t k = begin; k < end; ++k) block.add(from.position(from.position_order[k]), uint32_t(k - begin));
    block.run(bvh, group_size, hint);
    for (uint64_t k = begin; k < end; ++k) {
      const uint32_t p = from.position_order[k];
      const vec3f q = from.position(p);
      ClosestHit& h = block.hit(uint32_t(k - begin));
      const float d = std::sqrt(h.distance_squared);
      out.position_distance[p] = d;
      out.position_closest[p] = h.triangle;
      if (want_field) std::memcpy(&out.field[p], &d, 4);
      if (from.position_triangle[p] != UINT32_MAX && d > acc.max) {
        bvh.resolve(h, q);
        acc.take(d, {q, h.point, from.position_triangle[p], h.triangle});
      }
    }
  });
  for (uint32_t p = 0; p < positions; ++p) r.vertex_samples += from.position_triangle[p] != UINT32_MAX;

  // Edge points, evenly spaced; each belongs to the nearer end.
  const uint64_t edge_samples = plan.edge_start.back();
  run_stream(edge_samples, options.threads, progress, total, [&](uint64_t begin, uint64_t end, Accumulator& acc, uint32_t& hint) {
    const size_t first_edge =
        size_t(std::upper_bound(plan.edge_start.begin(), plan.edge_start.end(), begin) - plan.edge_start.begin()) - 1;
    auto sample = [&](size_t& e, uint64_t j) {
      while (plan.edge_start[e + 1] <= j) ++e;
      const Surface::Edge& edge = from.edges[e];
      const uint64_t n = plan.edge_start[e + 1] - plan.edge_start[e];
      const float t = float(double(j - plan.edge_start[e] + 1) / double(n + 1));
      const vec3f a = from.position(edge.lo), b = from.position(edge.hi);
      return a + (b - a) * t;
    };
    // A group never spans two edges (they part at their shared end): runs along one edge, 8 at most.
    BlockQueries& block = BlockQueries::local(per_thread);
    size_t e = first_edge;
    for (uint64_t j = begin; j < end; ++j) {
      const size_t before = e;
      const vec3f q = sample(e, j);
      if (e != before) block.cut();
      block.add(q, uint32_t(j - begin));
    }
    block.run(bvh, group_size / 2, hint);
    e = first_edge;
    for (uint64_t j = begin; j < end; ++j) {
      const vec3f q = sample(e, j);
      const Surface::Edge& edge = from.edges[e];
      ClosestHit& h = block.hit(uint32_t(j - begin));
      const float d = std::sqrt(h.distance_squared);
      if (d > acc.max) {
        bvh.resolve(h, q);
        acc.take(d, {q, h.point, edge.triangle, h.triangle});
      }
      if (want_field) raise(out.field, nearest_corner_position(from, edge.triangle, q), d);
    }
  });
  r.edge_samples = edge_samples;

  // Area points: triangle t owns samples [area_start[t], area_start[t+1]).
  const bool normals = options.attributes && !fm.normals.empty() && !tm.normals.empty();
  const bool uvs = options.attributes && !fm.uvs[0].empty() && !tm.uvs[0].empty();
  const bool colors = options.attributes && !fm.colors.empty() && !tm.colors.empty();
  run_stream(plan.area_samples, options.threads, progress, total, [&](uint64_t begin, uint64_t end, Accumulator& acc, uint32_t& hint) {
    const size_t first_triangle =
        size_t(std::upper_bound(plan.area_start.begin(), plan.area_start.end(), begin) - plan.area_start.begin()) - 1;
    // fn(t, a, b) for each triangle with samples in the block: its samples are the block's [a, b).
    auto each_triangle = [&](auto&& fn) {
      for (size_t t = first_triangle; plan.area_start[t] < end; ++t) {
        const uint32_t a = uint32_t(std::max(begin, plan.area_start[t]) - begin);
        const uint32_t b = uint32_t(std::min(end, plan.area_start[t + 1]) - begin);
        if (a < b) fn(t, a, b);
      }
    };
    auto sample = [&](uint64_t j) {
      const uint64_t bits = splitmix64(stream_seed + j);
      const float r1 = float(bits >> 40) * 0x1p-24f, r2 = float((bits >> 16) & 0xFFFFFF) * 0x1p-24f;
      return AreaSample{std::sqrt(r1), r2};
    };
    // Each sample drawn once per block, a triangle at a time.
    BlockQueries& block = BlockQueries::local(per_thread);
    const size_t n = size_t(end - begin);
    std::vector<AreaSample>& drawn = block.drawn;
    std::vector<vec3f>& at = block.at;
    drawn.resize(n), at.resize(n);
    each_triangle([&](size_t t, uint32_t a, uint32_t b) {
      const vec3f c0 = from.corner(t, 0), c1 = from.corner(t, 1), c2 = from.corner(t, 2);
      for (uint32_t o = a; o < b; ++o) {
        const AreaSample u = drawn[o] = sample(begin + o);
        at[o] = c0 * (1 - u.s) + c1 * u.w1() + c2 * u.w2();
      }
    });
    // Queries go a triangle at a time; a triangle with many samples is cut into patches (see
    // patch_size), each a group of queries close together: its samples sorted by cell (a counting
    // sort, stable), cut every patch_size samples.
    // Consecutive small triangles share a group while it has room and their boxes stay about as
    // large as the two together (neighbours, in a mesh whose order is mostly spatial).
    std::vector<uint32_t>&cell = block.cell, &cell_start = block.cell_start, &sorted = block.sorted;
    uint32_t open = 0;  // points in the current group of small triangles
    float open_lo[3] = {}, open_hi[3] = {};
    auto diagonal = [](const float* lo, const float* hi) {
      const float x = hi[0] - lo[0], y = hi[1] - lo[1], z = hi[2] - lo[2];
      return std::sqrt(x * x + y * y + z * z);
    };
    each_triangle([&](size_t t, uint32_t a, uint32_t b) {
      if (b - a <= group_size) {
        const vec3f c0 = from.corner(t, 0), c1 = from.corner(t, 1), c2 = from.corner(t, 2);
        float lo[3], hi[3];
        for (int k = 0; k < 3; ++k) {
          lo[k] = std::min({(&c0.x)[k], (&c1.x)[k], (&c2.x)[k]});
          hi[k] = std::max({(&c0.x)[k], (&c1.x)[k], (&c2.x)[k]});
        }
        if (open) {
          float ulo[3], uhi[3];
          for (int k = 0; k < 3; ++k) ulo[k] = std::min(lo[k], open_lo[k]), uhi[k] = std::max(hi[k], open_hi[k]);
          if (open + (b - a) > group_size || diagonal(ulo, uhi) > diagonal(lo, hi) + diagonal(open_lo, open_hi)) {
            block.cut();
            open = 0;
          } else {
            std::copy(ulo, ulo + 3, lo), std::copy(uhi, uhi + 3, hi);
          }
        }
        std::copy(lo, lo + 3, open_lo), std::copy(hi, hi + 3, open_hi);
        for (uint32_t o = a; o < b; ++o) block.add(at[o], o);
        open += b - a;
        return;
      }
      block.cut();
      open = 0;
      // The plane's frame: u along the longest edge from its first corner, v towards the third
      // corner; the triangle fills half of its [0, length] x [0, height] rectangle.
      vec3f corner[3] = {from.corner(t, 0), from.corner(t, 1), from.corner(t, 2)};
      int longest = 0;
      float longest_length = -1;
      for (int k = 0; k < 3; ++k)
        if (const float l = length_squared(corner[(k + 1) % 3] - corner[k]); l > longest_length) longest_length = l, longest = k;
      const vec3f origin = corner[longest], edge = corner[(longest + 1) % 3] - origin;
      const vec3f other = corner[(longest + 2) % 3] - origin;
      const float length = std::sqrt(longest_length);
      const vec3f u_axis = length > 0 ? edge * (1 / length) : vec3f{0, 0, 0};
      const vec3f across = other - u_axis * dot(other, u_axis);
      const float height = std::sqrt(length_squared(across));
      const vec3f v_axis = height > 0 ? across * (1 / height) : vec3f{0, 0, 0};
      const uint32_t count = b - a;
      const float side = std::sqrt(0.5f * length * height / float(count));
      const float per_side = side > 0 ? 1 / side : 0.0f;
      constexpr float max_cells = 4096;  // per axis (a sliver's long side)
      // NaN (an overflowed side: infinity times 0) gives one cell, never a conversion out of range.
      const auto cells = [&](float x) { return x >= 1 ? uint32_t(std::min(x, max_cells)) : 0u; };
      const uint32_t columns = cells(length * per_side) + 1, rows = cells(height * per_side) + 1;
      const uint32_t strips = (rows + patch_strip - 1) / patch_strip;
      cell.resize(count);
      cell_start.assign(size_t(strips) * columns * patch_strip + 1, 0);
      for (uint32_t o = a; o < b; ++o) {
        const vec3f d = at[o] - origin;
        // Bounded before the conversion: on a tiny patch a coordinate in cells can pass 2^32 (or be
        // NaN, 0 times an infinite per_side, which max(0, NaN) turns into 0).
        const uint32_t cu = uint32_t(std::min(std::max(0.0f, dot(d, u_axis) * per_side), float(columns - 1)));
        const uint32_t cv = uint32_t(std::min(std::max(0.0f, dot(d, v_axis) * per_side), float(rows - 1)));
        // Strips alternate direction, and so do the columns within a strip: each cell's successor
        // is a neighbour.
        const uint32_t strip = cv / patch_strip, column = strip & 1 ? columns - 1 - cu : cu;
        const uint32_t row = column & 1 ? patch_strip - 1 - cv % patch_strip : cv % patch_strip;
        cell[o - a] = (strip * columns + column) * patch_strip + row;
        ++cell_start[cell[o - a] + 1];
      }
      for (size_t c = 1; c < cell_start.size(); ++c) cell_start[c] += cell_start[c - 1];
      sorted.resize(b - a);
      for (uint32_t o = a; o < b; ++o) sorted[cell_start[cell[o - a]]++] = o;
      for (uint32_t i = 0; i < b - a; ++i) {
        block.add(at[sorted[i]], sorted[i]);
        if ((i + 1) % patch_size == 0) block.cut();
      }
      block.cut();
    });
    block.run(bvh, group_size, hint);
    each_triangle([&](size_t t, uint32_t a, uint32_t b) {
      const vec3f c0 = from.corner(t, 0), c1 = from.corner(t, 1), c2 = from.corner(t, 2);
      const uint32_t* corner_id = &from.mesh->indices[3 * t];
      // The triangle's largest distance in each corner's region, raised into the field once: an
      // atomic per triangle corner rather than per sample.
      float corner_max[3] = {-1, -1, -1};
      for (uint32_t o = a; o < b; ++o) {
        const uint64_t j = begin + o;
        const AreaSample u = drawn[o];
        const float w0 = 1 - u.s, w1 = u.w1(), w2 = u.w2();
        const vec3f q = at[o];
        ClosestHit& h = block.hit(o);
        const float d = std::sqrt(h.distance_squared);
        acc.sum += d;
        acc.sum_squares += double(d) * d;
        if (d > acc.max) {
          bvh.resolve(h, q);
          acc.take(d, {q, h.point, uint32_t(t), h.triangle});
        }
        if (options.refine && j == plan.area_start[t]) out.triangle_closest[t] = h.triangle;
        if (want_field) {
          float& m = corner_max[nearest_corner(c0, c1, c2, q)];
          m = std::max(m, d);
        }
        if (!(normals || uvs || colors)) continue;
        bvh.resolve(h, q);
        const uint32_t* fc = &fm.indices[3 * t];
        const uint32_t* tc = &tm.indices[3 * size_t(h.triangle)];
        const float u0 = 1 - h.v - h.w;
        if (normals) {
          const vec3f na = interpolate(fm.normals, fc, w0, w1, w2), nb = interpolate(tm.normals, tc, u0, h.v, h.w);
          const double la = length_squared(na), lb = length_squared(nb);
          if (la > 0 && lb > 0) {
            const double cx = double(na.y) * nb.z - double(na.z) * nb.y, cy = double(na.z) * nb.x - double(na.x) * nb.z,
                         cz = double(na.x) * nb.y - double(na.y) * nb.x;
            // atan2 keeps small angles accurate, where acos of a dot product near 1 does not.
            const double angle =
                std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), double(dot(na, nb))) * (180.0 / std::numbers::pi);
            acc.normal_sum += angle, acc.normal_max = std::max(acc.normal_max, angle), ++acc.normal_count;
          }
        }
        if (uvs) {
          const float2 ua = interpolate(fm.uvs[0], fc, w0, w1, w2), ub = interpolate(tm.uvs[0], tc, u0, h.v, h.w);
          const double du = double(ua.x) - ub.x, dv = double(ua.y) - ub.y;
          const double diff = std::sqrt(du * du + dv * dv);
          acc.uv_sum += diff, acc.uv_max = std::max(acc.uv_max, diff), ++acc.uv_count;
        }
        if (colors) {
          const float4 ca = interpolate(fm.colors, fc, w0, w1, w2), cb = interpolate(tm.colors, tc, u0, h.v, h.w);
          const double dr = double(ca.x) - cb.x, dg = double(ca.y) - cb.y, db = double(ca.z) - cb.z,
                       da = double(ca.w) - cb.w;
          const double diff = std::sqrt(dr * dr + dg * dg + db * db + da * da);
          acc.color_sum += diff, acc.color_max = std::max(acc.color_max, diff), ++acc.color_count;
        }
      }
      if (want_field)
        for (int k = 0; k < 3; ++k)
          if (corner_max[k] >= 0) raise(out.field, from.ids.id[corner_id[k]], corner_max[k]);
    });
  });
  r.area_samples = plan.area_samples;
  r.area = from.area;

  r.max = std::max(0.0f, total.max);
  r.max_location = total.where;
  r.max_bound = r.max;
  if (r.area_samples) {
    r.mean = total.sum / double(r.area_samples);
    r.rms = std::sqrt(total.sum_squares / double(r.area_samples));
  } else {
    // No area (every triangle degenerate): the surface is its vertices and edges.
    r.mean = r.rms = r.max;
  }
  AttributeDeviation& at = r.attributes;
  at.normals = normals, at.uvs = uvs, at.colors = colors;
  if (total.normal_count) at.max_normal_angle = total.normal_max, at.mean_normal_angle = total.normal_sum / double(total.normal_count);
  if (total.uv_count) at.max_uv = total.uv_max, at.mean_uv = total.uv_sum / double(total.uv_count);
  if (total.color_count) at.max_color = total.color_max, at.mean_color = total.color_sum / double(total.color_count);
  return out;
}

void refine_direction(Direction& dir, const Surface& from, const Surface& to_surface, const TriangleBvh& to,
                      const CompareOptions& options, float tolerance, uint64_t budget, Progress& progress) {
  const core::TriangleAdjacency to_adjacency =
      core::triangle_adjacency(to_surface.mesh->indices, to_surface.ids.id, to_surface.ids.count);
  measure::RefineInput in;
  in.from = from.mesh;
  in.position_id = &from.ids.id;
  in.position_distance = &dir.position_distance;
  in.position_closest = &dir.position_closest;
  in.triangle_closest = &dir.triangle_closest;
  in.to = &to;
  in.neighbours = &to_adjacency;
  in.tolerance = tolerance;
  in.budget = budget;
  in.threads = options.threads;
  const bool field = !dir.field.empty();
  const measure::RefineResult rr = measure::refine_max(
      in, float(dir.result.max), dir.result.max_location, [&](uint32_t t, const vec3f& q, float d) {
        if (field) raise(dir.field, nearest_corner_position(from, t, q), d);
      });
  OneSidedDeviation& r = dir.result;
  r.refined = true;
  r.refine_samples = rr.queries;
  r.max = rr.max;
  r.max_location = rr.location;
  r.max_bound = std::max<double>(rr.bound, r.max);
  progress.add(rr.queries);
}

}  // namespace

Deviation compare(const Mesh& a, const Mesh& b, const CompareOptions& options) {
  validate(a, "mesh a");
  validate(b, "mesh b");
  if (a.triangle_count() == 0) throw_bad_input("mesh a", "has no triangles to measure");
  if (b.triangle_count() == 0) throw_bad_input("mesh b", "has no triangles to measure");
  if (!(options.refine_tolerance >= 0)) throw_usage("compare: refine_tolerance must be >= 0");

  const auto start = std::chrono::steady_clock::now();
  Deviation dev;
  float3 lo, hi;
  bounding_box(a, lo, hi);
  const double dx = double(hi.x) - lo.x, dy = double(hi.y) - lo.y, dz = double(hi.z) - lo.z;
  dev.diagonal = std::sqrt(dx * dx + dy * dy + dz * dz);

  const uint64_t samples =
      options.samples ? options.samples
                      : std::clamp<uint64_t>(10 * std::max(a.triangle_count(), b.triangle_count()), 10'000, 2'000'000);
  // The larger mesh's tree is built alongside everything else: the smaller tree, both surfaces and
  // sample plans, then the direction that queries the smaller tree (its build's serial top levels
  // would leave a core idle). The two directions are independent, so their order changes nothing.
  // A tree frees its build's temporary arrays early, so building side by side costs no peak memory.
  const uint64_t seed_ab = splitmix64(options.seed ^ 0xA5A5A5A5ull), seed_ba = splitmix64(options.seed ^ 0x5A5A5A5Aull);
  const uint64_t budget = options.refine_budget ? options.refine_budget : samples;
  const size_t alongside = a.triangle_count() >= b.triangle_count() ? 0 : 1;
  std::optional<TriangleBvh> trees[2];
  std::optional<Surface> surfaces[2];
  Plan plans[2];
  Progress progress{&options.progress};
  Direction directions[2];  // a to b (queries b's tree), b to a
  auto measure = [&](size_t d) {
    directions[d] = d == 0 ? measure_direction(*surfaces[0], *surfaces[1], *trees[1], plans[0], seed_ab, true, options, progress)
                           : measure_direction(*surfaces[1], *surfaces[0], *trees[0], plans[1], seed_ba, false, options, progress);
  };
  core::run_alongside(
      options.threads, [&] { trees[alongside].emplace(alongside ? b : a, options.threads); },
      [&] {
        core::parallel_blocks(3, 1, options.threads, [&](size_t k, size_t, size_t) {
          if (k == 0) {
            trees[1 - alongside].emplace(alongside ? a : b, options.threads);
            return;
          }
          const size_t side = k - 1;
          plans[side] = plan_samples(surfaces[side].emplace(side ? b : a), samples, options.edge_samples, side ? seed_ba : seed_ab);
        });
        dev.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        dev.queries = surfaces[0]->ids.count + plans[0].edge_start.back() + plans[0].area_samples +
                      surfaces[1]->ids.count + plans[1].edge_start.back() + plans[1].area_samples;
        progress.total = dev.queries + (options.refine ? 2 * budget : 0);
        measure(alongside);  // the direction that queries the other tree
      });
  measure(1 - alongside);
  const TriangleBvh &bvh_a = *trees[0], &bvh_b = *trees[1];
  Surface &sa = *surfaces[0], &sb = *surfaces[1];
  Direction &ab = directions[0], &ba = directions[1];
  if (options.refine) {
    const float tolerance = float(options.refine_tolerance * dev.diagonal);
    refine_direction(ab, sa, sb, bvh_b, options, tolerance, budget, progress);
    refine_direction(ba, sb, sa, bvh_a, options, tolerance, budget, progress);
    dev.queries += ab.result.refine_samples + ba.result.refine_samples;
  }

  const double scale = dev.diagonal > 0 ? 1.0 / dev.diagonal : 0.0;
  for (OneSidedDeviation* r : {&ab.result, &ba.result}) {
    r->relative_max = r->max * scale, r->relative_mean = r->mean * scale, r->relative_rms = r->rms * scale;
    r->relative_max_bound = r->max_bound * scale;
  }
  dev.a_to_b = ab.result;
  dev.b_to_a = ba.result;
  dev.hausdorff = std::max(dev.a_to_b.max, dev.b_to_a.max);
  dev.hausdorff_bound = std::max(dev.a_to_b.max_bound, dev.b_to_a.max_bound);
  const double area = sa.area + sb.area;
  if (area > 0) {
    dev.mean = (sa.area * dev.a_to_b.mean + sb.area * dev.b_to_a.mean) / area;
    dev.rms = std::sqrt((sa.area * dev.a_to_b.rms * dev.a_to_b.rms + sb.area * dev.b_to_a.rms * dev.b_to_a.rms) / area);
  } else {
    dev.mean = std::max(dev.a_to_b.mean, dev.b_to_a.mean);
    dev.rms = std::max(dev.a_to_b.rms, dev.b_to_a.rms);
  }
  dev.relative_hausdorff = dev.hausdorff * scale, dev.relative_mean = dev.mean * scale, dev.relative_rms = dev.rms * scale;
  dev.relative_hausdorff_bound = dev.hausdorff_bound * scale;

  dev.vertex_distance.resize(a.vertex_count());
  dev.vertex_error.resize(a.vertex_count());
  for (size_t v = 0; v < a.vertex_count(); ++v) {
    const uint32_t p = sa.ids.id[v];
    dev.vertex_distance[v] = ab.position_distance[p];
    std::memcpy(&dev.vertex_error[v], &ab.field[p], 4);
  }
  dev.query_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() - dev.build_seconds;
  return dev;
}

}  // namespace lod
