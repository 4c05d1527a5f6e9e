// Brute-force reference for `lodkit compare` (issue 4's bench): no spatial structure, every sample
// against every triangle of the other surface, closest points in double precision with a point-
// triangle routine of its own (Ericson, Real-Time Collision Detection 5.1.5), so it shares nothing
// with lodkit's BVH or its triangle distance. O(samples x triangles): for small meshes only.
//
//   brute_force A B [--spacing F | --points N] [--tolerance R] [--threads T] [--json]
//   brute_force A B --point X Y Z [--json]   the distance from one point to B's surface (every triangle)
//
// Sampling is a dense barycentric grid on every triangle of the sampled surface, not random points:
// triangle t is cut into k_t^2 similar sub-triangles (cells), k_t = ceil(longest edge / h).
//   max   over every grid node (this includes every vertex and k_t - 1 points on every edge), then
//         certified: a cell's upper bound is the largest corner distance to one fixed triangle (the
//         distance to a triangle is convex, and the surface is at least that close), and every cell
//         whose bound exceeds (1 + R) x the largest distance found is split 1 -> 4, its new corners
//         measured by brute force. "hausdorff_bound" is the largest bound left: the true value lies
//         in [hausdorff, hausdorff_bound] (R = --tolerance, default 1e-3).
//   mean, rms   midpoint rule: each cell's centroid, weighted by its area (area_t / k_t^2).
// h is F times A's bounding-box diagonal (--spacing), or chosen so each surface gets about N cells
// (--points, default 200,000); at most 200,000 refinement queries per direction. Symmetric values combine the two directions as lod::compare does
// (Hausdorff: the larger; mean and RMS: area-weighted), and are also divided by A's bounding-box
// diagonal.
//
// The only pruning is exact: each triangle of the other surface has a bounding sphere (centre, radius
// grown by a relative 1e-5), and a triangle whose sphere is farther than the best distance so far is
// skipped without changing the answer. Zero-area triangles are skipped on both sides.
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <thread>

#include "harness.h"

namespace {

struct V {
  double x, y, z;
};
V operator-(V a, V b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V operator+(V a, V b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V operator*(V a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dot(V a, V b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V cross(V a, V b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double len(V a) { return std::sqrt(dot(a, a)); }

// Ericson's ClosestPtPointTriangle (Voronoi regions), double precision.
V closest_point(V p, V a, V b, V c) {
  const V ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const V bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const V cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

struct Surface {
  std::vector<std::array<V, 3>> triangles;  // non-degenerate only
  std::vector<double> areas;
  // Bounding spheres, structure of arrays for the pruning loop.
  std::vector<double> cx, cy, cz, r;
  double area = 0, diagonal = 0;
};

Surface make_surface(const lod::Mesh& mesh) {
  Surface s;
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    std::array<V, 3> tri;
    for (int k = 0; k < 3; ++k) {
      const lod::float3& p = mesh.positions[mesh.indices[3 * t + k]];
      tri[k] = {p.x, p.y, p.z};
    }
    const double area = 0.5 * len(cross(tri[1] - tri[0], tri[2] - tri[0]));
    if (!(area > 0)) continue;
    s.triangles.push_back(tri);
    s.areas.push_back(area);
    s.area += area;
    const V c = (tri[0] + tri[1] + tri[2]) * (1.0 / 3.0);
    const double radius = std::max({len(tri[0] - c), len(tri[1] - c), len(tri[2] - c)});
    s.cx.push_back(c.x), s.cy.push_back(c.y), s.cz.push_back(c.z);
    s.r.push_back(radius * (1 + 1e-5) + 1e-30);
  }
  lod::float3 lo, hi;
  lod::bounding_box(mesh, lo, hi);
  s.diagonal = std::sqrt(double(hi.x - lo.x) * (hi.x - lo.x) + double(hi.y - lo.y) * (hi.y - lo.y) +
                         double(hi.z - lo.z) * (hi.z - lo.z));
  return s;
}

// Squared distance from p to the surface; `hint` (a triangle) starts the search and becomes the answer.
double distance_squared(const Surface& to, V p, size_t& hint) {
  const std::array<V, 3>& h = to.triangles[hint];
  const V start = p - closest_point(p, h[0], h[1], h[2]);
  double best2 = dot(start, start);
  double best = std::sqrt(best2);
  const size_t n = to.triangles.size();
  for (size_t t = 0; t < n; ++t) {
    const double dx = p.x - to.cx[t], dy = p.y - to.cy[t], dz = p.z - to.cz[t];
    const double reach = best + to.r[t];
    if (dx * dx + dy * dy + dz * dz > reach * reach) continue;  // the whole triangle is farther than best
    const std::array<V, 3>& tri = to.triangles[t];
    const V q = p - closest_point(p, tri[0], tri[1], tri[2]);
    const double d2 = dot(q, q);
    if (d2 < best2) best2 = d2, best = std::sqrt(d2), hint = t;
  }
  return best2;
}

double point_triangle_squared(const Surface& to, V p, size_t t) {
  const std::array<V, 3>& tri = to.triangles[t];
  const V q = p - closest_point(p, tri[0], tri[1], tri[2]);
  return dot(q, q);
}

struct Direction {
  double max = 0, bound = 0, mean = 0, rms = 0, spacing = 0;
  V worst{0, 0, 0};
  uint64_t nodes = 0, cells = 0, refined = 0;
};

// A grid cell (a sub-triangle) with its corners' distances and closest triangles.
struct Cell {
  V p[3];
  double d[3];
  size_t closest[3];
  int depth;
};

// Upper bound on the distance to the surface over a cell: for any triangle T, the distance to T is
// convex, so over the cell it is at most its largest corner value; the distance to the surface is at
// most the distance to T. T is tried as each corner's closest triangle; the smallest bound wins.
double cell_bound(const Surface& to, const Cell& c) {
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    double m = c.d[k];
    for (int i = 0; i < 3 && m < best; ++i)
      if (i != k) m = std::max(m, std::sqrt(point_triangle_squared(to, c.p[i], c.closest[k])));
    best = std::min(best, m);
  }
  return best;
}

// Samples `from` on a grid of spacing h (every node, against every triangle of `to`), then certifies
// the maximum: every grid cell whose upper bound exceeds (1 + tolerance) x the largest node distance
// found is split 1 -> 4 (new corners measured by brute force, up to depth 16); "bound" is the largest
// upper bound left over all cells, so the true one-sided Hausdorff distance lies in [max, bound].
Direction one_way(const Surface& from, const Surface& to, double h, double tolerance, unsigned threads) {
  const size_t n = from.triangles.size();
  struct PerTriangle {
    double max = 0, bound = 0, sum = 0, sum2 = 0;  // sums already weighted by sub-triangle area
    V worst{0, 0, 0};
    uint64_t nodes = 0, cells = 0, refined = 0;
    int k = 1;
    std::vector<double> d;  // node distances, row by row (i, then j with i + j <= k)
    std::vector<size_t> closest;
  };
  std::vector<PerTriangle> out(n);
  auto parallel = [&](auto&& body) {
    std::atomic<size_t> next{0};
    auto work = [&] {
      size_t hint = 0;
      for (size_t t; (t = next.fetch_add(1)) < n;) body(t, hint);
    };
    std::vector<std::thread> pool;
    for (unsigned i = 1; i < threads; ++i) pool.emplace_back(work);
    work();
    for (std::thread& th : pool) th.join();
  };
  auto node_index = [](int k, int i, int j) { return size_t(i) * (2 * k + 3 - i) / 2 + j; };
  // Pass 1: grid nodes (max) and sub-triangle centroids (mean, RMS).
  parallel([&](size_t t, size_t& hint) {
    const std::array<V, 3>& tri = from.triangles[t];
    const double longest = std::max({len(tri[1] - tri[0]), len(tri[2] - tri[1]), len(tri[0] - tri[2])});
    const int k = std::max(1, int(std::ceil(longest / h)));
    const V e1 = (tri[1] - tri[0]) * (1.0 / k), e2 = (tri[2] - tri[0]) * (1.0 / k);
    PerTriangle& o = out[t];
    o.k = k;
    o.d.resize(node_index(k, k, 0) + 1);
    o.closest.resize(o.d.size());
    for (int i = 0; i <= k; ++i)
      for (int j = 0; i + j <= k; ++j) {
        const V p = tri[0] + e1 * i + e2 * j;
        const double d = std::sqrt(distance_squared(to, p, hint));
        o.d[node_index(k, i, j)] = d, o.closest[node_index(k, i, j)] = hint;
        ++o.nodes;
        if (d > o.max) o.max = d, o.worst = p;
      }
    // Sub-triangle centroids: k(k+1)/2 "up" cells and k(k-1)/2 "down" cells, each area_t / k^2.
    const double w = from.areas[t] / (double(k) * k);
    auto cell = [&](double a, double b) {
      const double d2 = distance_squared(to, tri[0] + e1 * a + e2 * b, hint);
      o.sum += w * std::sqrt(d2), o.sum2 += w * d2, ++o.cells;
    };
    for (int i = 0; i < k; ++i)
      for (int j = 0; i + j < k; ++j) {
        cell(i + 1.0 / 3, j + 1.0 / 3);
        if (i + j < k - 1) cell(i + 2.0 / 3, j + 2.0 / 3);
      }
  });
  double found = 0;
  for (const PerTriangle& o : out) found = std::max(found, o.max);
  // Pass 2: certify against the largest node distance.
  const double target = found * (1 + tolerance);
  std::atomic<uint64_t> spent{0};
  const uint64_t budget = 200'000;  // refinement queries per direction: beyond, the bound stays as it is
  parallel([&](size_t t, size_t& hint) {
    const std::array<V, 3>& tri = from.triangles[t];
    PerTriangle& o = out[t];
    const int k = o.k;
    const V e1 = (tri[1] - tri[0]) * (1.0 / k), e2 = (tri[2] - tri[0]) * (1.0 / k);
    auto node = [&](int i, int j, V& p, double& d, size_t& c) {
      p = tri[0] + e1 * i + e2 * j, d = o.d[node_index(k, i, j)], c = o.closest[node_index(k, i, j)];
    };
    std::vector<Cell> stack;
    auto push = [&](int i0, int j0, int i1, int j1, int i2, int j2) {
      Cell c;
      node(i0, j0, c.p[0], c.d[0], c.closest[0]);
      node(i1, j1, c.p[1], c.d[1], c.closest[1]);
      node(i2, j2, c.p[2], c.d[2], c.closest[2]);
      c.depth = 0;
      stack.push_back(c);
    };
    for (int i = 0; i < k; ++i)
      for (int j = 0; i + j < k; ++j) {
        push(i, j, i + 1, j, i, j + 1);
        if (i + j < k - 1) push(i + 1, j, i + 1, j + 1, i, j + 1);
      }
    while (!stack.empty()) {
      const Cell c = stack.back();
      stack.pop_back();
      const double b = cell_bound(to, c);
      if (b <= target || c.depth >= 16 || spent.load(std::memory_order_relaxed) >= budget) {
        o.bound = std::max(o.bound, b);
        continue;
      }
      // Split at the edge midpoints, each measured against every triangle.
      V m[3];
      double md[3];
      size_t mc[3];
      for (int e = 0; e < 3; ++e) {
        m[e] = (c.p[e] + c.p[(e + 1) % 3]) * 0.5;
        md[e] = std::sqrt(distance_squared(to, m[e], hint)), mc[e] = hint;
        ++o.refined;
        spent.fetch_add(1, std::memory_order_relaxed);
        if (md[e] > o.max) o.max = md[e], o.worst = m[e];
      }
      auto child = [&](V p0, double d0, size_t c0, V p1, double d1, size_t c1, V p2, double d2, size_t c2) {
        stack.push_back({{p0, p1, p2}, {d0, d1, d2}, {c0, c1, c2}, c.depth + 1});
      };
      child(c.p[0], c.d[0], c.closest[0], m[0], md[0], mc[0], m[2], md[2], mc[2]);
      child(m[0], md[0], mc[0], c.p[1], c.d[1], c.closest[1], m[1], md[1], mc[1]);
      child(m[2], md[2], mc[2], m[1], md[1], mc[1], c.p[2], c.d[2], c.closest[2]);
      child(m[0], md[0], mc[0], m[1], md[1], mc[1], m[2], md[2], mc[2]);
    }
  });
  Direction d;
  d.spacing = h;
  double sum = 0, sum2 = 0;
  for (const PerTriangle& o : out) {  // in triangle order: the result does not depend on the threads
    if (o.max > d.max) d.max = o.max, d.worst = o.worst;
    d.bound = std::max(d.bound, o.bound);
    sum += o.sum, sum2 += o.sum2, d.nodes += o.nodes, d.cells += o.cells, d.refined += o.refined;
  }
  d.bound = std::max(d.bound, d.max);
  d.mean = sum / from.area;
  d.rms = std::sqrt(sum2 / from.area);
  return d;
}

}  // namespace

int main(int argc, char** argv) {
  return bench::run_main("brute_force", "brute_force A B [--spacing F | --points N] [--tolerance R] [--threads T] [--json] | A B --point X Y Z [--json]", [&] {
    std::vector<std::string> a(argv + 1, argv + argc);
    std::vector<std::string> files;
    double spacing = 0, points = 2e5, tolerance = 1e-3;
    unsigned threads = std::max(1u, std::thread::hardware_concurrency());
    bool json = false;
    std::optional<V> point;
    for (size_t i = 0; i < a.size(); ++i) {
      if (a[i] == "--point" && i + 3 < a.size()) {
        point = V{std::stod(a[i + 1]), std::stod(a[i + 2]), std::stod(a[i + 3])};
        i += 3;
        continue;
      }
      if (a[i] == "--spacing" && i + 1 < a.size()) spacing = std::stod(a[++i]);
      else if (a[i] == "--points" && i + 1 < a.size()) points = std::stod(a[++i]);
      else if (a[i] == "--tolerance" && i + 1 < a.size()) tolerance = std::stod(a[++i]);
      else if (a[i] == "--threads" && i + 1 < a.size()) threads = unsigned(std::max(1, std::stoi(a[++i])));
      else if (a[i] == "--json") json = true;
      else if (a[i].rfind("--", 0) == 0) throw std::invalid_argument("unknown option " + a[i]);
      else files.push_back(a[i]);
    }
    if (files.size() != 2 || !(points >= 1) || !(spacing >= 0)) throw std::invalid_argument("expected two meshes");
    const Surface sa = make_surface(bench::load_positions(files[0]));
    const Surface sb = make_surface(bench::load_positions(files[1]));
    if (sa.triangles.empty() || sb.triangles.empty()) throw std::runtime_error("a mesh has no non-degenerate triangle");
    const double diag = sa.diagonal > 0 ? sa.diagonal : 1.0;
    if (point) {
      // A sampled Hausdorff value is a real distance from a point of one surface to the other, so it
      // is a lower bound of the true value; this recomputes one such distance independently.
      size_t hint = 0;
      const double d = std::sqrt(distance_squared(sb, *point, hint));
      if (json) std::printf("%s\n", nlohmann::json{{"tool", "brute_force"}, {"distance", d}, {"triangle", hint}}.dump().c_str());
      else std::printf("distance %.9g (triangle %zu)\n", d, hint);
      return 0;
    }
    // An equilateral sub-triangle of edge h has area h^2 sqrt(3) / 4.
    auto spacing_for = [&](const Surface& s) { return spacing > 0 ? spacing * diag : std::sqrt(s.area / points / 0.4330127); };
    const auto start = std::chrono::steady_clock::now();
    const Direction ab = one_way(sa, sb, spacing_for(sa), tolerance, threads);
    const Direction ba = one_way(sb, sa, spacing_for(sb), tolerance, threads);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double hausdorff = std::max(ab.max, ba.max);
    const double bound = std::max(ab.bound, ba.bound);
    const double wa = sa.area / (sa.area + sb.area), wb = 1 - wa;
    const double rms = std::sqrt(wa * ab.rms * ab.rms + wb * ba.rms * ba.rms), mean = wa * ab.mean + wb * ba.mean;
    auto side = [&](const Direction& d, const Surface& s) {
      return nlohmann::json{{"hausdorff", d.max}, {"max_bound", d.bound}, {"refine_queries", d.refined}, {"mean", d.mean}, {"rms", d.rms},
                            {"area", s.area}, {"spacing", d.spacing}, {"nodes", d.nodes}, {"cells", d.cells},
                            {"worst", {d.worst.x, d.worst.y, d.worst.z}}};
    };
    const nlohmann::json j = {{"tool", "brute_force"},
                              {"a", files[0]},
                              {"b", files[1]},
                              {"diagonal", sa.diagonal},
                              {"hausdorff", hausdorff},
                              {"hausdorff_bound", bound},
                              {"rms", rms},
                              {"mean", mean},
                              {"hausdorff_relative", hausdorff / diag},
                              {"hausdorff_bound_relative", bound / diag},
                              {"rms_relative", rms / diag},
                              {"mean_relative", mean / diag},
                              {"a_to_b", side(ab, sa)},
                              {"b_to_a", side(ba, sb)},
                              {"threads", threads},
                              {"seconds", seconds}};
    if (json) {
      std::printf("%s\n", j.dump().c_str());
    } else {
      std::printf("hausdorff %.6g (%.6g of diag, certified <= %.6g), rms %.6g (%.6g), mean %.6g; A->B %.6g, B->A %.6g; %.3f s\n",
                  hausdorff, hausdorff / diag, bound / diag, rms, rms / diag, mean, ab.max, ba.max, seconds);
    }
    return 0;
  });
}
