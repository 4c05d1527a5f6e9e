// Internal: Hoppe's (1999) attribute quadrics, one per wedge.
//
// On a face, each weighted attribute value is linear in position: s(p) = g.p + d. A wedge sums, over
// its faces, area * (g.p + d - s)^2 for every channel. Minimising over s gives
//   s*(p) = (G.p + D) / a,   G = sum area*g, D = sum area*d, a = sum area,
// and leaves a quadric in p alone: A - sum G G^T / a, b - sum G D / a, c - sum D^2 / a. Summed over the
// wedges of a collapse it joins the position quadric, so the solve stays 3x3 and the attribute
// values follow from s*(p). Stored per wedge: 11 floats (A, b, c, a) plus 4 per channel float.
#pragma once

#include <vector>

#include "simplify/metric.h"

namespace lod::collapse {

class AttributeQuadrics {
 public:
  explicit AttributeQuadrics(std::vector<Channel> channels) : channels_(std::move(channels)) {
    for (const Channel& c : channels_) floats_ += c.size;
    stride_ = 11 + 4 * floats_;
  }
  bool empty() const { return floats_ == 0; }
  uint32_t floats() const { return floats_; }
  const std::vector<Channel>& channels() const { return channels_; }

  void allocate(size_t wedges) {
    if (!empty()) data_.assign(wedges * stride_, 0.0f);
  }

  // Rebuilds the quadrics of every wedge of position u from its current faces.
  void rebuild_position(const State& state, uint32_t u) {
    const auto star = state.triangles_of(u);
    for (const uint32_t t : star)
      for (uint32_t k = 0; k < 3; ++k)
        if (state.corner_position(t, k) == u) std::fill_n(at(state.corners[3 * t + k]), stride_, 0.0f);
    thread_local std::vector<double> g, d;  // scratch: rebuilds run per position, in parallel
    g.assign(3 * floats_, 0.0), d.assign(floats_, 0.0);
    for (const uint32_t t : star) {
      vec3d p[3];
      for (uint32_t k = 0; k < 3; ++k) p[k] = state.normalized(state.corner_position(t, k));
      const vec3d e1 = p[1] - p[0], e2 = p[2] - p[0], n = cross(e1, e2);
      const double n2 = length_squared(n);
      if (!(n2 > 0)) continue;
      const double area = 0.5 * std::sqrt(n2);
      const vec3d u1 = cross(e2, n) * (1.0 / n2), u2 = cross(n, e1) * (1.0 / n2);
      uint32_t f = 0;
      for (const Channel& c : channels_)
        for (uint32_t i = 0; i < c.size; ++i, ++f) {
          double s[3];
          for (uint32_t k = 0; k < 3; ++k)
            s[k] = c.weight * state.attributes[size_t(state.corners[3 * t + k]) * state.layout.stride + c.offset + i];
          const vec3d grad = u1 * (s[1] - s[0]) + u2 * (s[2] - s[0]);
          g[3 * f] = grad.x, g[3 * f + 1] = grad.y, g[3 * f + 2] = grad.z;
          d[f] = s[0] - dot(grad, p[0]);
        }
      for (uint32_t k = 0; k < 3; ++k)
        if (state.corner_position(t, k) == u) accumulate(at(state.corners[3 * t + k]), area, g, d);
    }
  }

  // Adds, for every wedge kept will have, the reduced quadric of its merged attribute quadrics.
  void add_merged(const EdgeQuery& edge, core::QuadricD& q) const {
    thread_local std::vector<double> merged;
    for (const uint32_t a : edge.kept_wedges) {
      const float* src = at(a);
      merged.assign(src, src + stride_);
      for (size_t i = 0; i < edge.wedges.size(); ++i)
        if (edge.wedges[i].to == a && first_pair(edge, i)) {
          const float* other = at(edge.wedges[i].from);
          for (uint32_t j = 0; j < stride_; ++j) merged[j] += other[j];
        }
      add_reduced(merged.data(), q);
    }
  }

  void merge(std::span<const WedgePair> pairs) {
    if (empty()) return;
    for (size_t i = 0; i < pairs.size(); ++i) {
      bool seen = false;
      for (size_t j = 0; j < i; ++j) seen |= pairs[j].from == pairs[i].from && pairs[j].to == pairs[i].to;
      if (seen) continue;
      float* to = at(pairs[i].to);
      const float* from = at(pairs[i].from);
      for (uint32_t j = 0; j < stride_; ++j) to[j] += from[j];
    }
  }

  // s*(p) per channel float, unweighted; leaves `out` alone where the wedge has no area.
  void optimal_values(uint32_t wedge, const vec3d& p, float* out) const {
    if (empty()) return;
    const float* q = at(wedge);
    const double area = q[10];
    if (!(area > 0)) return;
    uint32_t f = 0;
    for (const Channel& c : channels_)
      for (uint32_t i = 0; i < c.size; ++i, ++f) {
        const float* G = q + 11 + 3 * f;
        const double s = (G[0] * p.x + G[1] * p.y + G[2] * p.z + q[11 + 3 * floats_ + f]) / area;
        out[f] = float(s / c.weight);
      }
  }

 private:
  float* at(uint32_t wedge) { return data_.data() + size_t(wedge) * stride_; }
  const float* at(uint32_t wedge) const { return data_.data() + size_t(wedge) * stride_; }

  // Pairs repeat per material; merge each (from, to) once.
  static bool first_pair(const EdgeQuery& edge, size_t i) {
    for (size_t j = 0; j < i; ++j)
      if (edge.wedges[j].from == edge.wedges[i].from && edge.wedges[j].to == edge.wedges[i].to) return false;
    return true;
  }

  void accumulate(float* q, double area, const std::vector<double>& g, const std::vector<double>& d) const {
    for (uint32_t f = 0; f < floats_; ++f) {
      const double gx = g[3 * f], gy = g[3 * f + 1], gz = g[3 * f + 2];
      q[0] += float(area * gx * gx), q[1] += float(area * gx * gy), q[2] += float(area * gx * gz);
      q[3] += float(area * gy * gy), q[4] += float(area * gy * gz), q[5] += float(area * gz * gz);
      q[6] += float(area * gx * d[f]), q[7] += float(area * gy * d[f]), q[8] += float(area * gz * d[f]);
      q[9] += float(area * d[f] * d[f]);
      q[11 + 3 * f] += float(area * gx), q[12 + 3 * f] += float(area * gy), q[13 + 3 * f] += float(area * gz);
      q[11 + 3 * floats_ + f] += float(area * d[f]);
    }
    q[10] += float(area);
  }

  void add_reduced(const double* m, core::QuadricD& q) const {
    const double area = m[10];
    if (!(area > 0)) return;
    double r[10] = {m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8], m[9]};
    for (uint32_t f = 0; f < floats_; ++f) {
      const double gx = m[11 + 3 * f], gy = m[12 + 3 * f], gz = m[13 + 3 * f], d = m[11 + 3 * floats_ + f];
      r[0] -= gx * gx / area, r[1] -= gx * gy / area, r[2] -= gx * gz / area;
      r[3] -= gy * gy / area, r[4] -= gy * gz / area, r[5] -= gz * gz / area;
      r[6] -= gx * d / area, r[7] -= gy * d / area, r[8] -= gz * d / area;
      r[9] -= d * d / area;
    }
    q.a00 += r[0], q.a01 += r[1], q.a02 += r[2], q.a11 += r[3], q.a12 += r[4], q.a22 += r[5];
    q.b0 += r[6], q.b1 += r[7], q.b2 += r[8], q.c += r[9];
  }

  std::vector<Channel> channels_;
  uint32_t floats_ = 0, stride_ = 11;
  std::vector<float> data_;
};

}  // namespace lod::collapse
