// Analyzers: simulate the post-transform vertex cache (FIFO or LRU), the memory fetches behind its
// misses, overdraw (a small depth-buffer rasteriser over several views), and read strip buffers.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

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

OverdrawStats analyze_overdraw(std::span<const uint32_t> indices, std::span<const float3> positions, const OverdrawOptions& options) {
  check_indices(indices, positions.size(), "analyze_overdraw");
  if (options.resolution == 0 || options.resolution > 16384) throw_usage("analyze_overdraw: resolution must be in [1, 16384]");
  OverdrawStats s;
  if (indices.empty()) return s;
  // The bounding sphere of the referenced vertices' box fills each view.
  double lo[3] = {std::numeric_limits<double>::max(), std::numeric_limits<double>::max(), std::numeric_limits<double>::max()};
  double hi[3] = {-lo[0], -lo[1], -lo[2]};
  for (const uint32_t i : indices) {
    const double p[3] = {positions[i].x, positions[i].y, positions[i].z};
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  }
  const double centre[3] = {(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2};
  const double radius = 0.5 * std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
  const uint32_t R = options.resolution;
  const double scale = radius > 0 ? R / (2 * radius) : 1;

  std::vector<std::array<double, 3>> views = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  if (options.diagonal_views)
    for (const double x : {-1.0, 1.0})
      for (const double y : {-1.0, 1.0})
        for (const double z : {-1.0, 1.0}) views.push_back({x / std::sqrt(3.0), y / std::sqrt(3.0), z / std::sqrt(3.0)});

  std::vector<double> depth(size_t(R) * R);
  std::vector<double> X(positions.size()), Y(positions.size()), Z(positions.size());
  for (const auto& d : views) {
    // Camera far out along d looking back: screen axes u, v with u x v = d, depth -d (smaller is nearer),
    // so a triangle counter-clockwise seen from the camera has positive area on screen.
    const std::array<double, 3> a = std::abs(d[2]) < 0.9 ? std::array<double, 3>{0, 0, 1} : std::array<double, 3>{1, 0, 0};
    std::array<double, 3> u = {a[1] * d[2] - a[2] * d[1], a[2] * d[0] - a[0] * d[2], a[0] * d[1] - a[1] * d[0]};
    const double ul = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (double& c : u) c /= ul;
    const std::array<double, 3> v = {d[1] * u[2] - d[2] * u[1], d[2] * u[0] - d[0] * u[2], d[0] * u[1] - d[1] * u[0]};
    for (const uint32_t i : indices) {
      const double p[3] = {positions[i].x - centre[0], positions[i].y - centre[1], positions[i].z - centre[2]};
      X[i] = (p[0] * u[0] + p[1] * u[1] + p[2] * u[2]) * scale + R / 2.0;
      Y[i] = (p[0] * v[0] + p[1] * v[1] + p[2] * v[2]) * scale + R / 2.0;
      Z[i] = -(p[0] * d[0] + p[1] * d[1] + p[2] * d[2]);
    }
    std::fill(depth.begin(), depth.end(), std::numeric_limits<double>::infinity());
    for (size_t k = 0; k < indices.size(); k += 3) {
      const uint32_t i0 = indices[k], i1 = indices[k + 1], i2 = indices[k + 2];
      const double x0 = X[i0], y0 = Y[i0], x1 = X[i1], y1 = Y[i1], x2 = X[i2], y2 = Y[i2];
      const double area = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0);
      if (!(area > 0)) continue;  // back face or edge-on
      const int xmin = std::max(0, int(std::floor(std::min({x0, x1, x2})))), xmax = std::min(int(R) - 1, int(std::ceil(std::max({x0, x1, x2}))));
      const int ymin = std::max(0, int(std::floor(std::min({y0, y1, y2})))), ymax = std::min(int(R) - 1, int(std::ceil(std::max({y0, y1, y2}))));
      // Edge (a -> b) owns the pixel centres exactly on it when it is a top or left edge, so two
      // triangles sharing an edge never both cover a pixel.
      auto owns = [](double ax, double ay, double bx, double by) { return by - ay < 0 || (by == ay && bx - ax > 0); };
      const bool own0 = owns(x1, y1, x2, y2), own1 = owns(x2, y2, x0, y0), own2 = owns(x0, y0, x1, y1);
      for (int py = ymin; py <= ymax; ++py)
        for (int px = xmin; px <= xmax; ++px) {
          const double cx = px + 0.5, cy = py + 0.5;
          const double w0 = (x2 - x1) * (cy - y1) - (y2 - y1) * (cx - x1);
          const double w1 = (x0 - x2) * (cy - y2) - (y0 - y2) * (cx - x2);
          const double w2 = (x1 - x0) * (cy - y0) - (y1 - y0) * (cx - x0);
          if (w0 < 0 || w1 < 0 || w2 < 0 || (w0 == 0 && !own0) || (w1 == 0 && !own1) || (w2 == 0 && !own2)) continue;
          const double z = (w0 * Z[i0] + w1 * Z[i1] + w2 * Z[i2]) / area;
          double& stored = depth[size_t(py) * R + px];
          if (z < stored) stored = z, ++s.pixels_shaded;
        }
    }
    for (const double z : depth) s.pixels_covered += z != std::numeric_limits<double>::infinity();
  }
  s.overdraw = s.pixels_covered ? double(s.pixels_shaded) / double(s.pixels_covered) : 0;
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
