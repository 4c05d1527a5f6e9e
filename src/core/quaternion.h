// Internal: unit quaternions (x, y, z, w) as glTF stores rotations; shared by the skinning code and
// the glTF writer's key reduction.
#pragma once

#include <algorithm>
#include <cmath>

#include "lodkit/mesh.h"

namespace lod::core {

// Unit length; a zero or non-finite quaternion becomes the identity rather than NaNs in every matrix.
inline float4 normalized(const float4& q) {
  const double len = std::sqrt(double(q.x) * q.x + double(q.y) * q.y + double(q.z) * q.z + double(q.w) * q.w);
  if (!(len > 0) || !std::isfinite(len)) return {0, 0, 0, 1};
  return {float(q.x / len), float(q.y / len), float(q.z / len), float(q.w / len)};
}

// Spherical interpolation along the shorter arc (q and -q are the same rotation).
inline float4 slerp(const float4& a, const float4& b_in, float t) {
  double b[4] = {b_in.x, b_in.y, b_in.z, b_in.w};
  double d = double(a.x) * b[0] + double(a.y) * b[1] + double(a.z) * b[2] + double(a.w) * b[3];
  if (d < 0) {
    for (double& c : b) c = -c;
    d = -d;
  }
  double wa = 1 - t, wb = t;
  // Nearly parallel: sin(theta) ~ 0, and the chord is the arc to float precision.
  if (d < 0.9999) {
    const double theta = std::acos(std::min(d, 1.0));
    const double s = std::sin(theta);
    wa = std::sin((1 - t) * theta) / s;
    wb = std::sin(t * theta) / s;
  }
  return normalized({float(wa * a.x + wb * b[0]), float(wa * a.y + wb * b[1]), float(wa * a.z + wb * b[2]),
                     float(wa * a.w + wb * b[3])});
}

// The angle in radians between the rotations two unit quaternions make (q and -q alike). From the
// chord and its complement, 4 atan2(|a - b|, |a + b|): 2 acos(a . b) would lose small angles to
// rounding (acos(1 - 1e-7) is 4.5e-4).
inline double rotation_angle(const float4& a, const float4& b) {
  const double d = double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z + double(a.w) * b.w, s = d < 0 ? -1 : 1;
  const double dx = a.x - s * b.x, dy = a.y - s * b.y, dz = a.z - s * b.z, dw = a.w - s * b.w;
  const double px = a.x + s * b.x, py = a.y + s * b.y, pz = a.z + s * b.z, pw = a.w + s * b.w;
  return 4 * std::atan2(std::sqrt(dx * dx + dy * dy + dz * dz + dw * dw), std::sqrt(px * px + py * py + pz * pz + pw * pw));
}

}  // namespace lod::core
