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

// A triangle made ready for closest-point queries: its first corner, its two edges from there, their
// squared lengths and its unit normal. One cache line; the BVH keeps one per triangle, so a query's work
// per triangle is a few dot products for the region and one for the distance to the plane.
struct alignas(64) PreparedTriangle {
  vec3f a, ab, ac;
  vec3f normal;  // unit, from doubles; zero for a degenerate triangle
  float ab2 = 0, ac2 = 0;  // |ab|^2, |ac|^2
  float det = 0;  // |ab|^2 |ac|^2 - (ab . ac)^2 (from doubles); 0 for a degenerate triangle: no face region
};

inline PreparedTriangle prepare_triangle(const vec3f& a, const vec3f& b, const vec3f& c) {
  PreparedTriangle t;
  t.a = a, t.ab = b - a, t.ac = c - a;
  t.ab2 = dot(t.ab, t.ab), t.ac2 = dot(t.ac, t.ac);
  const double ux = t.ab.x, uy = t.ab.y, uz = t.ab.z, vx = t.ac.x, vy = t.ac.y, vz = t.ac.z;
  const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
  const double length = std::sqrt(nx * nx + ny * ny + nz * nz);
  const double scale = std::max({std::fabs(ux), std::fabs(uy), std::fabs(uz), std::fabs(vx), std::fabs(vy), std::fabs(vz)});
  // Degenerate to rounding (a sliver whose normal would be noise): edges and corners only.
  if (length > 1e-6 * scale * scale) {
    t.normal = {float(nx / length), float(ny / length), float(nz / length)};
    t.det = float(length * length);  // |ab x ac|^2 = |ab|^2 |ac|^2 - (ab . ac)^2
  }
  return t;
}

namespace detail {
// The closest point of segment [p0, p0 + e] to the point at offset q from p0: parameter and squared distance.
inline float on_segment(const vec3f& q, const vec3f& e, float& s) {
  const float len2 = length_squared(e);
  s = len2 > 0 ? std::clamp(dot(q, e) / len2, 0.0f, 1.0f) : 0.0f;
  return length_squared(q - e * s);
}
// A degenerate triangle, or rounding that left a point in no region: the closest of the three edges
// (ap = p - a). On ties the first edge in the order ab, bc, ac.
[[gnu::noinline]] inline TrianglePoint closest_on_edges(const vec3f& ap, const PreparedTriangle& t) {
  float s0, s1, s2;
  const vec3f bc = t.ac - t.ab;
  const float e0 = on_segment(ap, t.ab, s0), e1 = on_segment(ap - t.ab, bc, s1), e2 = on_segment(ap, t.ac, s2);
  TrianglePoint r;
  if (e0 <= e1 && e0 <= e2) {
    r.point = t.a + t.ab * s0, r.v = s0, r.distance_squared = e0;
  } else if (e1 <= e2) {
    r.point = t.a + t.ab + bc * s1, r.v = 1 - s1, r.w = s1, r.distance_squared = e1;
  } else {
    r.point = t.a + t.ac * s2, r.w = s2, r.distance_squared = e2;
  }
  return r;
}
}  // namespace detail

namespace detail {
// The triangle's edges turned a quarter in its plane, pointing inwards (unit normal x edge). The
// point's side of edge ab is m.ab . (p - a): Ericson's vc = |ab|^2 ac.ap - (ab.ac)(ab.ap), divided by the
// normal's length, but from one dot product. His form cancels two products of size |ab|^2 |ac| |ap|
// to leave one of size |ab| |ac| sin(angle) |ap|: on a sliver that loses every digit, and a point of
// the face next to a long edge fell into an edge region (3.8e-4 too far on a 1.5-long sliver).
struct EdgeNormals {
  vec3f ab, ac, bc;
};
inline vec3f cross(const vec3f& a, const vec3f& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
[[gnu::always_inline]] inline EdgeNormals edge_normals(const PreparedTriangle& t) {
  return {cross(t.normal, t.ab), cross(t.ac, t.normal), cross(t.normal, t.ac - t.ab)};
}

// The exact closest point (Ericson's Voronoi regions, tested in his order: corner a, b, edge ab,
// corner c, edge ac, edge bc, face). A face point's distance is its distance to the plane. With
// want_point false only the squared distance is set (the same bits).
template <bool want_point>
[[gnu::always_inline]] inline TrianglePoint closest_on_triangle(const vec3f& p, const PreparedTriangle& t) {
  TrianglePoint r;
  const vec3f ap = p - t.a;
  auto done = [&](const vec3f& offset, float v, float w) {  // offset: the point's, from a
    r.point = t.a + offset, r.v = v, r.w = w;
    r.distance_squared = length_squared(ap - offset);
    return r;
  };
  // Ericson's regions assume a proper triangle (with a == b, say, the "edge ab" region would take
  // points of edge ac).
  if (!(t.det > 0)) [[unlikely]] return detail::closest_on_edges(ap, t);
  const float d1 = dot(t.ab, ap), d2 = dot(t.ac, ap);
  if (d1 <= 0 && d2 <= 0) return done({0, 0, 0}, 0, 0);
  // Dot products with p - b and p - c rather than d1 - |ab|^2 and the like: those cancel on a long
  // sliver and moved the foot on its short edge bc (5e-6 on a 2.9-long sliver).
  const vec3f bp = ap - t.ab, cp = ap - t.ac;
  const float d3 = dot(t.ab, bp), d4 = dot(t.ac, bp);  // ab . (p - b), ac . (p - b)
  if (d3 >= 0 && d4 <= d3) return done(t.ab, 1, 0);
  const EdgeNormals m = edge_normals(t);
  const float vc = dot(m.ab, ap);
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const float v = d1 / t.ab2;  // det > 0: no edge has length 0
    return done(t.ab * v, v, 0);
  }
  const float d5 = dot(t.ab, cp), d6 = dot(t.ac, cp);  // ab . (p - c), ac . (p - c)
  if (d6 >= 0 && d5 <= d6) return done(t.ac, 0, 1);
  const float vb = dot(m.ac, ap);
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const float w = d2 / t.ac2;
    return done(t.ac * w, 0, w);
  }
  const float va = dot(m.bc, bp);
  const float e43 = d4 - d3, e56 = d5 - d6;
  if (va <= 0 && e43 >= 0 && e56 >= 0) {
    const float len = e43 + e56;  // |bc|^2
    const float w = len > 0 ? e43 / len : 0;
    const vec3f bc = t.ac - t.ab;
    r.point = t.a + t.ab + bc * w, r.v = 1 - w, r.w = w;
    r.distance_squared = length_squared(bp - bc * w);
    return r;
  }
  if (va >= 0 && vb >= 0 && vc >= 0) {
    const float h = dot(t.normal, ap);
    r.distance_squared = h * h;
    if constexpr (!want_point) return r;
    // The weights from sub-triangle areas in double: vb and vc lose digits to cancellation on thin
    // triangles, which the distance (to the plane) does not need but the point does.
    const double ux = t.ab.x, uy = t.ab.y, uz = t.ab.z, vx = t.ac.x, vy = t.ac.y, vz = t.ac.z;
    const double wx = ap.x, wy = ap.y, wz = ap.z;
    const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    const double n2 = nx * nx + ny * ny + nz * nz;
    const double v = ((wy * vz - wz * vy) * nx + (wz * vx - wx * vz) * ny + (wx * vy - wy * vx) * nz) / n2;
    const double w = ((uy * wz - uz * wy) * nx + (uz * wx - ux * wz) * ny + (ux * wy - uy * wx) * nz) / n2;
    r.v = float(v), r.w = float(w);
    r.point = {float(t.a.x + ux * v + vx * w), float(t.a.y + uy * v + vy * w), float(t.a.z + uz * v + vz * w)};
    return r;
  }
  return detail::closest_on_edges(ap, t);
}
}  // namespace detail

inline TrianglePoint closest_on_triangle(const vec3f& p, const PreparedTriangle& t) {
  return detail::closest_on_triangle<true>(p, t);
}
// Its squared distance alone (what a search needs until it has its answer). Always inlined: the BVH
// calls it millions of times per compare.
[[gnu::always_inline]] inline float closest_distance_squared(const vec3f& p, const PreparedTriangle& t) {
  return detail::closest_on_triangle<false>(p, t).distance_squared;
}

// The same for a triangle given by its corners.
inline TrianglePoint closest_on_triangle(const vec3f& p, const vec3f& a, const vec3f& b, const vec3f& c) {
  return detail::closest_on_triangle<true>(p, prepare_triangle(a, b, c));
}

// The same squared distance for several points against one triangle, a point per lane, branch-free
// (GCC/Clang vector extensions: SSE or AVX on x86-64, NEON on ARM), equal to closest_on_triangle's
// bit for bit: each region's distance is formed by the same float operations, and the region is
// picked in the same order. The point and weights are left to closest_on_triangle, for the one
// winning triangle of a point.
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
namespace detail {
// Functions, not lambdas, so that they take an AVX2 caller's target when inlined.
template <int W>
[[gnu::always_inline]] inline typename Lanes<W>::F norm_lanes(const typename Lanes<W>::F& x, const typename Lanes<W>::F& y,
                                                              const typename Lanes<W>::F& z) {
  return x * x + y * y + z * z;
}
// on_segment's squared distance per lane.
template <int W>
[[gnu::always_inline]] inline typename Lanes<W>::F on_segment_lanes(const typename Lanes<W>::F& qx,
                                                                    const typename Lanes<W>::F& qy,
                                                                    const typename Lanes<W>::F& qz, const vec3f& e) {
  using F = typename Lanes<W>::F;
  const float len2 = length_squared(e);
  F s{};
  if (len2 > 0) {
    s = (qx * e.x + qy * e.y + qz * e.z) / len2;
    s = s < 0 ? F{} : s;
    s = s > 1 ? F{} + 1.0f : s;
  }
  return norm_lanes<W>(qx - e.x * s, qy - e.y * s, qz - e.z * s);
}
// closest_on_edges's squared distance per lane: the least of the three edges'.
template <int W>
[[gnu::always_inline]] inline typename Lanes<W>::F closest_on_edges_lanes(const typename Lanes<W>::F& apx,
                                                                          const typename Lanes<W>::F& apy,
                                                                          const typename Lanes<W>::F& apz,
                                                                          const PreparedTriangle& t) {
  using F = typename Lanes<W>::F;
  const vec3f bc = t.ac - t.ab;
  const F e0 = on_segment_lanes<W>(apx, apy, apz, t.ab);
  const F e1 = on_segment_lanes<W>(apx - t.ab.x, apy - t.ab.y, apz - t.ab.z, bc);
  const F e2 = on_segment_lanes<W>(apx, apy, apz, t.ac);
  const F m = e1 < e2 ? e1 : e2;
  return e0 < m ? e0 : m;
}
}  // namespace detail

// ap = p - t.a per lane, and h = t.normal . ap (the caller's plane test has them already).
template <int W>
[[gnu::always_inline]] inline typename Lanes<W>::F closest_on_triangle_lanes(const typename Lanes<W>::F& apx,
                                                                             const typename Lanes<W>::F& apy,
                                                                             const typename Lanes<W>::F& apz,
                                                                             const typename Lanes<W>::F& h,
                                                                             const PreparedTriangle& t) {
  using F = typename Lanes<W>::F;
  using I = typename Lanes<W>::I;
  const vec3f ab = t.ab, ac = t.ac, bc = t.ac - t.ab;
  const F zero{};
  if (!(t.det > 0)) [[unlikely]] return detail::closest_on_edges_lanes<W>(apx, apy, apz, t);
  const F d1 = ab.x * apx + ab.y * apy + ab.z * apz, d2 = ac.x * apx + ac.y * apy + ac.z * apz;
  const F bpx = apx - ab.x, bpy = apy - ab.y, bpz = apz - ab.z, cpx = apx - ac.x, cpy = apy - ac.y, cpz = apz - ac.z;
  const F d3 = ab.x * bpx + ab.y * bpy + ab.z * bpz, d4 = ac.x * bpx + ac.y * bpy + ac.z * bpz;
  const F d5 = ab.x * cpx + ab.y * cpy + ab.z * cpz, d6 = ac.x * cpx + ac.y * cpy + ac.z * cpz;
  const detail::EdgeNormals en = detail::edge_normals(t);
  const F vc = en.ab.x * apx + en.ab.y * apy + en.ab.z * apz, vb = en.ac.x * apx + en.ac.y * apy + en.ac.z * apz;
  const F va = en.bc.x * bpx + en.bc.y * bpy + en.bc.z * bpz;
  const F e43 = d4 - d3, e56 = d5 - d6;

  // The regions from the last tested to the first, each overriding the ones after it; a region no
  // lane is in is skipped (points of a group mostly share one or two regions).
  const I in_face = (va >= 0) & (vb >= 0) & (vc >= 0);
  I found = in_face;
  F d = h * h;
  auto take = [&](const I& m, const F& distance) {
    d = m ? distance : d;
    found |= m;
  };
  if (const I m = (va <= 0) & (e43 >= 0) & (e56 >= 0); any_lane<W>(m)) {
    const F len = e43 + e56, w = len > 0 ? e43 / len : zero;
    take(m, detail::norm_lanes<W>(bpx - bc.x * w, bpy - bc.y * w, bpz - bc.z * w));
  }
  if (const I m = (vb <= 0) & (d2 >= 0) & (d6 <= 0); any_lane<W>(m)) {
    const F w = d2 / t.ac2;
    take(m, detail::norm_lanes<W>(apx - ac.x * w, apy - ac.y * w, apz - ac.z * w));
  }
  if (const I m = (d6 >= 0) & (d5 <= d6); any_lane<W>(m)) take(m, detail::norm_lanes<W>(cpx, cpy, cpz));
  if (const I m = (vc <= 0) & (d1 >= 0) & (d3 <= 0); any_lane<W>(m)) {
    const F v = d1 / t.ab2;
    take(m, detail::norm_lanes<W>(apx - ab.x * v, apy - ab.y * v, apz - ab.z * v));
  }
  if (const I m = (d3 >= 0) & (d4 <= d3); any_lane<W>(m)) take(m, detail::norm_lanes<W>(bpx, bpy, bpz));
  if (const I m = (d1 <= 0) & (d2 <= 0); any_lane<W>(m)) take(m, detail::norm_lanes<W>(apx, apy, apz));
  if (const I none = ~found; any_lane<W>(none)) [[unlikely]] {
    const F e = detail::closest_on_edges_lanes<W>(apx, apy, apz, t);
    d = none ? e : d;
  }
  return d;
}
#pragma GCC diagnostic pop

}  // namespace lod::measure
