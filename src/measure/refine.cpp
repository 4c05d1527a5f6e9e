#include "measure/refine.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

#include "core/parallel.h"

namespace lod::measure {

namespace {

struct Patch {
  vec3f corner[3];
  float distance[3];
  uint32_t closest[3];
  uint32_t triangle;  // of `from`
  uint32_t extra;     // candidate triangle of `to` inherited from the parent (see patch_bound)
  float bound;
};

struct Split {
  Patch child[4];
  vec3f point[3];  // the new corners: edge midpoints 01, 12, 20; or the longest edge's alone
  ClosestHit hit[3];
  int children = 4, points = 3;
};

constexpr size_t max_batch = 8192;

// Sutherland-Hodgman: the part of a convex polygon (barycentric points) where g(b) <= 0, g linear,
// into `below`, and if `above` is given the part where g(b) >= 0 into it, in one pass (the cut
// points are the same bits either way). Returns the two vertex counts.
std::pair<int, int> split_polygon(const std::array<float, 3>* in, int n, const float g[3], std::array<float, 3>* below,
                                  std::array<float, 3>* above = nullptr) {
  auto value = [&](const std::array<float, 3>& b) { return b[0] * g[0] + b[1] * g[1] + b[2] * g[2]; };
  int m = 0, k = 0;
  const float v0 = value(in[0]);
  float va = v0;
  for (int i = 0; i < n; ++i) {
    const std::array<float, 3>& a = in[i];
    const std::array<float, 3>& b = in[i + 1 == n ? 0 : i + 1];
    const float vb = i + 1 == n ? v0 : value(b);
    if (va <= 0) below[m++] = a;
    if (above && va >= 0) above[k++] = a;
    if ((va < 0 && vb > 0) || (va > 0 && vb < 0)) {
      const float s = va / (va - vb);
      const std::array<float, 3> cut = {a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2])};
      below[m++] = cut;
      if (above) above[k++] = cut;
    }
    va = vb;
  }
  return {m, k};
}

constexpr int max_candidates = 4;  // each corner's closest triangle and the patch's extra

// Piecewise: split the patch where each candidate's linear interpolant l_k (from its corner values
// f[k]) is the lowest. The pieces cover the patch, each is convex, and on piece k the distance is at
// most dist(., T_k), which is convex: so the bound is the largest dist(v, T_k) over piece k's
// vertices. Where the distances are affine (over the interior of the candidates) the cut falls where
// they are equal and the bound meets the true maximum; one triangle alone is loose across a fold.
// Stops early once the bound reaches `give_up` (it can only grow).
float piecewise_bound(const vec3f corners[3], const uint32_t* candidate, const float (*f)[3], int count,
                      const TriangleBvh& to, float give_up) {
  float bound = 0;
  for (int k = 0; k < count && bound < give_up; ++k) {
    std::array<float, 3> buffer[2][max_candidates + 3];
    buffer[0][0] = {1, 0, 0}, buffer[0][1] = {0, 1, 0}, buffer[0][2] = {0, 0, 1};
    int n = 3, cur = 0;
    for (int j = 0; j < count && n > 0; ++j) {
      if (j == k) continue;
      const float g[3] = {f[k][0] - f[j][0], f[k][1] - f[j][1], f[k][2] - f[j][2]};
      n = split_polygon(buffer[cur], n, g, buffer[1 - cur]).first;
      cur = 1 - cur;
    }
    for (int v = 0; v < n; ++v) {
      const std::array<float, 3>& b = buffer[cur][v];
      float d;
      if (b[0] == 1 || b[1] == 1 || b[2] == 1) d = f[k][b[0] == 1 ? 0 : b[1] == 1 ? 1 : 2];
      else d = std::sqrt(to.distance_squared(corners[0] * b[0] + corners[1] * b[1] + corners[2] * b[2], candidate[k]));
      bound = std::max(bound, d);
    }
  }
  return bound;
}

// Prisms: the points whose foot on T's plane lies inside T (T's face region) are those between
// three planes through T's edges, which meet the patch along lines. Peel the patch: the part inside
// the first candidate's prism is one convex piece, the rest at most three, which the next candidate
// peels in turn, and what no prism takes is left over. Every piece is convex and bounded by one
// triangle's convex distance at its vertices (its prism's triangle; a leftover by the best
// candidate), so the bound holds however the cuts round: the prisms only choose where to cut. Inside
// a prism the distance is the distance to T's plane, so where the other surface lies flat under the
// patch (coincident or parallel faces: a flat or faceted part simplified without loss) the bound
// meets the true distance. The cuts by interpolated corner values (piecewise_bound) do not there:
// they shrink only with the patch, and a CAD cylinder's lossless level kept a bound of 0.0095 (the
// distance: 2.4e-7) after the chain's whole budget. `neighbours` (of `to`, may be null) lets
// leftovers recruit more candidates. Returns `give_up` when it cannot do better.
float prism_bound(const vec3f corners[3], const uint32_t* candidates, int count, const TriangleBvh& to,
                  const core::TriangleAdjacency* neighbours, float give_up) {
  constexpr int max_vertices = 12, max_pieces = 16;  // beyond them: give up (rare; the caller keeps its bound)
  // A leftover piece that would raise the bound recruits the neighbour across from it, at most this
  // many: a patch often covers triangles none of its corners is closest to (across a fold, or under
  // a fan of needles: a CAD blade's lossless levels have up to 35 coplanar needles 100 long meeting
  // at one apex), and a leftover's bound by the nearest candidate is the gap to it (0.0057 there
  // after the whole budget; the distance: 1e-7). Corpus chains: 0.77x the build time, bounds 0.95x.
  constexpr int max_recruits = 64;
  struct Piece {
    std::array<float, 3> v[max_vertices];  // barycentric in the patch
    int n;
  };
  uint32_t candidate[max_candidates + max_recruits];
  std::copy(candidates, candidates + count, candidate);
  Piece pieces[2][max_pieces];
  int live = 1, cur = 0;
  pieces[0][0].v[0] = {1, 0, 0}, pieces[0][0].v[1] = {0, 1, 0}, pieces[0][0].v[2] = {0, 0, 1};
  pieces[0][0].n = 3;
  auto point = [&](const std::array<float, 3>& b) { return corners[0] * b[0] + corners[1] * b[1] + corners[2] * b[2]; };
  auto worst = [&](const Piece& p, uint32_t t, float stop) {
    float d = 0;
    for (int i = 0; i < p.n && d < stop; ++i) d = std::max(d, to.distance_squared(point(p.v[i]), t));
    return d;
  };
  const float give_up2 = give_up * give_up;
  float bound2 = 0;
  // Takes triangle `id`'s prism out of every live piece; false: give up.
  auto peel_by = [&](uint32_t id) {
    const PreparedTriangle& t = to.prepared(id);
    if (t.det == 0) return true;  // degenerate: no face region
    const detail::EdgeNormals m = detail::edge_normals(t);
    const vec3f origin[3] = {t.a, t.a, t.a + t.ab};
    const vec3f normal[3] = {m.ab, m.ac, m.bc};
    float g[3][3];  // g[e][j]: patch corner j's side of T's edge e, positive inside
    bool finite = true;
    for (int e = 0; e < 3; ++e)
      for (int j = 0; j < 3; ++j) finite &= std::isfinite(g[e][j] = dot(normal[e], corners[j] - origin[e]));
    if (!finite) return true;  // overflowed: no cut (a NaN side would drop the piece from the cover)
    int next = 0;
    Piece* out = pieces[1 - cur];
    for (int i = 0; i < live; ++i) {
      const Piece& p = pieces[cur][i];
      // Whole pieces first: outside one edge (kept for the next candidate) or inside all three.
      bool outside_one = false, inside_all = true;
      for (int e = 0; e < 3 && !outside_one; ++e) {
        bool all_out = true;
        for (int v = 0; v < p.n; ++v) {
          const float value = p.v[v][0] * g[e][0] + p.v[v][1] * g[e][1] + p.v[v][2] * g[e][2];
          all_out &= value <= 0, inside_all &= value >= 0;
        }
        outside_one = all_out;
      }
      if (outside_one) {
        if (next == max_pieces) return false;
        out[next++] = p;
        continue;
      }
      if (inside_all) {
        bound2 = std::max(bound2, worst(p, id, give_up2));
        if (bound2 >= give_up2) return false;
        continue;
      }
      // Peel: the part outside edge 0 goes on, then of the rest the part outside edge 1, and so on;
      // what is inside all three is T's.
      if (next == max_pieces) return false;
      Piece rest[2];
      rest[0] = p;
      int r = 0;
      for (int e = 0; e < 3 && rest[r].n > 0; ++e) {
        // g is negative outside edge e: that part is cut off, the part inside goes on.
        if (rest[r].n >= max_vertices) return false;  // a clip adds one vertex at most
        Piece& cut = out[next];
        std::tie(cut.n, rest[1 - r].n) = split_polygon(rest[r].v, rest[r].n, g[e], cut.v, rest[1 - r].v);
        if (cut.n >= 3) {
          if (next + 1 == max_pieces) return false;
          ++next;
        }
        r = 1 - r;
      }
      if (rest[r].n >= 3) bound2 = std::max(bound2, worst(rest[r], id, give_up2));
      if (bound2 >= give_up2) return false;
    }
    live = next, cur = 1 - cur;
    return true;
  };
  for (int k = 0; k < count && live > 0; ++k)
    if (!peel_by(candidate[k])) return give_up;
  // The neighbour of the candidate nearest q across the edge q lies farthest beyond: a step over
  // the other surface towards q (a BVH query costs more, and on a fan of needles much more).
  auto across = [&](const vec3f& q) {
    if (!neighbours) return core::no_twin;
    int nearest = 0;
    float nearest2 = std::numeric_limits<float>::infinity();
    for (int k = 0; k < count; ++k) {
      const float d2 = to.distance_squared(q, candidate[k]);
      if (d2 < nearest2) nearest2 = d2, nearest = k;
    }
    const PreparedTriangle& t = to.prepared(candidate[nearest]);
    if (t.det == 0) return core::no_twin;
    const detail::EdgeNormals m = detail::edge_normals(t);
    // Half-edges 0, 1, 2 run a -> b, b -> c, c -> a; positive inside.
    const float side[3] = {dot(m.ab, q - t.a), dot(m.bc, q - (t.a + t.ab)), dot(m.ac, q - t.a)};
    const int e = side[0] <= side[1] && side[0] <= side[2] ? 0 : side[1] <= side[2] ? 1 : 2;
    return side[e] < 0 ? neighbours->neighbour(candidate[nearest], uint32_t(e)) : core::no_twin;
  };
  // What no prism took: each piece by the candidate nearest its vertices (the first, whose prism is
  // usually next to it, often suffices), and then set aside. A piece that would raise the bound
  // first recruits the triangle across from its centroid, if that is new, and the pieces left are
  // peeled by it.
  for (int recruits = 0; live > 0 && bound2 < give_up2;) {
    const Piece& p = pieces[cur][live - 1];
    float best = give_up2;
    for (int k = 0; k < count && best > bound2; ++k) best = std::min(best, worst(p, candidate[k], best));
    if (best > bound2 && recruits < max_recruits) {
      std::array<float, 3> mean = {0, 0, 0};
      for (int v = 0; v < p.n; ++v)
        for (int j = 0; j < 3; ++j) mean[j] += p.v[v][j] / float(p.n);
      const uint32_t t = across(point(mean));
      if (t != core::no_twin && std::find(candidate, candidate + count, t) == candidate + count) {
        ++recruits;
        candidate[count++] = t;
        if (!peel_by(t)) return give_up;
        continue;
      }
    }
    bound2 = std::max(bound2, best);
    --live;
  }
  return bound2 < give_up2 ? std::sqrt(bound2) : give_up;
}

}  // namespace

float patch_bound(const vec3f corners[3], const float distances[3], const uint32_t closest[3], uint32_t extra,
                  const TriangleBvh& to, const core::TriangleAdjacency* neighbours, float enough, uint32_t* best) {
  const float e01 = distance(corners[0], corners[1]), e12 = distance(corners[1], corners[2]),
              e20 = distance(corners[2], corners[0]);
  float bound = std::min({distances[0] + std::max(e01, e20), distances[1] + std::max(e01, e12),
                          distances[2] + std::max(e12, e20)});

  // Distinct candidate triangles and each corner's distance to each (f[k][i]).
  uint32_t candidate[max_candidates];
  float f[max_candidates][3];
  int count = 0;
  auto add = [&](uint32_t t) {
    if (t == UINT32_MAX || std::find(candidate, candidate + count, t) != candidate + count) return;
    candidate[count] = t;
    for (int i = 0; i < 3; ++i)
      f[count][i] = closest[i] == t ? distances[i] : std::sqrt(to.distance_squared(corners[i], t));
    ++count;
  };
  for (uint32_t t : {closest[0], closest[1], closest[2], extra}) add(t);
  // One triangle for the whole patch: dist(., T) is convex, so its largest corner value bounds it.
  uint32_t chosen = count ? candidate[0] : UINT32_MAX;
  for (int k = 0; k < count; ++k) {
    const float worst = std::max({f[k][0], f[k][1], f[k][2]});
    if (worst < bound) bound = worst, chosen = candidate[k];
  }
  if (best) *best = chosen;
  if (count >= 2 && bound > enough) bound = std::min(bound, piecewise_bound(corners, candidate, f, count, to, bound));
  // Still too loose: the patch may span triangles no corner is closest to, or lie flat on several;
  // the prisms recruit the triangles across from what their candidates miss. (Before the recruits,
  // the candidates' edge neighbours were added to the piecewise cuts here: corpus chains 0.85x the
  // build time without that step, bounds within the tolerance as before.)
  if (count >= 1 && bound > enough) bound = std::min(bound, prism_bound(corners, candidate, count, to, neighbours, bound));
  return bound;
}

namespace {

// The longest edge of a patch (from corner e to e + 1), and whether the patch is a needle: the edge
// over the height onto it above `needle_ratio`. A needle keeps its shape under 1 -> 4 splits: its
// children are needles half as long, so closing in on a distance takes (length / step)^2 patches.
// Bisecting the longest edge shortens it instead, and takes about length / step (a CAD blade's
// lossless levels, needles up to 8 long: bounds 1.1-2.4 after the whole budget, now 0.0013-0.0057).
constexpr float needle_ratio = 4;

int longest_edge(const vec3f c[3], bool* needle) {
  const float l[3] = {length_squared(c[1] - c[0]), length_squared(c[2] - c[1]), length_squared(c[0] - c[2])};
  const int e = l[0] >= l[1] && l[0] >= l[2] ? 0 : l[1] >= l[2] ? 1 : 2;
  const float area2 = std::sqrt(length_squared(detail::cross(c[1] - c[0], c[2] - c[0])));  // twice the area
  *needle = l[e] > needle_ratio * area2;  // longest / height = longest^2 / (2 area)
  return e;
}

void set_corner(Patch& child, int k, const vec3f& c, float d, uint32_t closest) {
  child.corner[k] = c, child.distance[k] = d, child.closest[k] = closest;
}

// Each child's bound, once bisect or quarter has set its corners.
void bound_children(const Patch& p, Split& s, const TriangleBvh& to, const core::TriangleAdjacency* neighbours,
                    float threshold) {
  for (int c = 0; c < s.children; ++c) {
    Patch& child = s.child[c];
    child.triangle = p.triangle;
    child.bound = patch_bound(child.corner, child.distance, child.closest, p.extra, to, neighbours, threshold, &child.extra);
  }
}

// A needle: at the longest edge's midpoint m, into (c_e, m, c_g) and (m, c_f, c_g).
void bisect(const Patch& p, int e, Split& s, const TriangleBvh& to) {
  const int f = (e + 1) % 3, g = (e + 2) % 3;
  s.children = 2, s.points = 1;
  s.point[0] = midpoint(p.corner[e], p.corner[f]);
  s.hit[0] = to.closest(s.point[0], p.closest[e]);
  const float md = std::sqrt(s.hit[0].distance_squared);
  const uint32_t mc = s.hit[0].triangle;
  set_corner(s.child[0], 0, p.corner[e], p.distance[e], p.closest[e]);
  set_corner(s.child[0], 1, s.point[0], md, mc);
  set_corner(s.child[0], 2, p.corner[g], p.distance[g], p.closest[g]);
  set_corner(s.child[1], 0, s.point[0], md, mc);
  set_corner(s.child[1], 1, p.corner[f], p.distance[f], p.closest[f]);
  set_corner(s.child[1], 2, p.corner[g], p.distance[g], p.closest[g]);
}

// Otherwise at the three edge midpoints, into (c0, m01, m20), (m01, c1, m12), (m20, m12, c2) and
// (m01, m12, m20).
void quarter(const Patch& p, Split& s, const TriangleBvh& to) {
  s.children = 4, s.points = 3;
  for (int e = 0; e < 3; ++e) {
    s.point[e] = midpoint(p.corner[e], p.corner[(e + 1) % 3]);
    s.hit[e] = to.closest(s.point[e], p.closest[e]);
  }
  const vec3f* m = s.point;
  const float md[3] = {std::sqrt(s.hit[0].distance_squared), std::sqrt(s.hit[1].distance_squared),
                       std::sqrt(s.hit[2].distance_squared)};
  const uint32_t mc[3] = {s.hit[0].triangle, s.hit[1].triangle, s.hit[2].triangle};
  for (int c = 0; c < 3; ++c) {
    set_corner(s.child[c], c, p.corner[c], p.distance[c], p.closest[c]);
    set_corner(s.child[c], (c + 1) % 3, m[c], md[c], mc[c]);
    set_corner(s.child[c], (c + 2) % 3, m[(c + 2) % 3], md[(c + 2) % 3], mc[(c + 2) % 3]);
  }
  for (int k = 0; k < 3; ++k) set_corner(s.child[3], k, m[k], md[k], mc[k]);
}

}  // namespace

RefineResult refine_max(const RefineInput& input, float max, const MaxLocation& location,
                        const std::function<void(uint32_t, const vec3f&, float)>& on_sample) {
  const Mesh& from = *input.from;
  const std::vector<uint32_t>& pid = *input.position_id;
  const TriangleBvh& to = *input.to;
  RefineResult result;
  result.max = max;
  result.location = location;

  // Every triangle's bound from its corners; those that may hold more than the max become patches.
  const size_t triangles = from.triangle_count();
  constexpr size_t block = 2048;
  const size_t blocks = (triangles + block - 1) / block;
  std::vector<std::vector<Patch>> open_per_block(blocks);
  std::vector<float> settled_per_block(blocks, 0.0f);
  core::parallel_blocks(triangles, block, input.threads, [&](size_t b, size_t begin, size_t end) {
    for (size_t t = begin; t < end; ++t) {
      Patch p;
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = from.indices[3 * t + k];
        p.corner[k] = from.positions[v];
        p.distance[k] = (*input.position_distance)[pid[v]];
        p.closest[k] = (*input.position_closest)[pid[v]];
      }
      p.triangle = uint32_t(t);
      const uint32_t inner = input.triangle_closest ? (*input.triangle_closest)[t] : UINT32_MAX;
      p.bound = patch_bound(p.corner, p.distance, p.closest, inner, to, input.neighbours, max + input.tolerance, &p.extra);
      if (p.bound > max + input.tolerance) open_per_block[b].push_back(p);
      else settled_per_block[b] = std::max(settled_per_block[b], p.bound);
    }
  });
  std::vector<Patch> open;
  float settled = 0;  // the largest bound of the patches set aside
  for (size_t b = 0; b < blocks; ++b) {
    open.insert(open.end(), open_per_block[b].begin(), open_per_block[b].end());
    settled = std::max(settled, settled_per_block[b]);
  }
  open_per_block.clear();

  std::vector<Split> splits;
  std::vector<Patch> next;
  while (!open.empty() && result.queries + 3 <= input.budget) {
    // The worst first; equal bounds keep their order, so the rounds repeat exactly.
    std::stable_sort(open.begin(), open.end(), [](const Patch& x, const Patch& y) { return x.bound > y.bound; });
    const size_t batch = std::min({open.size(), size_t((input.budget - result.queries) / 3), max_batch});
    splits.resize(batch);
    const float threshold = result.max + input.tolerance;  // the max only grows: a safe "enough"
    core::parallel_for(
        batch, input.threads,
        [&](size_t i) {
          const Patch& p = open[i];
          Split& s = splits[i];
          bool needle;
          const int e = longest_edge(p.corner, &needle);
          if (needle) bisect(p, e, s, to);
          else quarter(p, s, to);
          bound_children(p, s, to, input.neighbours, threshold);
        },
        64);
    for (size_t i = 0; i < batch; ++i) {
      result.queries += splits[i].points;
      for (int e = 0; e < splits[i].points; ++e) {
        const ClosestHit& h = splits[i].hit[e];
        const float d = std::sqrt(h.distance_squared);
        if (on_sample) on_sample(open[i].triangle, splits[i].point[e], d);
        if (d > result.max) {
          result.max = d;
          result.location = {splits[i].point[e], h.point, open[i].triangle, h.triangle};
        }
      }
    }
    next.clear();
    auto keep = [&](const Patch& p) {
      if (p.bound > result.max + input.tolerance) next.push_back(p);
      else settled = std::max(settled, p.bound);
    };
    for (size_t i = 0; i < batch; ++i)
      for (int c = 0; c < splits[i].children; ++c) keep(splits[i].child[c]);
    for (size_t i = batch; i < open.size(); ++i) keep(open[i]);
    open.swap(next);
  }
  // Patches still open when the budget ran out bound the rest of the surface: without them the
  // bound would be only the sampled maximum there (a few of them hold the true one).
  for (const Patch& p : open) settled = std::max(settled, p.bound);
  result.bound = std::max(result.max, settled);
  return result;
}

}  // namespace lod::measure
