#include "simplify/fit.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <tuple>

#include "core/buckets.h"
#include "core/heap.h"
#include "core/parallel.h"
#include "core/union_find.h"
#include "measure/bvh.h"

namespace lod::collapse {
namespace {

constexpr uint32_t none = ~0u;
constexpr uint32_t max_group = 32;  // samples per closest_group query
// The cap of the edge term's emphasis on large residuals (its weight against the input samples' is
// SimplifyOptions::fit_edge_weight, 0.1 by default).
constexpr double edge_cap = 30;
// Each Jacobi move is this share of the solution of its own equation: neighbours solve theirs at
// the same time, towards the same residuals, so full moves overshoot and the fit oscillates (on
// fandisk_large at 10%, RMS after 1, 2 and 3 iterations 1.66, 1.44, 1.58e-4; 1.40e-4 before the
// fit). Chosen with the edge weight on the corpus at 10% and 1% (bench/README, twelfth session).
constexpr double step = 0.7;
// Jacobi sweeps per iteration: the feet, the edges' closest points and the pull's closest points
// stay fixed, the residuals follow the moves. The searches are most of an iteration's cost; more
// sweeps bring each iteration closer to the least-squares solution for its feet (Hoppe et al.
// solve it exactly). Corpus: 3 sweeps, geometric means of lodkit / best peer 10% Hausdorff 0.741 ->
// 0.739, 1% 0.868 -> 0.855, at +2% of the time on armadillo-s2 -> 83,200 (bench/README).
constexpr uint32_t sweeps = 3;
// From the fifth iteration on, the input's samples are reweighted towards the largest residuals: a
// sample's weight is 1 + sample_emphasis * min(sample_cap, r^2 / mean r^2), r its distance from its
// foot (an iteratively reweighted step towards the maximum, as the edge term takes). Far down, where
// the fit runs its dozen iterations, the Hausdorff distance is the input's farthest point as often
// as the result's. Not from the start: the first iterations move the result most, and emphasis on
// residuals they remove anyway did worse. On dense inputs reduced 10x the fit has stopped by then.
// Corpus at 1%: Hausdorff distance over the best peer 0.789 -> 0.757 (geometric mean), turbine
// 1.24x -> 1.08x, fandisk 1.18x -> 1.02x; at 10% unchanged (bench/README, seventeenth session).
constexpr uint32_t emphasis_from = 4;
constexpr double sample_emphasis = 0.1, sample_cap = 50;
// The input vertices the fit samples at most (more on inputs that keep over 4,096 positions: 16 per
// position). Corpus meshes (at most 26k vertices) at 1%, all vertices rather than 16 per position:
// Hausdorff distance over the best peer 0.757 -> 0.746 (geometric mean), worst case 1.22x -> 1.18x,
// RMS 0.681 -> 0.667; armadillo (52k triangles) -> 520 fits in 0.12 s rather than 0.05 s. Above the
// budget the fit is unchanged: armadillo-s2 -> 8,320 takes 2.3 s rather than 1.0 s to fit with
// every vertex (bench/README, eighteenth session).
constexpr size_t sample_budget = size_t(1) << 16;
// The fit stops early once an iteration moved no position by more than this share of the result's
// mean edge length: on dense inputs simplified by 10x the result already lies near the input and
// the moves fade at once (armadillo subdivided, 832k and 3.3M triangles: one iteration, before the
// fit was skipped on results that lie on the input; fit_skip_error in fit.h), while far
// down they stay at 1e-3 to 1e-2 and every further iteration still helps (bench/README, sixteenth
// session).
constexpr double converged = 1e-3;
// A flip must lower its samples' squared distances by this share of their sum; below flip_noise
// (a mean squared distance, normalised frame: 1e-6 of the extent) they are float noise. Corpus at
// 10% and 1%: margins 0.02-0.25 gave the same shares within a case (bench/README, fifteenth session).
constexpr double flip_margin = 0.02, flip_noise = 1e-12;
// At iteration reflip_at (the eleventh, two before the default cap; a fixed index, so that a fit
// capped at k iterations stays the first k of a longer one) edges are flipped once more, now also
// "far" ones: edges whose midpoint's squared distance from its closest input point is over
// far_edge times the edges' area-weighted mean. A far edge's flip is judged by the result -> input
// side: the new edge's midpoint and faces' centroids must come far_margin nearer the input
// (squared) than the old pair's farthest point, the input samples' squared distances may rise by
// at most far_budget of their total, and the new faces are held to the flip limit against the
// input triangles nearest to their centroids rather than against the old faces (a far edge often
// cuts across a fold that only a steep turn undoes). Far flips go first, by how much nearer they
// come. Dense inputs reduced 10x stop the fit before this. Corpus: Hausdorff distance at 10% 94% of
// the cases (worst 1.17x) -> 96% (1.10x), rotor_small at 1% 1.14x -> 1.07x (bench/README,
// eighteenth session).
constexpr uint32_t reflip_at = 10;
constexpr double far_edge = 4, far_margin = 0.1, far_budget = 0.1;

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

// The squared distance from x to input triangle t's bounding box, widened by float rounding (never
// more than the distance to the triangle).
float box_gap_squared(const Mesh& input, uint32_t t, const measure::vec3f& x) {
  const uint32_t* corner = &input.indices[3 * size_t(t)];
  const float3& a = input.positions[corner[0]];
  const float3& b = input.positions[corner[1]];
  const float3& e = input.positions[corner[2]];
  const auto gap = [](float p, float u, float v, float w) {
    const float lo = std::min({u, v, w}), hi = std::max({u, v, w});
    const float slack = 1e-6f * std::max(std::abs(lo), std::abs(hi)) + 1e-30f;
    const float g = std::max({lo - slack - p, p - hi - slack, 0.0f});
    return g * g;
  };
  return gap(x.x, a.x, b.x, e.x) + gap(x.y, a.y, b.y, e.y) + gap(x.z, a.z, b.z, e.z);
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
  const core::Buckets<uint32_t> chunk = core::bucket<uint32_t>(chunks, [&](auto&& emit) {
    for (size_t t = 0; t < triangles; ++t) emit(chunk_of(t), uint32_t(t));  // increasing within a chunk
  });
  const std::vector<uint32_t>&first = chunk.first, &order = chunk.items;
  // Each chunk's tree is built over its triangles in the Morton order of their first corners (by
  // position id, then triangle) by halving, not by SAH: about 2^17 triangles per tree against one
  // query per result edge, so the build was most of this search's time. `coherent` lists the chunk's
  // triangles so, as indices within the chunk (a counting sort over the chunk's position ids).
  std::vector<uint32_t> coherent;
  Mesh part;
  core::copy_huge(part.positions, input.positions);
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
      coherent = core::bucket<uint32_t>(size_t(high - low) + 1, [&](auto&& emit) {
                   for (uint32_t i = first[c]; i < first[c + 1]; ++i) emit(key(i) - low, i - first[c]);
                 }).items;
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

uint32_t fit_positions(State& s, uint32_t iterations, double weight, double edge_weight, bool flips,
                       std::vector<FittedPosition>* fitted, std::vector<Relink>* flipped) {
  const Mesh& input = s.mesh;
  const size_t triangles = s.alive.size();

  // The live position each position ended in: its collapse chain, shortened as it is walked.
  std::vector<uint32_t> end;
  core::copy_huge(end, s.successor);
  const auto last = [&](uint32_t p) { return core::chain_end(end, p); };

  // The result with its own compact numbering: live positions in order of first use.
  std::vector<uint32_t> slot = core::make_huge<uint32_t>(s.position_count, none), position;  // position id -> slot, and back
  std::vector<uint32_t> first_use;  // per slot: the first result triangle at it
  std::vector<uint32_t> state_triangle;  // per result triangle: its (input) triangle id
  Mesh result;
  for (size_t t = 0; t < triangles; ++t) {
    if (!s.alive[t]) continue;
    state_triangle.push_back(uint32_t(t));
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
  if (m == 0) return 0;
  result.positions.resize(m);
  for (size_t j = 0; j < m; ++j) result.positions[j] = s.position[position[j]];
  const size_t result_triangles = result.indices.size() / 3;

  // Each input corner stands for a third of its triangle's area (normalised frame): the weight of
  // its vertex as a sample, and of the position that vertex ended in ("mass", for the pull below).
  // The pull's candidates are the input triangles with a corner that ended in the position.
  // The slot each input vertex ended in is looked up once: per corner, the chain walks and slot
  // reads were most of this setup.
  std::vector<uint32_t> vertex_slot = core::make_huge<uint32_t>(input.vertex_count());
  for (size_t v = 0; v < input.vertex_count(); ++v) vertex_slot[v] = slot[last(s.position_of[v])];
  std::vector<double> share = core::make_huge<double>(input.vertex_count(), 0.0), mass(m, 0.0);
  core::Buckets<uint32_t> candidate = core::bucket<uint32_t>(m, [&](auto&& emit) {
    for (size_t t = 0; t < triangles; ++t) {
      const uint32_t* corner = &input.indices[3 * t];
      const uint32_t j[3] = {vertex_slot[corner[0]], vertex_slot[corner[1]], vertex_slot[corner[2]]};
      for (uint32_t k = 0; k < 3; ++k)
        if (j[k] != none && !(k > 0 && j[k] == j[0]) && !(k > 1 && j[k] == j[1])) emit(j[k], uint32_t(t));
    }
  });
  const std::vector<uint32_t>& candidates_first = candidate.first;
  std::vector<uint32_t>& candidates = candidate.items;
  for (size_t t = 0; t < triangles; ++t) {
    const uint32_t* corner = &input.indices[3 * t];
    vec3d p[3];
    for (uint32_t k = 0; k < 3; ++k) p[k] = s.normalized_input(input.positions[corner[k]]);
    const double third = length(cross(p[1] - p[0], p[2] - p[0])) / 6;
    for (uint32_t k = 0; k < 3; ++k) share[corner[k]] += third;
  }
  for (size_t v = 0; v < input.vertex_count(); ++v)
    if (vertex_slot[v] != none) mass[vertex_slot[v]] += share[v];
  // Every input vertex is a sample, up to sample_budget of them. Far down a large input, with many
  // vertices per surviving position, 16 per position fix it almost as well (every k-th input
  // vertex, weighted k times) at a fraction of the closest-point searches.
  const size_t stride = std::max<size_t>(1, input.vertex_count() / std::max<size_t>(16 * m, sample_budget));
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
  const std::vector<uint32_t> by_slot = core::bucket<uint32_t>(m + 1, [&](auto&& emit) {
                                          for (size_t i = 0; i < samples.size(); ++i) emit(sample_slot(i), uint32_t(i));
                                        }).items;
  std::vector<uint32_t> group_first;
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
  // Without flips or the edge term (the search's plain fit) the edges' targets are never read: the
  // edges are not searched (each point's search is exact and alone, so the positions' answers are
  // the same either way) and have no residuals.
  const bool edge_targets = flips || edge_weight > 0;
  const size_t edge_points = edge_targets ? edges.size() : 0;
  std::vector<measure::vec3f> edge_target(edge_points);  // found in the first iteration, after the flips
  std::vector<vec3d> edge_residual(edge_points);
  std::vector<double> edge_area(edge_points);
  std::vector<vec3d> num(m);
  std::vector<double> den(m);
  std::vector<uint8_t> moved(m), revert(m);
  std::vector<measure::vec3f> pulled(m);  // per position: the pull's target in this iteration
  std::vector<uint32_t> nearest(m, 0);  // per position: its closest candidate (index) in the last iteration
  std::vector<float3> before;
  const std::vector<float3> start = result.positions;
  const auto normalized = [&](size_t j) { return s.normalized_input(result.positions[j]); };
  // Each position's candidates sorted by their boxes' distance from its start, with that distance
  // (`reach`): a scan in this order can stop at the first candidate whose box, less the position's
  // move since, is beyond the bound below, and most stop after a few of the hundreds of candidates
  // a position has far down. Ties keep triangle order. Short lists (a few dozen, as when the input
  // is reduced 10x) are scanned whole: sorting them costs more than it saves (reach 0: no stop).
  std::vector<float> reach(candidates.size(), 0.0f);
  core::parallel_blocks(m, 256, s.threads, [&](size_t, size_t block_begin, size_t block_end) {
    std::vector<std::pair<float, uint32_t>> order;
    for (size_t j = block_begin; j < block_end; ++j) {
      if (candidates_first[j + 1] - candidates_first[j] <= 64) continue;
      order.clear();
      for (uint32_t i = candidates_first[j]; i < candidates_first[j + 1]; ++i)
        order.push_back({std::sqrt(box_gap_squared(input, candidates[i], measure::vec3f(start[j]))), candidates[i]});
      std::sort(order.begin(), order.end());
      for (uint32_t i = candidates_first[j], k = 0; i < candidates_first[j + 1]; ++i, ++k)
        reach[i] = order[k].first, candidates[i] = order[k].second;
    }
  });
  // Per position: the input triangle nearest to where it stood when the edges were searched (found
  // by the same exact search). A position can end up beyond the triangles it stands for (a
  // quadric's optimum slides along a flat or cylindrical stretch) while it lies on the input: the
  // nearest of its candidates is then off by up to an edge length, and pulling it there took it off
  // the input (armadillo-s2 -> 83,200: Hausdorff distance 8.9e-8 before the fit, 6e-6 after).
  std::vector<uint32_t> nearest_input(m, none);
  // The closest point to x among position j's candidate input triangles and its nearest input
  // triangle (x itself if it has none): the lowest triangle at the least distance, as a scan of all
  // would find it. The last iteration's winner (moves are small) bounds that distance; a candidate
  // whose box is farther cannot win and is skipped. The box is widened by float rounding and the
  // bound loosened by 0.1%, so a skipped candidate could never have tied with the winner.
  const auto closest_candidate = [&](size_t j, const measure::vec3f& x) {
    const auto distance = [&](uint32_t t) {
      const measure::TrianglePoint hit = on_input_triangle(input, t, x);
      return std::pair{measure::length_squared(x - hit.point), hit.point};
    };
    const uint32_t begin = candidates_first[j], stop = candidates_first[j + 1];
    measure::vec3f c = x;
    float best = std::numeric_limits<float>::infinity();
    uint32_t best_triangle = none;
    if (nearest_input[j] != none) std::tie(best, c) = distance(nearest_input[j]), best_triangle = nearest_input[j];
    float bound = best * 1.001f;
    if (begin < stop) bound = std::min(bound, distance(candidates[std::clamp(nearest[j], begin, stop - 1)]).first * 1.001f);
    // The box's distance from x is at least its distance from the start less the move since.
    const double travel = std::sqrt(double(measure::length_squared(x - measure::vec3f(start[j])))) * (1 + 1e-6);
    for (uint32_t i = begin; i < stop; ++i) {
      const double beyond = double(reach[i]) * (1 - 1e-6) - travel;
      if (beyond > 0 && beyond * beyond > double(bound)) break;
      if (box_gap_squared(input, candidates[i], x) > bound) continue;
      const auto [d, point] = distance(candidates[i]);
      if (d < best || (d == best && candidates[i] < best_triangle)) best = d, c = point, best_triangle = candidates[i], nearest[j] = i;
    }
    return c;
  };
  // Per result triangle, the samples whose feet lie in it, and each sample's squared distance to
  // its foot (for the flips, on the feet of the iterations that flip).
  core::Buckets<uint32_t> feet;
  std::vector<float> foot_distance(flips ? samples.size() : 0, 0.0f);
  // Edges are flipped before the first iteration's sweeps and again, with the far ones, before the
  // sweeps of iteration reflip_at (see far_edge).
  const auto flip_round = [&](uint32_t iteration) { return flips && (iteration == 0 || iteration == reflip_at); };
  const auto file_feet = [&]() {
    feet = core::bucket<uint32_t>(result_triangles, [&](auto&& emit) {
      for (size_t i = 0; i < foot.size(); ++i) emit(foot[i].triangle, uint32_t(i));
    });
  };
  // The triangle of result triangle t's corners, prepared for distance queries.
  const auto prepared = [&](size_t t) {
    const uint32_t* c = &result.indices[3 * t];
    return measure::prepare_triangle(result.positions[c[0]], result.positions[c[1]], result.positions[c[2]]);
  };
  // A flip candidate: interior edge e runs p -> q on side k1 of result triangle t1 = (p, q, r) and
  // q -> p on side k2 of t2 = (q, p, s); flipped, t1 becomes (p, s, r) and t2 (q, r, s), each
  // changing one corner (k1 + 1 and k2 + 1).
  struct Flip {
    uint32_t edge, t1, k1, t2, k2;
    double gain;  // the drop in the samples' weighted squared distance
    bool far = false;  // a far edge's flip (see far_edge)
  };
  const auto flip_corners = [&](const Flip& f, uint32_t& p, uint32_t& q, uint32_t& r, uint32_t& x) {
    const uint32_t* c1 = &result.indices[3 * size_t(f.t1)];
    p = c1[f.k1], q = c1[(f.k1 + 1) % 3], r = c1[(f.k1 + 2) % 3], x = result.indices[3 * size_t(f.t2) + (f.k2 + 2) % 3];
  };
  // Edges whose flip brings the input samples in its two triangles nearer (this iteration's feet),
  // by more than flip_margin of their sum, and with far_level > 0 the far edges' flips (those whose
  // squared residual is over far_level; see far_edge): candidates, before the guards in apply_flips.
  const auto propose_flips = [&](double far_level) {
    std::vector<Flip> proposed;
    std::vector<uint32_t> sides_of(2 * edges.size(), none);  // the two sides of each edge (none: border)
    std::vector<uint8_t> sides(edges.size(), 0);
    for (uint32_t i = 0; i < 3 * result_triangles; ++i) {
      const uint32_t e = edge_of_side[i];
      if (sides[e] < 2) sides_of[2 * e + sides[e]] = i;
      sides[e] = uint8_t(std::min(3, sides[e] + 1));
    }
    std::vector<uint64_t> existing(edges.size());  // slot pairs, for "r-s is already an edge"
    const auto key = [](uint32_t a, uint32_t b) { return (uint64_t(std::min(a, b)) << 32) | std::max(a, b); };
    for (size_t e = 0; e < edges.size(); ++e) existing[e] = key(edges[e].first, edges[e].second);
    std::sort(existing.begin(), existing.end());
    file_feet();
    const auto flip_of = [&](uint32_t e, double gain) {  // edge e's two sides (an interior edge)
      return Flip{e, sides_of[2 * e] / 3, sides_of[2 * e] % 3, sides_of[2 * e + 1] / 3, sides_of[2 * e + 1] % 3, gain};
    };
    // Per edge, the gain of its flip (0: none proposed); 8 bytes an edge, not a Flip's 32, at the
    // fit's peak memory.
    std::vector<double> gain(edges.size(), 0.0);
    std::vector<uint8_t> far_flip(edges.size(), 0);
    double total_sum = 0;  // the samples' weighted squared distances, for far_budget
    if (far_level > 0)
      for (size_t i = 0; i < samples.size(); ++i) total_sum += share[samples[i]] * foot_distance[i];
    const double min_dot = s.options.min_normal_dot, scale2 = s.scale * s.scale;
    core::parallel_for(edges.size(), s.threads, [&](size_t e) {
      if (sides[e] != 2) return;
      // The samples' squared distances now; below the noise level (squared, normalised frame)
      // there is nothing to gain.
      double old_sum = 0, weights = 0;
      for (const uint32_t t : {sides_of[2 * e] / 3, sides_of[2 * e + 1] / 3})
        for (const uint32_t i : feet[t]) {
          const double a = share[samples[i]];
          old_sum += a * foot_distance[i], weights += a;
        }
      const bool far = far_level > 0 && length_squared(edge_residual[e]) > far_level;
      if (!far && !(old_sum * scale2 > flip_noise * weights)) return;
      const Flip f = flip_of(uint32_t(e), 0);
      uint32_t p, q, r, x;
      flip_corners(f, p, q, r, x);
      const uint32_t* c2 = &result.indices[3 * size_t(f.t2)];
      if (c2[f.k2] != q || c2[(f.k2 + 1) % 3] != p || r == x) return;  // not an oriented manifold edge
      for (const uint32_t j : {p, q, r, x})
        if (s.flags[position[j]] & flag_complex) return;
      // A seam or material boundary along p-q stays (the flipped faces take p's and q's wedges
      // from either face).
      const uint32_t* w1 = &s.corners[3 * size_t(state_triangle[f.t1])];
      const uint32_t* w2 = &s.corners[3 * size_t(state_triangle[f.t2])];
      if (w1[f.k1] != w2[(f.k2 + 1) % 3] || w1[(f.k1 + 1) % 3] != w2[f.k2] ||
          s.material(state_triangle[f.t1]) != s.material(state_triangle[f.t2]))
        return;
      if (std::binary_search(existing.begin(), existing.end(), key(r, x))) return;
      // Neither flipped face may degenerate or turn by more than the flip limit from either old
      // face (each keeps its triangle id: the engine's rule for a face that a collapse changes); a
      // far flip's faces are held to the input instead, in apply_flips.
      const vec3d P = normalized(p), Q = normalized(q), R = normalized(r), X = normalized(x);
      const vec3d n1 = cross(Q - P, R - P), n2 = cross(P - Q, X - Q);
      const double l1 = length(n1), l2 = length(n2);
      if (!(l1 > 0) || !(l2 > 0) || dot(n1, n2) >= l1 * l2) return;  // coplanar: the flip changes nothing
      const double longest = std::max({length_squared(X - P), length_squared(R - X), length_squared(R - P),
                                       length_squared(R - Q), length_squared(X - Q)});
      for (const vec3d& n : {cross(X - P, R - P), cross(R - Q, X - Q)}) {
        const double ln = length(n);
        if (!(ln > 1e-12 * longest)) return;
        if (!far && (dot(n, n1) < min_dot * ln * l1 || dot(n, n2) < min_dot * ln * l2)) return;
      }
      const measure::vec3f fp(result.positions[p]), fq(result.positions[q]), fr(result.positions[r]), fx(result.positions[x]);
      const measure::PreparedTriangle new1 = measure::prepare_triangle(fp, fx, fr), new2 = measure::prepare_triangle(fq, fr, fx);
      double new_sum = 0;
      for (const uint32_t t : {f.t1, f.t2})
        for (const uint32_t i : feet[t]) {
          const uint32_t v = samples[i];
          const measure::vec3f point(input.positions[v]);
          new_sum += share[v] * std::min(measure::closest_distance_squared(point, new1), measure::closest_distance_squared(point, new2));
        }
      if (far) far_flip[e] = new_sum - old_sum <= far_budget * total_sum;
      else if (new_sum < (1 - flip_margin) * old_sum) gain[e] = old_sum - new_sum;
    });
    for (uint32_t e = 0; e < edges.size(); ++e)
      if (gain[e] > 0 || far_flip[e]) {
        proposed.push_back(flip_of(e, gain[e]));
        proposed.back().far = far_flip[e];
      }
    return proposed;
  };
  // Result -> input: each proposed flip's old faces' centroids, then the flipped edge's midpoint and
  // the flipped faces' centroids (the old edge's midpoint is among the edges' own points).
  constexpr uint32_t probes_per_flip = 5;
  const auto flip_probes = [&](const Flip& f, measure::vec3f* out) {
    uint32_t p, q, r, x;
    flip_corners(f, p, q, r, x);
    const measure::vec3f fp(result.positions[p]), fq(result.positions[q]), fr(result.positions[r]), fx(result.positions[x]);
    const float third = 1.0f / 3;
    out[0] = (fp + fq + fr) * third, out[1] = (fq + fp + fx) * third;
    out[2] = (fr + fx) * 0.5f, out[3] = (fp + fx + fr) * third, out[4] = (fq + fr + fx) * third;
  };
  // The closest input points apply_flips needs per proposed flip: the old edge's midpoint, then the
  // flip's probes.
  constexpr uint32_t hits_per_flip = 1 + probes_per_flip;
  // Whether a far flip's new faces lie within the flip limit of the input triangles nearest to their
  // centroids (`h`: the flip's probes).
  const auto follows_input = [&](const Flip& f, const measure::ClosestHit* h) {
    uint32_t p, q, r, x;
    flip_corners(f, p, q, r, x);
    const vec3d P = normalized(p), Q = normalized(q), R = normalized(r), X = normalized(x);
    const vec3d faces[2] = {cross(X - P, R - P), cross(R - Q, X - Q)};
    for (uint32_t k = 0; k < 2; ++k) {
      const uint32_t t = h[3 + k].triangle;
      if (t == none) return false;
      const uint32_t* c = &input.indices[3 * size_t(t)];
      const vec3d a = s.normalized_input(input.positions[c[0]]);
      const vec3d n = cross(s.normalized_input(input.positions[c[1]]) - a, s.normalized_input(input.positions[c[2]]) - a);
      if (!(dot(n, faces[k]) > s.options.min_normal_dot * length(n) * length(faces[k]))) return false;
    }
    return true;
  };
  // Applies the proposed flips whose points lie no farther from the input than the old pair's
  // farthest (far flips: far_margin nearer, and following the input), none sharing a position with
  // another, greedily: far ones first by how much nearer they come, then by gain. `hits`:
  // hits_per_flip per proposed flip. Records them and moves the feet in their faces.
  const auto apply_flips = [&](const std::vector<Flip>& proposed, const std::vector<measure::ClosestHit>& hits) {
    std::vector<uint32_t> order;
    std::vector<double> nearer(proposed.size(), 0.0);
    for (uint32_t i = 0; i < proposed.size(); ++i) {
      const measure::ClosestHit* h = &hits[hits_per_flip * i + 1];
      const float old_far = std::max({hits[hits_per_flip * i].distance_squared, h[0].distance_squared, h[1].distance_squared});
      const float new_far = std::max({h[2].distance_squared, h[3].distance_squared, h[4].distance_squared});
      nearer[i] = double(old_far) - double(new_far);
      if (proposed[i].far ? new_far < (1 - far_margin) * old_far && follows_input(proposed[i], h) : new_far <= old_far)
        order.push_back(i);
    }
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      const Flip &fa = proposed[a], &fb = proposed[b];
      if (fa.far != fb.far) return fa.far;
      const double ka = fa.far ? nearer[a] : fa.gain, kb = fb.far ? nearer[b] : fb.gain;
      return ka > kb || (ka == kb && a < b);
    });
    std::vector<uint8_t> taken(m, 0);
    for (const uint32_t i : order) {
      const Flip& f = proposed[i];
      uint32_t p, q, r, x;
      flip_corners(f, p, q, r, x);
      if (taken[p] | taken[q] | taken[r] | taken[x]) continue;
      taken[p] = taken[q] = taken[r] = taken[x] = 1;
      const uint32_t t1 = state_triangle[f.t1], t2 = state_triangle[f.t2];
      const uint32_t c1 = 3 * t1 + (f.k1 + 1) % 3, c2 = 3 * t2 + (f.k2 + 1) % 3;  // the corners that change
      const uint32_t wedge_x = s.corners[3 * size_t(t2) + (f.k2 + 2) % 3], wedge_r = s.corners[3 * size_t(t1) + (f.k1 + 2) % 3];
      if (flipped) {
        flipped->push_back({t1, (f.k1 + 1) % 3, s.corners[c1], wedge_x});
        flipped->push_back({t2, (f.k2 + 1) % 3, s.corners[c2], wedge_r});
      }
      s.corners[c1] = wedge_x, s.corners[c2] = wedge_r;
      s.corner_pos[c1] = s.position_of[wedge_x], s.corner_pos[c2] = s.position_of[wedge_r];
      result.indices[3 * size_t(f.t1) + (f.k1 + 1) % 3] = x;
      result.indices[3 * size_t(f.t2) + (f.k2 + 1) % 3] = r;
      // Sides: t1 = (p, s, r) runs p->s (was t2's) and s->r (the new edge); t2 = (q, r, s) runs
      // q->r (was t1's) and r->s.
      uint32_t* side1 = &edge_of_side[3 * size_t(f.t1)];
      uint32_t* side2 = &edge_of_side[3 * size_t(f.t2)];
      const uint32_t qr = side1[(f.k1 + 1) % 3], px = side2[(f.k2 + 1) % 3];
      side1[f.k1] = px, side1[(f.k1 + 1) % 3] = f.edge;
      side2[f.k2] = qr, side2[(f.k2 + 1) % 3] = f.edge;
      edges[f.edge] = {r, x};
      const measure::ClosestHit& mid = hits[hits_per_flip * i + 3];
      if (mid.triangle != none) edge_target[f.edge] = mid.point;
      else edge_target[f.edge] = (measure::vec3f(result.positions[r]) + measure::vec3f(result.positions[x])) * 0.5f;
      const measure::PreparedTriangle new1 = prepared(f.t1), new2 = prepared(f.t2);
      for (const uint32_t t : {f.t1, f.t2})
        for (const uint32_t i_sample : feet[t]) {
          const measure::vec3f point(input.positions[samples[i_sample]]);
          const measure::TrianglePoint h1 = measure::closest_on_triangle(point, new1), h2 = measure::closest_on_triangle(point, new2);
          foot[i_sample] = h1.distance_squared <= h2.distance_squared ? Foot{f.t1, h1.v, h1.w} : Foot{f.t2, h2.v, h2.w};
        }
    }
  };
  const auto midpoint = [&](size_t e) {
    const float3 &a = result.positions[edges[e].first], &b = result.positions[edges[e].second];
    return measure::vec3f((a.x + b.x) * 0.5f, (a.y + b.y) * 0.5f, (a.z + b.z) * 0.5f);
  };
  // A first answer to the exact search for `point`: the nearest of the first candidate input
  // triangles of `corners` (a bound that lets the search skip the input's far chunks, and its start).
  const auto seed_hit = [&](const measure::vec3f& point, measure::ClosestHit& best, std::initializer_list<uint32_t> corners) {
    for (const uint32_t j : corners) {
      if (candidates_first[j] == candidates_first[j + 1]) continue;
      const uint32_t t = candidates[candidates_first[j]];
      const measure::TrianglePoint hit = on_input_triangle(input, t, point);
      if (closer(hit.distance_squared, t, best)) best.distance_squared = hit.distance_squared, best.triangle = t, best.point = hit.point;
    }
  };
  // Each result edge's midpoint (each proposed flip's points, each position) against the input: the
  // exact closest point, seeded by seed_hit with the point's corners.
  const auto search_edges = [&](const std::vector<Flip>& proposed) {
    const size_t first_position = edge_points + probes_per_flip * proposed.size();
    std::vector<measure::vec3f> points(first_position + m);
    for (size_t j = 0; j < m; ++j) points[first_position + j] = measure::vec3f(result.positions[j]);
    for (size_t e = 0; e < edge_points; ++e) points[e] = midpoint(e);
    for (size_t i = 0; i < proposed.size(); ++i) flip_probes(proposed[i], &points[edge_points + probes_per_flip * i]);
    std::vector<measure::ClosestHit> hits(points.size());
    const auto seed = [&](size_t i, std::initializer_list<uint32_t> corners) { seed_hit(points[i], hits[i], corners); };
    core::parallel_for(edge_points, s.threads, [&](size_t e) { seed(e, {edges[e].first, edges[e].second}); });
    core::parallel_for(proposed.size(), s.threads, [&](size_t i) {
      uint32_t p, q, r, x;
      flip_corners(proposed[i], p, q, r, x);
      for (uint32_t k = 0; k < probes_per_flip; ++k) seed(edge_points + probes_per_flip * i + k, {p, q, r, x});
    });
    core::parallel_for(m, s.threads, [&](size_t j) { seed(first_position + j, {uint32_t(j)}); });
    closest_on_input(s, points, hits, fit_chunk_triangles);
    for (size_t j = 0; j < m; ++j) nearest_input[j] = hits[first_position + j].triangle;
    for (size_t e = 0; e < edge_points; ++e) edge_target[e] = hits[e].triangle != none ? hits[e].point : points[e];  // none: no pull
    if (proposed.empty()) return;
    std::vector<measure::ClosestHit> flip_hits(hits_per_flip * proposed.size());
    for (size_t i = 0; i < proposed.size(); ++i) {
      flip_hits[hits_per_flip * i] = hits[proposed[i].edge];
      std::copy_n(&hits[edge_points + probes_per_flip * i], probes_per_flip, &flip_hits[hits_per_flip * i + 1]);
    }
    apply_flips(proposed, flip_hits);
  };
  // The second flip round (see far_edge): the flips' points against the input, as search_edges
  // finds them (the edges keep their closest points: searched again from moved midpoints, one can
  // jump across a thin part).
  const auto flip_again = [&](double far_level) {
    const std::vector<Flip> proposed = propose_flips(far_level);
    if (proposed.empty()) return;
    std::vector<measure::vec3f> points(hits_per_flip * proposed.size());
    for (size_t i = 0; i < proposed.size(); ++i) {
      points[hits_per_flip * i] = midpoint(proposed[i].edge);
      flip_probes(proposed[i], &points[hits_per_flip * i + 1]);
    }
    std::vector<measure::ClosestHit> hits(points.size());
    core::parallel_for(proposed.size(), s.threads, [&](size_t i) {
      uint32_t p, q, r, x;
      flip_corners(proposed[i], p, q, r, x);
      for (uint32_t k = 0; k < hits_per_flip; ++k) seed_hit(points[hits_per_flip * i + k], hits[hits_per_flip * i + k], {p, q, r, x});
    });
    closest_on_input(s, points, hits, fit_chunk_triangles);
    apply_flips(proposed, hits);
  };
  // Converged: an iteration moved no position by more than `converged` of the mean edge length.
  double mean_edge = 0;
  for (const auto& [a, b] : edges) mean_edge += length(normalized(a) - normalized(b));
  mean_edge /= double(std::max<size_t>(edges.size(), 1));
  std::vector<float3> iteration_start;
  std::vector<vec3d> sample_residual;  // per sample, in the sweeps with emphasis
  double edge_mean_square = 0;  // of the edges' residuals, area-weighted, in the last sweep
  uint32_t iteration = 0;
  // The feet's tree over the result: built once, then refitted as the positions move (the same
  // answers at a fraction of a build's cost; bunny00 to half, one thread: the fit 0.691 -> 0.622 s,
  // medians of 7); built again after the iterations that flip edges, which change the triangles.
  std::optional<measure::TriangleBvh> bvh;
  while (iteration < iterations) {
    iteration_start = result.positions;
    if (!bvh || (iteration > 0 && flip_round(iteration - 1))) bvh.emplace(result, s.threads);
    else bvh->refit(result, s.threads);
    core::parallel_blocks(group_first.size() - 1, 256, s.threads, [&](size_t, size_t group_begin, size_t group_end) {
      measure::TriangleBvh::GroupScratch scratch;
      measure::vec3f points[max_group];
      measure::ClosestHit hits[max_group];
      for (size_t g = group_begin; g < group_end; ++g) {
        const uint32_t first = group_first[g], count = group_first[g + 1] - first;
        for (uint32_t k = 0; k < count; ++k) points[k] = measure::vec3f(input.positions[samples[by_slot[first + k]]]);
        bvh->closest_group(points, count, foot[by_slot[first]].triangle, hits, scratch);
        for (uint32_t k = 0; k < count; ++k) {
          measure::ClosestHit& hit = hits[k];
          // No triangle: every distance overflowed (coordinates near FLT_MAX); the sample keeps its
          // last foot, which is always a triangle of the result.
          if (hit.triangle == none) continue;
          bvh->resolve(hit, points[k]);
          Foot& f = foot[by_slot[first + k]];
          f.triangle = hit.triangle, f.v = hit.v, f.w = hit.w;
          if (flip_round(iteration)) foot_distance[by_slot[first + k]] = hit.distance_squared;
        }
      }
    });
    if (iteration == 0) {
      std::vector<Flip> proposed;
      if (flips) proposed = propose_flips(0);
      search_edges(proposed);
    } else if (flip_round(iteration)) {
      flip_again(far_edge * edge_mean_square);  // far by the last sweep's residuals
    }
    for (uint32_t sweep = 0; sweep < sweeps; ++sweep) {
      // Each position's normal equation with its neighbours held still, summed in sample order (so
      // the sums do not depend on the thread count).
      std::fill(num.begin(), num.end(), vec3d{});
      std::fill(den.begin(), den.end(), 0.0);
      const auto residual = [&](const Foot& f, uint32_t sample, const double* beta) {
        const uint32_t* c = &result.indices[3 * size_t(f.triangle)];
        return s.normalized_input(input.positions[sample]) -
               (normalized(c[0]) * beta[0] + normalized(c[1]) * beta[1] + normalized(c[2]) * beta[2]);
      };
      const auto weights = [](const Foot& f) { return std::array<double, 3>{1.0 - double(f.v) - double(f.w), f.v, f.w}; };
      // From iteration emphasis_from on, the samples' weights follow their residuals (see
      // sample_emphasis), which are then computed once, for the mean and the sums below.
      double sample_mean_square = 0;
      const bool emphasised = iteration >= emphasis_from;
      if (emphasised) {
        sample_residual.resize(samples.size());
        double squares = 0, area = 0;
        for (size_t i = 0; i < samples.size(); ++i) {
          const double a = share[samples[i]];
          sample_residual[i] = residual(foot[i], samples[i], weights(foot[i]).data());
          squares += a * length_squared(sample_residual[i]), area += a;
        }
        sample_mean_square = area > 0 ? squares / area : 0;
      }
      for (size_t i = 0; i < samples.size(); ++i) {
        const Foot& f = foot[i];
        const std::array<double, 3> beta = weights(f);
        const uint32_t* c = &result.indices[3 * size_t(f.triangle)];
        const vec3d r = emphasised ? sample_residual[i] : residual(f, samples[i], beta.data());
        double a = share[samples[i]] * double(stride);
        if (sample_mean_square > 0) a *= 1 + sample_emphasis * std::min(sample_cap, length_squared(r) / sample_mean_square);
        for (uint32_t k = 0; k < 3; ++k) {
          const uint32_t j = c[k];
          num[j] = num[j] + r * (a * beta[k]);
          den[j] += a * beta[k] * beta[k];
        }
      }
      if (edge_targets) {  // else no edge term and no far edges (edge_mean_square) to find
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
        const double mean_square = edge_mean_square = area > 0 ? squares / area : 0;
        for (size_t e = 0; e < edges.size(); ++e) {
          const double emphasis = mean_square > 0 ? std::min(edge_cap, length_squared(edge_residual[e]) / mean_square) : 0;
          const double a = edge_weight * edge_area[e] * emphasis;
          // The midpoint moves by half of each end's move: (d_j + d_k) / 2 against the residual.
          for (const uint32_t j : {edges[e].first, edges[e].second})
            num[j] = num[j] + edge_residual[e] * (a * 0.5), den[j] += a * 0.25;
        }
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
      // Take back every move around a face that would degenerate or turn by more than the flip limit
      // from where it stood before the fit (not the last sweep: over many sweeps small turns would
      // add up), until none does (each round only takes moves back, so this ends).
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
          const vec3d old_corners[3] = {corner(start, 0), corner(start, 1), corner(start, 2)};
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
    ++iteration;
    double farthest = 0;
    for (size_t j = 0; j < m; ++j)
      farthest = std::max(farthest, length_squared(normalized(j) - s.normalized_input(iteration_start[j])));
    if (std::sqrt(farthest) < converged * mean_edge) break;
  }

  for (size_t j = 0; j < m; ++j) {
    if (result.positions[j] == start[j]) continue;
    const uint32_t p = position[j];
    s.position[p] = result.positions[j];
    ++s.moves[p];
    if (fitted) fitted->push_back({s.external[p], start[j], result.positions[j]});
  }
  return iteration;
}

}  // namespace lod::collapse
