// Internal: triangle-triangle adjacency across edges (the triangle connectivity graph), shared by
// orientation repair, the stripifiers and anything else that walks from a triangle to its neighbours.
//
// Half-edge h = 3 * t + k runs from corner k to corner (k + 1) % 3 of triangle t. An edge used by
// exactly two half-edges links them as twins; an edge used once is a boundary, three or more times is
// non-manifold (no twins: a walk does not cross it). Triangles with a repeated vertex id are
// degenerate and take no part. Edges are keyed by caller-supplied vertex ids: position ids so that
// attribute seams do not cut the surface, or the indices themselves when the shared index matters
// (strips).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace lod::core {

inline constexpr uint32_t no_twin = 0xFFFFFFFFu;

struct TriangleAdjacency {
  std::vector<uint32_t> twin;  // per half-edge: its twin half-edge, or no_twin
  // Per half-edge, whether the twin runs the same way (the two triangles disagree on winding).
  std::vector<uint8_t> twin_same_direction;
  std::vector<uint8_t> degenerate;  // per triangle
  uint64_t boundary_edges = 0;
  uint64_t manifold_edges = 0;        // edges with twins
  uint64_t inconsistent_edges = 0;    // manifold edges whose two triangles disagree on winding
  uint64_t non_manifold_edges = 0;
  uint64_t degenerate_triangles = 0;

  size_t triangle_count() const { return degenerate.size(); }
  // The triangle across corner k's edge of triangle t, or no_twin.
  uint32_t neighbour(uint32_t t, uint32_t k) const {
    const uint32_t h = twin[3 * t + k];
    return h == no_twin ? no_twin : h / 3;
  }
};

// `ids` maps each vertex index to its key (e.g. position ids); empty means the indices themselves.
// `id_count` bounds the keys (the vertex count when `ids` is empty). Linear time: half-edges are
// bucketed by their smaller key, then matched within each bucket.
TriangleAdjacency triangle_adjacency(std::span<const uint32_t> indices, std::span<const uint32_t> ids, size_t id_count);

}  // namespace lod::core
