// Internal: the working mesh of the collapse engine, shared by the engine and the cost metrics.
//
// Topology lives on position ids; triangle corners hold wedges (input vertex indices). Each pass
// rebuilds a compact position -> triangles table (CSR) from the live triangles, so nothing is
// allocated per collapse: within a pass every collapse locks the positions around it, which keeps
// the table, positions and costs of all other candidates exact until the next rebuild.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "core/quadric.h"
#include "lodkit/mesh.h"
#include "lodkit/simplify.h"

namespace lod::collapse {

using core::vec3d;

// Per-position flags.
enum : uint8_t {
  flag_border = 1,      // on an edge with a single triangle
  flag_complex = 2,     // non-manifold, inconsistently wound, or on a degenerate triangle: never collapses
  flag_locked = 4,      // never moves (user lock, or lock_border on a border)
  flag_pass_locked = 8, // touched by a collapse in this pass
  flag_dead = 16,       // removed by a collapse
  flag_dirty = 32,      // its star changed in the last pass (or this is the first): re-evaluate
  flag_seam = 64,       // its corners use more than one wedge or material
};

// Attribute layout of a wedge: normals (3), each UV set (2), colour (4), for the streams present.
struct AttributeLayout {
  uint32_t stride = 0;
  int normal = -1;                      // offset, -1 if absent
  int uv[max_uv_sets] = {-1, -1, -1, -1};
  uint32_t uv_sets = 0;
  int color = -1;
};

// A star triangle seen from its centre: the other two corners in winding order, the wedge (input
// vertex) at the centre's corner, and the triangle. One 16-byte entry (never split across cache
// lines): rebuilding the table scatters one write per corner, and most walks read both.
struct Wing {
  uint32_t next, prev, wedge, triangle;
};

// The triangle ids of a star, in increasing order (a view of its wings).
struct StarTriangles {
  const Wing* first;
  const Wing* last;
  struct iterator {
    const Wing* w;
    uint32_t operator*() const { return w->triangle; }
    iterator& operator++() { return ++w, *this; }
    bool operator==(const iterator& o) const { return w == o.w; }
  };
  iterator begin() const { return {first}; }
  iterator end() const { return {last}; }
  size_t size() const { return size_t(last - first); }
  bool empty() const { return first == last; }
  uint32_t operator[](size_t i) const { return first[i].triangle; }
};

struct State {
  const Mesh& mesh;
  const SimplifyOptions& options;
  unsigned threads = 1;

  // Positions are numbered internally in spatial (Morton) order, so neighbours sit close in memory
  // whatever the input's vertex order; the record speaks the public ids (lod::position_ids).
  uint32_t position_count = 0;
  std::vector<uint32_t> position_of;  // per wedge: internal position id
  std::vector<uint32_t> external;     // per internal position: public position id
  std::vector<float3> position;       // per position, object space
  std::vector<uint32_t> moves;        // per position: collapses that moved it (0: input positions)
  std::vector<uint32_t> successor;    // per position: the position it collapsed into (~0u while live)
  // Per wedge: the wedge of the kept position its corners were relinked to (~0u while none was):
  // where the data lodkit does not model (glTF morph targets) goes (SimplifyResult::vertex_successor).
  std::vector<uint32_t> wedge_successor;
  std::vector<uint8_t> flags;         // per position
  std::vector<float> importance;      // per position (largest of its wedges'); empty: all 1
  std::vector<uint32_t> corners;      // 3 wedges per triangle
  std::vector<uint32_t> corner_pos;   // 3 positions per triangle: position_of[corners], kept in step
  std::vector<uint8_t> alive;         // per triangle
  uint64_t live_triangles = 0;
  // Input triangles with two corners on one position (zero area; a UV sphere's poles often have a
  // row of them). Their positions would be complex, never collapsing, so they are dead from the
  // start and leave with the first collapse: it lists them among its removed faces (replay and
  // undo stay exact) and live_triangles counts them until then. Empty once they have left.
  std::vector<uint32_t> degenerate;

  AttributeLayout layout;
  std::vector<float> attributes;  // layout.stride per wedge, working values

  // Normalised frame for the metrics: q = (p - center) * scale, so the largest extent is ~1.
  vec3d center;
  double scale = 1;

  // Position -> live triangles, rebuilt each pass from the live triangle list (increasing ids).
  std::vector<uint32_t> live;   // live triangle ids, compacted each pass
  std::vector<uint32_t> first;  // position_count + 1
  std::vector<Wing> wings;      // per star triangle: the hot loops read neighbours without a lookup

  State(const Mesh& m, const SimplifyOptions& o) : mesh(m), options(o) {}

  StarTriangles triangles_of(uint32_t p) const { return {wings.data() + first[p], wings.data() + first[p + 1]}; }
  std::span<const Wing> wings_of(uint32_t p) const { return {wings.data() + first[p], wings.data() + first[p + 1]}; }
  uint32_t corner_position(uint32_t triangle, uint32_t k) const { return corner_pos[3 * triangle + k]; }
  uint32_t material(uint32_t triangle) const { return mesh.materials.empty() ? 0 : mesh.materials[triangle]; }
  vec3d normalized(uint32_t p) const { return normalized_input(position[p]); }
  vec3d normalized_input(const float3& v) const {
    return vec3d{(double(v.x) - center.x) * scale, (double(v.y) - center.y) * scale, (double(v.z) - center.z) * scale};
  }
  float3 object(const vec3d& q) const {
    return {float(q.x / scale + center.x), float(q.y / scale + center.y), float(q.z / scale + center.z)};
  }
  // Corner k of `triangle` in the normalised frame, with position `moved` standing at `to`.
  vec3d corner_at(uint32_t triangle, uint32_t k, uint32_t moved, const vec3d& to) const {
    const uint32_t p = corner_position(triangle, k);
    return p == moved ? to : normalized(p);
  }
};

// Number of live triangles around u that also hold position v. Counted in the smaller of the two
// stars (the same triangles): next to a position with thousands of faces, a border test stays cheap.
inline uint32_t shared_triangles(const State& state, uint32_t u, uint32_t v) {
  if (state.triangles_of(v).size() < state.triangles_of(u).size()) std::swap(u, v);
  uint32_t count = 0;
  for (const Wing& w : state.wings_of(u)) count += w.next == v || w.prev == v;
  return count;
}
inline bool is_border_edge(const State& state, uint32_t u, uint32_t v) { return shared_triangles(state, u, v) == 1; }

// A triangle whose corners move from `before` to `after` (same winding): whether it becomes
// degenerate or turns by more than the angle whose cosine is `min_dot`; |n| and the longest squared
// edge after the move, for aspect-ratio checks (L^2 / |n| is the longest edge over its altitude).
struct FaceChange {
  bool degenerate = false, flipped = false;
  double normal_length = 0, longest = 0;
};
inline FaceChange face_change(const vec3d* before, const vec3d* after, double min_dot) {
  const vec3d n0 = cross(before[1] - before[0], before[2] - before[0]);
  const vec3d n1 = cross(after[1] - after[0], after[2] - after[0]);
  const double l0 = length(n0), l1 = length(n1);
  const double longest = std::max({length_squared(after[1] - after[0]), length_squared(after[2] - after[1]),
                                   length_squared(after[0] - after[2])});
  FaceChange change{.normal_length = l1, .longest = longest};
  change.degenerate = !(l1 > 1e-12 * longest);
  change.flipped = l0 > 0 && dot(n0, n1) < min_dot * l0 * l1;
  return change;
}

// Which wedge of the kept position each wedge (and material) of the removed position continues as.
struct WedgePair {
  uint32_t from, to, material;
};

}  // namespace lod::collapse
