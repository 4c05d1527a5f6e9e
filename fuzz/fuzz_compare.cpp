// libFuzzer harness for lod::compare's certified bound (the refinement: corner, piecewise and prism
// bounds, 1 -> 4 splits and needle bisections). The input describes two small meshes on a grid of
// 1/16 steps, which makes flat, coincident, folded and needle-shaped pieces common:
//
//   byte 0: options (bits 0-1 the budget: 30, 300, 3,000 or 30,000 queries; bit 2 the edge samples;
//           bits 3-4 the area samples: 3, 30, 300 or 3,000)
//   byte 1: vertices of a (3..34), byte 2: its triangles (1..32); the same for b in bytes 3 and 4
//   then per vertex three signed bytes (x, y, z in 1/16), a's then b's, then per triangle three
//   bytes (corners, modulo the vertex count), a's then b's.
//
// compare() may refuse the meshes only with lod::Error(bad_input). Otherwise its bound must hold
// what a dense scan finds: for each direction, points on a barycentric grid of every triangle against
// every triangle of the other mesh, in double precision with this file's own point-triangle distance.
// The bound may fall short of that only by float rounding; and the largest sampled distance must not
// exceed the bound.
#include <algorithm>
#include <array>
#include <cmath>

#include "fuzz_common.h"
#include "lodkit/measure.h"

namespace {

using D3 = std::array<double, 3>;

D3 sub(const D3& a, const D3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const D3& a, const D3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
D3 cross(const D3& a, const D3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

double segment_distance(const D3& p, const D3& a, const D3& b) {
  const D3 ab = sub(b, a), ap = sub(p, a);
  const double len2 = dot(ab, ab);
  const double t = len2 > 0 ? std::clamp(dot(ap, ab) / len2, 0.0, 1.0) : 0.0;
  const D3 q{a[0] + t * ab[0] - p[0], a[1] + t * ab[1] - p[1], a[2] + t * ab[2] - p[2]};
  return std::sqrt(dot(q, q));
}

// The distance from p to the triangle: its plane's where the foot lies inside, else the nearest edge.
double triangle_distance(const D3& p, const D3& a, const D3& b, const D3& c) {
  double d = std::min({segment_distance(p, a, b), segment_distance(p, b, c), segment_distance(p, c, a)});
  const D3 n = cross(sub(b, a), sub(c, a));
  const double n2 = dot(n, n);
  if (n2 > 0) {
    const bool inside = dot(cross(sub(b, a), sub(p, a)), n) >= 0 && dot(cross(sub(c, b), sub(p, b)), n) >= 0 &&
                        dot(cross(sub(a, c), sub(p, c)), n) >= 0;
    if (inside) d = std::min(d, std::fabs(dot(sub(p, a), n)) / std::sqrt(n2));
  }
  return d;
}

D3 position(const lod::Mesh& m, uint32_t v) {
  const lod::float3& p = m.positions[v];
  return {p.x, p.y, p.z};
}

// The largest distance from points on a grid over each triangle of `from` to the surface `to`.
double dense_max(const lod::Mesh& from, const lod::Mesh& to, int n) {
  double worst = 0;
  for (size_t t = 0; t < from.triangle_count(); ++t) {
    const D3 a = position(from, from.indices[3 * t]), b = position(from, from.indices[3 * t + 1]),
             c = position(from, from.indices[3 * t + 2]);
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const double u = double(i) / n, v = double(j) / n, w = 1 - u - v;
        const D3 p{w * a[0] + u * b[0] + v * c[0], w * a[1] + u * b[1] + v * c[1], w * a[2] + u * b[2] + v * c[2]};
        double best = std::numeric_limits<double>::infinity();
        for (size_t s = 0; s < to.triangle_count(); ++s)
          best = std::min(best, triangle_distance(p, position(to, to.indices[3 * s]), position(to, to.indices[3 * s + 1]),
                                                  position(to, to.indices[3 * s + 2])));
        worst = std::max(worst, best);
      }
  }
  return worst;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace lod;
  if (size < 5) return 0;
  const uint8_t options = data[0];
  const uint32_t va = 3 + data[1] % 32, ta = 1 + data[2] % 32, vb = 3 + data[3] % 32, tb = 1 + data[4] % 32;
  if (size < 5 + 3 * (va + vb) + 3 * (ta + tb)) return 0;
  const uint8_t* p = data + 5;
  Mesh meshes[2];
  for (int m = 0; m < 2; ++m)
    for (uint32_t v = 0; v < (m ? vb : va); ++v, p += 3)
      meshes[m].positions.push_back({float(int8_t(p[0])) / 16, float(int8_t(p[1])) / 16, float(int8_t(p[2])) / 16});
  for (int m = 0; m < 2; ++m) {
    const uint32_t count = m ? vb : va;
    for (uint32_t t = 0; t < (m ? tb : ta); ++t, p += 3)
      for (int k = 0; k < 3; ++k) meshes[m].indices.push_back(p[k] % count);
  }
  const uint64_t budgets[] = {30, 300, 3'000, 30'000}, samples[] = {3, 30, 300, 3'000};
  CompareOptions o;
  o.refine = true;
  o.refine_budget = budgets[options & 3];
  o.edge_samples = options & 4;
  o.samples = samples[(options >> 3) & 3];
  o.refine_tolerance = 1e-5f;
  o.attributes = false;
  o.threads = 1;
  const auto d = fuzz::run_step("compare", true, [&] { return compare(meshes[0], meshes[1], o); });
  if (!d) return 0;
  const double slack = 1e-5 * (1 + d->diagonal);  // float rounding of the points and distances
  const double dense[2] = {dense_max(meshes[0], meshes[1], 12), dense_max(meshes[1], meshes[0], 12)};
  const OneSidedDeviation* sides[2] = {&d->a_to_b, &d->b_to_a};
  for (int s = 0; s < 2; ++s) {
    if (sides[s]->max_bound < dense[s] - slack)
      fuzz::fail("compare", std::string(s ? "b to a" : "a to b") + ": bound " + std::to_string(sides[s]->max_bound) +
                                " below a dense scan's " + std::to_string(dense[s]));
    if (!(sides[s]->max <= sides[s]->max_bound))
      fuzz::fail("compare", "the largest sampled distance exceeds the bound");
  }
  if (!(d->hausdorff_bound >= std::max(sides[0]->max_bound, sides[1]->max_bound)))
    fuzz::fail("compare", "the symmetric bound is below a one-sided one");
  return 0;
}
