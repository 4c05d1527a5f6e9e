// lod::compare against distances derived by hand: nested cubes, parallel planes, a sphere and its
// inscribed icosphere; refinement bounds against a dense brute-force scan; thread independence.
#include "lodkit/measure.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/simplify.h"
#include "measure/triangle_distance.h"

namespace lod {
namespace {

Mesh scaled(Mesh m, float s) {
  for (float3& p : m.positions) p = {p.x * s, p.y * s, p.z * s};
  return m;
}

Mesh translated(Mesh m, float3 d) {
  for (float3& p : m.positions) p = {p.x + d.x, p.y + d.y, p.z + d.z};
  return m;
}

// The smallest distance from the origin to the plane of any face (all faces of these meshes face
// away from the origin), in double.
double min_plane_distance(const Mesh& m) {
  double best = 1e300;
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    const float3 &a = m.positions[m.indices[3 * t]], &b = m.positions[m.indices[3 * t + 1]],
                 &c = m.positions[m.indices[3 * t + 2]];
    const double ux = double(b.x) - a.x, uy = double(b.y) - a.y, uz = double(b.z) - a.z;
    const double vx = double(c.x) - a.x, vy = double(c.y) - a.y, vz = double(c.z) - a.z;
    const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
    best = std::min(best, std::fabs(nx * a.x + ny * a.y + nz * a.z) / len);
  }
  return best;
}

TEST(MeasureCompare, UnitCubeAgainstTheCubeScaledBy1_1) {
  // a = [-0.5, 0.5]^3, b = [-0.55, 0.55]^3.
  const Mesh a = scaled(shapes::cube(), 0.5f), b = scaled(shapes::cube(), 0.55f);
  const Deviation d = compare(a, b, {.samples = 200'000, .seed = 3});
  const double g = 0.05;  // the gap between parallel faces

  // a -> b: a point of a's surface has max |p_i| = 0.5 and every |p_i| <= 0.5, and its distance to the
  // inside of b's boundary is min_i (0.55 - |p_i|) = 0.05: the same everywhere.
  EXPECT_NEAR(d.a_to_b.max, g, 1e-6);
  EXPECT_NEAR(d.a_to_b.mean, g, 1e-6);
  EXPECT_NEAR(d.a_to_b.rms, g, 1e-6);

  // b -> a: b lies outside a, so its distance to a's surface is the distance to the solid cube,
  // sqrt(sum_i max(|p_i| - 0.5, 0)^2). On b's face x = 0.55 that is sqrt(g^2 + f(|y|)^2 + f(|z|)^2)
  // with f(s) = max(s - 0.5, 0), and |y|, |z| uniform on [0, 0.55] for an area-uniform point.
  // Largest at b's corners: g * sqrt(3).
  EXPECT_NEAR(d.b_to_a.max, g * std::sqrt(3.0), 1e-6);
  // RMS^2 = g^2 + 2 E[f^2] = g^2 + 2 (g^3 / 3) / 0.55 = g^2 (1 + 2/33).
  const double rms = g * std::sqrt(35.0 / 33.0);
  // Mean: with probability (10/11)^2 neither f is positive (distance g); 2 (10/11)(1/11) exactly one
  // is, uniform on [0, g], where E sqrt(g^2 + t^2) = g (sqrt 2 + asinh 1) / 2; (1/11)^2 both are,
  // where the mean is g times the integral of sqrt(1 + x^2 + y^2) over the unit square (Simpson).
  const int n = 400;
  double integral = 0;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const double wi = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2), wj = (j == 0 || j == n) ? 1 : (j % 2 ? 4 : 2);
      const double x = double(i) / n, y = double(j) / n;
      integral += wi * wj * std::sqrt(1 + x * x + y * y);
    }
  integral /= 9.0 * n * n;
  const double mean =
      g * (100.0 / 121 + 20.0 / 121 * (std::sqrt(2.0) + std::asinh(1.0)) / 2 + 1.0 / 121 * integral);
  EXPECT_NEAR(d.b_to_a.rms, rms, 1e-3 * rms);
  EXPECT_NEAR(d.b_to_a.mean, mean, 1e-3 * mean);

  // Symmetric: the larger maximum; mean and RMS over both surfaces (areas 6 and 6 * 1.21).
  EXPECT_NEAR(d.a_to_b.area, 6.0, 1e-5);
  EXPECT_NEAR(d.b_to_a.area, 6.0 * 1.21, 1e-5);
  EXPECT_NEAR(d.hausdorff, g * std::sqrt(3.0), 1e-6);
  EXPECT_NEAR(d.mean, (6 * g + 7.26 * mean) / 13.26, 1e-3 * g);
  EXPECT_NEAR(d.rms, std::sqrt((6 * g * g + 7.26 * rms * rms) / 13.26), 1e-3 * g);

  // Relative to a's diagonal, sqrt(3).
  EXPECT_NEAR(d.diagonal, std::sqrt(3.0), 1e-6);
  EXPECT_NEAR(d.relative_hausdorff, g, 1e-6);
  // The maximum is a corner of b and its closest point the matching corner of a.
  const MaxLocation& at = d.b_to_a.max_location;
  EXPECT_FLOAT_EQ(std::fabs(at.point.x), 0.55f);
  EXPECT_FLOAT_EQ(std::fabs(at.point.y), 0.55f);
  EXPECT_FLOAT_EQ(std::fabs(at.point.z), 0.55f);
  EXPECT_FLOAT_EQ(at.closest.x, std::copysign(0.5f, at.point.x));
  EXPECT_FLOAT_EQ(at.closest.y, std::copysign(0.5f, at.point.y));
  EXPECT_FLOAT_EQ(at.closest.z, std::copysign(0.5f, at.point.z));

  // Sample counts: 8 vertices each; exactly the asked area samples.
  EXPECT_EQ(d.a_to_b.vertex_samples, 8u);
  EXPECT_EQ(d.b_to_a.vertex_samples, 8u);
  EXPECT_NEAR(double(d.a_to_b.area_samples), 200'000.0, 1.0);
  EXPECT_GT(d.a_to_b.edge_samples, 0u);
}

TEST(MeasureCompare, PlaneAgainstTheSamePlaneShiftedByD) {
  const float shift = 0.125f;
  const Mesh a = shapes::grid(10, 10), b = translated(a, {0, 0, shift});
  for (bool refine : {false, true}) {
    const Deviation d = compare(a, b, {.samples = 20'000, .refine = refine});
    for (const OneSidedDeviation* r : {&d.a_to_b, &d.b_to_a}) {
      EXPECT_NEAR(r->max, shift, 1e-6);
      EXPECT_NEAR(r->mean, shift, 1e-6);
      EXPECT_NEAR(r->rms, shift, 1e-6);
      // Every corner's closest triangle holds the whole patch within the same distance: the bound is
      // exact, and nothing needs refining.
      if (refine) {
        EXPECT_NEAR(r->max_bound, shift, 1e-6);
      }
      EXPECT_EQ(r->refined, refine);
    }
    EXPECT_NEAR(d.hausdorff, shift, 1e-6);
    EXPECT_NEAR(d.mean, shift, 1e-6);
    EXPECT_NEAR(d.rms, shift, 1e-6);
    EXPECT_NEAR(d.relative_hausdorff, shift / std::sqrt(2.0), 1e-6);
  }
}

TEST(MeasureCompare, IcosphereAgainstTheSphere) {
  // a = icosphere(1) inscribed in the unit sphere; the sphere is stood in for by icosphere(5), which
  // lies between radii 1 - gap_b and 1. For p on a with |p| = rho, dist(p, b) is between
  // (1 - gap_b) - rho and 1 - rho, and the smallest rho is the nearest face plane: the one-sided
  // Hausdorff distance a -> b lies in [gap_a - gap_b, gap_a] with gap = 1 - min plane distance.
  const Mesh a = shapes::icosphere(1), b = shapes::icosphere(5);
  const double gap_a = 1 - min_plane_distance(a), gap_b = 1 - min_plane_distance(b);
  ASSERT_GT(gap_a, 20 * gap_b);
  const Deviation d =
      compare(a, b, {.samples = 100'000, .refine = true, .refine_tolerance = 1e-5f, .refine_budget = 2'000'000});
  // Sampling misses the top of a smooth maximum by (spacing)^2 / 2, about 1e-4 here.
  EXPECT_GE(d.a_to_b.max, gap_a - gap_b - 2e-4);
  EXPECT_LE(d.a_to_b.max, gap_a + 1e-6);
  // The certified bound holds the true value, and refinement closed in on it.
  EXPECT_GE(d.a_to_b.max_bound, gap_a - gap_b - 1e-6);
  EXPECT_LE(d.a_to_b.max_bound - d.a_to_b.max, 1e-5 * d.diagonal + 1e-6);
  EXPECT_GE(d.a_to_b.max, gap_a - gap_b - 1e-5 * d.diagonal - 1e-6);
  // b -> a: b lies within radius 1 and a's surface at radius >= 1 - gap_a along every ray.
  EXPECT_LE(d.b_to_a.max, gap_a + 1e-6);
  EXPECT_GE(d.b_to_a.max, gap_a - 2 * gap_b - 2e-4);
}

TEST(MeasureCompare, IdenticalMeshesGiveZero) {
  const Mesh m = shapes::icosphere(3);
  const Deviation d = compare(m, m, {.samples = 50'000});
  const double tiny = 1e-6 * d.diagonal;
  EXPECT_LE(d.hausdorff, tiny);
  EXPECT_LE(d.mean, tiny);
  EXPECT_LE(d.rms, tiny);
  // A vertex is its own closest point exactly.
  for (float v : d.vertex_distance) EXPECT_EQ(v, 0.0f);
  EXPECT_TRUE(d.a_to_b.attributes.normals);
  EXPECT_LE(d.a_to_b.attributes.max_normal_angle, 0.01);
}

// A sliver 1e20 times longer than its height: its samples' cell coordinates along the long side
// once passed 2^32 before being clamped to the grid (a float to uint32 conversion out of range,
// undefined; found by fuzz_simplify through the simplifier's search). Against itself: zero.
TEST(MeasureCompare, ExtremeSliverAgainstItself) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1e15f, 0, 0}, {0, 1e-5f, 0}, {0, 0, 1}};
  m.indices = {0, 1, 2, 0, 2, 3};
  const Deviation d = compare(m, m, {.samples = 20'000, .threads = 1});
  EXPECT_TRUE(std::isfinite(d.hausdorff));
  EXPECT_LE(d.hausdorff, 1e-6 * d.diagonal);
}

TEST(MeasureCompare, AttributeDifferencesAtTheClosestPoint) {
  // b is a lifted above itself, with every normal tilted by 30 degrees, UVs shifted by (0.1, 0) and
  // colours halved in red; the closest point of every sample is straight above it, at the same
  // barycentric coordinates.
  Mesh a = shapes::grid(4, 4);
  a.colors.assign(a.vertex_count(), {1, 0, 0, 1});
  Mesh b = translated(a, {0, 0, 0.2f});
  const float angle = 30.0f * std::numbers::pi_v<float> / 180;
  for (float3& n : b.normals) n = {0, std::sin(angle), std::cos(angle)};
  for (float2& uv : b.uvs[0]) uv.x += 0.1f;
  for (float4& c : b.colors) c.x = 0.5f;
  const Deviation d = compare(a, b, {.samples = 5'000});
  for (const OneSidedDeviation* r : {&d.a_to_b, &d.b_to_a}) {
    const AttributeDeviation& at = r->attributes;
    ASSERT_TRUE(at.normals && at.uvs && at.colors);
    EXPECT_NEAR(at.max_normal_angle, 30.0, 1e-3);
    EXPECT_NEAR(at.mean_normal_angle, 30.0, 1e-3);
    // A sample within about d * sqrt(float epsilon) of an edge of b ties in float between the two
    // triangles there, and the other one's closest point sits on the edge: up to ~5e-5 away here.
    EXPECT_NEAR(at.max_uv, 0.1, 1e-4);
    EXPECT_NEAR(at.mean_uv, 0.1, 1e-5);
    EXPECT_NEAR(at.max_color, 0.5, 1e-6);
    EXPECT_NEAR(at.mean_color, 0.5, 1e-6);
  }
  // Streams only one side carries are not compared.
  Mesh bare = b;
  bare.normals.clear();
  bare.colors.clear();
  const Deviation e = compare(a, bare, {.samples = 1'000, .attributes = true});
  EXPECT_FALSE(e.a_to_b.attributes.normals);
  EXPECT_FALSE(e.a_to_b.attributes.colors);
  EXPECT_TRUE(e.a_to_b.attributes.uvs);
}

// The largest distance from a's first triangle to b, by brute force: the points w a0 + u a1 + v a2
// at u, v = i / n, j / n (i + j <= n) against every triangle of b.
double dense_max_distance(const Mesh& a, const Mesh& b, int n) {
  const float3 &a0 = a.positions[a.indices[0]], &a1 = a.positions[a.indices[1]], &a2 = a.positions[a.indices[2]];
  double dense = 0;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j) {
      const float u = float(i) / n, v = float(j) / n, w = 1 - u - v;
      const measure::vec3f p{w * a0.x + u * a1.x + v * a2.x, w * a0.y + u * a1.y + v * a2.y,
                             w * a0.z + u * a1.z + v * a2.z};
      float best = 1e30f;
      for (size_t t = 0; t < b.triangle_count(); ++t)
        best = std::min(best, measure::closest_on_triangle(p, b.positions[b.indices[3 * t]],
                                                           b.positions[b.indices[3 * t + 1]],
                                                           b.positions[b.indices[3 * t + 2]])
                                  .distance_squared);
      dense = std::max(dense, double(std::sqrt(best)));
    }
  return dense;
}

// A bowl (b) under a flat triangle (a): the largest distance is inside the triangle, off every sample.
void bowl_under_triangle(Mesh& a, Mesh& b) {
  a.positions = {{0, 0, 0}, {1, 0, 0}, {0.3f, 0.9f, 0}};
  a.indices = {0, 1, 2};
  b = shapes::grid(24, 24);
  for (float3& p : b.positions) {
    const float x = p.x - 0.43f, y = p.y - 0.31f;
    p.z = -0.3f * std::exp(-(x * x + y * y) * 20) - 0.05f;
  }
  b.normals.clear();
}

TEST(MeasureRefine, BoundHoldsAgainstADenseBruteForceScan) {
  Mesh a, b;
  bowl_under_triangle(a, b);
  const Deviation d = compare(a, b, {.samples = 3, .edge_samples = false, .refine = true,
                                     .refine_tolerance = 1e-4f, .refine_budget = 200'000});
  // The distance over a dense grid of a's points, by brute force over b's triangles.
  const double dense = dense_max_distance(a, b, 200);
  const OneSidedDeviation& r = d.a_to_b;
  EXPECT_TRUE(r.refined);
  EXPECT_GT(r.refine_samples, 0u);
  EXPECT_LE(r.refine_samples, 200'000u);
  EXPECT_GE(r.max_bound, dense - 1e-6);  // the bound holds the true maximum
  EXPECT_LE(r.max, r.max_bound);
  EXPECT_LE(r.max_bound - r.max, 1e-4 * d.diagonal + 1e-6);  // and came within the tolerance
  // The few area samples alone fall clearly short of it.
  const Deviation coarse = compare(a, b, {.samples = 3, .edge_samples = false});
  EXPECT_LT(coarse.a_to_b.max, dense - 1e-3);
  EXPECT_EQ(coarse.a_to_b.max_bound, coarse.a_to_b.max);
}

// The same bowl with a budget too small to close in on the maximum: the patches still open when it
// runs out must count in the bound, which then stays certified, only looser.
TEST(MeasureRefine, BoundHoldsWhenTheBudgetRunsOut) {
  Mesh a, b;
  bowl_under_triangle(a, b);
  const double dense = dense_max_distance(a, b, 200);
  for (const uint64_t budget : {3u, 30u}) {
    const Deviation d = compare(a, b, {.samples = 3, .edge_samples = false, .refine = true,
                                       .refine_tolerance = 1e-5f, .refine_budget = budget});
    const OneSidedDeviation& r = d.a_to_b;
    EXPECT_LE(r.refine_samples, budget);
    EXPECT_LT(r.max, dense - 1e-4) << budget;  // the budget did run out short of the maximum
    EXPECT_GE(r.max_bound, dense - 1e-6) << budget;
    EXPECT_GE(d.hausdorff_bound, dense - 1e-6) << budget;
  }
}

// A big triangle cutting through a finely folded sheet (ridges and valleys along grid lines): every
// patch spans several folds, so no single triangle of b bounds it. The bound must hold the true
// maximum (a dense brute-force scan) and close in on it with a small budget.
TEST(MeasureRefine, FoldedSurfaceIsBoundedTightlyAndSafely) {
  Mesh a;
  a.positions = {{0.05f, 0.05f, 0.005f}, {0.95f, 0.1f, 0.005f}, {0.4f, 0.9f, 0.0055f}};
  a.indices = {0, 1, 2};
  Mesh b = shapes::grid(40, 40);
  for (float3& p : b.positions) {
    const float x = p.x * 40 / 4;  // folds every 4 cells
    const float saw = std::abs(x - 2 * std::round(x / 2));  // 0 .. 1
    p.z = 0.008f * saw + 0.005f * p.y * p.y;
  }
  b.normals.clear();
  const Deviation d = compare(a, b, {.samples = 3, .edge_samples = false, .refine = true,
                                     .refine_tolerance = 1e-5f, .refine_budget = 30'000});
  const double dense = dense_max_distance(a, b, 240);
  const OneSidedDeviation& r = d.a_to_b;
  EXPECT_GE(r.max_bound, dense - 1e-6);
  EXPECT_LE(r.max_bound - r.max, 1e-5 * d.diagonal);
  EXPECT_LE(r.refine_samples, 30'000u);
}

// A simplified surface lies within a fraction of its triangles' size of the original: corners sit on
// the other surface, so the Lipschitz bound (distance + patch size) is far too loose, and a patch
// spans several of the finer surface's triangles. The bound must still come within 5% of the max.
TEST(MeasureRefine, SimplifiedSurfaceBoundIsTight) {
  Mesh a = shapes::torus(1.0f, 0.3f, 96, 48);
  for (float3& p : a.positions) p.z += 0.02f * std::sin(7 * p.x) * std::cos(5 * p.y);  // no symmetry
  a.normals.clear();
  SimplifyOptions so;
  so.target_ratio = 0.25f;
  const Mesh b = simplify(a, so).mesh;
  const Deviation d = compare(a, b, {.refine = true, .refine_tolerance = 1e-5f});
  EXPECT_GE(d.hausdorff_bound, d.hausdorff);
  EXPECT_LE(d.hausdorff_bound, 1.05 * d.hausdorff);
}

// Two triangulations of one surface (a roof: two planes meeting at a ridge), coarse against fine,
// and a flat square against a coarser one lifted by 0.01: faces of one lie on (or parallel to) faces
// of the other, where the distance is flat or constant and the corner values barely vary. The
// bound must close to within the tolerance of the distance in both directions, with a budget
// that suffices for a curved surface: a coarse patch spans many fine triangles, and bounds cut by
// interpolated corner values only shrink with the patch (a CAD cylinder's level, exact to 2.4e-7,
// was bounded at 0.0095 with a 160,000-query budget).
Mesh roof(uint32_t n) {
  Mesh m = shapes::grid(n, n);
  for (float3& p : m.positions) p.z = 0.3f * (0.5f - std::abs(p.x - 0.5f));
  m.normals.clear();
  return m;
}

TEST(MeasureRefine, CoincidentAndParallelFacesAreBoundedTightly) {
  Mesh lifted = shapes::grid(3, 3);
  for (float3& p : lifted.positions) p.z = 0.01f;
  lifted.normals.clear();
  Mesh flat = shapes::grid(40, 40);
  flat.normals.clear();
  const struct {
    Mesh a, b;
    double distance;
  } cases[] = {{roof(40), roof(4), 0.0}, {roof(4), roof(40), 0.0}, {flat, lifted, 0.01}, {lifted, flat, 0.01}};
  for (size_t c = 0; c < std::size(cases); ++c) {
    const float tolerance = 1e-5f;
    const Deviation d = compare(cases[c].a, cases[c].b, {.samples = 2'000, .refine = true, .refine_tolerance = tolerance,
                                                           .refine_budget = 30'000, .attributes = false});
    EXPECT_NEAR(d.hausdorff, cases[c].distance, 1e-6) << c;
    EXPECT_GE(d.hausdorff_bound, d.hausdorff) << c;
    EXPECT_LE(d.hausdorff_bound, d.hausdorff + tolerance * d.diagonal + 1e-6) << c;
    EXPECT_LE(d.a_to_b.refine_samples, 30'000u) << c;
  }
}

// A needle (1 long, 0.002 wide) on a flat sheet of 400 x 4 cells: the distance is 0, and a piece of
// the needle is bounded by it once it spans a cell or two. Split 1 -> 4, the needle's children stay
// needles and that takes 4^8 patches; bisected, a few thousand. The bound must close within the
// budget. Then the sheet dips under x = 0.63, off the few samples: the bound must hold a dense
// scan's maximum there (the needle's far half lies in one child of its first bisection only: both
// children must count).
TEST(MeasureRefine, ANeedleIsBoundedWithinTheBudget) {
  Mesh a;
  a.positions = {{0.0f, 0.501f, 0.0f}, {1.0f, 0.5f, 0.0f}, {0.001f, 0.503f, 0.0f}};
  a.indices = {0, 1, 2};
  Mesh b = shapes::grid(400, 4);
  b.normals.clear();
  const float tolerance = 1e-5f;
  const CompareOptions options{.samples = 3, .edge_samples = false, .refine = true, .refine_tolerance = tolerance,
                               .refine_budget = 30'000, .attributes = false};
  const Deviation flat = compare(a, b, options);
  EXPECT_LE(flat.a_to_b.max_bound, flat.a_to_b.max + tolerance * flat.diagonal + 1e-6);
  EXPECT_LE(flat.a_to_b.refine_samples, 30'000u);

  for (float3& p : b.positions) p.z = -0.02f * std::exp(-(p.x - 0.63f) * (p.x - 0.63f) / 0.002f);
  const Deviation dip = compare(a, b, options);
  const double dense = dense_max_distance(a, b, 100);
  EXPECT_GT(dense, 0.015);
  EXPECT_GE(dip.a_to_b.max_bound, dense - 1e-6);
}

// A unit square against the same square as a fan of 128 needles from one corner (a CAD blade's
// lossless levels have such fans: up to 35 coplanar needles 100 long meeting at an apex). The
// distance is 0. Near the apex a patch of the square covers needles none of its corners is closest
// to; bounded by the nearest candidate, the rest of it was off by the gap (the blade's levels:
// 0.0057 after the whole budget, the distance 1e-7). The bound must close.
TEST(MeasureRefine, AFanOfNeedlesIsBoundedWithinTheBudget) {
  Mesh square = shapes::grid(4, 4);
  square.normals.clear();
  square.uvs[0].clear();
  Mesh fan;
  fan.positions.push_back({0, 0, 0});
  constexpr int side = 64;
  for (int i = 0; i <= side; ++i) fan.positions.push_back({1, float(i) / side, 0});
  for (int i = 1; i <= side; ++i) fan.positions.push_back({1 - float(i) / side, 1, 0});
  for (uint32_t i = 1; i + 1 < fan.positions.size(); ++i) fan.indices.insert(fan.indices.end(), {0, i, i + 1});
  const float tolerance = 1e-5f;
  const uint64_t budget = 2'000;
  const Deviation d = compare(square, fan, {.samples = 200, .refine = true, .refine_tolerance = tolerance,
                                            .refine_budget = budget, .attributes = false});
  EXPECT_NEAR(d.hausdorff, 0.0, 1e-6);
  EXPECT_GE(d.hausdorff_bound, d.hausdorff);
  EXPECT_LE(d.a_to_b.max_bound, d.a_to_b.max + tolerance * d.diagonal + 1e-6);
  EXPECT_LE(d.a_to_b.refine_samples, budget);

  // Corrugated (the rim alternately up and down): near the apex the bound must still hold a dense
  // scan's maximum (a soundness check; no recruit fires here, even on a 30-query budget).
  for (size_t i = 1; i < fan.positions.size(); ++i) fan.positions[i].z = (i % 2 ? 0.01f : -0.01f);
  Mesh corner;
  corner.positions = {{0.02f, 0.01f, 0.0f}, {0.3f, 0.05f, 0.0f}, {0.2f, 0.25f, 0.0f}};
  corner.indices = {0, 1, 2};
  const Deviation folded = compare(corner, fan, {.samples = 3, .refine = true, .refine_tolerance = tolerance,
                                                 .refine_budget = budget, .attributes = false});
  const double dense = dense_max_distance(corner, fan, 300);
  EXPECT_GT(dense, 0.001);
  EXPECT_GE(folded.a_to_b.max_bound, dense - 1e-6);
}

TEST(MeasureCompare, SameResultOnAnyThreadCount) {
  const Mesh a = shapes::torus(1.0f, 0.3f, 64, 32), b = shapes::torus(1.02f, 0.28f, 24, 12);
  Deviation first;
  for (unsigned threads : {1u, 2u, 8u}) {
    const Deviation d =
        compare(a, b, {.samples = 60'000, .seed = 9, .refine = true, .refine_budget = 30'000, .threads = threads});
    if (threads == 1) {
      first = d;
      EXPECT_GT(d.a_to_b.refine_samples, 0u);
      continue;
    }
    EXPECT_EQ(d.a_to_b, first.a_to_b) << threads;
    EXPECT_EQ(d.b_to_a, first.b_to_a) << threads;
    EXPECT_EQ(d.hausdorff, first.hausdorff);
    EXPECT_EQ(d.mean, first.mean);
    EXPECT_EQ(d.rms, first.rms);
    EXPECT_EQ(d.hausdorff_bound, first.hausdorff_bound);
    EXPECT_EQ(d.vertex_distance, first.vertex_distance);
    EXPECT_EQ(d.vertex_error, first.vertex_error);
    EXPECT_EQ(d.queries, first.queries);
  }
  // Another seed moves the area samples (and so the mean a little) but not the vertex distances.
  const Deviation other = compare(a, b, {.samples = 60'000, .seed = 10});
  EXPECT_NE(other.a_to_b.mean, first.a_to_b.mean);
  EXPECT_NEAR(other.a_to_b.mean, first.a_to_b.mean, 0.01 * first.a_to_b.mean);
  EXPECT_EQ(other.vertex_distance, first.vertex_distance);
}

TEST(MeasureCompare, VertexErrorFieldPeaksAtTheMaximum) {
  const Mesh a = shapes::torus(1.0f, 0.3f, 48, 24), b = shapes::torus(1.0f, 0.3f, 12, 6);
  const Deviation d = compare(a, b, {.samples = 30'000});
  ASSERT_EQ(d.vertex_error.size(), a.vertex_count());
  float peak = 0;
  for (size_t v = 0; v < a.vertex_count(); ++v) {
    EXPECT_LE(d.vertex_distance[v], d.vertex_error[v]);
    peak = std::max(peak, d.vertex_error[v]);
  }
  EXPECT_EQ(double(peak), d.a_to_b.max);
  // The maximum belongs to the corner of its triangle nearest to it, which is red on the heat map.
  const MaxLocation& at = d.a_to_b.max_location;
  const uint32_t* corner = &a.indices[3 * size_t(at.triangle)];
  uint32_t nearest = corner[0];
  for (int k = 1; k < 3; ++k)
    if (length_squared(measure::vec3f(a.positions[corner[k]]) - at.point) <
        length_squared(measure::vec3f(a.positions[nearest]) - at.point))
      nearest = corner[k];
  EXPECT_EQ(d.vertex_error[nearest], float(d.a_to_b.max));
  const Mesh heat = heatmap_mesh(a, d.vertex_error, float(d.a_to_b.max));
  EXPECT_EQ(heat.colors[nearest], (float4{1, 0, 0, 1}));
  EXPECT_EQ(heat.positions, a.positions);
  EXPECT_EQ(heat.indices, a.indices);
}

TEST(MeasureHeatmap, FixedRamp) {
  EXPECT_EQ(heat_color(0.0f), (float4{0, 0, 1, 1}));
  EXPECT_EQ(heat_color(0.25f), (float4{0, 1, 1, 1}));
  EXPECT_EQ(heat_color(0.5f), (float4{0, 1, 0, 1}));
  EXPECT_EQ(heat_color(0.75f), (float4{1, 1, 0, 1}));
  EXPECT_EQ(heat_color(1.0f), (float4{1, 0, 0, 1}));
  // Half way from blue to cyan: green 0.5, on the byte grid 127.5 rounded away from zero, 128 / 255.
  EXPECT_EQ(heat_color(0.125f), (float4{0, float(128 * (1.0 / 255)), 1, 1}));
  for (float t = 0; t <= 1; t += 1.0f / 64) {
    const float4 c = heat_color(t);
    for (float v : {c.x, c.y, c.z}) EXPECT_EQ(float(std::round(double(v) * 255) * (1.0 / 255)), v) << t;
  }
  EXPECT_EQ(heat_color(-1.0f), heat_color(0.0f));
  EXPECT_EQ(heat_color(7.0f), heat_color(1.0f));
  EXPECT_EQ(heat_color(std::nanf("")), heat_color(0.0f));
  const Mesh m = shapes::icosphere(0);
  try {
    heatmap_mesh(m, std::vector<float>(3, 0.0f), 1.0f);
    FAIL() << "a field of the wrong size was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.category(), ErrorCategory::usage);
  }
}

TEST(MeasureCompare, RejectsMeshesWithoutTrianglesOrInvalid) {
  const Mesh good = shapes::icosphere(1);
  Mesh empty;
  empty.positions = {{0, 0, 0}};
  Mesh broken = good;
  broken.indices[4] = 9999;
  for (const auto& [a, b] : {std::pair<const Mesh&, const Mesh&>{good, empty}, {empty, good}, {good, broken}}) {
    try {
      compare(a, b);
      FAIL() << "accepted a mesh it cannot measure";
    } catch (const Error& e) {
      EXPECT_EQ(e.category(), ErrorCategory::bad_input) << e.what();
    }
  }
}

}  // namespace
}  // namespace lod
