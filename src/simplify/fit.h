// Internal: fitting the surviving positions to the input surface after the collapses (the vertex
// step of Hoppe et al. 1993, "Mesh optimization").
//
// Collapses place each position once, from quadrics, and never revisit it; far down (1% of the
// input) the result is then noticeably off the input in places. The fit moves every live position
// x_j by d_j to minimise, in the least-squares sense,
//   sum over input vertices i of a_i |S at i's foot - p_i|^2    (the input onto the result)
// + weight * sum over positions j of m_j |x_j + d_j - c_j|^2     (the result onto the input)
// where a_i is i's share of the input's area, i's foot its closest point on the current result,
// m_j the area of the input vertices that ended in position j and c_j the closest point of x_j on
// the input triangles around those vertices and on the input triangle nearest to x_j (found once,
// with the edges' closest points below: a position can lie on the input beyond its own triangles),
// + edge_weight * sum over result edges e of A_e w_e |(d_j + d_k) / 2 - (c_e - m_e)|^2
//                                                             (the result's edges onto the input)
// with m_e the edge's midpoint, c_e its exact closest input point (found once, through a BVH over
// one chunk of the input at a time), A_e a third of its faces' area and w_e = (|c_e - m_e| / rms)^2,
// capped: a reweighted step towards the largest distances, which are mostly at the midpoints of
// long edges whose ends lie on the input. Each iteration fixes the feet and closest points, then
// runs three Jacobi sweeps: each moves every position by 0.7 of the solution of its own normal
// equation (damped: full steps overshoot, neighbours moving together), then takes back the moves
// around any face that would degenerate or turn by more than the flip limit from where it stood
// before the fit. From the fifth iteration on, the input samples are reweighted the same way (a_i
// times 1 + 0.1 min(50, r_i^2 / mean r^2)), towards the input's farthest points. The iterations
// stop once one moved no position by more than 0.1% of the mean edge length: after one on dense
// inputs simplified 10x, where the result already lies near the input (and none run when the
// collapses left it on the input: fit_skip_error below); far down, where each further iteration
// still helps, at the cap (12 by default). Corpus
// meshes (10% and 1%, with the finer late passes): Hausdorff distance about -8%, RMS about -20%
// (10%) and -25% (1%), geometric means; the edge term takes the corpus's 10% Hausdorff distance
// further down where it was worst (bench/README, eleventh session). The feet come from measure's BVH over the (small) result,
// the edges' closest points from chunks of about 2^17 input triangles, so the fit adds little
// memory. The result does not depend on the thread count.
//
// Before the first sweeps, edges are flipped (the flip step of Hoppe et al.): an interior edge
// whose two faces' input samples lie nearer, in sum of squared distances, to the other diagonal of
// their quad, when the flipped faces' centroids and the new edge's midpoint lie no farther from the
// input than the farthest of the old faces' (one search with the edges' midpoints). Collapses only
// ever remove edges, so a diagonal left across a ridge or a saddle otherwise stays for good. At the
// eleventh iteration edges are flipped again, now also those far from the input (judged by the
// result -> input side, and against the input's normals; fit.cpp, far_edge). Corpus
// (10% and 1%): geometric means of lodkit / best peer, Hausdorff 0.739 -> 0.72 and 0.855 -> 0.84,
// RMS 0.754 -> 0.74 and 0.724 -> 0.71 (bench/README, fifteenth session).
#pragma once

#include <vector>

#include "measure/bvh.h"
#include "simplify/state.h"

namespace lod::collapse {

// Moves state.position of live positions (never locked ones), counts each moved position in
// state.moves and appends it to `fitted` (public ids), if given. With `flips`, first flips edges
// (state.corners and corner_pos), each as two corner relinks appended to `flipped`, if given.
// `weight` weighs the positions' pull onto the input, `edge_weight` the edge term (0: none).
// Runs at most `iterations` iterations and returns how many ran (fewer once the moves fade).
uint32_t fit_positions(State& state, uint32_t iterations, double weight, double edge_weight, bool flips,
                       std::vector<FittedPosition>* fitted, std::vector<Relink>* flipped);

// The fit is skipped when the collapses' largest error (a distance) is below this share of the
// input's bounding-box diagonal: every position then lies on the planes of the input faces it
// merged, to float precision, and the result on the input. Such results come from inputs
// subdivided without smoothing and simplified back (armadillo-s2 -> 83,200: relative error 1.2e-8,
// Hausdorff distance 7.6e-8 of the diagonal without the fit, 7.4e-8 with it, and the fit was a
// quarter of the time) and from flat or boxy corpus meshes, whose errors are 0. The next corpus
// error is 1.6e-5 (bench/README, twenty-first session).
constexpr double fit_skip_error = 1e-6;

// Input triangles per BVH in closest_on_input, as the fit uses it.
constexpr size_t fit_chunk_triangles = size_t(1) << 17;

// The exact closest point of state.mesh (the input) to each of `points`, ties going to the lowest
// input triangle, as a scan of all would find it. `hits` holds a first answer per point (squared
// distance, input triangle and point, or an infinite distance) and is improved in place. The input
// is searched through a BVH over about `chunk_triangles` of its triangles at a time (nearby ones; the
// tree built by halving their Morton order), skipping a chunk whose box is farther from a point than
// its best so far. Reads state.position_of and position_count (to group the triangles) and
// state.threads; the answers never depend on these.
void closest_on_input(const State& state, const std::vector<measure::vec3f>& points,
                      std::vector<measure::ClosestHit>& hits, size_t chunk_triangles);

}  // namespace lod::collapse
