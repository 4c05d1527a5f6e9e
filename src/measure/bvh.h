// Internal: a 4-wide bounding volume hierarchy over a mesh's triangles for exact closest-point
// queries. Built with binned SAH (binary; or by halving a given spatially coherent order, for few
// queries), then collapsed to 4-wide nodes whose child boxes are structure-of-arrays floats, so one
// SSE pass measures the point's distance to all four.
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "lodkit/mesh.h"
#include "measure/triangle_distance.h"

namespace lod::measure {

// A node of TriangleBvh's 4-wide tree.
struct alignas(64) BvhNode {
  // Child boxes, one lane per child: min x, y, z then max x, y, z, four lanes each (the layout
  // Probe::within reads); an empty lane has min = +inf, max = -inf.
  float box[24];
  // Inner child: node index. Leaf: bvh_leaf_bit | first << 4 | (count - 1), first into the leaf-order triangles.
  uint32_t child[4];
};
constexpr uint32_t bvh_leaf_bit = 0x80000000u;
constexpr uint32_t bvh_empty_child = 0xFFFFFFFFu;

struct ClosestHit {
  float distance_squared = std::numeric_limits<float>::infinity();
  uint32_t triangle = UINT32_MAX;  // triangle index in the mesh
  vec3f point;
  float v = 0, w = 0;  // barycentric weights of the triangle's corners 1 and 2
  // closest_group leaves the point and the weights to TriangleBvh::resolve (most samples never need them).
  bool resolved = true;
};

class TriangleBvh {
 public:
  // Builds over every triangle of `mesh` (at least one; at most 2^27). Positions are copied, so the
  // mesh may go away. The layout depends only on the mesh, never on `threads`.
  explicit TriangleBvh(const Mesh& mesh, unsigned threads = 0);
  // The same queries over a tree built by halving `coherent_order`, which lists every triangle once in
  // a spatially coherent order (such as the Morton order of a corner), down to leaves of a few: one
  // pass instead of the SAH search, for many triangles and few queries. The answers are the same (a
  // brute-force scan's); a looser tree only makes each query visit more nodes.
  TriangleBvh(const Mesh& mesh, std::span<const uint32_t> coherent_order, unsigned threads = 0);

  // Moves the tree to `mesh`, which has the triangles (indices) it was built over at new positions:
  // the boxes are recomputed bottom-up, the tree kept. The answers stay exact; after large moves a
  // query only visits more nodes. Much cheaper than a build, for a mesh that moves a little at a time.
  void refit(const Mesh& mesh, unsigned threads = 0);

  // The exact closest point over all triangles; ties go to the lowest triangle index, so the answer
  // equals a brute-force scan's. `hint` is a triangle whose distance starts the search (the previous
  // query's answer is a good one); it changes only the speed. With a `bound` (squared distance) only
  // triangles at most that far are looked for (a caller that knows a point elsewhere prunes sooner):
  // the answer is the same when one is; when none is, the hit has no triangle (UINT32_MAX).
  ClosestHit closest(const vec3f& p, uint32_t hint = 0,
                     float bound = std::numeric_limits<float>::infinity()) const;
  // Fills in a closest_group hit's point and weights (p: its query point); nothing when they are set.
  void resolve(ClosestHit& hit, const vec3f& p) const {
    if (hit.resolved) return;
    const TrianglePoint tp = closest_on_triangle(p, triangles_[slot_[hit.triangle]]);
    hit.point = tp.point, hit.v = tp.v, hit.w = tp.w;
    hit.resolved = true;
  }
  // The squared distance from p to one triangle (mesh index), as the searches compute it.
  float distance_squared(const vec3f& p, uint32_t triangle) const {
    return closest_distance_squared(p, triangles_[slot_[triangle]]);
  }

  // One triangle (mesh index) as the searches hold it: corner, edges, unit normal.
  const PreparedTriangle& prepared(uint32_t triangle) const { return triangles_[slot_[triangle]]; }

  // Reusable memory for closest_group (one per thread).
  struct GroupScratch {
    // Per point, padded to whole batches of lanes: x, y, z and the squared distance (floats), then
    // the triangle (mesh index).
    std::vector<float> lane_floats;
    std::vector<int32_t> lane_ints;
  };
  // closest() for each of `count` points, with identical answers (once resolved), for points close
  // together (the samples of one small patch): one traversal for the whole group, nearest boxes to the
  // group's centre first, scans each leaf's triangles for all points at once (4 or 8 lanes: box,
  // plane, then the exact distance), and prunes boxes farther from the points' box than the largest
  // of the points' best distances so far. `hint` (as for closest()) is every point's first triangle,
  // and `bounds`, if given, each point's bound (as for closest()). Points spread too far for that
  // fall back to closest(), one by one.
  void closest_group(const vec3f* points, uint32_t count, uint32_t hint, ClosestHit* out, GroupScratch& scratch,
                     const float* bounds = nullptr) const;

  // closest_group's lane width: 0 picks 8 when the CPU has AVX2, else 4 (the default); tests force
  // 4 or 8 to check both. Process-wide; the results never depend on it.
  static void set_lane_width(unsigned width);

  uint32_t triangle_count() const { return uint32_t(original_.size()); }
  size_t node_count() const { return nodes_.size(); }
  uint32_t depth() const { return depth_; }

 private:
  // Takes leaf-order triangle `slot` into `best` when it is closer to p (ties: the lower mesh index wins,
  // as in a brute-force scan), its point left to resolve(); true when it did.
  bool consider(const vec3f& p, uint32_t slot, ClosestHit& best) const;

  // triangles_, triangle_box_ and plane_slack_ from `mesh`'s positions, for the leaf order in
  // original_; returns the growth of the boxes.
  float place_triangles(const Mesh& mesh, unsigned threads);

  using Node = BvhNode;
  static constexpr uint32_t leaf_bit = bvh_leaf_bit;
  static constexpr uint32_t empty_child = bvh_empty_child;

  std::vector<Node> nodes_;        // nodes_[0] is the root
  std::vector<PreparedTriangle> triangles_;  // in leaf order
  std::vector<uint32_t> original_;  // leaf order -> mesh triangle
  std::vector<uint32_t> slot_;      // mesh triangle -> leaf order
  std::vector<float> triangle_box_;  // per leaf-order triangle: grown min x, y, z, max x, y, z
  float plane_slack_ = 0;              // rounding allowance of a distance to a triangle's plane
  uint32_t depth_ = 0;              // of the 4-wide tree
};

}  // namespace lod::measure
