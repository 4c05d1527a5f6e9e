// Internal: float 3-vectors and the exact closest point on a triangle (Ericson, "Real-Time Collision
// Detection", 5.1.5: find the Voronoi region of the triangle that holds the point from the signs of
// a few dot products, then project onto that vertex, edge or face). Float is enough: distances are
// compared against a bounding-box diagonal, and the BVH and the brute-force reference share this
// one function, so they agree bit for bit.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "lodkit/mesh.h"

namespace lod::measure {

struct vec3f {
  float x = 0, y = 0, z = 0;
  vec3f() = default;
  vec3f(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
  vec3f(const float3& p) : x(p.x), y(p.y), z(p.z) {}  // NOLINT: implicit on purpose
  operator float3() const { return {x, y, z}; }
  vec3f operator+(const vec3f& o) const { return {x + o.x, y + o.y, z + o.z}; }
  vec3f operator-(const vec3f& o) const { return {x - o.x, y - o.y, z - o.z}; }
  vec3f operator*(float s) const { return {x * s, y * s, z * s}; }
  friend bool operator==(const vec3f&, const vec3f&) = default;
};
inline float dot(const vec3f& a, const vec3f& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline float length_squared(const vec3f& a) { return dot(a, a); }
inline float distance(const vec3f& a, const vec3f& b) { return std::sqrt(length_squared(a - b)); }
inline vec3f midpoint(const vec3f& a, const vec3f& b) { return {(a.x + b.x) * 0.5f, (a.y + b.y) * 0.5f, (a.z + b.z) * 0.5f}; }

// The closest point of a triangle and its barycentric weights: point = (1-v-w) a + v b + w c.
struct TrianglePoint {
  vec3f point;
  float v = 0, w = 0;
  float distance_squared = 0;
};

namespace detail {
inline TrianglePoint on_segment(const vec3f& p, const vec3f& a, const vec3f& b, float& t) {
  const vec3f ab = b - a;
  const float len2 = length_squared(ab);
  t = len2 > 0 ? std::clamp(dot(p - a, ab) / len2, 0.0f, 1.0f) : 0.0f;
  TrianglePoint r;
  r.point = a + ab * t;
  r.distance_squared = length_squared(p - r.point);
  return r;
}
}  // namespace detail

// Always inlined: the BVH scans call it millions of times per compare, and a call costs a tenth of it.
[[gnu::always_inline]] inline TrianglePoint closest_on_triangle(const vec3f& p, const vec3f& a, const vec3f& b,
                                                             const vec3f& c) {
  TrianglePoint r;
  auto done = [&](const vec3f& q, float v, float w) {
    r.point = q, r.v = v, r.w = w;
    r.distance_squared = length_squared(p - q);
    return r;
  };
  const vec3f ab = b - a, ac = c - a, ap = p - a;
  const float d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return done(a, 0, 0);
  const vec3f bp = p - b;
  const float d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return done(b, 1, 0);
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const float len = d1 - d3;  // |ab|^2; zero only when a == b
    const float v = len > 0 ? d1 / len : 0;
    return done(a + ab * v, v, 0);
  }
  const vec3f cp = p - c;
  const float d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return done(c, 0, 1);
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const float len = d2 - d6;  // |ac|^2
    const float w = len > 0 ? d2 / len : 0;
    return done(a + ac * w, 0, w);
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const float len = (d4 - d3) + (d5 - d6);  // |bc|^2
    const float w = len > 0 ? (d4 - d3) / len : 0;
    return done(b + (c - b) * w, 1 - w, w);
  }
  const float denom = va + vb + vc;
  if (denom > 0 && va >= 0 && vb >= 0 && vc >= 0) {
    const float v = vb / denom, w = vc / denom;
    return done(a + ab * v + ac * w, v, w);
  }
  // A degenerate (collinear) triangle, or rounding that left no region: the closest of the edges.
  float t0, t1, t2;
  TrianglePoint e0 = detail::on_segment(p, a, b, t0);
  e0.v = t0;
  TrianglePoint e1 = detail::on_segment(p, b, c, t1);
  e1.v = 1 - t1, e1.w = t1;
  TrianglePoint e2 = detail::on_segment(p, a, c, t2);
  e2.w = t2;
  TrianglePoint best = e0;
  if (e1.distance_squared < best.distance_squared) best = e1;
  if (e2.distance_squared < best.distance_squared) best = e2;
  return best;
}

}  // namespace lod::measure
