// Orientation repair, as the course describes it: start from a triangle taken as correctly wound,
// visit its neighbours breadth first, and reverse a neighbour whose shared edge runs the same way as
// in the current triangle (two consistently wound triangles traverse their common edge in opposite
// directions). Then each part as a whole faces outward (closed) or keeps its majority winding (open).
#include <cmath>

#include "core/adjacency.h"
#include "core/vec3d.h"
#include "lodkit/optimize.h"

namespace lod {

namespace {

// Six times the signed volume of the tetrahedron (origin, p, q, r), positions taken relative to `o`
// (a point of the part) so that a part far from the origin keeps its precision.
double signed_volume6(const Mesh& m, uint32_t t, const float3& o) {
  const float3 &p = m.positions[m.indices[3 * t]], &q = m.positions[m.indices[3 * t + 1]], &r = m.positions[m.indices[3 * t + 2]];
  const double ax = double(p.x) - o.x, ay = double(p.y) - o.y, az = double(p.z) - o.z;
  const double bx = double(q.x) - o.x, by = double(q.y) - o.y, bz = double(q.z) - o.z;
  const double cx = double(r.x) - o.x, cy = double(r.y) - o.y, cz = double(r.z) - o.z;
  return ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
}

}  // namespace

OrientResult orient(const Mesh& mesh, const OrientOptions& options) {
  OrientResult r;
  const PositionIds pids = position_ids(mesh);
  const core::TriangleAdjacency adj = core::triangle_adjacency(mesh.indices, pids.id, pids.count);
  r.non_manifold_edges = adj.non_manifold_edges;
  const uint32_t F = uint32_t(mesh.triangle_count());

  std::vector<uint8_t> flip(F, 0), visited(F, 0);
  std::vector<uint32_t> part;  // the current part's triangles, in visiting order (also the BFS queue)
  part.reserve(F);
  for (uint32_t seed = 0; seed < F; ++seed) {
    if (visited[seed] || adj.degenerate[seed]) continue;
    part.clear();
    part.push_back(seed);
    visited[seed] = 1;
    bool closed = true, orientable = true;
    for (size_t head = 0; head < part.size(); ++head) {
      const uint32_t t = part[head];
      for (uint32_t k = 0; k < 3; ++k) {
        const uint32_t h = 3 * t + k, twin = adj.twin[h];
        if (twin == core::no_twin) {
          closed = false;  // a boundary or non-manifold edge
          continue;
        }
        const uint32_t n = twin / 3;
        // Disagreeing input windings (the edge runs the same way in both) need opposite flips.
        const uint8_t wanted = flip[t] ^ adj.twin_same_direction[h];
        if (visited[n]) {
          if (flip[n] != wanted) orientable = false;
          continue;
        }
        visited[n] = 1;
        flip[n] = wanted;
        part.push_back(n);
      }
    }
    ++r.components;
    bool reverse_all = false;
    if (closed && orientable) ++r.closed_components;
    if (!orientable) ++r.non_orientable_components;
    if (closed && orientable && options.outward) {
      const float3 o = mesh.positions[mesh.indices[3 * seed]];
      double volume6 = 0;
      for (const uint32_t t : part) volume6 += flip[t] ? -signed_volume6(mesh, t, o) : signed_volume6(mesh, t, o);
      reverse_all = volume6 < 0;
      r.turned_outward += reverse_all;
    } else {
      // Keep the winding most of the input area already had.
      double kept = 0, flipped = 0;
      for (const uint32_t t : part) (flip[t] ? flipped : kept) += core::triangle_area(mesh, t);
      reverse_all = flipped > kept;
    }
    if (reverse_all)
      for (const uint32_t t : part) flip[t] ^= 1;
  }

  r.mesh = mesh;
  for (uint32_t t = 0; t < F; ++t)
    if (flip[t]) {
      std::swap(r.mesh.indices[3 * t + 1], r.mesh.indices[3 * t + 2]);
      ++r.flipped_triangles;
    }
  return r;
}

}  // namespace lod
