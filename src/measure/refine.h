// Internal: refinement of a one-sided Hausdorff distance with a certified upper bound.
//
// f(q) = distance from q to the other surface. Over a triangular patch with corners c_i:
//  - f is 1-Lipschitz, so f <= f(c_i) + max_j |c_i - c_j| for any corner i;
//  - f(q) <= dist(q, T) for any one triangle T of the other surface, and dist(., T) is convex, so
//    over the patch it is at most its largest corner value. T = each corner's closest triangle;
//  - piecewise: the patch is cut where the candidates' (linearly interpolated) distances cross, and
//    each piece is bounded by its own triangle's convex distance at the piece's vertices. This is
//    what makes the bound tight across folds of the other surface (a simplified mesh against its
//    original: corners on the surface, several of its triangles under one patch);
//  - prisms: the patch is cut by each candidate's face region (where the foot on its plane lies
//    inside it), and each piece bounded by its own triangle; tight where the other surface's faces
//    lie under the patch flat or parallel, where the interpolated cuts above only shrink with it.
//    A piece no prism takes recruits the triangle across from it (a step over the adjacency).
// The smallest of these bounds each patch. Patches whose bound exceeds the largest distance found
// are split 1 -> 4 (three new corner queries each; a needle is bisected at its longest edge, one
// query), the worst first, in rounds.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "lodkit/measure.h"
#include "core/adjacency.h"
#include "measure/bvh.h"

namespace lod::measure {

struct RefineInput {
  const Mesh* from = nullptr;
  const std::vector<uint32_t>* position_id = nullptr;        // per vertex of `from`
  const std::vector<float>* position_distance = nullptr;     // per position id: distance to `to`
  const std::vector<uint32_t>* position_closest = nullptr;   // per position id: closest triangle of `to`
  // Per triangle of `from`: the closest triangle of `to` to a point inside it (an area sample), or
  // UINT32_MAX. Corners often tie between the triangles around them; an inner point's answer is the
  // one triangle that may cover the whole patch. May be null.
  const std::vector<uint32_t>* triangle_closest = nullptr;
  const TriangleBvh* to = nullptr;
  const core::TriangleAdjacency* neighbours = nullptr;  // of `to`: candidates a patch's corners miss
  float tolerance = 0;  // object space: stop when the bound is within this of the largest distance
  uint64_t budget = 0;  // queries
  unsigned threads = 0;
};

struct RefineResult {
  float max = 0;  // the largest distance found (at least the input's)
  MaxLocation location;
  float bound = 0;  // upper bound on the one-sided Hausdorff distance
  uint64_t queries = 0;
};

// `max`/`location`: the largest sampled distance so far. on_sample(triangle, point, distance) is
// called for every new sample, in a fixed order, from the calling thread.
RefineResult refine_max(const RefineInput& input, float max, const MaxLocation& location,
                        const std::function<void(uint32_t, const vec3f&, float)>& on_sample);

// The bound of one patch. Candidate triangles for the convexity bound: each corner's closest and
// `extra` (UINT32_MAX for none); `best` receives the candidate that gave the smallest bound.
// Above `enough` the cheaper bounds give way to the costlier ones; below it the bound is returned as
// is. `neighbours` (the adjacency of `to`, may be null) lets the prisms recruit more candidates.
float patch_bound(const vec3f corners[3], const float distances[3], const uint32_t closest[3], uint32_t extra,
                  const TriangleBvh& to, const core::TriangleAdjacency* neighbours, float enough,
                  uint32_t* best = nullptr);

}  // namespace lod::measure
