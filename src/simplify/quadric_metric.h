// Internal: the quadric metrics. One class covers four of the five costs, since they differ only in
// which planes a vertex quadric holds and when it is built:
//   qem                      area-weighted face planes, summed on collapse (Q_a = Q_u + Q_v)
//   constrained_qem          plus, per border edge, the plane through it perpendicular to its face,
//                            weighted by border_weight * length^2 (Garland–Heckbert 97)
//   memoryless               rebuilt from the current faces every pass (Lindstrom–Turk), plus a
//                            volume-preservation plane and the border-area term of the collapse
//   constrained_memoryless   memoryless plus the border planes
// Attributes add Hoppe's (1999) per-wedge quadric: minimising over the attribute values in closed
// form leaves a quadric in position only, so the 3x3 solve stays 3x3 (see attribute_quadric.h).
#pragma once

#include <vector>

#include "core/heap.h"
#include "core/parallel.h"
#include "simplify/attribute_quadric.h"
#include "simplify/metric.h"

namespace lod::collapse {

using core::Quadric;
using core::QuadricD;

// Planes through the border edges at `u` in triangle t (corners p, unit normal `unit`), perpendicular
// to t, weighted by border_weight * length^2 * importance.
inline void add_border_planes(const State& state, uint32_t u, uint32_t t, const vec3d* p, const vec3d& unit,
                              double importance, QuadricD& q) {
  for (uint32_t k = 0; k < 3; ++k) {
    const uint32_t i = state.corner_position(t, k), j = state.corner_position(t, (k + 1) % 3);
    if ((i != u && j != u) || !is_border_edge(state, u, i == u ? j : i)) continue;
    const vec3d edge = p[(k + 1) % 3] - p[k];
    const vec3d m = cross(edge, unit);
    const double len = length(m);
    if (!(len > 0)) continue;
    const vec3d normal = m * (1.0 / len);
    QuadricD plane = core::plane_quadric(normal, -dot(normal, p[k]),
                                         state.options.border_weight * length_squared(edge) * importance);
    plane.w = 0;
    q += plane;
  }
}

// What triangle t contributes to the quadric of its corner position u, with the corners at p (any
// frame: the rest positions, or a skinned pose): its area-weighted plane and, when `constrained`,
// the planes through its border edges at u.
inline void add_face_quadric(const State& state, uint32_t u, uint32_t t, const vec3d* p, double importance,
                             bool constrained, QuadricD& q) {
  const vec3d n = cross(p[1] - p[0], p[2] - p[0]);
  const double double_area = length(n);
  if (!(double_area > 0)) return;
  const vec3d unit = n * (1.0 / double_area);
  QuadricD face = core::plane_quadric(unit, -dot(unit, p[0]), 0.5 * double_area * importance);
  face.w = 0.5 * double_area;  // the normalising area is not scaled by importance
  q += face;
  // Only a position flagged border (or complex, which classify may leave unflagged) has border
  // edges: the flags are set before the first quadrics and kept as supersets after collapses.
  if (constrained && (state.flags[u] & (flag_border | flag_complex))) add_border_planes(state, u, t, p, unit, importance, q);
}

class QuadricMetric {
 public:
  QuadricMetric(bool constrained, bool memoryless, std::vector<Channel> channels)
      : constrained_(constrained), memoryless_(memoryless), attributes_(std::move(channels)) {}

  void initialize(State& state) {
    core::assign_huge(quadric_, state.position_count, {});
    attributes_.allocate(state.mesh.vertex_count());
    rebuild(state);
  }
  void begin_pass(State& state) {
    if (memoryless_) rebuild(state);
  }

  Placement place(const State& state, const EdgeQuery& edge) const {
    QuadricD q(quadric_[edge.kept]);
    q += quadric_[edge.removed];
    const double area = q.w;
    if (memoryless_) add_preservation_terms(state, edge, q);
    if (!attributes_.empty()) attributes_.add_merged(edge, q);
    const vec3d a = state.normalized(edge.kept), b = state.normalized(edge.removed);
    vec3d p = a;
    if (edge.on_edge) {
      p = core::segment_optimum(q, a, b);
    } else if (!edge.fixed) {
      // Trust the 3x3 optimum only near the edge: a far optimum of an ill-fitting quadric makes spikes.
      const bool near = core::optimum(q, p) && length_squared(p - (a + b) * 0.5) <= 4 * length_squared(b - a);
      if (!near) p = core::segment_optimum(q, a, b);
    }
    const double value = core::evaluate(q, p);
    return {area > 0 ? value / area : value, p};
  }

  void collapsed(State&, const EdgeQuery& edge, const vec3d&) {
    if (!memoryless_) quadric_[edge.kept] += quadric_[edge.removed];
    attributes_.merge(edge.wedges);
  }

  void attributes_at(const State&, uint32_t wedge, const vec3d& position, float* out) const {
    attributes_.optimal_values(wedge, position, out);
  }

  bool reads_neighbourhood() const { return memoryless_; }

  // Starts loading a position's quadric (88 bytes, two cache lines): ranking u's edges reads the
  // quadrics of neighbours scattered in memory, and asking for all of them first overlaps the misses.
  void prefetch(uint32_t position) const {
    const char* q = reinterpret_cast<const char*>(&quadric_[position]);
    __builtin_prefetch(q);
    __builtin_prefetch(q + sizeof(QuadricD) - 1);
  }

  // The stored quadric of a position (for tests: memoryless quadrics equal a rebuild from scratch).
  const QuadricD& quadric(uint32_t position) const { return quadric_[position]; }

 private:
  // Every live position's quadric (and its wedges' attribute quadrics) from its current faces.
  void rebuild(State& state) {
    core::parallel_for(state.position_count, state.threads, [&](size_t u) {
      if ((state.flags[u] & flag_dead) || !(state.flags[u] & flag_dirty)) return;
      const auto star = state.triangles_of(uint32_t(u));
      QuadricD q;
      const double importance = state.importance.empty() ? 1.0 : state.importance[u];
      for (const uint32_t t : star) {
        vec3d p[3];
        for (uint32_t k = 0; k < 3; ++k) p[k] = state.normalized(state.corner_position(t, k));
        add_face_quadric(state, uint32_t(u), t, p, importance, constrained_, q);
      }
      quadric_[u] = q;
      if (!attributes_.empty()) attributes_.rebuild_position(state, uint32_t(u));
    });
  }

  // Lindstrom–Turk: keep the volume enclosed by the star (one plane, the volume gradient) and, when
  // either end is on a border, the border's area vector (|c x p - e|^2, see below).
  void add_preservation_terms(const State& state, const EdgeQuery& edge, QuadricD& q) const {
    vec3d gradient, sources_minus_targets, old_area_vector;
    double h = 0, star_area = 0;
    const bool border = (state.flags[edge.kept] | state.flags[edge.removed]) & flag_border;
    for (const uint32_t x : {edge.kept, edge.removed}) {
      const vec3d px = state.normalized(x);
      for (const uint32_t t : state.triangles_of(x)) {
        uint32_t k = 0;
        while (state.corner_position(t, k) != x) ++k;
        const uint32_t next = state.corner_position(t, (k + 1) % 3), prev = state.corner_position(t, (k + 2) % 3);
        const vec3d pn = state.normalized(next), pp = state.normalized(prev);
        if (next != edge.kept && next != edge.removed && prev != edge.kept && prev != edge.removed) {
          // Volume swept by x moving to p over this face: (p - x) . n / 6.
          const vec3d n = cross(pn - px, pp - px);
          gradient = gradient + n;
          h += dot(n, px);
          star_area += 0.5 * length(n);
        }
        if (!border) continue;
        // Directed border edges: each x->next once from its source's star; prev->x only when prev
        // is outside the edge (otherwise it was met as x->next). Edges inside the edge vanish.
        const bool next_inside = next == edge.kept || next == edge.removed;
        const bool prev_inside = prev == edge.kept || prev == edge.removed;
        if (is_border_edge(state, x, next)) {
          old_area_vector = old_area_vector + cross(px, pn);
          if (!next_inside) sources_minus_targets = sources_minus_targets - pn;
        }
        if (!prev_inside && is_border_edge(state, x, prev)) {
          old_area_vector = old_area_vector + cross(pp, px);
          sources_minus_targets = sources_minus_targets + pp;
        }
      }
    }
    const double g = length(gradient);
    if (g > 1e-12 && star_area > 0) {
      QuadricD plane = core::plane_quadric(gradient * (1.0 / g), -h / g, star_area);
      plane.w = 0;
      q += plane;
    }
    if (border) {
      // After the collapse the border runs ... -> p -> ...; its area vector is c x p. Keep it at e.
      const vec3d& c = sources_minus_targets;
      const vec3d& e = old_area_vector;
      const double s = state.options.border_weight, cc = dot(c, c);
      QuadricD term;
      term.a00 = s * (cc - c.x * c.x), term.a01 = -s * c.x * c.y, term.a02 = -s * c.x * c.z;
      term.a11 = s * (cc - c.y * c.y), term.a12 = -s * c.y * c.z, term.a22 = s * (cc - c.z * c.z);
      const vec3d ce = cross(c, e);
      term.b0 = s * ce.x, term.b1 = s * ce.y, term.b2 = s * ce.z;
      term.c = s * dot(e, e);
      q += term;
    }
  }

  bool constrained_, memoryless_;
  // Per position, in double: float sums of plane quadrics lose ~1e-7 of |p|^2, which on flat regions
  // is noise far above the true (zero) costs and scrambles the collapse order there.
  std::vector<QuadricD> quadric_;
  AttributeQuadrics attributes_;
};

}  // namespace lod::collapse
