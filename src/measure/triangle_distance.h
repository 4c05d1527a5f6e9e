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

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

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

// The same answer for several points against one triangle, a point per lane, branch-free (GCC/Clang
// vector extensions: SSE or AVX on x86-64, NEON on ARM). Every lane's squared distance equals
// closest_on_triangle's bit for bit: each region's point is formed by the same float operations, and
// the region is picked in the same order. The point and weights are left to triangle_point_at, for
// the one winning triangle of a point.
template <int W>
struct Lanes;
template <>
struct Lanes<4> {
  typedef float F __attribute__((vector_size(16)));
  typedef int32_t I __attribute__((vector_size(16)));
};
template <>
struct Lanes<8> {
  typedef float F __attribute__((vector_size(32)));
  typedef int32_t I __attribute__((vector_size(32)));
};

// Regions of closest_on_triangle, in its order of tests; `none` when rounding or a degenerate
// triangle left no region (the scalar function is run for that lane).
enum TriangleRegion : int32_t { region_a, region_b, region_ab, region_c, region_ac, region_bc, region_face, region_none };

// closest_on_triangle's squared distance, out of line: the lanes' rare fallback.
[[gnu::noinline]] inline float closest_on_triangle_distance(const vec3f& p, const vec3f& a, const vec3f& b, const vec3f& c) {
  return closest_on_triangle(p, a, b, c).distance_squared;
}

template <int W>
struct LanePoints {
  typename Lanes<W>::F distance_squared;
  typename Lanes<W>::I region;
  typename Lanes<W>::F s, t;  // the region's parameters: v (ab, face) or w (ac, bc), and w (face)
};

// Whether any lane of a comparison's mask is set. Only SSE2 instructions, so that it also serves code
// compiled for AVX2 (which inlines it).
template <int W>
[[gnu::always_inline]] inline bool any_lane(const typename Lanes<W>::I& m) {
#if defined(__SSE2__)
  if constexpr (W == 4) {
    return _mm_movemask_ps(__m128(m)) != 0;
  } else {
    const typename Lanes<4>::I half = __builtin_shufflevector(m, m, 0, 1, 2, 3) | __builtin_shufflevector(m, m, 4, 5, 6, 7);
    return _mm_movemask_ps(__m128(half)) != 0;
  }
#else
  int32_t bits = 0;
  for (int k = 0; k < W; ++k) bits |= m[k];
  return bits != 0;
#endif
}

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"  // 32-byte vectors only cross inlined calls
template <int W>
[[gnu::always_inline]] inline LanePoints<W> closest_on_triangle_lanes(const typename Lanes<W>::F& px,
                                                                     const typename Lanes<W>::F& py,
                                                                     const typename Lanes<W>::F& pz, const vec3f& a,
                                                                     const vec3f& b, const vec3f& c) {
  using F = typename Lanes<W>::F;
  using I = typename Lanes<W>::I;
  const vec3f ab = b - a, ac = c - a, bc = c - b;
  const F zero{};
  auto norm = [](const F& x, const F& y, const F& z) { return x * x + y * y + z * z; };
  const F apx = px - a.x, apy = py - a.y, apz = pz - a.z;
  const F d1 = ab.x * apx + ab.y * apy + ab.z * apz, d2 = ac.x * apx + ac.y * apy + ac.z * apz;
  const F bpx = px - b.x, bpy = py - b.y, bpz = pz - b.z;
  const F d3 = ab.x * bpx + ab.y * bpy + ab.z * bpz, d4 = ac.x * bpx + ac.y * bpy + ac.z * bpz;
  const F cpx = px - c.x, cpy = py - c.y, cpz = pz - c.z;
  const F d5 = ab.x * cpx + ab.y * cpy + ab.z * cpz, d6 = ac.x * cpx + ac.y * cpy + ac.z * cpz;
  const F vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
  const F e43 = d4 - d3, e56 = d5 - d6;

  // The regions from the last tested to the first, each overriding the ones after it.
  LanePoints<W> r;
  const F denom = va + vb + vc;
  const I in_face = (denom > 0) & (va >= 0) & (vb >= 0) & (vc >= 0);
  const F fv = vb / denom, fw = vc / denom;
  r.distance_squared = norm(px - (a.x + ab.x * fv + ac.x * fw), py - (a.y + ab.y * fv + ac.y * fw),
                            pz - (a.z + ab.z * fv + ac.z * fw));
  r.region = in_face ? I{} + int32_t(region_face) : I{} + int32_t(region_none);
  r.s = fv, r.t = fw;
  // A region no lane is in is skipped: its distances would be computed and thrown away (points of a
  // group mostly share one or two regions).
  auto take = [&](const I& m, TriangleRegion region, const F& d, const F& s) {
    r.distance_squared = m ? d : r.distance_squared;
    r.region = m ? I{} + int32_t(region) : r.region;
    r.s = m ? s : r.s;
  };
  if (const I m = (va <= 0) & (e43 >= 0) & (e56 >= 0); any_lane<W>(m)) {
    const F len = e43 + e56, w = len > 0 ? e43 / len : zero;
    take(m, region_bc, norm(px - (b.x + bc.x * w), py - (b.y + bc.y * w), pz - (b.z + bc.z * w)), w);
  }
  if (const I m = (vb <= 0) & (d2 >= 0) & (d6 <= 0); any_lane<W>(m)) {
    const F len = d2 - d6, w = len > 0 ? d2 / len : zero;
    take(m, region_ac, norm(px - (a.x + ac.x * w), py - (a.y + ac.y * w), pz - (a.z + ac.z * w)), w);
  }
  if (const I m = (d6 >= 0) & (d5 <= d6); any_lane<W>(m)) take(m, region_c, norm(cpx, cpy, cpz), zero);
  if (const I m = (vc <= 0) & (d1 >= 0) & (d3 <= 0); any_lane<W>(m)) {
    const F len = d1 - d3, v = len > 0 ? d1 / len : zero;
    take(m, region_ab, norm(px - (a.x + ab.x * v), py - (a.y + ab.y * v), pz - (a.z + ab.z * v)), v);
  }
  if (const I m = (d3 >= 0) & (d4 <= d3); any_lane<W>(m)) take(m, region_b, norm(bpx, bpy, bpz), zero);
  if (const I m = (d1 <= 0) & (d2 <= 0); any_lane<W>(m)) take(m, region_a, norm(apx, apy, apz), zero);
  const I none = r.region == int32_t(region_none);
  if (any_lane<W>(none)) [[unlikely]] {
    for (int k = 0; k < W; ++k)
      if (none[k]) r.distance_squared[k] = closest_on_triangle_distance({px[k], py[k], pz[k]}, a, b, c);
  }
  return r;
}
#pragma GCC diagnostic pop

// closest_on_triangle's answer from a lane of closest_on_triangle_lanes: the same floats.
inline TrianglePoint triangle_point_at(const vec3f& p, const vec3f& a, const vec3f& b, const vec3f& c,
                                       int32_t region, float s, float t, float distance_squared) {
  TrianglePoint r;
  r.distance_squared = distance_squared;
  switch (region) {
    case region_a: r.point = a; break;
    case region_b: r.point = b, r.v = 1; break;
    case region_ab: r.point = a + (b - a) * s, r.v = s; break;
    case region_c: r.point = c, r.w = 1; break;
    case region_ac: r.point = a + (c - a) * s, r.w = s; break;
    case region_bc: r.point = b + (c - b) * s, r.v = 1 - s, r.w = s; break;
    case region_face: r.point = a + (b - a) * s + (c - a) * t, r.v = s, r.w = t; break;
    default: return closest_on_triangle(p, a, b, c);
  }
  return r;
}

}  // namespace lod::measure
