#include "simplify/fit.h"

#include <algorithm>
#include <cmath>

#include "core/parallel.h"
#include "measure/bvh.h"

namespace lod::collapse {

void fit_positions(State& s, uint32_t iterations, double weight, std::vector<FittedPosition>* fitted) {
  const Mesh& input = s.mesh;
  const uint32_t n = s.position_count;
  const size_t triangles = s.alive.size();

  // Each input corner stands for a third of its triangle's area (normalised frame): the weight of
  // its vertex as a sample, and of the position that vertex ended in ("mass", for the pull below).
  std::vector<double> share(input.vertex_count(), 0.0);
  for (size_t t = 0; t < triangles; ++t) {
    vec3d p[3];
    for (uint32_t k = 0; k < 3; ++k) p[k] = s.normalized_input(input.positions[input.indices[3 * t + k]]);
    const double third = length(cross(p[1] - p[0], p[2] - p[0])) / 6;
    for (uint32_t k = 0; k < 3; ++k) share[input.indices[3 * t + k]] += third;
  }
  // The live position each position ended in: its collapse chain, shortened as it is walked.
  std::vector<uint32_t> end = s.successor;
  const auto last = [&](uint32_t p) {
    uint32_t r = p;
    while (end[r] != ~0u) r = end[r];
    while (p != r) {  // point the walked chain at r
      const uint32_t next = end[p];
      end[p] = r;
      p = next;
    }
    return r;
  };
  std::vector<double> mass(n, 0.0);
  for (size_t v = 0; v < input.vertex_count(); ++v) mass[last(s.position_of[v])] += share[v];
  // Far down, the input has many vertices per surviving position; 16 per position fix it as well
  // (every k-th input vertex, weighted k times) at a fraction of the closest-point searches.
  uint32_t live_positions = 0;
  for (uint32_t j = 0; j < n; ++j) live_positions += mass[j] > 0;
  const size_t stride = std::max<size_t>(1, input.vertex_count() / (16 * size_t(std::max(1u, live_positions))));
  if (stride > 1)
    for (size_t v = 0; v < input.vertex_count(); ++v) share[v] = v % stride ? 0.0 : share[v] * double(stride);
  const measure::TriangleBvh input_bvh(input, s.threads);

  // Per input vertex: its closest point on the current surface (a live triangle and the barycentric
  // weights of its corners) and the residual input - surface point, normalised frame.
  struct Foot {
    uint32_t triangle = ~0u;
    double beta[3] = {};
    vec3d residual;
  };
  std::vector<Foot> foot(input.vertex_count());
  std::vector<vec3d> num(n);
  std::vector<double> den(n);
  std::vector<uint8_t> moved(n), revert(n);
  std::vector<float3> before;
  const std::vector<float3> start = s.position;
  Mesh current;
  std::vector<uint32_t> live, index_of;  // current's triangle -> state triangle, and back
  for (uint32_t iteration = 0; iteration < iterations; ++iteration) {
    current.positions = s.position;
    current.indices.clear(), live.clear();
    for (size_t t = 0; t < triangles; ++t)
      if (s.alive[t]) {
        live.push_back(uint32_t(t));
        current.indices.insert(current.indices.end(), &s.corner_pos[3 * t], &s.corner_pos[3 * t] + 3);
      }
    if (live.empty()) return;
    const measure::TriangleBvh current_bvh(current, s.threads);
    // The previous foot's triangle starts each search (it is usually still the answer).
    index_of.assign(triangles, 0);
    for (uint32_t i = 0; i < live.size(); ++i) index_of[live[i]] = i;
    core::parallel_for(input.vertex_count(), s.threads, [&](size_t v) {
      Foot& f = foot[v];
      const uint32_t hint = f.triangle == ~0u ? 0 : index_of[f.triangle];
      f = Foot{};
      if (!(share[v] > 0)) return;
      const measure::ClosestHit hit = current_bvh.closest(input.positions[v], hint);
      f.triangle = live[hit.triangle];
      f.beta[0] = 1.0 - double(hit.v) - double(hit.w), f.beta[1] = hit.v, f.beta[2] = hit.w;
      const uint32_t* c = &s.corner_pos[3 * size_t(f.triangle)];
      const vec3d q = s.normalized(c[0]) * f.beta[0] + s.normalized(c[1]) * f.beta[1] + s.normalized(c[2]) * f.beta[2];
      f.residual = s.normalized_input(input.positions[v]) - q;
    });
    // Each position's normal equations with its neighbours held still, summed in input order (so
    // the sums do not depend on the thread count).
    std::fill(num.begin(), num.end(), vec3d{});
    std::fill(den.begin(), den.end(), 0.0);
    for (size_t v = 0; v < input.vertex_count(); ++v) {
      const Foot& f = foot[v];
      if (f.triangle == ~0u) continue;
      for (uint32_t k = 0; k < 3; ++k) {
        const uint32_t j = s.corner_pos[3 * size_t(f.triangle) + k];
        num[j] = num[j] + f.residual * (share[v] * f.beta[k]);
        den[j] += share[v] * f.beta[k] * f.beta[k];
      }
    }
    before = s.position;
    core::parallel_for(n, s.threads, [&](size_t j) {
      moved[j] = 0;
      if (!(den[j] > 0) || (s.flags[j] & (flag_locked | flag_dead))) return;
      // Minimise sum a |r - beta d|^2 + weight mass |x + d - c|^2 over the move d, c being the
      // position's closest point on the input.
      const measure::ClosestHit hit = input_bvh.closest(before[j]);
      const vec3d x = s.normalized(uint32_t(j));
      const vec3d c = s.normalized_input(float3{hit.point.x, hit.point.y, hit.point.z});
      const double pull = weight * mass[j];
      const vec3d d = (num[j] - (x - c) * pull) * (1.0 / (den[j] + pull));
      const float3 to = s.object(x + d);
      if (!std::isfinite(to.x) || !std::isfinite(to.y) || !std::isfinite(to.z) || to == before[j]) return;
      s.position[j] = to;
      moved[j] = 1;
    });
    // Take back every move around a face that would turn by more than the flip limit or degenerate,
    // until none does (each round only takes moves back, so this ends).
    const double min_dot = s.options.min_normal_dot;
    for (bool changed = true; changed;) {
      changed = false;
      std::fill(revert.begin(), revert.end(), 0);
      for (const uint32_t t : live) {
        const uint32_t* c = &s.corner_pos[3 * size_t(t)];
        if (!(moved[c[0]] | moved[c[1]] | moved[c[2]])) continue;
        const auto corner = [&](const std::vector<float3>& from, uint32_t k) {
          const float3& p = from[c[k]];
          return vec3d{p.x, p.y, p.z};
        };
        const vec3d a0 = corner(before, 0), b0 = corner(before, 1), c0 = corner(before, 2);
        const vec3d a1 = corner(s.position, 0), b1 = corner(s.position, 1), c1 = corner(s.position, 2);
        const vec3d n0 = cross(b0 - a0, c0 - a0), n1 = cross(b1 - a1, c1 - a1);
        const double l0 = length(n0), l1 = length(n1);
        const double longest = std::max({length_squared(b1 - a1), length_squared(c1 - b1), length_squared(a1 - c1)});
        if (!(l1 > 1e-12 * longest) || (l0 > 0 && dot(n0, n1) < min_dot * l0 * l1))
          for (uint32_t k = 0; k < 3; ++k) revert[c[k]] |= moved[c[k]];
      }
      for (uint32_t j = 0; j < n; ++j)
        if (revert[j]) s.position[j] = before[j], moved[j] = 0, changed = true;
    }
  }

  for (uint32_t j = 0; j < n; ++j) {
    if (s.position[j] == start[j]) continue;
    ++s.moves[j];
    if (fitted) fitted->push_back({s.external[j], start[j], s.position[j]});
  }
}

}  // namespace lod::collapse
