// Where a simplified result's vertices lie on the input: lod::vertex_blends (simplify.h).
#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

#include "core/buckets.h"
#include "core/vec3d.h"
#include "lodkit/error.h"
#include "lodkit/simplify.h"
#include "measure/triangle_distance.h"

namespace lod {

std::vector<VertexBlend> vertex_blends(const Mesh& input, std::span<const uint32_t> vertex_successor, const Mesh& output) {
  constexpr uint32_t none = ~0u;
  if (vertex_successor.size() != input.vertex_count())
    throw_usage("vertex_blends: " + std::to_string(vertex_successor.size()) + " successors for " +
                std::to_string(input.vertex_count()) + " input vertices");
  const size_t n = output.vertex_count(), triangles = input.triangle_count();
  for (const uint32_t s : vertex_successor)
    if (s != none && s >= n) throw_usage("vertex_blends: a successor is out of range for " + std::to_string(n) + " output vertices");

  // The patch each output position replaces: the input triangles with a corner that became one of
  // its wedges. Positions, not wedges: a seam wedge's own triangles may all lie on the far side of
  // where its position moved to (a collapse along the seam brings the other wedges' triangles).
  const PositionIds in = position_ids(input), out = position_ids(output);
  const auto positions = [&](size_t t, uint32_t (&s)[3]) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = vertex_successor[input.indices[3 * t + k]];
      s[k] = v == none ? none : out.id[v];
    }
    if (s[1] == s[0]) s[1] = none;
    if (s[2] == s[0] || s[2] == s[1]) s[2] = none;
  };
  const core::Buckets<uint32_t> region = core::bucket<uint32_t>(out.count, [&](auto&& emit) {
    for (size_t t = 0; t < triangles; ++t) {
      uint32_t s[3];
      positions(t, s);
      for (const uint32_t p : s)
        if (p != none) emit(p, uint32_t(t));
    }
  });
  // The input vertices at each input position that became each output vertex, to give a blend the
  // corners on its own vertex's side of a seam: (input position, output vertex) -> input vertex.
  // Only positions with several input vertices (seams) can have a choice.
  std::vector<uint8_t> copies(in.count, 0);
  for (uint32_t u = 0; u < input.vertex_count(); ++u) copies[in.id[u]] = uint8_t(std::min(copies[in.id[u]] + 1, 2));
  std::unordered_map<uint64_t, uint32_t> side;
  for (uint32_t u = 0; u < input.vertex_count(); ++u)
    if (copies[in.id[u]] > 1 && vertex_successor[u] != none) side.try_emplace(uint64_t(in.id[u]) << 32 | vertex_successor[u], u);

  // A vertex within a thousandth of the bounding-box diagonal of its own side of a seam blends that
  // side: values that jump at the seam (UVs, the normals of a hard edge) stay its own, and smooth
  // ones (morph targets' positions) change by little over that distance.
  float3 lo, hi;
  bounding_box(input, lo, hi);
  const double own_side = 1e-3 * std::hypot(double(hi.x) - lo.x, double(hi.y) - lo.y, double(hi.z) - lo.z);

  // A triangle faces an output vertex when its normal is on the side of the vertex's normal: of a
  // double-sided surface only the vertex's own side does. (Without normals: every triangle.)
  const auto facing = [&](const uint32_t* c, size_t v) {
    if (output.normals.empty()) return true;
    const core::vec3d face = core::triangle_cross(input.positions[c[0]], input.positions[c[1]], input.positions[c[2]]);
    return core::dot(face, core::to_double(output.normals[v])) > 0;
  };

  std::vector<VertexBlend> blends(n);
  for (size_t v = 0; v < n; ++v) {
    const uint32_t p = out.id[v];
    if (region[p].empty())
      throw_usage("vertex_blends: output vertex " + std::to_string(v) + " has no input vertex among its successors' sources");
    // The nearest point of the patch; and, within a thousandth of the diagonal of it, of the
    // triangles on the vertex's own side of a seam (a corner became this very wedge), else of those
    // facing it (a restored form's vertex may be no input vertex's successor: the twin of a
    // double-sided triangle is as near).
    const measure::vec3f x = output.positions[v];
    double best = INFINITY, best_own = INFINITY, best_facing = INFINITY;
    // Until a distance is finite (coordinates near the float range overflow): a corner of the patch.
    const uint32_t* c0 = &input.indices[3 * size_t(region[p][0])];
    uint32_t k0 = 0;
    while (k0 < 2 && (vertex_successor[c0[k0]] == none || out.id[vertex_successor[c0[k0]]] != p)) ++k0;
    VertexBlend any{{c0[k0], c0[k0], c0[k0]}, {1.0f, 0.0f, 0.0f}}, own, facing_one;
    for (const uint32_t t : region[p]) {
      const uint32_t* c = &input.indices[3 * size_t(t)];
      const measure::TrianglePoint q =
          measure::closest_on_triangle(x, input.positions[c[0]], input.positions[c[1]], input.positions[c[2]]);
      if (!std::isfinite(q.v) || !std::isfinite(q.w)) continue;
      const VertexBlend b{{c[0], c[1], c[2]}, {1.0f - q.v - q.w, q.v, q.w}};
      // Strictly nearer: ties go to the first triangle, so the result does not depend on anything else.
      if (q.distance_squared < best) best = q.distance_squared, any = b;
      const bool mine = vertex_successor[c[0]] == v || vertex_successor[c[1]] == v || vertex_successor[c[2]] == v;
      if (mine && q.distance_squared < best_own) best_own = q.distance_squared, own = b;
      if (q.distance_squared < best_facing && facing(c, v)) best_facing = q.distance_squared, facing_one = b;
    }
    const auto near = [&](double d) { return d < INFINITY && std::sqrt(d) <= std::sqrt(best) + own_side; };
    blends[v] = near(best_own) ? own : near(best_facing) ? facing_one : any;
    // Corners at a seam: the copy that became this wedge, where the input has one.
    for (uint32_t& c : blends[v].vertex) {
      if (copies[in.id[c]] < 2) continue;
      const auto mine = side.find(uint64_t(in.id[c]) << 32 | uint32_t(v));
      if (mine != side.end()) c = mine->second;
    }
  }
  return blends;
}

}  // namespace lod
