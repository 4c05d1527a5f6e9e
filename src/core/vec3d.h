// Internal: double-precision 3-vectors, and a triangle's geometry from float positions computed in
// double (edge differences of nearby large coordinates would cancel in float).
#pragma once

#include <cmath>
#include <cstddef>

#include "lodkit/mesh.h"

namespace lod::core {

struct vec3d {
  double x = 0, y = 0, z = 0;
  vec3d operator+(const vec3d& o) const { return {x + o.x, y + o.y, z + o.z}; }
  vec3d operator-(const vec3d& o) const { return {x - o.x, y - o.y, z - o.z}; }
  vec3d operator*(double s) const { return {x * s, y * s, z * s}; }
  vec3d& operator+=(const vec3d& o) { return *this = *this + o; }
};
inline double dot(const vec3d& a, const vec3d& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline vec3d cross(const vec3d& a, const vec3d& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length_squared(const vec3d& a) { return dot(a, a); }
inline double length(const vec3d& a) { return std::sqrt(dot(a, a)); }
inline vec3d to_double(const float3& p) { return {p.x, p.y, p.z}; }
// v / |v| in float, or `fallback` when v has no length (or is not finite).
inline float3 unit_float3(const vec3d& v, const float3& fallback) {
  const double l = length(v);
  return l > 0 && std::isfinite(l) ? float3{float(v.x / l), float(v.y / l), float(v.z / l)} : fallback;
}

// The cross product of triangle abc's edges from a: its normal (by the winding) times twice its area.
inline vec3d triangle_cross(const float3& a, const float3& b, const float3& c) {
  return cross(to_double(b) - to_double(a), to_double(c) - to_double(a));
}
// Triangle t of `mesh`'s.
inline vec3d triangle_cross(const Mesh& mesh, size_t t) {
  return triangle_cross(mesh.positions[mesh.indices[3 * t]], mesh.positions[mesh.indices[3 * t + 1]],
                        mesh.positions[mesh.indices[3 * t + 2]]);
}
inline double triangle_area(const Mesh& mesh, size_t t) { return 0.5 * length(triangle_cross(mesh, t)); }

}  // namespace lod::core
