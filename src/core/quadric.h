// Internal: the Garland–Heckbert quadric (A, b, c) with its weight. Quadrics can be stored as 11
// floats (Quadric) or doubles (QuadricD) and are evaluated in double.
#pragma once

#include <cmath>

#include "core/vec3d.h"

namespace lod::core {

// Q(p) = p^T A p + 2 b^T p + c, a sum of weighted squared distances to planes; `w` sums the weights
// so that Q(p) / w is a mean squared distance.
// Summed and solved as double.
template <class T>
struct BasicQuadric {
  T a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;
  T b0 = 0, b1 = 0, b2 = 0;
  T c = 0;
  T w = 0;

  template <class U>
  BasicQuadric& operator+=(const BasicQuadric<U>& o) {
    a00 += T(o.a00), a01 += T(o.a01), a02 += T(o.a02), a11 += T(o.a11), a12 += T(o.a12), a22 += T(o.a22);
    b0 += T(o.b0), b1 += T(o.b1), b2 += T(o.b2), c += T(o.c), w += T(o.w);
    return *this;
  }
  template <class U>
  BasicQuadric& add_scaled(const BasicQuadric<U>& o, T s) {
    a00 += T(o.a00) * s, a01 += T(o.a01) * s, a02 += T(o.a02) * s, a11 += T(o.a11) * s;
    a12 += T(o.a12) * s, a22 += T(o.a22) * s;
    b0 += T(o.b0) * s, b1 += T(o.b1) * s, b2 += T(o.b2) * s, c += T(o.c) * s, w += T(o.w) * s;
    return *this;
  }
  template <class U>
  explicit operator BasicQuadric<U>() const {
    return {U(a00), U(a01), U(a02), U(a11), U(a12), U(a22), U(b0), U(b1), U(b2), U(c), U(w)};
  }
};
using Quadric = BasicQuadric<float>;
using QuadricD = BasicQuadric<double>;

// The plane n.p + d = 0 (n unit length), weighted.
inline QuadricD plane_quadric(const vec3d& n, double d, double weight) {
  QuadricD q;
  q.a00 = weight * n.x * n.x, q.a01 = weight * n.x * n.y, q.a02 = weight * n.x * n.z;
  q.a11 = weight * n.y * n.y, q.a12 = weight * n.y * n.z, q.a22 = weight * n.z * n.z;
  q.b0 = weight * d * n.x, q.b1 = weight * d * n.y, q.b2 = weight * d * n.z;
  q.c = weight * d * d;
  q.w = weight;
  return q;
}

template <class T>
vec3d apply_a(const BasicQuadric<T>& q, const vec3d& p) {
  return {q.a00 * p.x + q.a01 * p.y + q.a02 * p.z, q.a01 * p.x + q.a11 * p.y + q.a12 * p.z,
          q.a02 * p.x + q.a12 * p.y + q.a22 * p.z};
}

// Q(p); never negative (rounding can make it slightly so).
template <class T>
double evaluate(const BasicQuadric<T>& q, const vec3d& p) {
  const double value = dot(p, apply_a(q, p)) + 2.0 * (q.b0 * p.x + q.b1 * p.y + q.b2 * p.z) + double(q.c);
  return value > 0 ? value : 0;
}

// The minimiser -A^-1 b, if A is well enough conditioned: the determinant must not be tiny against
// the cube of A's scale, otherwise the "optimum" runs off along a valley (flat or creased regions).
template <class T>
bool optimum(const BasicQuadric<T>& q, vec3d& p) {
  const double a00 = q.a00, a01 = q.a01, a02 = q.a02, a11 = q.a11, a12 = q.a12, a22 = q.a22;
  const double c00 = a11 * a22 - a12 * a12, c01 = a02 * a12 - a01 * a22, c02 = a01 * a12 - a02 * a11;
  const double det = a00 * c00 + a01 * c01 + a02 * c02;
  const double trace = a00 + a11 + a22;
  if (!(trace > 0) || !(std::fabs(det) > 1e-5 * trace * trace * trace / 27.0)) return false;
  const double c11 = a00 * a22 - a02 * a02, c12 = a01 * a02 - a00 * a12, c22 = a00 * a11 - a01 * a01;
  const double inv = -1.0 / det;
  p = {inv * (c00 * q.b0 + c01 * q.b1 + c02 * q.b2), inv * (c01 * q.b0 + c11 * q.b1 + c12 * q.b2),
       inv * (c02 * q.b0 + c12 * q.b1 + c22 * q.b2)};
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

// The minimiser of Q on the segment [a, b]; when Q does not curve along it, the best of the two
// endpoints and the midpoint (Garland–Heckbert's fallback).
template <class T>
vec3d segment_optimum(const BasicQuadric<T>& q, const vec3d& a, const vec3d& b) {
  const vec3d d = b - a;
  const double curvature = dot(d, apply_a(q, d));
  const vec3d grad = apply_a(q, a) + vec3d{double(q.b0), double(q.b1), double(q.b2)};
  if (curvature > 1e-12 * (q.a00 + q.a11 + q.a22) * length_squared(d)) {
    double t = -dot(d, grad) / curvature;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return a + d * t;
  }
  const vec3d mid = (a + b) * 0.5;
  const double ea = evaluate(q, a), eb = evaluate(q, b), em = evaluate(q, mid);
  return em <= ea && em <= eb ? mid : ea <= eb ? a : b;
}

}  // namespace lod::core
