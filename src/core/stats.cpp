// Mesh statistics. Topology is taken on position ids (so UV and normal seams do not cut the surface):
// one sort of the 3F edge records gives edges, boundary, non-manifold edges and seams; a union-find on
// corners gives the fans around each vertex (non-manifold vertices), and boundary edges chained
// through those fans give the boundary loops, even where two holes touch at a vertex.
#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "core/buckets.h"
#include "core/union_find.h"
#include "core/vec3d.h"
#include "lodkit/mesh.h"

namespace lod {

namespace {

constexpr uint32_t none = std::numeric_limits<uint32_t>::max();

struct EdgeRecord {
  uint64_t key;     // (min pid << 32) | max pid
  uint32_t corner;  // 3 * triangle + k: the edge runs from corner k to corner (k + 1) % 3
};

}  // namespace

MeshStats compute_stats(const Mesh& mesh) {
  MeshStats s;
  s.vertices = mesh.vertex_count();
  s.triangles = mesh.triangle_count();
  bounding_box(mesh, s.bbox_min, s.bbox_max);
  {
    double dx = double(s.bbox_max.x) - s.bbox_min.x, dy = double(s.bbox_max.y) - s.bbox_min.y,
           dz = double(s.bbox_max.z) - s.bbox_min.z;
    s.diagonal = std::sqrt(dx * dx + dy * dy + dz * dz);
  }
  uint32_t max_material = 0;
  for (uint32_t m : mesh.materials) max_material = std::max(max_material, m);
  s.materials = mesh.triangle_count() ? uint64_t(max_material) + 1 : 0;

  const PositionIds pids = position_ids(mesh);
  s.unique_positions = pids.count;
  const uint32_t F = uint32_t(mesh.triangle_count());
  auto pid = [&](uint32_t corner) { return pids.id[mesh.indices[corner]]; };

  // Degenerate (repeated position) triangles take no part in the topology.
  std::vector<uint8_t> live(F, 1);
  for (uint32_t t = 0; t < F; ++t) {
    uint32_t a = pid(3 * t), b = pid(3 * t + 1), c = pid(3 * t + 2);
    if (a == b || b == c || a == c) {
      live[t] = 0;
      ++s.degenerate_triangles;
      continue;
    }
    const core::vec3d n = core::triangle_cross(mesh, t);
    if (n.x == 0 && n.y == 0 && n.z == 0) ++s.zero_area_triangles;
  }

  // Duplicate triangles: same sorted position-id triple as an earlier live triangle.
  {
    struct Tri {
      uint32_t a, b, c, t;
    };
    std::vector<Tri> tris;
    tris.reserve(F);
    for (uint32_t t = 0; t < F; ++t) {
      if (!live[t]) continue;
      uint32_t v[3] = {pid(3 * t), pid(3 * t + 1), pid(3 * t + 2)};
      std::sort(v, v + 3);
      tris.push_back({v[0], v[1], v[2], t});
    }
    std::sort(tris.begin(), tris.end(), [](const Tri& x, const Tri& y) {
      return std::tie(x.a, x.b, x.c, x.t) < std::tie(y.a, y.b, y.c, y.t);
    });
    for (size_t i = 1; i < tris.size(); ++i)
      if (tris[i].a == tris[i - 1].a && tris[i].b == tris[i - 1].b && tris[i].c == tris[i - 1].c) ++s.duplicate_triangles;
  }

  std::vector<EdgeRecord> edges;
  edges.reserve(size_t(F) * 3);
  for (uint32_t t = 0; t < F; ++t) {
    if (!live[t]) continue;
    for (uint32_t k = 0; k < 3; ++k) {
      uint32_t a = pid(3 * t + k), b = pid(3 * t + (k + 1) % 3);
      edges.push_back({(uint64_t(std::min(a, b)) << 32) | std::max(a, b), 3 * t + k});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const EdgeRecord& x, const EdgeRecord& y) {
    return x.key != y.key ? x.key < y.key : x.corner < y.corner;
  });

  // Corner clusters: corners of one vertex joined across manifold edges form one fan.
  core::UnionFind fans(size_t(F) * 3);
  core::UnionFind vertex_sets(pids.count);
  // Orientation: parity[t] says whether t must be flipped to agree with its neighbours.
  struct Link {
    uint32_t a, b;
    bool same_direction;  // both triangles run the shared edge the same way: one must flip
  };
  std::vector<Link> manifold_links;
  std::vector<uint32_t> boundary_halfedges;  // corners whose edge has a single triangle
  std::vector<uint32_t> edge_owner;          // first triangle of each edge, for per-component counts
  std::vector<uint32_t> non_manifold_edge_triangles;

  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].key == edges[i].key) ++j;
    const size_t m = j - i;
    ++s.edges;
    edge_owner.push_back(edges[i].corner / 3);
    const uint32_t c0 = edges[i].corner, t0 = c0 / 3;
    const uint32_t c0_next = 3 * t0 + (c0 % 3 + 1) % 3;
    vertex_sets.unite(pid(c0), pid(c0_next));
    if (m == 1) {
      ++s.boundary_edges;
      boundary_halfedges.push_back(c0);
    } else if (m == 2) {
      const uint32_t c1 = edges[i + 1].corner, t1 = c1 / 3;
      const uint32_t c1_next = 3 * t1 + (c1 % 3 + 1) % 3;
      // Join the fans at both ends: corner of t0 at pid p with the corner of t1 at the same pid.
      if (pid(c0) == pid(c1)) {
        fans.unite(c0, c1);
        fans.unite(c0_next, c1_next);
      } else {
        fans.unite(c0, c1_next);
        fans.unite(c0_next, c1);
      }
      manifold_links.push_back({t0, t1, pid(c0) == pid(c1)});
      // A seam: the two sides reference different vertices (attributes) for the same positions.
      uint32_t v0a = mesh.indices[c0], v0b = mesh.indices[c0_next];
      uint32_t v1a = mesh.indices[c1], v1b = mesh.indices[c1_next];
      bool same = pid(c0) == pid(c1) ? (v0a == v1a && v0b == v1b) : (v0a == v1b && v0b == v1a);
      if (!same) ++s.seam_edges;
    } else {
      ++s.non_manifold_edges;
      for (size_t k = i; k < j; ++k) non_manifold_edge_triangles.push_back(edges[k].corner / 3);
    }
    i = j;
  }

  // Connected components over position ids, numbered in order of their first live triangle.
  std::vector<uint32_t> component_of_root(pids.count, none);
  std::vector<uint32_t> triangle_component(F, none);
  for (uint32_t t = 0; t < F; ++t) {
    if (!live[t]) continue;
    uint32_t root = vertex_sets.find(pid(3 * t));
    if (component_of_root[root] == none) {
      component_of_root[root] = uint32_t(s.components.size());
      s.components.push_back({});
    }
    triangle_component[t] = component_of_root[root];
    ++s.components[triangle_component[t]].triangles;
  }
  s.connected_components = s.components.size();
  {
    std::vector<uint8_t> referenced(pids.count, 0);
    for (uint32_t t = 0; t < F; ++t)
      if (live[t])
        for (uint32_t k = 0; k < 3; ++k) referenced[pid(3 * t + k)] = 1;
    // A vertex used only by degenerate triangles counts as unreferenced: it bounds no surface.
    for (uint32_t p = 0; p < pids.count; ++p) {
      if (!referenced[p]) {
        ++s.unreferenced_positions;
        continue;
      }
      ++s.components[component_of_root[vertex_sets.find(p)]].vertices;
    }
  }
  for (uint32_t t : edge_owner) ++s.components[triangle_component[t]].edges;
  std::vector<uint8_t> component_non_manifold(s.components.size(), 0);
  for (uint32_t t : non_manifold_edge_triangles) component_non_manifold[triangle_component[t]] = 1;

  // Non-manifold vertices: a position whose corners fall into more than one fan.
  {
    std::vector<uint32_t> first_fan(pids.count, none);
    std::vector<uint8_t> counted(pids.count, 0);
    for (uint32_t t = 0; t < F; ++t) {
      if (!live[t]) continue;
      for (uint32_t k = 0; k < 3; ++k) {
        uint32_t c = 3 * t + k, p = pid(c), root = fans.find(c);
        if (first_fan[p] == none) first_fan[p] = root;
        else if (first_fan[p] != root && !counted[p]) {
          counted[p] = 1;
          ++s.non_manifold_vertices;
          component_non_manifold[triangle_component[t]] = 1;
        }
      }
    }
  }

  // Boundary loops: each boundary edge joins the fans at its two ends; a loop is a connected set of
  // boundary edges. Fans (not vertices) keep two holes that touch at one vertex apart, and no edge
  // direction is used, so inconsistent winding (a Moebius strip) still gives one loop.
  {
    core::UnionFind loops(size_t(F) * 3);
    for (uint32_t c : boundary_halfedges) loops.unite(fans.find(c), fans.find(3 * (c / 3) + (c % 3 + 1) % 3));
    std::vector<uint8_t> counted(size_t(F) * 3, 0);
    for (uint32_t c : boundary_halfedges) {
      uint32_t root = loops.find(fans.find(c));
      if (counted[root]) continue;
      counted[root] = 1;
      ++s.boundary_loops;
      ++s.components[triangle_component[c / 3]].boundary_loops;
    }
  }

  // Orientability per component: propagate flips across manifold edges; a contradiction means the
  // component (a Moebius strip, a Klein bottle) cannot be wound consistently.
  std::vector<uint8_t> component_orientable(s.components.size(), 1);
  {
    using Neighbour = std::pair<uint32_t, uint8_t>;  // (triangle, same direction)
    const core::Buckets<Neighbour> adjacency = core::bucket<Neighbour>(F, [&](auto&& emit) {
      for (const Link& l : manifold_links) {
        emit(l.a, Neighbour{l.b, uint8_t(l.same_direction)});
        emit(l.b, Neighbour{l.a, uint8_t(l.same_direction)});
      }
    });
    std::vector<uint8_t> flip(F, 2);  // 2 = not visited
    std::vector<uint32_t> stack;
    for (uint32_t t0 = 0; t0 < F; ++t0) {
      if (!live[t0] || flip[t0] != 2) continue;
      flip[t0] = 0;
      stack.push_back(t0);
      while (!stack.empty()) {
        uint32_t t = stack.back();
        stack.pop_back();
        for (const auto& [n, same] : adjacency[t]) {
          uint8_t want = uint8_t(flip[t] ^ same);
          if (flip[n] == 2) {
            flip[n] = want;
            stack.push_back(n);
          } else if (flip[n] != want) {
            component_orientable[triangle_component[t]] = 0;
          }
        }
      }
    }
  }

  for (size_t c = 0; c < s.components.size(); ++c) {
    ComponentStats& cs = s.components[c];
    cs.euler_characteristic = int64_t(cs.vertices) - int64_t(cs.edges) + int64_t(cs.triangles);
    cs.closed = cs.boundary_loops == 0;
    cs.manifold = !component_non_manifold[c];
    cs.orientable = cs.manifold && component_orientable[c];
    int64_t twice_genus = 2 - cs.euler_characteristic - int64_t(cs.boundary_loops);
    cs.genus = (cs.orientable && twice_genus >= 0 && twice_genus % 2 == 0) ? twice_genus / 2 : -1;
    s.euler_characteristic += cs.euler_characteristic;
  }
  return s;
}

}  // namespace lod
