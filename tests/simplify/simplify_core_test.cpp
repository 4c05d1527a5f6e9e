// Core properties of the collapse engine: quadric math by hand, flat cases, exact replay and undo,
// thread-count independence, invariants after every collapse, seams and locks.
#include <gtest/gtest.h>

#include <limits>

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>

#include "core/quadric.h"
#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/simplify.h"
#include "test_support.h"

namespace lod {
namespace {

using core::vec3d;

double triangle_area(const Mesh& m, size_t t) {
  const float3 &a = m.positions[m.indices[3 * t]], &b = m.positions[m.indices[3 * t + 1]],
               &c = m.positions[m.indices[3 * t + 2]];
  const vec3d e1{double(b.x) - a.x, double(b.y) - a.y, double(b.z) - a.z};
  const vec3d e2{double(c.x) - a.x, double(c.y) - a.y, double(c.z) - a.z};
  return 0.5 * core::length(core::cross(e1, e2));
}

vec3d normal_of(const Mesh& m, size_t t) {
  const float3 &a = m.positions[m.indices[3 * t]], &b = m.positions[m.indices[3 * t + 1]],
               &c = m.positions[m.indices[3 * t + 2]];
  const vec3d e1{double(b.x) - a.x, double(b.y) - a.y, double(b.z) - a.z};
  const vec3d e2{double(c.x) - a.x, double(c.y) - a.y, double(c.z) - a.z};
  return core::cross(e1, e2);
}

TEST(SimplifyCoreQuadric, PlaneGivesSquaredDistance) {
  // Plane x + 2y - 2z = 3, unit normal (1, 2, -2) / 3, offset -1.
  const vec3d n{1.0 / 3, 2.0 / 3, -2.0 / 3};
  const core::Quadric q(core::plane_quadric(n, -1.0, 1.0));
  for (const vec3d p : {vec3d{0, 0, 0}, vec3d{1, 1, 1}, vec3d{3, 0, 0}, vec3d{-2, 5, 0.5}}) {
    const double distance = (p.x + 2 * p.y - 2 * p.z - 3) / 3.0;
    EXPECT_NEAR(core::evaluate(q, p), distance * distance, 1e-5 * (1 + distance * distance));
  }
}

TEST(SimplifyCoreQuadric, CubeCornerIsTheOptimumWithZeroCost) {
  core::QuadricD q;  // the three face planes through the corner (1, 1, 1): x = 1, y = 1, z = 1
  q += core::plane_quadric({1, 0, 0}, -1, 1);
  q += core::plane_quadric({0, 1, 0}, -1, 1);
  q += core::plane_quadric({0, 0, 1}, -1, 1);
  vec3d p;
  ASSERT_TRUE(core::optimum(q, p));
  EXPECT_NEAR(p.x, 1, 1e-12);
  EXPECT_NEAR(p.y, 1, 1e-12);
  EXPECT_NEAR(p.z, 1, 1e-12);
  EXPECT_NEAR(core::evaluate(q, p), 0, 1e-12);
}

TEST(SimplifyCoreQuadric, CoplanarFacesFallBackWithoutNaN) {
  core::QuadricD q;  // two copies of z = 0: A has rank 1
  q += core::plane_quadric({0, 0, 1}, 0, 1);
  q += core::plane_quadric({0, 0, 1}, 0, 2);
  vec3d p;
  EXPECT_FALSE(core::optimum(q, p));
  const vec3d a{0, 0, 1}, b{1, 0, -3};  // the segment crosses z = 0 at t = 0.25
  const vec3d s = core::segment_optimum(q, a, b);
  EXPECT_TRUE(std::isfinite(s.x) && std::isfinite(s.y) && std::isfinite(s.z));
  EXPECT_NEAR(s.x, 0.25, 1e-9);
  EXPECT_NEAR(s.z, 0.0, 1e-9);
  // Flat along the segment (both ends on the plane): the best of the ends and the midpoint, cost 0.
  const vec3d m = core::segment_optimum(q, vec3d{0, 0, 0}, vec3d{1, 1, 0});
  EXPECT_NEAR(core::evaluate(q, m), 0, 1e-12);
}

TEST(SimplifyCore, FlatGridReachesTwoTrianglesWithZeroError) {
  const Mesh grid = shapes::grid(10, 10);
  for (const Metric metric : {Metric::qem, Metric::constrained_qem, Metric::memoryless, Metric::constrained_memoryless}) {
    SCOPED_TRACE(metric_name(metric));
    const SimplifyResult r = simplify(grid, {.target_triangles = 2, .metric = metric, .lock_border = false});
    EXPECT_EQ(r.output_triangles, 2u);
    double area = 0;
    for (size_t t = 0; t < r.mesh.triangle_count(); ++t) area += triangle_area(r.mesh, t);
    for (const float3& p : r.mesh.positions) EXPECT_EQ(p.z, 0.0f);
    // Plain QEM has nothing holding the border (Garland–Heckbert); the others keep the square.
    if (metric != Metric::qem) {
      EXPECT_NEAR(area, 1.0, 1e-6);
      // The border stays on the unit square.
      for (const float3& p : r.mesh.positions) {
        const bool on_border = std::fabs(p.x) < 1e-6 || std::fabs(p.x - 1) < 1e-6 || std::fabs(p.y) < 1e-6 ||
                               std::fabs(p.y - 1) < 1e-6;
        EXPECT_TRUE(on_border) << p.x << " " << p.y;
      }
    }
    EXPECT_LT(r.error, 2e-4f);  // zero up to float-stored quadrics (relative 1e-7 -> sqrt ~3e-4)
  }
}

std::vector<Mesh> test_meshes() {
  Mesh cube = subdivide_midpoint(subdivide_midpoint(shapes::cube()));
  cube.materials.resize(cube.triangle_count());
  for (size_t t = 0; t < cube.triangle_count(); ++t) cube.materials[t] = uint32_t(t / (cube.triangle_count() / 6));
  cube.material_names = {"a", "b", "c", "d", "e", "f"};
  return {shapes::icosphere(2), shapes::torus(1.0f, 0.3f, 24, 12), cube, shapes::grid(8, 6)};
}

TEST(SimplifyCore, ReplayAndUndoAreExact) {
  // The final fit's moves and edge flips are part of the record: replay ends with them.
  size_t fitted = 0, flipped = 0;
  for (const Mesh& mesh : test_meshes())
    for (const Metric metric : {Metric::edge_length, Metric::qem, Metric::constrained_qem, Metric::memoryless,
                                Metric::constrained_memoryless})
      for (const bool keep : {false, true}) {
        SCOPED_TRACE(std::string(metric_name(metric)) + (keep ? " keep_vertices" : ""));
        const SimplifyResult r =
            simplify(mesh, {.target_ratio = 0.2f, .metric = metric, .keep_vertices = keep, .normal_weight = 0.5f,
                            .uv_weight = 0.5f});
        ASSERT_GT(r.collapses, 0u);
        if (keep) {
          EXPECT_TRUE(r.record.fitted.empty());
          EXPECT_TRUE(r.record.flipped.empty());
        }
        fitted += r.record.fitted.size(), flipped += r.record.flipped.size();
        EXPECT_EQ(replay(mesh, r.record, r.record.collapses.size()), r.mesh);
        EXPECT_EQ(replay_and_undo(mesh, r.record), mesh);
      }
  EXPECT_GT(fitted, 0u);
  EXPECT_GT(flipped, 0u);
}

// The fit's moves are checked sweep by sweep, but the flip limit holds against each face as it was
// before the fit: small turns must not add up. On the elephant they did (1 to 9 faces past the limit
// at 10% and 1%, limits 0.2 and 0.9) while each sweep was checked against the last one.
TEST(SimplifyCore, FitTurnsNoFacePastTheLimit) {
  if (test::corpus_dir().empty()) GTEST_SKIP() << "data/corpus is absent (scripts/fetch-corpus.sh)";
  const Mesh mesh = read_mesh(test::corpus_dir() / "elephant.off");
  for (const float ratio : {0.1f, 0.01f})
    for (const float limit : {0.2f, 0.9f}) {
      const SimplifyOptions o{.target_ratio = ratio, .min_normal_dot = limit, .fit_flips = false, .search_input_triangles = 0};
      SimplifyOptions no_fit = o;
      no_fit.fit_iterations = 0;
      const SimplifyResult collapsed = simplify(mesh, no_fit), fitted = simplify(mesh, o);
      ASSERT_GT(fitted.fitted_positions, 0u);
      ASSERT_EQ(fitted.mesh.indices, collapsed.mesh.indices);  // the same collapses
      for (size_t t = 0; t < collapsed.mesh.triangle_count(); ++t) {
        const vec3d n0 = normal_of(collapsed.mesh, t), n1 = normal_of(fitted.mesh, t);
        ASSERT_GE(core::dot(n0, n1), limit * core::length(n0) * core::length(n1) - 1e-12)
            << "face " << t << " at ratio " << ratio << ", limit " << limit;
      }
    }
}

TEST(SimplifyCore, SameResultOnAnyThreadCount) {
  const Mesh mesh = subdivide_midpoint(shapes::torus(1.0f, 0.3f, 48, 24));
  const SimplifyResult one = simplify(mesh, {.target_ratio = 0.05f, .threads = 1});
  for (const unsigned threads : {2u, 8u}) {
    const SimplifyResult r = simplify(mesh, {.target_ratio = 0.05f, .threads = threads});
    EXPECT_EQ(r.mesh, one.mesh);
    ASSERT_EQ(r.record.collapses.size(), one.record.collapses.size());
    for (size_t i = 0; i < r.record.collapses.size(); ++i) {
      EXPECT_EQ(r.record.collapses[i].kept, one.record.collapses[i].kept);
      EXPECT_EQ(r.record.collapses[i].removed, one.record.collapses[i].removed);
      EXPECT_EQ(r.record.collapses[i].new_position, one.record.collapses[i].new_position);
    }
  }
}

// A batch gives each mesh, with its own options, the result simplify gives it alone, whichever of
// its meshes go side by side (the small ones) and on how many threads; progress rises to 1.
TEST(SimplifyCore, ABatchSimplifiesEachMeshAsAlone) {
  const Mesh large = shapes::torus(1.0f, 0.3f, 200, 90);  // 36,000 triangles: simplified alone
  ASSERT_GE(large.triangle_count(), 32768u);
  const std::vector<Mesh> meshes = {shapes::icosphere(3), large, shapes::torus(1.0f, 0.4f, 24, 12),
                                    subdivide_midpoint(subdivide_midpoint(shapes::cube()))};
  const std::vector<SimplifyOptions> options = {{.target_ratio = 0.1f},
                                                {.target_ratio = 0.05f},
                                                {.target_triangles = 100, .metric = Metric::edge_length},
                                                {.target_ratio = 0, .max_relative_error = 0.01f}};
  const std::vector<const Mesh*> pointers = {&meshes[0], &meshes[1], &meshes[2], &meshes[3]};
  std::vector<SimplifyResult> alone;
  for (size_t i = 0; i < meshes.size(); ++i) {
    SimplifyOptions one = options[i];
    one.threads = 1;
    alone.push_back(simplify(meshes[i], one));
  }
  for (const unsigned threads : {1u, 2u}) {
    std::vector<double> progress;
    const std::vector<SimplifyResult> batch = simplify_batch(pointers, options, threads, [&](double f) { progress.push_back(f); });
    ASSERT_EQ(batch.size(), meshes.size());
    for (size_t i = 0; i < meshes.size(); ++i) {
      SCOPED_TRACE(testing::Message() << "mesh " << i << ", " << threads << " threads");
      EXPECT_EQ(batch[i].mesh, alone[i].mesh);
      EXPECT_EQ(batch[i].error, alone[i].error);
      EXPECT_EQ(batch[i].vertex_successor, alone[i].vertex_successor);
      EXPECT_EQ(batch[i].vertex_origin, alone[i].vertex_origin);
      EXPECT_EQ(batch[i].record.collapses.size(), alone[i].record.collapses.size());
    }
    EXPECT_EQ(batch[2].output_triangles, 100u);
    EXPECT_GT(batch[3].record.collapses.size(), 0u);
    ASSERT_FALSE(progress.empty());
    EXPECT_TRUE(std::is_sorted(progress.begin(), progress.end()));
    EXPECT_EQ(progress.back(), 1.0);
  }
  EXPECT_TRUE(simplify_batch({}, {}).empty());
  const std::vector<const Mesh*> with_null = {&meshes[0], nullptr};
  EXPECT_THROW(simplify_batch(with_null, std::vector<SimplifyOptions>(2)), Error);
  EXPECT_THROW(simplify_batch(pointers, std::vector<SimplifyOptions>(3)), Error);
}

// After every collapse: genus and Euler characteristic kept, still manifold, no degenerate or
// flipped face (each surviving face's normal against its own normal one collapse earlier). The final
// fit after them is checked by FitTurnsNoFacePastTheLimit.
TEST(SimplifyCore, InvariantsHoldAfterEveryCollapse) {
  for (const Mesh& mesh : {shapes::icosphere(2), shapes::torus(1.0f, 0.35f, 16, 8)}) {
    const MeshStats before = compute_stats(mesh);
    const float min_dot = 0.2f;
    const SimplifyResult r = simplify(mesh, {.target_ratio = 0.0f, .min_normal_dot = min_dot, .fit_iterations = 0});
    ASSERT_GT(r.record.collapses.size(), 10u);
    for (size_t k = 1; k <= r.record.collapses.size(); ++k) {
      const Mesh m = replay(mesh, r.record, k);
      const MeshStats stats = compute_stats(m);
      ASSERT_EQ(stats.euler_characteristic, before.euler_characteristic) << "after collapse " << k;
      ASSERT_EQ(stats.components.size(), 1u);
      ASSERT_EQ(stats.components[0].genus, before.components[0].genus) << "after collapse " << k;
      ASSERT_TRUE(stats.components[0].manifold) << "after collapse " << k;
      ASSERT_EQ(stats.degenerate_triangles, 0u);
      ASSERT_EQ(stats.zero_area_triangles, 0u);
    }
    // Flip check, collapse by collapse, on triangles kept by input index.
    for (size_t k = 1; k <= r.record.collapses.size(); ++k) {
      const Mesh a = replay(mesh, r.record, k - 1), b = replay(mesh, r.record, k);
      // Map surviving input triangles: replay keeps live triangles in input order; recover input ids
      // by removing the faces the record removed.
      std::vector<uint8_t> alive(mesh.triangle_count(), 1);
      for (size_t i = 0; i + 1 < k; ++i)
        for (uint32_t f = 0; f < r.record.collapses[i].removed_face_count; ++f)
          alive[r.record.removed_faces[r.record.collapses[i].faces_begin + f]] = 0;
      std::vector<uint8_t> alive_after = alive;
      const Collapse& c = r.record.collapses[k - 1];
      for (uint32_t f = 0; f < c.removed_face_count; ++f) alive_after[r.record.removed_faces[c.faces_begin + f]] = 0;
      size_t ia = 0, ib = 0;
      for (size_t t = 0; t < mesh.triangle_count(); ++t) {
        if (!alive[t]) continue;
        if (alive_after[t]) {
          const vec3d n0 = normal_of(a, ia), n1 = normal_of(b, ib);
          ASSERT_GE(core::dot(n0, n1), min_dot * core::length(n0) * core::length(n1) - 1e-12)
              << "face " << t << " flipped at collapse " << k;
          ++ib;
        }
        ++ia;
      }
    }
  }
}

TEST(SimplifyCore, HardEdgedCubeKeepsThreeNormalsPerCorner) {
  const Mesh cube = subdivide_midpoint(subdivide_midpoint(shapes::cube()));
  const SimplifyResult r = simplify(cube, {.target_ratio = 0.1f});
  ASSERT_LT(r.output_triangles, cube.triangle_count());
  size_t corners = 0;
  for (size_t v = 0; v < r.mesh.vertex_count(); ++v) {
    const float3& p = r.mesh.positions[v];
    if (std::fabs(std::fabs(p.x) - 1) > 1e-6 || std::fabs(std::fabs(p.y) - 1) > 1e-6 || std::fabs(std::fabs(p.z) - 1) > 1e-6)
      continue;
    std::set<std::tuple<float, float, float>> normals;
    for (size_t w = 0; w < r.mesh.vertex_count(); ++w)
      if (r.mesh.positions[w] == p) normals.insert({r.mesh.normals[w].x, r.mesh.normals[w].y, r.mesh.normals[w].z});
    EXPECT_EQ(normals.size(), 3u);
    ++corners;
  }
  EXPECT_EQ(corners, 8u * 3u);  // 8 corners, each held by 3 wedges
  // Every vertex still lies on the cube's surface (no seam vertex wandered off its faces).
  for (const float3& p : r.mesh.positions) {
    const float m = std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)});
    EXPECT_NEAR(m, 1.0f, 1e-5f);
  }
}

TEST(SimplifyCore, KeepVerticesUsesInputPositionsOnly) {
  const Mesh mesh = shapes::torus(1.0f, 0.3f, 32, 16);
  const SimplifyResult r = simplify(mesh, {.target_ratio = 0.1f, .keep_vertices = true});
  std::set<std::tuple<float, float, float>> input;
  for (const float3& p : mesh.positions) input.insert({p.x, p.y, p.z});
  for (const float3& p : r.mesh.positions) EXPECT_TRUE(input.count({p.x, p.y, p.z}));
}

TEST(SimplifyCore, LocksAndBordersStayPut) {
  const Mesh grid = shapes::grid(12, 12);
  const SimplifyResult r = simplify(grid, {.target_ratio = 0.1f, .lock_border = true});
  const MeshStats before = compute_stats(grid), after = compute_stats(r.mesh);
  EXPECT_EQ(after.boundary_edges, before.boundary_edges);  // no border vertex moved or vanished
  std::vector<uint8_t> locked(grid.vertex_count(), 0);
  locked[7 * 13 + 5] = 1;
  const SimplifyResult l = simplify(grid, {.target_ratio = 0.05f, .locked = locked});
  bool found = false;
  for (const float3& p : l.mesh.positions) found |= p == grid.positions[7 * 13 + 5];
  EXPECT_TRUE(found);
}

TEST(SimplifyCore, ErrorLimitIsRespected) {
  const Mesh mesh = shapes::icosphere(4);
  const SimplifyResult r = simplify(mesh, {.target_ratio = 0.0f, .max_relative_error = 0.01f});
  EXPECT_LE(r.relative_error, 0.01f);
  EXPECT_LT(r.output_triangles, mesh.triangle_count());
  EXPECT_GT(r.output_triangles, 20u);
}

TEST(SimplifyCore, NonManifoldInputDoesNotCrash) {
  const SimplifyResult r = simplify(shapes::fin(), {.target_ratio = 0.0f});
  validate(r.mesh);
  // Two spheres touching at one shared position (a non-manifold vertex): the icosphere is centrally
  // symmetric, so moving a copy by 2c puts its vertex at -c onto the first sphere's vertex c.
  Mesh two = shapes::icosphere(2);
  const Mesh other = shapes::icosphere(2);
  const float3 c = two.positions[0];
  const uint32_t base = uint32_t(two.vertex_count());
  for (size_t v = 0; v < other.vertex_count(); ++v) {
    append_vertex(two, other, uint32_t(v));
    const float3 p = other.positions[v];
    two.positions.back() = {p.x + 2 * c.x, p.y + 2 * c.y, p.z + 2 * c.z};
  }
  for (const uint32_t i : other.indices) two.indices.push_back(base + i);
  ASSERT_EQ(compute_stats(two).non_manifold_vertices, 1u);
  const SimplifyResult s = simplify(two, {.target_ratio = 0.05f});
  validate(s.mesh);
  EXPECT_LT(s.output_triangles, two.triangle_count());
}

TEST(SimplifyCore, BadOptionsAreUsageErrors) {
  const Mesh mesh = shapes::icosphere(1);
  const auto category = [&](const SimplifyOptions& o) {
    try {
      simplify(mesh, o);
    } catch (const Error& e) {
      return e.category();
    }
    return ErrorCategory::internal;
  };
  EXPECT_EQ(category({.target_ratio = 2.0f}), ErrorCategory::usage);
  EXPECT_EQ(category({.locked = std::vector<uint8_t>(3, 1)}), ErrorCategory::usage);
  EXPECT_EQ(category({.aggregate_distance = -0.1f}), ErrorCategory::usage);
  constexpr float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(category({.target_ratio = nan}), ErrorCategory::usage);
  EXPECT_EQ(category({.aggregate_distance = nan}), ErrorCategory::usage);
  // NaN is not "no limit" (only a negative limit is).
  EXPECT_EQ(category({.max_error = nan}), ErrorCategory::usage);
  EXPECT_EQ(category({.max_relative_error = nan}), ErrorCategory::usage);
  EXPECT_EQ(category({.target_ratio = 0.5f, .max_relative_error = -1.0f}), ErrorCategory::internal);  // no error
}

}  // namespace
}  // namespace lod
