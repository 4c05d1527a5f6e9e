// The closest point on a triangle, region by region by hand, and the BVH against a brute-force scan.
#include "measure/bvh.h"

#include <gtest/gtest.h>

#include <cmath>

#include <algorithm>
#include <numeric>
#include <random>
#include <span>
#include <vector>

#include "core/shapes.h"
#include "measure/triangle_distance.h"

#pragma GCC diagnostic ignored "-Wpsabi"  // eight-lane vectors, in inlined calls only

namespace lod::measure {
namespace {

// Triangle a = origin, b = +x, c = +y: every Voronoi region has a point whose answer is obvious.
TEST(MeasureTriangle, EveryRegionByHand) {
  const vec3f a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  struct Case {
    vec3f p, expected;
    float distance_squared, v, w;
    const char* region;
  };
  const Case cases[] = {
      {{-1, -1, 1}, {0, 0, 0}, 3.0f, 0, 0, "vertex a"},
      {{2, -1, 0}, {1, 0, 0}, 2.0f, 1, 0, "vertex b"},
      {{-0.5f, 2, 0}, {0, 1, 0}, 1.25f, 0, 1, "vertex c"},
      {{0.5f, -1, 0}, {0.5f, 0, 0}, 1.0f, 0.5f, 0, "edge ab"},
      {{-1, 0.5f, 0}, {0, 0.5f, 0}, 1.0f, 0, 0.5f, "edge ac"},
      {{1, 1, 0}, {0.5f, 0.5f, 0}, 0.5f, 0.5f, 0.5f, "edge bc"},
      {{0.25f, 0.25f, 2}, {0.25f, 0.25f, 0}, 4.0f, 0.25f, 0.25f, "face, above"},
      {{0.25f, 0.5f, -3}, {0.25f, 0.5f, 0}, 9.0f, 0.25f, 0.5f, "face, below"},
  };
  for (const Case& k : cases) {
    const TrianglePoint r = closest_on_triangle(k.p, a, b, c);
    EXPECT_FLOAT_EQ(r.point.x, k.expected.x) << k.region;
    EXPECT_FLOAT_EQ(r.point.y, k.expected.y) << k.region;
    EXPECT_FLOAT_EQ(r.point.z, k.expected.z) << k.region;
    EXPECT_FLOAT_EQ(r.distance_squared, k.distance_squared) << k.region;
    EXPECT_FLOAT_EQ(r.v, k.v) << k.region;
    EXPECT_FLOAT_EQ(r.w, k.w) << k.region;
  }
}

TEST(MeasureTriangle, DegenerateTrianglesGiveFiniteAnswers) {
  // All corners equal: the corner.
  const vec3f p{1, 2, 2}, o{0, 0, 0};
  TrianglePoint r = closest_on_triangle(p, o, o, o);
  EXPECT_EQ(r.point, o);
  EXPECT_FLOAT_EQ(r.distance_squared, 9.0f);
  // Collinear corners: the closest point of the segment they span.
  r = closest_on_triangle({1.5f, 1, 0}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0});
  EXPECT_FLOAT_EQ(r.point.x, 1.5f);
  EXPECT_FLOAT_EQ(r.point.y, 0.0f);
  EXPECT_FLOAT_EQ(r.distance_squared, 1.0f);
  r = closest_on_triangle({3, 0, 1}, {0, 0, 0}, {2, 0, 0}, {1, 0, 0});
  EXPECT_FLOAT_EQ(r.point.x, 2.0f);
  EXPECT_FLOAT_EQ(r.distance_squared, 2.0f);
}

// The closest distance in double, computed independently: the plane when the projection falls inside
// the triangle, else the nearest of the three edges.
double reference_distance_squared(const vec3f& pf, const vec3f& af, const vec3f& bf, const vec3f& cf) {
  struct D3 {
    double x, y, z;
  };
  auto d3 = [](const vec3f& v) { return D3{v.x, v.y, v.z}; };
  auto sub = [](D3 u, D3 v) { return D3{u.x - v.x, u.y - v.y, u.z - v.z}; };
  auto dotd = [](D3 u, D3 v) { return u.x * v.x + u.y * v.y + u.z * v.z; };
  const D3 p = d3(pf), a = d3(af), b = d3(bf), c = d3(cf);
  auto segment = [&](D3 s, D3 e) {
    const D3 d = sub(e, s);
    const double len2 = dotd(d, d);
    const double t = len2 > 0 ? std::clamp(dotd(sub(p, s), d) / len2, 0.0, 1.0) : 0.0;
    const D3 q = sub(sub(p, s), D3{d.x * t, d.y * t, d.z * t});
    return dotd(q, q);
  };
  double best = std::min({segment(a, b), segment(b, c), segment(a, c)});
  const D3 u = sub(b, a), v = sub(c, a), w = sub(p, a);
  const D3 n{u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
  const double n2 = dotd(n, n);
  if (n2 > 0) {
    // Barycentrics of the projection from the sub-triangle areas' signs.
    auto cross_dot = [&](D3 e, D3 f) {
      return dotd(D3{e.y * f.z - e.z * f.y, e.z * f.x - e.x * f.z, e.x * f.y - e.y * f.x}, n);
    };
    const double beta = cross_dot(w, v) / n2, gamma = cross_dot(u, w) / n2;
    if (beta >= 0 && gamma >= 0 && beta + gamma <= 1) best = std::min(best, dotd(w, n) * dotd(w, n) / n2);
  }
  return best;
}

// closest_on_triangle agrees with the double-precision reference; its point lies at its distance; and
// the lane version gives its squared distance bit for bit, in every region, on degenerate triangles
// and on points placed on region boundaries (where rounding decides).
template <int W>
void expect_lanes_match_scalar(uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::uniform_int_distribution<int> kind(0, 5);
  auto random_point = [&] { return vec3f{unit(rng), unit(rng), unit(rng)}; };
  for (int trial = 0; trial < 4000; ++trial) {
    vec3f a = random_point(), b = random_point(), c = random_point();
    switch (kind(rng)) {
      case 0: c = a + (b - a) * 0.5f; break;  // collinear
      case 1: b = a; break;                   // two corners equal
      case 2: b = c = a; break;               // a point
      case 3: c = {b.x, b.y, a.z}; break;     // axis-aligned pieces
      case 4: c = a + (b - a) * 0.7f + vec3f{1e-3f, -2e-3f, 1e-3f}; break;  // a sliver
      default: break;
    }
    const PreparedTriangle tri = prepare_triangle(a, b, c);
    typename Lanes<W>::F apx, apy, apz, h;
    vec3f p[W];
    for (int k = 0; k < W; ++k) {
      // Anywhere, on a corner, on an edge, in the plane, and just off an edge.
      const float t = unit(rng) * 0.5f + 0.5f;
      switch ((trial + k) % 5) {
        case 0: p[k] = random_point() * 2.0f; break;
        case 1: p[k] = k % 2 ? a : c; break;
        case 2: p[k] = a + (b - a) * t; break;
        case 3: p[k] = a + (b - a) * t + (c - a) * (1 - t) * 0.5f; break;
        default: p[k] = b + (c - b) * t + vec3f{1e-7f, -1e-7f, 1e-7f}; break;
      }
      const vec3f ap = p[k] - tri.a;
      apx[k] = ap.x, apy[k] = ap.y, apz[k] = ap.z;
      h[k] = tri.normal.x * ap.x + tri.normal.y * ap.y + tri.normal.z * ap.z;
    }
    const typename Lanes<W>::F d = closest_on_triangle_lanes<W>(apx, apy, apz, h, tri);
    for (int k = 0; k < W; ++k) {
      const TrianglePoint expected = closest_on_triangle(p[k], a, b, c);
      ASSERT_EQ(d[k], expected.distance_squared) << "trial " << trial << " lane " << k;
      // Sizes are about 1: a few float ulps of 1, squared distances up to ~30.
      const double reference = reference_distance_squared(p[k], a, b, c);
      ASSERT_NEAR(expected.distance_squared, reference, 1e-5 * (1 + reference)) << "trial " << trial << " lane " << k;
      ASSERT_NEAR(length_squared(p[k] - expected.point), reference, 1e-5 * (1 + reference))
          << "trial " << trial << " lane " << k;
    }
  }
}

TEST(MeasureTriangle, LanesMatchTheScalarFunction) {
  expect_lanes_match_scalar<4>(17);
  expect_lanes_match_scalar<8>(19);
}

// Slivers (a long triangle with a short side, as simplification leaves on a cylinder) with points
// next to an edge, inside or outside: the distance stays within float rounding of the double
// reference's, not just its square within 1e-5. The first two cases are from simplified cylinders:
// a point 6e-8 from the sliver was reported 3.8e-4 away (in the region of edge bc), and a point on
// the short edge 5e-6 away (its foot moved along the edge).
TEST(MeasureTriangle, SliversKeepTheirDistanceToFloatRounding) {
  struct Case {
    vec3f p, a, b, c;
  };
  std::vector<Case> cases = {{{1.4910873f, -0.8856195f, 0.4643783f},
                              {0.0f, -0.919979f, 0.391967f},
                              {1.55172f, -0.885456f, 0.464723f},
                              {1.44828f, -0.885456f, 0.464723f}},
                             {{2.8706875f, 0.2000260f, 0.9797910f},
                              {-7.6875506e-10f, 0.278217f, 0.960518f},
                              {2.7931f, 0.200026f, 0.979791f},
                              {2.89655f, 0.200026f, 0.979791f}}};
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), sign(-1.0f, 1.0f);
  for (int trial = 0; trial < 20000; ++trial) {
    // Long side 0.5-3 in a random direction, width down to 1e-4 of it, the short side anywhere.
    const vec3f a{sign(rng), sign(rng), sign(rng)};
    const vec3f axis = vec3f{sign(rng), sign(rng), sign(rng)} * (0.5f + 2.5f * unit(rng));
    const vec3f side = vec3f{sign(rng), sign(rng), sign(rng)} * (std::pow(10.0f, -1 - 3 * unit(rng)) * 3);
    const vec3f b = a + axis, c = a + axis * unit(rng) + side;
    // Near an edge at barycentrics down to 1e-4 of the way in, or as far out (the edge's or a
    // corner's region), lifted by up to 1e-6.
    float u = std::pow(10.0f, -4 * unit(rng)) * (trial % 2 ? 1 : -1), v = unit(rng) * (1 - u);
    const float weights[3] = {u, v, 1 - u - v};
    const int k = trial % 3;  // which corner is the near one's opposite
    const float wa = weights[k], wb = weights[(k + 1) % 3], wc = weights[(k + 2) % 3];
    const vec3f lift = vec3f{sign(rng), sign(rng), sign(rng)} * 1e-6f;
    cases.push_back({a * wa + b * wb + c * wc + lift, a, b, c});
  }
  for (size_t i = 0; i < cases.size(); ++i) {
    const Case& k = cases[i];
    const double reference = std::sqrt(reference_distance_squared(k.p, k.a, k.b, k.c));
    const double size = std::sqrt(std::max({length_squared(k.b - k.a), length_squared(k.c - k.a)}));
    const TrianglePoint r = closest_on_triangle(k.p, k.a, k.b, k.c);
    // Coordinates up to ~4: about an ulp of the triangle's size (the reference takes the same float
    // inputs); the largest error over these cases is 9e-8 * (1 + size).
    ASSERT_NEAR(std::sqrt(double(r.distance_squared)), reference, 2e-7 * (1 + size)) << "case " << i;
  }
}

// The lowest-index triangle among the closest ones, by scanning them all.
ClosestHit brute_force(const Mesh& m, const vec3f& p) {
  ClosestHit best;
  for (uint32_t t = 0; t < m.triangle_count(); ++t) {
    const TrianglePoint r = closest_on_triangle(p, m.positions[m.indices[3 * t]], m.positions[m.indices[3 * t + 1]],
                                                m.positions[m.indices[3 * t + 2]]);
    if (r.distance_squared < best.distance_squared) {
      best.distance_squared = r.distance_squared;
      best.triangle = t;
      best.point = r.point;
      best.v = r.v, best.w = r.w;
    }
  }
  return best;
}

// With a build order: the tree built by halving it (TriangleBvh's coherent-order constructor). With
// `built_over` (the same triangles elsewhere): the tree built over that mesh, then refitted to m.
void expect_matches_brute_force(const Mesh& m, uint32_t points, uint32_t seed, std::span<const uint32_t> order,
                                const Mesh* built_over);

// closest_group at both lane widths (8 falls back to 4 without AVX2).
void expect_matches_brute_force_both_widths(const Mesh& m, uint32_t points, uint32_t seed,
                                            std::span<const uint32_t> order = {}, const Mesh* built_over = nullptr) {
  for (const unsigned width : {4u, 8u}) {
    SCOPED_TRACE(width);
    TriangleBvh::set_lane_width(width);
    expect_matches_brute_force(m, points, seed, order, built_over);
  }
  TriangleBvh::set_lane_width(0);
}

void expect_matches_brute_force(const Mesh& m, uint32_t points, uint32_t seed, std::span<const uint32_t> order,
                                const Mesh* built_over) {
  const Mesh& first = built_over ? *built_over : m;
  TriangleBvh bvh = order.empty() ? TriangleBvh(first) : TriangleBvh(first, order);
  if (built_over) bvh.refit(m, seed % 2 ? 1 : 0);
  float3 lo, hi;
  bounding_box(m, lo, hi);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(-0.25f, 1.25f), jitter(-0.01f, 0.01f);
  std::uniform_int_distribution<uint32_t> vertex(0, uint32_t(m.vertex_count() - 1)),
      triangle(0, uint32_t(m.triangle_count() - 1));
  for (uint32_t i = 0; i < points; ++i) {
    vec3f p;
    if (i % 2) {  // anywhere around the mesh
      p = {lo.x + (hi.x - lo.x) * unit(rng), lo.y + (hi.y - lo.y) * unit(rng), lo.z + (hi.z - lo.z) * unit(rng)};
    } else {  // close to the surface, where many triangles are nearly as close
      const float3 v = m.positions[vertex(rng)];
      p = {v.x + jitter(rng), v.y + jitter(rng), v.z + jitter(rng)};
    }
    const ClosestHit expected = brute_force(m, p);
    // Any hint: the answer may not depend on where the search starts.
    const ClosestHit got = bvh.closest(p, i % 3 ? triangle(rng) : 0);
    ASSERT_EQ(got.distance_squared, expected.distance_squared) << "point " << i;
    ASSERT_EQ(got.triangle, expected.triangle) << "point " << i;
    ASSERT_EQ(got.point, expected.point) << "point " << i;
    // A bound at or above the answer's distance finds the same answer (ties too); one just below it
    // finds nothing.
    for (const float bound : {expected.distance_squared, 2 * expected.distance_squared + 1e-3f}) {
      const ClosestHit within = bvh.closest(p, i % 3 ? triangle(rng) : 0, bound);
      ASSERT_EQ(within.triangle, expected.triangle) << "point " << i << " bound " << bound;
      ASSERT_EQ(within.point, expected.point) << "point " << i << " bound " << bound;
    }
    if (expected.distance_squared > 0) {
      const float below = std::nextafter(expected.distance_squared, 0.0f);
      const ClosestHit none = bvh.closest(p, i % 3 ? triangle(rng) : 0, below);
      ASSERT_EQ(none.triangle, UINT32_MAX) << "point " << i;
    }
  }

  // Groups: tight clusters (one traversal serves them all) up to clusters spread over the whole mesh
  // (too many candidates: each point falls back to its own query); the answers may not change.
  TriangleBvh::GroupScratch scratch;
  const float extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  const float spreads[] = {1e-4f, 1e-2f, 0.1f, 1.0f};
  std::uniform_int_distribution<uint32_t> size(1, 24);
  for (uint32_t g = 0; g < points / 8; ++g) {
    const float3 c = m.positions[vertex(rng)];
    const float r = spreads[g % 4] * extent;
    std::vector<vec3f> group(size(rng));
    for (vec3f& p : group) p = {c.x + r * jitter(rng) * 100, c.y + r * jitter(rng) * 100, c.z + r * jitter(rng) * 100};
    std::vector<ClosestHit> got(group.size());
    // Every third group with bounds: per point its answer's distance, a looser one, or just below
    // (nothing then).
    std::vector<float> bounds(group.size());
    std::vector<uint8_t> below(group.size(), 0);
    for (size_t i = 0; i < group.size(); ++i) {
      const float d = brute_force(m, group[i]).distance_squared;
      bounds[i] = i % 3 == 0 ? d : i % 3 == 1 ? 4 * d + 1e-3f : std::nextafter(d, 0.0f);
      below[i] = i % 3 == 2 && d > 0;
    }
    const bool bounded = g % 3 == 1;
    bvh.closest_group(group.data(), uint32_t(group.size()), g % 3 ? triangle(rng) : 0, got.data(), scratch,
                      bounded ? bounds.data() : nullptr);
    for (size_t i = 0; i < group.size(); ++i) {
      const ClosestHit expected = brute_force(m, group[i]);
      if (bounded && below[i]) {
        ASSERT_EQ(got[i].triangle, UINT32_MAX) << "group " << g << " point " << i;
        continue;
      }
      bvh.resolve(got[i], group[i]);
      ASSERT_EQ(got[i].distance_squared, expected.distance_squared) << "group " << g << " point " << i;
      ASSERT_EQ(got[i].triangle, expected.triangle) << "group " << g << " point " << i;
      ASSERT_EQ(got[i].point, expected.point) << "group " << g << " point " << i;
      ASSERT_EQ(got[i].v, expected.v) << "group " << g << " point " << i;
      ASSERT_EQ(got[i].w, expected.w) << "group " << g << " point " << i;
    }
  }
}

TEST(MeasureBvh, MatchesBruteForceOnATorus) {
  expect_matches_brute_force_both_widths(shapes::torus(1.0f, 0.3f, 48, 24), 3000, 7);
}

TEST(MeasureBvh, MatchesBruteForceWithTiesAndDegenerateTriangles) {
  // A flat grid twice over (every closest point is tied between two triangles: the lower index must
  // win), plus a zero-area triangle and a triangle far away.
  Mesh m = shapes::grid(24, 24);
  const size_t n = m.indices.size();
  for (size_t i = 0; i < n; ++i) m.indices.push_back(m.indices[i]);
  m.indices.insert(m.indices.end(), {0, 1, 1});
  m.positions.push_back({5, 5, 5});
  m.positions.push_back({6, 5, 5});
  m.positions.push_back({5, 6, 5});
  m.normals.resize(m.positions.size());
  m.uvs[0].resize(m.positions.size());
  const uint32_t v = uint32_t(m.positions.size());
  m.indices.insert(m.indices.end(), {v - 3, v - 2, v - 1});
  expect_matches_brute_force_both_widths(m, 2000, 11);
}

TEST(MeasureBvh, SingleTriangleAndSmallMeshes) {
  Mesh one;
  one.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  one.indices = {0, 1, 2};
  const TriangleBvh bvh(one);
  const ClosestHit h = bvh.closest({0.25f, 0.25f, 1});
  EXPECT_EQ(h.triangle, 0u);
  EXPECT_FLOAT_EQ(h.distance_squared, 1.0f);
  expect_matches_brute_force_both_widths(shapes::icosphere(0), 500, 3);
  expect_matches_brute_force_both_widths(shapes::cube(), 500, 5);
}

TEST(MeasureBvh, LargeMeshStaysShallowAndExact) {
  const Mesh sphere = shapes::icosphere(5);  // 20480 triangles
  const TriangleBvh bvh(sphere);
  EXPECT_LE(bvh.depth(), 16u);
  // The subtrees are built side by side, but the layout may not depend on how many threads did it.
  const TriangleBvh one(sphere, 1), four(sphere, 4);
  EXPECT_EQ(one.node_count(), bvh.node_count());
  EXPECT_EQ(four.node_count(), bvh.node_count());
  EXPECT_EQ(one.depth(), four.depth());
  EXPECT_GE(bvh.node_count(), sphere.triangle_count() / (4 * 8));
  expect_matches_brute_force_both_widths(sphere, 300, 13);
}

// The tree built by halving a given order answers as the SAH tree does, whatever the order: coherent
// (triangles by their centroids' x, then y), reversed, or shuffled (a poor tree, but still exact).
TEST(MeasureBvh, CoherentOrderBuildMatchesBruteForce) {
  const auto orders = [](const Mesh& m) {
    const uint32_t n = uint32_t(m.triangle_count());
    std::vector<uint32_t> by_x(n), reversed(n), shuffled(n);
    std::iota(by_x.begin(), by_x.end(), 0u);
    const auto centroid = [&](uint32_t t, int axis) {
      float sum = 0;
      for (int k = 0; k < 3; ++k) sum += (&m.positions[m.indices[3 * size_t(t) + k]].x)[axis];
      return sum;
    };
    std::sort(by_x.begin(), by_x.end(), [&](uint32_t a, uint32_t b) {
      return std::pair{centroid(a, 0), centroid(a, 1)} < std::pair{centroid(b, 0), centroid(b, 1)};
    });
    std::iota(reversed.rbegin(), reversed.rend(), 0u);
    std::iota(shuffled.begin(), shuffled.end(), 0u);
    std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(5));
    return std::vector{by_x, reversed, shuffled};
  };
  Mesh ties = shapes::grid(16, 16);  // every triangle twice: ties go to the lower index
  const size_t n = ties.indices.size();
  for (size_t i = 0; i < n; ++i) ties.indices.push_back(ties.indices[i]);
  for (const Mesh& m : {shapes::torus(1.0f, 0.3f, 48, 24), ties, shapes::cube()}) {
    int which = 0;
    for (const std::vector<uint32_t>& order : orders(m)) {
      SCOPED_TRACE(which++);
      expect_matches_brute_force_both_widths(m, 600, 17, order);
    }
  }
  // One triangle: a leaf at the root.
  Mesh one;
  one.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  one.indices = {0, 1, 2};
  const uint32_t only[] = {0};
  EXPECT_EQ(TriangleBvh(one, only).closest({0.25f, 0.25f, 1}).triangle, 0u);
}

// A tree refitted to moved positions answers as a scan of the moved mesh does: small moves (a fit's),
// large ones (every vertex anywhere in the box), a scale that changes the boxes' growth, ties, and
// the coherent-order tree. Refitting to other triangles is refused.
TEST(MeasureBvh, RefitToMovedPositionsMatchesBruteForce) {
  const auto moved = [](Mesh m, float amount, float scale, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> move(-amount, amount);
    for (float3& p : m.positions) p = {scale * (p.x + move(rng)), scale * (p.y + move(rng)), scale * (p.z + move(rng))};
    return m;
  };
  const Mesh torus = shapes::torus(1.0f, 0.3f, 48, 24);
  for (const auto& [amount, scale] : {std::pair{0.01f, 1.0f}, {0.5f, 1.0f}, {0.02f, 1000.0f}, {0.0f, 1e-3f}}) {
    SCOPED_TRACE(amount);
    SCOPED_TRACE(scale);
    const Mesh m = moved(torus, amount, scale, 3);
    expect_matches_brute_force_both_widths(m, 1500, 19, {}, &torus);
  }
  Mesh ties = shapes::grid(16, 16);  // every triangle twice: ties go to the lower index
  const size_t n = ties.indices.size();
  for (size_t i = 0; i < n; ++i) ties.indices.push_back(ties.indices[i]);
  Mesh wavy = ties;
  for (float3& p : wavy.positions) p.z = 0.1f * std::sin(7 * p.x) * std::cos(5 * p.y);
  expect_matches_brute_force_both_widths(wavy, 800, 23, {}, &ties);
  std::vector<uint32_t> reversed(torus.triangle_count());
  std::iota(reversed.rbegin(), reversed.rend(), 0u);
  expect_matches_brute_force_both_widths(moved(torus, 0.05f, 1.0f, 9), 800, 29, reversed, &torus);

  TriangleBvh bvh(torus);
  Mesh fewer = torus;
  fewer.indices.resize(fewer.indices.size() - 3);
  EXPECT_ANY_THROW(bvh.refit(fewer));
}

TEST(MeasureBvh, CoherentOrderMustListEveryTriangleOnce) {
  const Mesh m = shapes::cube();  // 12 triangles
  std::vector<uint32_t> order(12);
  std::iota(order.begin(), order.end(), 0u);
  EXPECT_NO_THROW(TriangleBvh(m, order));
  std::vector<uint32_t> twice = order, short_one(order.begin(), order.end() - 1), out_of_range = order;
  twice[3] = 4;
  out_of_range[0] = 12;
  EXPECT_ANY_THROW(TriangleBvh(m, twice));
  EXPECT_ANY_THROW(TriangleBvh(m, short_one));
  EXPECT_ANY_THROW(TriangleBvh(m, out_of_range));
}

}  // namespace
}  // namespace lod::measure
