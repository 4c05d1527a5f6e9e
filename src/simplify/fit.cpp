#include "simplify/fit.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/parallel.h"
#include "core/union_find.h"
#include "measure/bvh.h"

namespace lod::collapse {
namespace {

constexpr uint32_t none = ~0u;
constexpr uint32_t max_group = 32;  // samples per closest_group query
// The edge term (see fit_positions): its weight against the input samples', and the cap of its
// emphasis on large residuals.
constexpr double edge_weight = 0.1, edge_cap = 30;
// Each Jacobi move is this share of the solution of its own equation: neighbours solve theirs at
// the same time, towards the same residuals, so full moves overshoot and the fit oscillates (on
// fandisk_large at 10%, RMS after 1, 2 and 3 iterations 1.66, 1.44, 1.58e-4; 1.40e-4 before the
// fit). Chosen with edge_weight on the corpus at 10% and 1% (bench/README, twelfth session).
constexpr double step = 0.7;
// Jacobi sweeps per iteration: the feet, the edges' closest points and the pull's closest points
// stay fixed, the residuals follow the moves. The searches are most of an iteration's cost; more
// sweeps bring each iteration closer to the least-squares solution for its feet (Hoppe et al.
// solve it exactly). Corpus: 3 sweeps, geometric means of lodkit / best peer 10% Hausdorff 0.741 ->
// 0.739, 1% 0.868 -> 0.855, at +2% of the time on armadillo-s2 -> 83,200 (bench/README).
constexpr uint32_t sweeps = 3;

// An input vertex's closest point on the result (found once per iteration): the result's triangle
// and the barycentric weights of its corners 1 and 2, which move with the triangle's corners.
struct Foot {
  uint32_t triangle = none;
  float v = 0, w = 0;
};

// The closest point of x on input triangle t.
measure::TrianglePoint on_input_triangle(const Mesh& input, uint32_t t, const measure::vec3f& x) {
  const uint32_t* corner = &input.indices[3 * size_t(t)];
  return measure::closest_on_triangle(x, input.positions[corner[0]], input.positions[corner[1]], input.positions[corner[2]]);
}

// Whether a point at squared distance d on input triangle t beats `best`: nearer, or as near on a
// lower triangle (the answer a scan of every triangle gives).
bool closer(float d, uint32_t t, const measure::ClosestHit& best) {
  return d < best.distance_squared || (d == best.distance_squared && t < best.triangle);
}

}  // namespace

// A BVH of the whole input would add about 90 bytes per input triangle to the peak memory; one chunk
// at a time adds that for the chunk only. Chunks are ranges of the internal position ids (Morton
// order) of the triangles' first corners, so each is compact in space.
void closest_on_input(const State& s, const std::vector<measure::vec3f>& points, std::vector<measure::ClosestHit>& hits,
                      size_t chunk_triangles) {
  const Mesh& input = s.mesh;
  const size_t triangles = input.triangle_count(), n = points.size();
  if (triangles == 0 || n == 0) return;
  const size_t chunks = (triangles + chunk_triangles - 1) / chunk_triangles;
  const auto chunk_of = [&](size_t t) { return size_t(s.position_of[input.indices[3 * t]]) * chunks / s.position_count; };
  std::vector<uint32_t> first(chunks + 1, 0), order(triangles);
  for (size_t t = 0; t < triangles; ++t) ++first[chunk_of(t) + 1];
  std::partial_sum(first.begin(), first.end(), first.begin());
  {
    std::vector<uint32_t> fill(first.begin(), first.end() - 1);
    for (size_t t = 0; t < triangles; ++t) order[fill[chunk_of(t)]++] = uint32_t(t);  // increasing within a chunk
  }
  // Each chunk's tree is built over its triangles in the Morton order of their first corners (by
  // position id, then triangle) by halving, not by SAH: about 2^17 triangles per tree against one
  // query per result edge, so the build was most of this search's time. `coherent` lists the chunk's
  // triangles so, as indices within the chunk (a counting sort over the chunk's position ids).
  std::vector<uint32_t> coherent, start;
  Mesh part;
  part.positions = input.positions;
  for (size_t c = 0; c < chunks; ++c) {
    if (first[c] == first[c + 1]) continue;
    part.indices.clear();
    measure::vec3f lo(std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                      std::numeric_limits<float>::infinity());
    measure::vec3f hi(-lo.x, -lo.y, -lo.z);
    for (uint32_t i = first[c]; i < first[c + 1]; ++i)
      for (uint32_t k = 0; k < 3; ++k) {
        const uint32_t v = input.indices[3 * size_t(order[i]) + k];
        part.indices.push_back(v);
        const float3& q = input.positions[v];
        lo = {std::min(lo.x, q.x), std::min(lo.y, q.y), std::min(lo.z, q.z)};
        hi = {std::max(hi.x, q.x), std::max(hi.y, q.y), std::max(hi.z, q.z)};
      }
    {
      const auto key = [&](uint32_t i) { return s.position_of[input.indices[3 * size_t(order[i])]]; };
      uint32_t low = key(first[c]), high = low;
      for (uint32_t i = first[c]; i < first[c + 1]; ++i) low = std::min(low, key(i)), high = std::max(high, key(i));
      start.assign(size_t(high - low) + 2, 0);
      for (uint32_t i = first[c]; i < first[c + 1]; ++i) ++start[key(i) - low + 1];
      std::partial_sum(start.begin(), start.end(), start.begin());
      coherent.resize(first[c + 1] - first[c]);
      for (uint32_t i = first[c]; i < first[c + 1]; ++i) coherent[start[key(i) - low]++] = i - first[c];
    }
    const measure::TriangleBvh bvh(part, coherent, s.threads);
    // Groups of consecutive points (neighbours on the result) share one traversal (closest_group,
    // same answers as closest()).
    const auto local = [&](uint32_t triangle) {  // its index in this chunk, or 0 (any start)
      const auto at = std::lower_bound(order.begin() + first[c], order.begin() + first[c + 1], triangle);
      return at != order.begin() + first[c + 1] && *at == triangle ? uint32_t(at - order.begin() - first[c]) : 0u;
    };
    core::parallel_blocks(n, 8 * max_group, s.threads, [&](size_t, size_t begin, size_t end) {
      measure::TriangleBvh::GroupScratch scratch;
      measure::vec3f group[max_group];
      measure::ClosestHit found[max_group];
      float bound[max_group];
      uint32_t which[max_group];
      for (size_t g = begin; g < end; g += max_group) {
        uint32_t count = 0;
        for (size_t i = g; i < std::min(end, g + max_group); ++i) {
          const measure::vec3f& p = points[i];
          const auto gap = [](float x, float l, float h) { return std::max({l - x, x - h, 0.0f}); };
          const float gx = gap(p.x, lo.x, hi.x), gy = gap(p.y, lo.y, hi.y), gz = gap(p.z, lo.z, hi.z);
          // Skipped only when surely farther (the 0.1% covers the rounding of both distances).
          if ((gx * gx + gy * gy + gz * gz) > hits[i].distance_squared * 1.001f) continue;
          // The search looks only as far as the best so far (ties included, for the lower triangle).
          group[count] = p, bound[count] = hits[i].distance_squared, which[count++] = uint32_t(i);
        }
        if (count == 0) continue;
        bvh.closest_group(group, count, local(hits[which[0]].triangle), found, scratch, bound);
        for (uint32_t k = 0; k < count; ++k) {
          measure::ClosestHit& hit = found[k];
          measure::ClosestHit& best = hits[which[k]];
          // No triangle: none in this chunk within the bound (or every distance overflowed, with
          // coordinates near FLT_MAX).
          if (hit.triangle >= first[c + 1] - first[c]) continue;
          bvh.resolve(hit, group[k]);
          hit.triangle = order[first[c] + hit.triangle];
          if (closer(hit.distance_squared, hit.triangle, best)) best = hit;
        }
      }
    });
  }
}

void fit_positions(State& s, uint32_t iterations, double weight, std::vector<FittedPosition>* fitted) {
  const Mesh& input = s.mesh;
  const size_t triangles = s.alive.size();

  // The live position each position ended in: its collapse chain, shortened as it is walked.
  std::vector<uint32_t> end = s.successor;
  const auto last = [&](uint32_t p) { return core::chain_end(end, p); };

  // The result with its own compact numbering: live positions in order of first use.
  std::vector<uint32_t> slot(s.position_count, none), position;  // position id -> slot, and back
  std::vector<uint32_t> first_use;  // per slot: the first result triangle at it
  Mesh result;
  for (size_t t = 0; t < triangles; ++t) {
    if (!s.alive[t]) continue;
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t p = s.corner_pos[3 * t + k];
      if (slot[p] == none) {
        slot[p] = uint32_t(position.size()), position.push_back(p);
        first_use.push_back(uint32_t(result.indices.size() / 3));
      }
      result.indices.push_back(slot[p]);
    }
  }
  const size_t m = position.size();
  if (m == 0) return;
  result.positions.resize(m);
  for (size_t j = 0; j < m; ++j) result.positions[j] = s.position[position[j]];
  const size_t result_triangles = result.indices.size() / 3;

  // Each input corner stands for a third of its triangle's area (normalised frame): the weight of
  // its vertex as a sample, and of the position that vertex ended in ("mass", for the pull below).
  // The pull's candidates are the input triangles with a corner that ended in the position.
  // The slot each input vertex ended in is looked up once: per corner, the chain walks and slot
  // reads were most of this setup.
  std::vector<uint32_t> vertex_slot(input.vertex_count());
  for (size_t v = 0; v < input.vertex_count(); ++v) vertex_slot[v] = slot[last(s.position_of[v])];
  std::vector<double> share(input.vertex_count(), 0.0), mass(m, 0.0);
  std::vector<uint32_t> candidates_first(m + 1, 0), candidates;
  for (int fill = 0; fill < 2; ++fill) {
    for (size_t t = 0; t < triangles; ++t) {
      const uint32_t* corner = &input.indices[3 * t];
      const uint32_t j[3] = {vertex_slot[corner[0]], vertex_slot[corner[1]], vertex_slot[corner[2]]};
      for (uint32_t k = 0; k < 3; ++k) {
        if (j[k] == none || (k > 0 && j[k] == j[0]) || (k > 1 && j[k] == j[1])) continue;
        if (fill) candidates[candidates_first[j[k]]++] = uint32_t(t);
        else ++candidates_first[j[k] + 1];
      }
      if (fill) continue;
      vec3d p[3];
      for (uint32_t k = 0; k < 3; ++k) p[k] = s.normalized_input(input.positions[corner[k]]);
      const double third = length(cross(p[1] - p[0], p[2] - p[0])) / 6;
      for (uint32_t k = 0; k < 3; ++k) share[corner[k]] += third;
    }
    if (fill) break;
    for (size_t j = 0; j < m; ++j) candidates_first[j + 1] += candidates_first[j];
    candidates.resize(candidates_first[m]);
  }
  std::rotate(candidates_first.rbegin(), candidates_first.rbegin() + 1, candidates_first.rend());  // back to starts
  candidates_first[0] = 0;
  for (size_t v = 0; v < input.vertex_count(); ++v)
    if (vertex_slot[v] != none) mass[vertex_slot[v]] += share[v];
  // Far down, the input has many vertices per surviving position; 16 per position fix it as well
  // (every k-th input vertex, weighted k times) at a fraction of the closest-point searches.
  const size_t stride = std::max<size_t>(1, input.vertex_count() / (16 * m));
  std::vector<uint32_t> samples;
  for (size_t v = 0; v < input.vertex_count(); v += stride)
    if (share[v] > 0) samples.push_back(uint32_t(v));

  // The first search of each sample starts from a triangle at the position it ended in (nearby);
  // later ones from its last foot. The start changes only the speed.
  std::vector<Foot> foot(samples.size());
  for (size_t i = 0; i < samples.size(); ++i) {
    const uint32_t j = vertex_slot[samples[i]];
    foot[i].triangle = j == none ? 0 : first_use[j];
  }
  // The searches run in groups of samples that ended in the same position (close together), so one
  // traversal serves a group (TriangleBvh::closest_group, same answers as closest()); the sums below
  // stay in sample order.
  // (A counting sort by slot; a sample at no slot goes last.)
  const auto sample_slot = [&](size_t i) { return std::min<size_t>(vertex_slot[samples[i]], m); };
  std::vector<uint32_t> slot_start(m + 2, 0), by_slot(samples.size()), group_first;
  for (size_t i = 0; i < samples.size(); ++i) ++slot_start[sample_slot(i) + 1];
  std::partial_sum(slot_start.begin(), slot_start.end(), slot_start.begin());
  for (size_t i = 0; i < samples.size(); ++i) by_slot[slot_start[sample_slot(i)]++] = uint32_t(i);
  for (size_t k = 0; k < by_slot.size(); ++k)
    if (k == 0 || sample_slot(by_slot[k]) != sample_slot(by_slot[k - 1]) || k - group_first.back() == max_group)
      group_first.push_back(uint32_t(k));
  group_first.push_back(uint32_t(by_slot.size()));
  // Result -> input at the edges: the maximum distance of a result from its input is mostly at the
  // midpoint of a long edge whose ends both lie on the input (the surface bends away between them).
  // Each result edge's midpoint is pulled towards its closest input point, found once, before the
  // iterations (the moves are small next to the edges).
  // Edges in the order of their ends' position ids (Morton order), so that neighbouring edges, which
  // share the closest-point searches below, are close in space.
  std::vector<std::pair<uint32_t, uint32_t>> edges;  // position ids
  std::vector<uint32_t> edge_of_side(3 * result_triangles);  // per triangle side: its edge
  const auto side = [&](size_t t, uint32_t k) {
    const uint32_t a = position[result.indices[3 * t + k]], b = position[result.indices[3 * t + (k + 1) % 3]];
    return std::pair{std::min(a, b), std::max(a, b)};
  };
  for (size_t t = 0; t < result_triangles; ++t)
    for (uint32_t k = 0; k < 3; ++k) edges.push_back(side(t, k));
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  for (size_t t = 0; t < result_triangles; ++t)
    for (uint32_t k = 0; k < 3; ++k)
      edge_of_side[3 * t + k] = uint32_t(std::lower_bound(edges.begin(), edges.end(), side(t, k)) - edges.begin());
  for (auto& [a, b] : edges) a = slot[a], b = slot[b];  // from here on, slots
  std::vector<measure::vec3f> edge_target(edges.size());
  for (size_t e = 0; e < edges.size(); ++e) {
    const float3 &a = result.positions[edges[e].first], &b = result.positions[edges[e].second];
    edge_target[e] = measure::vec3f((a.x + b.x) * 0.5f, (a.y + b.y) * 0.5f, (a.z + b.z) * 0.5f);
  }
  {
    // A first answer from an input triangle at each end (the first of the pull's candidates): a
    // bound that lets the exact search skip the input's far chunks, and its starting triangle.
    std::vector<measure::ClosestHit> hits(edges.size());
    core::parallel_for(edges.size(), s.threads, [&](size_t e) {
      measure::ClosestHit& best = hits[e];
      for (const uint32_t j : {edges[e].first, edges[e].second}) {
        if (candidates_first[j] == candidates_first[j + 1]) continue;
        const uint32_t t = candidates[candidates_first[j]];
        const measure::TrianglePoint hit = on_input_triangle(input, t, edge_target[e]);
        if (closer(hit.distance_squared, t, best)) best.distance_squared = hit.distance_squared, best.triangle = t, best.point = hit.point;
      }
    });
    closest_on_input(s, edge_target, hits, fit_chunk_triangles);
    for (size_t e = 0; e < edges.size(); ++e)
      if (hits[e].triangle != none) edge_target[e] = hits[e].point;  // else the midpoint: no pull
  }
  std::vector<vec3d> edge_residual(edges.size());
  std::vector<double> edge_area(edges.size());
  std::vector<vec3d> num(m);
  std::vector<double> den(m);
  std::vector<uint8_t> moved(m), revert(m);
  std::vector<measure::vec3f> pulled(m);  // per position: the pull's target in this iteration
  std::vector<uint32_t> nearest(m, 0);  // per position: its closest candidate in the last iteration
  std::vector<float3> before;
  const std::vector<float3> start = result.positions;
  const auto normalized = [&](size_t j) { return s.normalized_input(result.positions[j]); };
  // The closest point to x among position j's candidate input triangles (x itself if it has none):
  // the first candidate at the least distance, as a scan of all would find it. The last iteration's
  // winner (moves are small) bounds that distance; a candidate whose box is farther cannot win and
  // is skipped. The box is widened by float rounding and the bound loosened by 0.1%, so a skipped
  // candidate could never have tied with the winner.
  const auto closest_candidate = [&](size_t j, const measure::vec3f& x) {
    const auto distance = [&](uint32_t i) {
      const measure::TrianglePoint hit = on_input_triangle(input, candidates[i], x);
      return std::pair{measure::length_squared(x - hit.point), hit.point};
    };
    const uint32_t begin = candidates_first[j], stop = candidates_first[j + 1];
    const float bound = begin < stop ? distance(std::clamp(nearest[j], begin, stop - 1)).first * 1.001f : 0.0f;
    measure::vec3f c = x;
    float best = std::numeric_limits<float>::infinity();
    for (uint32_t i = begin; i < stop; ++i) {
      const uint32_t* corner = &input.indices[3 * size_t(candidates[i])];
      const float3& a = input.positions[corner[0]];
      const float3& b = input.positions[corner[1]];
      const float3& e = input.positions[corner[2]];
      const auto gap = [](float p, float u, float v, float w) {
        const float lo = std::min({u, v, w}), hi = std::max({u, v, w});
        const float slack = 1e-6f * std::max(std::abs(lo), std::abs(hi)) + 1e-30f;
        const float g = std::max({lo - slack - p, p - hi - slack, 0.0f});
        return g * g;
      };
      if (gap(x.x, a.x, b.x, e.x) + gap(x.y, a.y, b.y, e.y) + gap(x.z, a.z, b.z, e.z) > bound) continue;
      const auto [d, point] = distance(i);
      if (d < best) best = d, c = point, nearest[j] = uint32_t(i);
    }
    return c;
  };
  for (uint32_t iteration = 0; iteration < iterations; ++iteration) {
    const measure::TriangleBvh bvh(result, s.threads);
    core::parallel_blocks(group_first.size() - 1, 256, s.threads, [&](size_t, size_t group_begin, size_t group_end) {
      measure::TriangleBvh::GroupScratch scratch;
      measure::vec3f points[max_group];
      measure::ClosestHit hits[max_group];
      for (size_t g = group_begin; g < group_end; ++g) {
        const uint32_t first = group_first[g], count = group_first[g + 1] - first;
        for (uint32_t k = 0; k < count; ++k) points[k] = measure::vec3f(input.positions[samples[by_slot[first + k]]]);
        bvh.closest_group(points, count, foot[by_slot[first]].triangle, hits, scratch);
        for (uint32_t k = 0; k < count; ++k) {
          measure::ClosestHit& hit = hits[k];
          // No triangle: every distance overflowed (coordinates near FLT_MAX); the sample keeps its
          // last foot, which is always a triangle of the result.
          if (hit.triangle == none) continue;
          bvh.resolve(hit, points[k]);
          Foot& f = foot[by_slot[first + k]];
          f.triangle = hit.triangle, f.v = hit.v, f.w = hit.w;
        }
      }
    });
    for (uint32_t sweep = 0; sweep < sweeps; ++sweep) {
      // Each position's normal equation with its neighbours held still, summed in sample order (so
      // the sums do not depend on the thread count).
      std::fill(num.begin(), num.end(), vec3d{});
      std::fill(den.begin(), den.end(), 0.0);
      for (size_t i = 0; i < samples.size(); ++i) {
        const Foot& f = foot[i];
        const double a = share[samples[i]] * double(stride);
        const double beta[3] = {1.0 - double(f.v) - double(f.w), f.v, f.w};
        const uint32_t* c = &result.indices[3 * size_t(f.triangle)];
        const vec3d r = s.normalized_input(input.positions[samples[i]]) -
                        (normalized(c[0]) * beta[0] + normalized(c[1]) * beta[1] + normalized(c[2]) * beta[2]);
        for (uint32_t k = 0; k < 3; ++k) {
          const uint32_t j = c[k];
          num[j] = num[j] + r * (a * beta[k]);
          den[j] += a * beta[k] * beta[k];
        }
      }
      // Each edge stands for a third of its faces' area, scaled by (residual / rms)^2 up to a cap:
      // reweighted towards the largest residuals, which decide the Hausdorff distance (an
      // iteratively reweighted least-squares step towards the maximum).
      std::fill(edge_area.begin(), edge_area.end(), 0.0);
      for (size_t t = 0; t < result_triangles; ++t) {
        const uint32_t* c = &result.indices[3 * t];
        const double third = length(cross(normalized(c[1]) - normalized(c[0]), normalized(c[2]) - normalized(c[0]))) / 6;
        for (uint32_t k = 0; k < 3; ++k) edge_area[edge_of_side[3 * t + k]] += third;
      }
      double squares = 0, area = 0;
      for (size_t e = 0; e < edges.size(); ++e) {
        const measure::vec3f& c = edge_target[e];
        edge_residual[e] = s.normalized_input(float3{c.x, c.y, c.z}) - (normalized(edges[e].first) + normalized(edges[e].second)) * 0.5;
        if (!std::isfinite(length_squared(edge_residual[e]))) edge_residual[e] = {};  // overflowed: no pull
        squares += edge_area[e] * length_squared(edge_residual[e]), area += edge_area[e];
      }
      const double mean_square = area > 0 ? squares / area : 0;
      for (size_t e = 0; e < edges.size(); ++e) {
        const double emphasis = mean_square > 0 ? std::min(edge_cap, length_squared(edge_residual[e]) / mean_square) : 0;
        const double a = edge_weight * edge_area[e] * emphasis;
        // The midpoint moves by half of each end's move: (d_j + d_k) / 2 against the residual.
        for (const uint32_t j : {edges[e].first, edges[e].second})
          num[j] = num[j] + edge_residual[e] * (a * 0.5), den[j] += a * 0.25;
      }
      before = result.positions;
      core::parallel_for(m, s.threads, [&](size_t j) {
        moved[j] = 0;
        if (s.flags[position[j]] & flag_locked) return;
        // The pull's target stays fixed for the iteration, like the feet. Found for every position
        // in the first sweep, also those that do not move in it: a later sweep may move them.
        if (sweep == 0) pulled[j] = closest_candidate(j, measure::vec3f(before[j]));
        if (!(den[j] > 0)) return;
        // Minimise sum a |r - beta d|^2 + weight mass |x + d - c|^2 over the move d, c being the
        // position's closest point on the input (among the input triangles it stands for).
        const measure::vec3f& c = pulled[j];
        const double pull = weight * mass[j];
        const vec3d here = normalized(j);
        const vec3d d = (num[j] - (here - s.normalized_input(float3{c.x, c.y, c.z})) * pull) * (step / (den[j] + pull));
        const float3 to = s.object(here + d);
        if (!std::isfinite(to.x) || !std::isfinite(to.y) || !std::isfinite(to.z) || to == before[j]) return;
        result.positions[j] = to;
        moved[j] = 1;
      });
      // Take back every move around a face that would turn by more than the flip limit or degenerate,
      // until none does (each round only takes moves back, so this ends).
      const double min_dot = s.options.min_normal_dot;
      for (bool changed = true; changed;) {
        changed = false;
        std::fill(revert.begin(), revert.end(), 0);
        for (size_t t = 0; t < result_triangles; ++t) {
          const uint32_t* c = &result.indices[3 * t];
          if (!(moved[c[0]] | moved[c[1]] | moved[c[2]])) continue;
          const auto corner = [&](const std::vector<float3>& from, uint32_t k) {
            const float3& p = from[c[k]];
            return vec3d{p.x, p.y, p.z};
          };
          const vec3d old_corners[3] = {corner(before, 0), corner(before, 1), corner(before, 2)};
          const vec3d new_corners[3] = {corner(result.positions, 0), corner(result.positions, 1),
                                        corner(result.positions, 2)};
          const FaceChange change = face_change(old_corners, new_corners, min_dot);
          if (change.degenerate || change.flipped)
            for (uint32_t k = 0; k < 3; ++k) revert[c[k]] |= moved[c[k]];
        }
        for (size_t j = 0; j < m; ++j)
          if (revert[j]) result.positions[j] = before[j], moved[j] = 0, changed = true;
      }
    }
  }

  for (size_t j = 0; j < m; ++j) {
    if (result.positions[j] == start[j]) continue;
    const uint32_t p = position[j];
    s.position[p] = result.positions[j];
    ++s.moves[p];
    if (fitted) fitted->push_back({s.external[p], start[j], result.positions[j]});
  }
}

}  // namespace lod::collapse
