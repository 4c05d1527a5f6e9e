// The search (SimplifyOptions::search_input_triangles): the input is simplified several ways and the
// result nearest the input is kept. Checked against the ways run one by one with the search off,
// and measured by lod::compare with its default samples, which are not the search's own.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "core/shapes.h"
#include "lodkit/io.h"
#include "lodkit/measure.h"
#include "lodkit/simplify.h"
#include "test_support.h"

namespace lod {
namespace {

// The five ways of the default options, each alone: as set, guard 0, guard 2, memoryless, plain fit.
std::vector<SimplifyOptions> default_ways(uint64_t target) {
  const SimplifyOptions as_set{.target_triangles = target, .search_input_triangles = 0};
  std::vector<SimplifyOptions> ways(5, as_set);
  ways[1].distance_guard = 0;
  ways[2].distance_guard = 2;
  ways[3].metric = Metric::constrained_memoryless;
  ways[4].fit_flips = false, ways[4].fit_edge_weight = 0;
  return ways;
}

void expect_nearest_way(const Mesh& mesh, uint64_t target) {
  const SimplifyResult searched = simplify(mesh, {.target_triangles = target});
  EXPECT_EQ(searched.search_ways, 5u);
  double nearest = 1e30, kept = -1;
  int same = 0;
  for (const SimplifyOptions& way : default_ways(target)) {
    const SimplifyResult r = simplify(mesh, way);
    EXPECT_EQ(r.search_ways, 1u);
    const double h = compare(mesh, r.mesh, {.samples = 50'000}).relative_hausdorff;
    nearest = std::min(nearest, h);
    if (r.mesh.indices == searched.mesh.indices && r.mesh.positions == searched.mesh.positions) {
      ++same, kept = h;
      // The report names the way it kept.
      EXPECT_EQ(searched.metric, way.metric);
      EXPECT_EQ(searched.distance_guard, way.metric == Metric::constrained_qem ? way.distance_guard : 0.0f);
      EXPECT_EQ(searched.fit_flips, way.fit_flips);
      EXPECT_EQ(searched.fit_edge_weight, way.fit_edge_weight);
    }
  }
  ASSERT_GE(same, 1) << "the search's result is none of its ways";
  // Its own samples may rank two close ways the other way round, but not by much.
  EXPECT_LE(kept, 1.03 * nearest);
  EXPECT_NEAR(searched.search_hausdorff, kept, 0.03 * kept);  // the distance it reports
}

TEST(SimplifySearch, KeepsTheWayNearestTheInput) {
  expect_nearest_way(shapes::torus(1.0f, 0.3f, 48, 24), 48);
  expect_nearest_way(shapes::icosphere(3), 40);
}

// On the corpus's handle at 1%, the guard as set leaves the handle's far side 0.076 of the diagonal
// from the result (bench/README); with guard 2 it stays within 0.05: the search finds that.
TEST(SimplifySearch, FindsABetterGuardOnTheHandle) {
  if (test::corpus_dir().empty()) GTEST_SKIP() << "data/corpus is absent (scripts/fetch-corpus.sh)";
  const Mesh mesh = read_mesh(test::corpus_dir() / "handle.off");
  const uint64_t target = mesh.triangle_count() / 100;
  expect_nearest_way(mesh, target);
  const SimplifyResult as_set = simplify(mesh, {.target_triangles = target, .search_input_triangles = 0});
  const SimplifyResult searched = simplify(mesh, {.target_triangles = target});
  EXPECT_LT(compare(mesh, searched.mesh).hausdorff, 0.8 * compare(mesh, as_set.mesh).hausdorff);
}

// Only qem and cqem with a triangle target, no error limit and no aggregation, within both size limits.
TEST(SimplifySearch, OnlyWhereItApplies) {
  const Mesh mesh = shapes::torus(1.0f, 0.3f, 32, 16);
  const SimplifyOptions base{.target_ratio = 0.1f};
  const auto ways = [&](auto change) {
    SimplifyOptions o = base;
    change(o);
    return simplify(mesh, o).search_ways;
  };
  EXPECT_EQ(ways([](SimplifyOptions&) {}), 5u);
  EXPECT_EQ(ways([](SimplifyOptions& o) { o.metric = Metric::qem; }), 5u);
  EXPECT_EQ(ways([](SimplifyOptions& o) { o.distance_guard = 2; }), 4u);  // guard 2 is the way as set
  // The plain fit is a way only where there is a fit, and not when it is the way as set.
  EXPECT_EQ(ways([](SimplifyOptions& o) { o.fit_iterations = 0; }), 4u);
  EXPECT_EQ(ways([](SimplifyOptions& o) { o.keep_vertices = true; }), 4u);
  EXPECT_EQ(ways([](SimplifyOptions& o) { o.fit_flips = false, o.fit_edge_weight = 0; }), 4u);
  EXPECT_EQ(ways([](SimplifyOptions& o) { o.fit_flips = false; }), 5u);
  for (const Metric m : {Metric::edge_length, Metric::memoryless, Metric::constrained_memoryless})
    EXPECT_EQ(ways([m](SimplifyOptions& o) { o.metric = m; }), 1u) << metric_name(m);
  EXPECT_EQ(ways([](SimplifyOptions& o) { o.max_relative_error = 0.5f; }), 1u);
  EXPECT_EQ(ways([](SimplifyOptions& o) { o.aggregate_distance = 0.01f; }), 1u);
  EXPECT_EQ(ways([&](SimplifyOptions& o) { o.search_input_triangles = mesh.triangle_count() - 1; }), 1u);
  EXPECT_EQ(ways([&](SimplifyOptions& o) { o.search_input_triangles = mesh.triangle_count(); }), 5u);
  EXPECT_EQ(ways([&](SimplifyOptions& o) { o.search_output_triangles = 101; }), 1u);  // the target is 102
  EXPECT_EQ(ways([&](SimplifyOptions& o) { o.search_output_triangles = 102; }), 5u);

  // Without a search the report names the options as set, and there is no measure.
  const SimplifyResult a = simplify(mesh, {.target_ratio = 0.1f, .distance_guard = 3, .search_input_triangles = 0});
  EXPECT_EQ(a.search_ways, 1u);
  EXPECT_EQ(a.search_hausdorff, 0.0);
  EXPECT_EQ(a.metric, Metric::constrained_qem);
  EXPECT_EQ(a.distance_guard, 3.0f);
  EXPECT_TRUE(a.fit_flips);
  EXPECT_EQ(a.fit_edge_weight, SimplifyOptions{}.fit_edge_weight);
}

// The progress callback runs through the ways: never backwards, never past 1, ending at 1.
TEST(SimplifySearch, ProgressGoesThroughTheWays) {
  std::vector<double> seen;
  SimplifyOptions o{.target_ratio = 0.05f};
  o.progress = [&](double f) { seen.push_back(f); };
  ASSERT_EQ(simplify(shapes::torus(1.0f, 0.3f, 32, 16), o).search_ways, 5u);
  ASSERT_FALSE(seen.empty());
  EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
  EXPECT_GT(seen.front(), 0.0 - 1e-12);
  EXPECT_EQ(seen.back(), 1.0);
}

}  // namespace
}  // namespace lod
