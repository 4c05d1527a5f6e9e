// Strips: both stripifiers, both joins, decode back to exactly the input triangles with their winding.
#include <gtest/gtest.h>

#include "core/adjacency.h"
#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/optimize.h"
#include "optimize_test_support.h"

namespace lod {
namespace {

std::vector<std::pair<std::string, Mesh>> strip_inputs() {
  std::vector<std::pair<std::string, Mesh>> inputs = {
      {"icosphere", shapes::icosphere(3)},     {"torus", shapes::torus(1.0f, 0.3f, 30, 14)},
      {"grid", shapes::grid(17, 9)},           {"cube", shapes::cube()},
      {"cylinder", shapes::cylinder(20, 2.0f)}, {"fin", shapes::fin()},
      {"moebius", test::moebius_strip(16)}};
  // Shuffled triangles and a few flipped ones: strips must not cross edges where windings disagree.
  Mesh shuffled = shapes::torus(1.0f, 0.3f, 20, 10);
  shuffled.indices = test::shuffled_triangles(shuffled.indices, 3);
  for (size_t t = 0; t < shuffled.triangle_count(); t += 7) std::swap(shuffled.indices[3 * t], shuffled.indices[3 * t + 1]);
  inputs.push_back({"shuffled torus", shuffled});
  return inputs;
}

TEST(Strips, DecodeToTheInputTrianglesWithTheirWinding) {
  for (const auto& [name, mesh] : strip_inputs())
    for (const StripMethod method : {StripMethod::sgi, StripMethod::best})
      for (const bool restart : {false, true}) {
        SCOPED_TRACE(name + " " + strip_method_name(method) + (restart ? " restart" : " degenerate"));
        const Strips s = stripify(mesh.indices, mesh.vertex_count(), {.method = method, .use_restart = restart});
        EXPECT_EQ(test::index_triangles(unstripify(s.indices, restart, s.restart_index)), test::index_triangles(mesh.indices));
        EXPECT_EQ(s.triangles, mesh.triangle_count());
        EXPECT_EQ(s.dropped_degenerate, 0u);
        // triangle_order lists every triangle once.
        std::vector<uint32_t> order = s.triangle_order;
        std::sort(order.begin(), order.end());
        for (uint32_t t = 0; t < order.size(); ++t) ASSERT_EQ(order[t], t);
        EXPECT_EQ(order.size(), mesh.triangle_count());
        // The buffer's own statistics agree, and a strip costs at least one index per triangle.
        const StripStats st = analyze_strips(s.indices, restart, s.restart_index);
        EXPECT_EQ(st.triangles, mesh.triangle_count());
        EXPECT_GE(st.indices_per_triangle, 1.0);
        if (restart) {
          EXPECT_EQ(st.strips, s.strips);
          // Restart indices appear only between strips.
          EXPECT_EQ(uint64_t(std::count(s.indices.begin(), s.indices.end(), s.restart_index)), s.strips - 1);
        }
      }
}

TEST(Strips, DecoderByHand) {
  // 0 1 2 3 4: (0,1,2), then the odd one reversed (2,1,3), then (2,3,4).
  EXPECT_EQ(unstripify(std::vector<uint32_t>{0, 1, 2, 3, 4}), (std::vector<uint32_t>{0, 1, 2, 2, 1, 3, 2, 3, 4}));
  // A degenerate join: 0 1 2 | 2 5 | 5 6 7: the only non-degenerate triangles are (0,1,2) and the one
  // at odd position 5, reversed: (6,5,7).
  EXPECT_EQ(unstripify(std::vector<uint32_t>{0, 1, 2, 2, 5, 5, 6, 7}), (std::vector<uint32_t>{0, 1, 2, 6, 5, 7}));
  // A restart resets the parity: the second strip's first triangle is not reversed.
  const uint32_t R = 0xFFFFFFFFu;
  EXPECT_EQ(unstripify(std::vector<uint32_t>{0, 1, 2, 3, R, 4, 5, 6}, true),
            (std::vector<uint32_t>{0, 1, 2, 2, 1, 3, 4, 5, 6}));
  // A swap (the repeated 1) turns the strip: (0,1,2), the degenerate (1,2,1), then (2,1,3) at even position 2.
  EXPECT_EQ(unstripify(std::vector<uint32_t>{0, 1, 2, 1, 3}), (std::vector<uint32_t>{0, 1, 2, 2, 1, 3}));
}

TEST(Strips, StatisticsByHand) {
  const uint32_t R = 0xFFFFFFFFu;
  const StripStats a = analyze_strips(std::vector<uint32_t>{0, 1, 2, 3, R, 4, 5, 6}, true);
  EXPECT_EQ(a.indices, 8u);
  EXPECT_EQ(a.strips, 2u);
  EXPECT_EQ(a.triangles, 3u);
  EXPECT_DOUBLE_EQ(a.indices_per_triangle, 8.0 / 3.0);
  // Degenerate join: 0 1 2 3 3 4 4 5 6: triangles (0,1,2), (1,2,3), then four degenerate, then (4,5,6).
  const StripStats b = analyze_strips(std::vector<uint32_t>{0, 1, 2, 3, 3, 4, 4, 5, 6});
  EXPECT_EQ(b.triangles, 3u);
  EXPECT_EQ(b.degenerate_triangles, 4u);
  EXPECT_EQ(b.strips, 2u);
}

TEST(Strips, ARowOfQuadsIsOneStrip) {
  // A 12 x 1 grid: 24 triangles in a row, every quad split along the same diagonal, which is what the
  // plain zig-zag b0 t0 b1 t1 ... draws. Both stripifiers start at an end triangle (one neighbour)
  // and the forced alternation then follows the row: one strip of 24 + 2 indices.
  const Mesh row = shapes::grid(12, 1);
  for (const StripMethod method : {StripMethod::sgi, StripMethod::best}) {
    const Strips s = stripify(row.indices, row.vertex_count(), {.method = method, .use_restart = true});
    EXPECT_EQ(s.strips, 1u) << strip_method_name(method);
    EXPECT_EQ(s.indices.size(), 26u) << strip_method_name(method);
  }
}

TEST(Strips, BestUsesFewerIndicesThanSgiOnClosedShapes) {
  for (const Mesh& m : {shapes::icosphere(4), shapes::torus(1.0f, 0.3f, 48, 24)})
    for (const bool restart : {false, true}) {
      const Strips sgi = stripify(m.indices, m.vertex_count(), {.method = StripMethod::sgi, .use_restart = restart});
      const Strips best = stripify(m.indices, m.vertex_count(), {.method = StripMethod::best, .use_restart = restart});
      EXPECT_LE(best.indices.size(), sgi.indices.size()) << restart;
      // Far from one strip per triangle: well under 3 indices per triangle.
      EXPECT_LT(double(best.indices.size()) / double(m.triangle_count()), 2.0);
    }
}

TEST(Strips, DegenerateInputTrianglesAreLeftOutAndCounted) {
  Mesh m = shapes::icosphere(1);
  m.indices.insert(m.indices.end(), {0, 0, 1, 2, 3, 3});
  const Strips s = stripify(m.indices, m.vertex_count());
  EXPECT_EQ(s.dropped_degenerate, 2u);
  EXPECT_EQ(s.triangles, m.triangle_count() - 2);
  std::vector<uint32_t> kept(m.indices.begin(), m.indices.end() - 6);
  EXPECT_EQ(test::index_triangles(unstripify(s.indices)), test::index_triangles(kept));
}

TEST(Strips, RestartIndexMustNotBeAVertex) {
  const Mesh m = shapes::icosphere(0);
  EXPECT_THROW(stripify(m.indices, m.vertex_count(), {.use_restart = true, .restart_index = 3}), Error);
}

TEST(Strips, JoinedBuffersStayDecodable) {
  const Mesh a = shapes::icosphere(1), b = shapes::torus(1.0f, 0.3f, 10, 6);
  for (const bool restart : {false, true}) {
    Strips joined = stripify(a.indices, a.vertex_count(), {.use_restart = restart});
    // b's vertices numbered after a's.
    std::vector<uint32_t> shifted = b.indices;
    for (uint32_t& i : shifted) i += uint32_t(a.vertex_count());
    const Strips more = stripify(shifted, a.vertex_count() + b.vertex_count(), {.use_restart = restart});
    append_strips(joined, more);
    std::vector<uint32_t> all = a.indices;
    all.insert(all.end(), shifted.begin(), shifted.end());
    EXPECT_EQ(test::index_triangles(unstripify(joined.indices, restart)), test::index_triangles(all));
    EXPECT_EQ(joined.triangles, a.triangle_count() + b.triangle_count());
  }
}

TEST(Adjacency, TwinsBoundaryAndNonManifoldEdges) {
  // Two triangles on a square: one shared edge (twins, consistent), four boundary edges.
  const std::vector<uint32_t> square = {0, 1, 2, 0, 2, 3};
  const core::TriangleAdjacency a = core::triangle_adjacency(square, {}, 4);
  EXPECT_EQ(a.manifold_edges, 1u);
  EXPECT_EQ(a.boundary_edges, 4u);
  EXPECT_EQ(a.inconsistent_edges, 0u);
  EXPECT_EQ(a.twin[2], 3u);  // triangle 0's edge 2->0 pairs with triangle 1's edge 0->2
  EXPECT_EQ(a.twin[3], 2u);
  EXPECT_EQ(a.neighbour(0, 2), 1u);
  EXPECT_EQ(a.neighbour(0, 0), core::no_twin);
  // Flip the second: the shared edge now runs the same way in both.
  const core::TriangleAdjacency f = core::triangle_adjacency(std::vector<uint32_t>{0, 1, 2, 0, 3, 2}, {}, 4);
  EXPECT_EQ(f.inconsistent_edges, 1u);
  EXPECT_EQ(f.twin_same_direction[2], 1u);
  // The fin: one edge with three triangles, no twins anywhere.
  const Mesh fin = shapes::fin();
  const core::TriangleAdjacency n = core::triangle_adjacency(fin.indices, {}, fin.vertex_count());
  EXPECT_EQ(n.non_manifold_edges, 1u);
  EXPECT_EQ(n.manifold_edges, 0u);
  EXPECT_EQ(n.boundary_edges, 6u);
  // Keyed by position ids, the cube's 12 triangles close up: 18 manifold edges, no boundary.
  const Mesh cube = shapes::cube();
  const PositionIds ids = position_ids(cube);
  const core::TriangleAdjacency c = core::triangle_adjacency(cube.indices, ids.id, ids.count);
  EXPECT_EQ(c.manifold_edges, 18u);
  EXPECT_EQ(c.boundary_edges, 0u);
  // Keyed by indices, its hard edges are boundaries.
  EXPECT_GT(core::triangle_adjacency(cube.indices, {}, cube.vertex_count()).boundary_edges, 0u);
  // Degenerate triangles take no part.
  const core::TriangleAdjacency d = core::triangle_adjacency(std::vector<uint32_t>{0, 0, 1}, {}, 2);
  EXPECT_EQ(d.degenerate_triangles, 1u);
  EXPECT_EQ(d.boundary_edges, 0u);
}

}  // namespace
}  // namespace lod
