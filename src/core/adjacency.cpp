#include "core/adjacency.h"

#include <algorithm>

#include "core/buckets.h"
#include "lodkit/error.h"

namespace lod::core {

TriangleAdjacency triangle_adjacency(std::span<const uint32_t> indices, std::span<const uint32_t> ids, size_t id_count) {
  if (indices.size() % 3) throw_internal("triangle_adjacency: index count is not a multiple of 3");
  const size_t F = indices.size() / 3;
  auto key = [&](size_t corner) { return ids.empty() ? indices[corner] : ids[indices[corner]]; };

  TriangleAdjacency adj;
  adj.twin.assign(3 * F, no_twin);
  adj.twin_same_direction.assign(3 * F, 0);
  adj.degenerate.assign(F, 0);

  for (size_t t = 0; t < F; ++t) {
    const uint32_t a = key(3 * t), b = key(3 * t + 1), c = key(3 * t + 2);
    if (a >= id_count || b >= id_count || c >= id_count) throw_internal("triangle_adjacency: vertex id out of range");
    if (a == b || b == c || a == c) {
      adj.degenerate[t] = 1;
      ++adj.degenerate_triangles;
    }
  }
  // Every half-edge of a live triangle under its smaller key.
  struct Entry {
    uint32_t other;     // the larger key
    uint32_t halfedge;  // 3 * t + k
  };
  Buckets<Entry> edges = bucket<Entry>(id_count, [&](auto&& emit) {
    for (size_t t = 0; t < F; ++t) {
      if (adj.degenerate[t]) continue;
      for (uint32_t k = 0; k < 3; ++k) {
        const uint32_t a = key(3 * t + k), b = key(3 * t + (k + 1) % 3);
        emit(std::min(a, b), Entry{std::max(a, b), uint32_t(3 * t + k)});
      }
    }
  });
  // Within a bucket (a handful of entries), equal `other` keys are one edge. Entries were filled in
  // half-edge order, so a stable sort keeps the result independent of anything but the input.
  auto starts_at_smaller = [&](uint32_t h) {
    const uint32_t t = h / 3, k = h % 3;
    return key(3 * t + k) < key(3 * t + (k + 1) % 3);
  };
  for (size_t v = 0; v < id_count; ++v) {
    if (edges[v].empty()) continue;  // its data() may be null, and null + 1 is undefined
    Entry* begin = edges[v].data();
    Entry* end = begin + edges[v].size();
    // Insertion sort: buckets are tiny.
    for (Entry* i = begin + 1; i < end; ++i)
      for (Entry* j = i; j > begin && j[-1].other > j[0].other; --j) std::swap(j[-1], j[0]);
    for (Entry* run = begin; run < end;) {
      Entry* run_end = run + 1;
      while (run_end < end && run_end->other == run->other) ++run_end;
      const size_t n = size_t(run_end - run);
      if (n == 1) {
        ++adj.boundary_edges;
      } else if (n == 2) {
        const uint32_t h0 = run[0].halfedge, h1 = run[1].halfedge;
        adj.twin[h0] = h1, adj.twin[h1] = h0;
        const uint8_t same = starts_at_smaller(h0) == starts_at_smaller(h1);
        adj.twin_same_direction[h0] = adj.twin_same_direction[h1] = same;
        ++adj.manifold_edges;
        adj.inconsistent_edges += same;
      } else {
        ++adj.non_manifold_edges;
      }
      run = run_end;
    }
  }
  return adj;
}

}  // namespace lod::core
