// The fit's exact closest-point search over the input in chunks (closest_on_input), against a
// brute-force scan of every input triangle.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <span>
#include <string>

#include "core/shapes.h"
#include "lodkit/io.h"
#include "lodkit/measure.h"
#include "lodkit/simplify.h"
#include "measure/triangle_distance.h"
#include "simplify/fit.h"
#include "simplify/record.h"

namespace lod::collapse {
namespace {

// Every triangle's distance, the lowest triangle winning ties.
measure::ClosestHit brute_force(const Mesh& mesh, const measure::vec3f& p) {
  measure::ClosestHit best;
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    const uint32_t* c = &mesh.indices[3 * size_t(t)];
    const measure::TrianglePoint hit =
        measure::closest_on_triangle(p, mesh.positions[c[0]], mesh.positions[c[1]], mesh.positions[c[2]]);
    if (hit.distance_squared < best.distance_squared)
      best.distance_squared = hit.distance_squared, best.triangle = t, best.point = hit.point;
  }
  return best;
}

TEST(FitClosestOnInput, EqualsAScanOfEveryTriangleForAnyChunkSizeAndStart) {
  // A torus and a sphere inside it (two parts), plus copies of a few triangles at higher indices:
  // the copies tie with their originals, which must win.
  Mesh mesh = shapes::torus(1.0f, 0.4f, 24, 12);
  const Mesh sphere = shapes::icosphere(2);
  const uint32_t base = uint32_t(mesh.positions.size());
  mesh.positions.insert(mesh.positions.end(), sphere.positions.begin(), sphere.positions.end());
  for (const uint32_t i : sphere.indices) mesh.indices.push_back(base + i);
  for (uint32_t t = 0; t < 40; t += 3) mesh.indices.insert(mesh.indices.end(), &mesh.indices[3 * t], &mesh.indices[3 * t + 3]);

  std::mt19937 rng(5);
  std::uniform_real_distribution<float> coordinate(-2.0f, 2.0f);
  std::vector<measure::vec3f> points;
  for (int i = 0; i < 400; ++i) points.emplace_back(coordinate(rng), coordinate(rng), 0.6f * coordinate(rng));
  for (size_t v = 0; v < mesh.positions.size(); v += 7) points.emplace_back(mesh.positions[v]);  // on the surface
  std::vector<measure::ClosestHit> expected;
  for (const measure::vec3f& p : points) expected.push_back(brute_force(mesh, p));

  const SimplifyOptions options;
  State state(mesh, options);
  state.position_count = uint32_t(mesh.positions.size());
  state.position_of.resize(mesh.positions.size());
  std::iota(state.position_of.begin(), state.position_of.end(), 0u);
  std::shuffle(state.position_of.begin(), state.position_of.end(), rng);  // chunks of scattered triangles too

  for (const size_t chunk : {size_t(1), size_t(7), size_t(100), fit_chunk_triangles}) {
    for (const unsigned threads : {1u, 2u}) {
      state.threads = threads;
      for (const bool seeded : {false, true}) {
        // A first answer: none, or some far triangle's (a loose bound, a poor start).
        std::vector<measure::ClosestHit> hits(points.size());
        if (seeded)
          for (size_t i = 0; i < points.size(); ++i) {
            const uint32_t t = uint32_t((i * 37) % mesh.triangle_count());
            const uint32_t* c = &mesh.indices[3 * size_t(t)];
            const measure::TrianglePoint hit = measure::closest_on_triangle(
                points[i], mesh.positions[c[0]], mesh.positions[c[1]], mesh.positions[c[2]]);
            hits[i].distance_squared = hit.distance_squared, hits[i].triangle = t, hits[i].point = hit.point;
          }
        closest_on_input(state, points, hits, chunk);
        for (size_t i = 0; i < points.size(); ++i) {
          SCOPED_TRACE(testing::Message() << "chunk " << chunk << ", threads " << threads << ", seeded " << seeded
                                          << ", point " << i);
          EXPECT_EQ(hits[i].triangle, expected[i].triangle);
          EXPECT_EQ(hits[i].distance_squared, expected[i].distance_squared);
          EXPECT_EQ(hits[i].point.x, expected[i].point.x);
          EXPECT_EQ(hits[i].point.y, expected[i].point.y);
          EXPECT_EQ(hits[i].point.z, expected[i].point.z);
        }
      }
    }
  }
}

// Coordinates near FLT_MAX overflow every squared distance: the search then finds no triangle and
// the fit leaves those edges alone (found by fuzz_simplify: resolve() read past the BVH).
TEST(FitClosestOnInput, OverflowingDistancesFindNothingAndTheFitStillRuns) {
  Mesh mesh;
  mesh.positions = {{0, 0, 1e38f}, {1, -10, 0}, {1, 1, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, -1e38f}};
  mesh.indices = {0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 1, 5, 2, 1, 5, 3, 2, 5, 4, 3, 5, 1, 4};
  const SimplifyOptions options;
  State state(mesh, options);
  state.position_count = uint32_t(mesh.positions.size());
  state.position_of = {0, 1, 2, 3, 4, 5};
  const std::vector<measure::vec3f> points = {{0, 0.5f, 3e38f}, {0, 0, -3e38f}};
  std::vector<measure::ClosestHit> hits(points.size());
  closest_on_input(state, points, hits, 2);
  for (const measure::ClosestHit& hit : hits) {
    EXPECT_EQ(hit.triangle, UINT32_MAX);
    EXPECT_FALSE(hit.distance_squared < std::numeric_limits<float>::infinity());
  }
  const SimplifyResult r = simplify(mesh, {.target_triangles = 4});
  EXPECT_NO_THROW(validate(r.mesh));
}

// Found by fuzz_simplify: a vertex at 1e38 makes every distance from the input samples to the result
// overflow, so the feet search finds no triangle; the sample must keep a foot on the result (it
// read the triangle "none" and crashed).
TEST(FitClosestOnInput, SamplesWithoutAFootKeepTheirLastOne) {
  const std::string off =
      "COFF\n4 2 0\n0 0 1e38 255 0 0 2\n0 1 0 255 255 0 255\n1 1 0 0 0 255 255\n0 1 0 255 255 255 255\n"
      "3 0 1 2 0.0 0.0 0.0\n3 0 2 3\n";
  const Mesh mesh = read_off(std::span(reinterpret_cast<const uint8_t*>(off.data()), off.size()), "overflow.off");
  SimplifyOptions options;  // as the fuzz input chose them
  options.metric = Metric::qem;
  options.target_ratio = 0;
  options.min_normal_dot = 51 / 127.5f - 1;
  options.distance_guard = 0;
  options.fit_iterations = 3;
  options.normal_weight = options.uv_weight = options.color_weight = 1.75f;
  options.aggregate_distance = (1e38f + 2) * 255 / 1020;
  options.aggregate_neighbours = 8;
  options.locked = {1, 0, 0, 0};
  options.importance = {0, 3, 6, 2};
  for (const unsigned threads : {1u, 2u}) {
    options.threads = threads;
    const SimplifyResult r = simplify(mesh, options);
    EXPECT_NO_THROW(validate(r.mesh));
    EXPECT_EQ(replay(mesh, r.record, r.record.collapses.size()), r.mesh);
  }
}


// A roof over the unit square, z = h (1 - |x + y - 1|) (ridge from (0, 1) to (1, 0)) or, with
// `ridge_on_main_diagonal`, z = h (1 - |x - y|) (ridge from (0, 0) to (1, 1)), finely triangulated
// with every cell split along the ridge's direction, so the mesh is exactly the roof.
Mesh roof(uint32_t n, float h, bool ridge_on_main_diagonal) {
  Mesh mesh;
  for (uint32_t j = 0; j <= n; ++j)
    for (uint32_t i = 0; i <= n; ++i) {
      const float x = float(i) / float(n), y = float(j) / float(n);
      const float d = ridge_on_main_diagonal ? std::fabs(x - y) : std::fabs(x + y - 1);
      mesh.positions.push_back({x, y, h * (1 - d)});
    }
  const auto at = [&](uint32_t i, uint32_t j) { return j * (n + 1) + i; };
  for (uint32_t j = 0; j < n; ++j)
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
      if (ridge_on_main_diagonal) mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
      else mesh.indices.insert(mesh.indices.end(), {a, b, d, b, c, d});
    }
  return mesh;
}

// The fit on a hand-made collapse state over `input`: every input vertex collapsed into the nearest
// of the input vertices `kept` (the first on ties), and the result the triangles `live` over them,
// as triangles 0, 1, ... (their corners overwrite the input's first ones).
struct QuadResult {
  std::vector<uint32_t> corners;  // of the live triangles, after the fit
  std::vector<Relink> flipped;
  std::vector<FittedPosition> fitted;
  uint32_t iterations = 0;  // that ran
};
QuadResult fit_collapsed(const Mesh& input, const std::vector<uint32_t>& kept, const std::vector<uint32_t>& live,
                         bool flips, unsigned threads, uint32_t iterations) {
  const SimplifyOptions options;
  State state(input, options);
  state.threads = threads;
  const uint32_t v = uint32_t(input.vertex_count());
  state.position_count = v;
  state.position_of.resize(v), state.external.resize(v);
  std::iota(state.position_of.begin(), state.position_of.end(), 0u);
  std::iota(state.external.begin(), state.external.end(), 0u);
  state.position = input.positions;
  state.moves.assign(v, 0);
  state.flags.assign(v, 0);
  state.successor.resize(v);
  for (uint32_t i = 0; i < v; ++i) {
    const float3& x = input.positions[i];
    float best = std::numeric_limits<float>::infinity();
    for (const uint32_t k : kept) {
      const float3& c = input.positions[k];
      const float d = (x.x - c.x) * (x.x - c.x) + (x.y - c.y) * (x.y - c.y) + (x.z - c.z) * (x.z - c.z);
      if (d < best) best = d, state.successor[i] = k;
    }
  }
  for (const uint32_t k : kept) state.successor[k] = ~0u;
  state.corners = input.indices;
  std::copy(live.begin(), live.end(), state.corners.begin());
  state.corner_pos = state.corners;
  state.alive.assign(input.triangle_count(), 0);
  std::fill_n(state.alive.begin(), live.size() / 3, uint8_t(1));
  state.live_triangles = live.size() / 3;
  state.center = {0.5, 0.5, 0.5};
  state.scale = 1.0;
  QuadResult out;
  out.iterations = fit_positions(state, iterations, 0.2, SimplifyOptions{}.fit_edge_weight, flips, &out.fitted, &out.flipped);
  out.corners.assign(state.corners.begin(), state.corners.begin() + live.size());
  return out;
}

// fit_collapsed on an n x n grid over the unit square: the result is the two triangles (p, q, r)
// and (q, p, s) with p = (0, 0), q = (1, 1), r = (0, 1), s = (1, 0): its diagonal runs from p to q.
QuadResult fit_quad(const Mesh& input, uint32_t n, bool flips, unsigned threads, uint32_t iterations = 1) {
  const uint32_t p = 0, q = n * (n + 1) + n, r = n * (n + 1), s = n;
  return fit_collapsed(input, {p, q, r, s}, {p, q, r, q, p, s}, flips, threads, iterations);
}

// The quad's diagonal p-q crosses the roof's ridge r-s: the samples lie nearer the other diagonal
// (on it, exactly), so the fit flips the edge: each triangle changes one corner (triangle 0's q to
// s, triangle 1's p to r), the result is then the roof itself, and the fit has nothing left to
// move. Without flips, or with the ridge along p-q already, the triangles stay.
TEST(FitFlips, AQuadAcrossARidgeFlipsOntoIt) {
  const uint32_t n = 8;
  const uint32_t p = 0, q = n * (n + 1) + n, r = n * (n + 1), s = n;
  const Mesh across = roof(n, 0.5f, false);
  for (const unsigned threads : {1u, 2u}) {
    const QuadResult flipped = fit_quad(across, n, true, threads);
    ASSERT_EQ(flipped.flipped.size(), 2u);
    EXPECT_EQ(flipped.flipped[0].triangle, 0u);
    EXPECT_EQ(flipped.flipped[0].corner, 1u);
    EXPECT_EQ(flipped.flipped[0].from, q);
    EXPECT_EQ(flipped.flipped[0].to, s);
    EXPECT_EQ(flipped.flipped[1].triangle, 1u);
    EXPECT_EQ(flipped.flipped[1].corner, 1u);
    EXPECT_EQ(flipped.flipped[1].from, p);
    EXPECT_EQ(flipped.flipped[1].to, r);
    EXPECT_EQ(flipped.corners, (std::vector<uint32_t>{p, s, r, q, r, s}));
    for (const FittedPosition& f : flipped.fitted) {
      EXPECT_NEAR(f.new_position.x, f.old_position.x, 1e-5f);
      EXPECT_NEAR(f.new_position.y, f.old_position.y, 1e-5f);
      EXPECT_NEAR(f.new_position.z, f.old_position.z, 1e-5f);
    }
    Mesh result;
    result.positions = across.positions;
    result.indices = flipped.corners;
    EXPECT_LT(compare(across, result, {.samples = 20'000}).hausdorff, 1e-5);

    const QuadResult kept = fit_quad(across, n, false, threads);
    EXPECT_TRUE(kept.flipped.empty());
    EXPECT_EQ(kept.corners, (std::vector<uint32_t>{p, q, r, q, p, s}));
  }
  const QuadResult along = fit_quad(roof(n, 0.5f, true), n, true, 1);
  EXPECT_TRUE(along.flipped.empty());
  EXPECT_EQ(along.corners, (std::vector<uint32_t>{p, q, r, q, p, s}));
}

// A strip of cells [k, k + 1] x [0, 1] of a surface: on the first a steep roof z = h (1 - |x + y - 1|)
// (h = 1.5, ridge from (0, 1) to (1, 0)), on the others the plane z = h (1 - y) that meets it along
// x = 1; finely triangulated along the ridge's direction, so the mesh is exact. The result: each
// cell as two triangles, the first across the ridge (diagonal p-q). Flipping p-q would turn the
// faces from the old ones by more than the flip limit (cos = 1 / (2 h^2 + 1) = 0.18 < 0.2), so the
// first flip round keeps it. Its midpoint lies far below the ridge while the other cells lie on
// the input: a far edge. The second round (iteration 10) flips it, since the flipped faces follow
// the input triangles under them (their normals are the roof's), and the first cell is then the
// roof itself; a fit stopped before iteration 10, or without flips, keeps the diagonal.
TEST(FitFlips, AFarEdgeAcrossASteepRidgeFlipsInTheSecondRound) {
  const uint32_t n = 8, cells = 6, w = cells * n + 1;  // grid steps per unit, vertices per row
  const float h = 1.5f;
  Mesh input;
  for (uint32_t j = 0; j <= n; ++j)
    for (uint32_t i = 0; i < w; ++i) {
      const float x = float(i) / float(n), y = float(j) / float(n);
      input.positions.push_back({x, y, x <= 1 ? h * (1 - std::fabs(x + y - 1)) : h * (1 - y)});
    }
  const auto at = [&](uint32_t i, uint32_t j) { return j * w + i; };
  for (uint32_t j = 0; j < n; ++j)
    for (uint32_t i = 0; i + 1 < w; ++i) {
      const uint32_t a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
      input.indices.insert(input.indices.end(), {a, b, d, b, c, d});  // along the anti-diagonal
    }
  // Corners: (k, 0) and (k, 1) for k = 0 .. cells.
  std::vector<uint32_t> kept, live;
  for (uint32_t k = 0; k <= cells; ++k) kept.push_back(at(k * n, 0)), kept.push_back(at(k * n, n));
  const uint32_t p = at(0, 0), q = at(n, n), r = at(0, n), s = at(n, 0);
  live = {p, q, r, q, p, s};
  for (uint32_t k = 1; k < cells; ++k) {
    const uint32_t a = at(k * n, 0), b = at((k + 1) * n, 0), c = at((k + 1) * n, n), d = at(k * n, n);
    live.insert(live.end(), {a, b, c, a, c, d});
  }
  const auto first_cell = [](const QuadResult& fit) { return std::vector<uint32_t>(fit.corners.begin(), fit.corners.begin() + 6); };
  const auto distance = [&](const QuadResult& fit) {
    Mesh result;
    result.positions = input.positions;
    for (const FittedPosition& f : fit.fitted) result.positions[f.position] = f.new_position;
    result.indices = fit.corners;
    return compare(input, result, {.samples = 20'000}).hausdorff;
  };
  for (const unsigned threads : {1u, 2u}) {
    const QuadResult early = fit_collapsed(input, kept, live, true, threads, 10);
    EXPECT_EQ(first_cell(early), (std::vector<uint32_t>{p, q, r, q, p, s}));

    const QuadResult late = fit_collapsed(input, kept, live, true, threads, 12);
    ASSERT_GT(late.iterations, 10u) << "the fit must still be running at iteration 10";
    EXPECT_EQ(first_cell(late), (std::vector<uint32_t>{p, s, r, q, r, s}));
    const QuadResult unflipped = fit_collapsed(input, kept, live, false, threads, 12);
    EXPECT_EQ(first_cell(unflipped), (std::vector<uint32_t>{p, q, r, q, p, s}));
    const double late_distance = distance(late), unflipped_distance = distance(unflipped);
    SCOPED_TRACE(testing::Message() << "Hausdorff distance " << late_distance << ", unflipped " << unflipped_distance);
    EXPECT_LT(late_distance, 0.5 * unflipped_distance);
  }
}
}  // namespace
}  // namespace lod::collapse
