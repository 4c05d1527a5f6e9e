// The whole consolidation on a Mesh: every step keeps the triangles (as position triples with their
// winding) and the per-triangle streams; strips decode to the output mesh's triangles.
#include <gtest/gtest.h>

#include <tuple>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/optimize.h"
#include "optimize_test_support.h"

namespace lod {
namespace {

// Each triangle as (its position triple, its material, its group), sorted.
std::vector<std::tuple<test::TriangleKey, uint32_t, uint32_t>> tagged_triangles(const Mesh& m) {
  std::vector<std::tuple<test::TriangleKey, uint32_t, uint32_t>> out;
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    const std::vector<uint32_t> one(m.indices.begin() + long(3 * t), m.indices.begin() + long(3 * t + 3));
    out.emplace_back(test::position_triangles(m.positions, one)[0], m.material(t), m.groups.empty() ? 0 : m.groups[t]);
  }
  std::sort(out.begin(), out.end());
  return out;
}

Mesh with_materials(Mesh m) {
  for (size_t t = 0; t < m.triangle_count(); ++t) m.materials.push_back(uint32_t(t % 3)), m.groups.push_back(uint32_t(t % 2));
  m.material_names = {"a", "b", "c"};
  return m;
}

TEST(Optimize, EveryStepKeepsTheTriangles) {
  const Mesh inputs[] = {with_materials(shapes::torus(1.0f, 0.3f, 24, 12)), shapes::cube(), shapes::cylinder(), shapes::icosphere(2)};
  for (const Mesh& input : inputs)
    for (const bool strips : {false, true})
      for (const bool fetch : {false, true}) {
        SCOPED_TRACE(std::to_string(input.triangle_count()) + (strips ? " strips" : "") + (fetch ? " fetch" : ""));
        const OptimizeResult r = optimize(input, {.weld = true, .orient = false, .cache = {.cache_size = 16}, .strips = strips, .vertex_fetch = fetch});
        EXPECT_EQ(tagged_triangles(r.mesh), tagged_triangles(input));
        validate(r.mesh);
        // The cache order is never worse than the input's (strips follow their own order, and
        // materials split the mesh into ranges the input did not have).
        if (!strips && input.materials.empty()) {
          EXPECT_LE(r.cache_after.misses, r.cache_before.misses);
        }
        // Every output vertex carries the streams of the input vertex source_vertices names.
        EXPECT_EQ(r.mesh.normals.empty(), input.normals.empty());
        ASSERT_EQ(r.source_vertices.size(), r.mesh.vertex_count());
        for (size_t v = 0; v < r.mesh.vertex_count(); ++v) {
          const uint32_t s = r.source_vertices[v];
          ASSERT_LT(s, input.vertex_count());
          ASSERT_EQ(r.mesh.positions[v], input.positions[s]) << v;
          if (!input.normals.empty()) {
            ASSERT_EQ(r.mesh.normals[v], input.normals[s]) << v;
          }
          if (!input.uvs[0].empty()) {
            ASSERT_EQ(r.mesh.uvs[0][v], input.uvs[0][s]) << v;
          }
        }
        if (strips) {
          // The strip buffer draws the output mesh's triangles, over its vertices.
          EXPECT_EQ(test::position_triangles(r.mesh.positions, unstripify(r.strips.indices, r.strips.use_restart, r.strips.restart_index)),
                    test::position_triangles(r.mesh));
          for (uint32_t k = 0; k < r.strips.triangle_order.size(); ++k) EXPECT_EQ(r.strips.triangle_order[k], k);
        }
        if (fetch) {
          // Vertices in order of first use.
          uint32_t next = 0;
          for (const uint32_t i : r.mesh.indices) {
            ASSERT_LE(i, next);
            if (i == next) ++next;
          }
        }
      }
}

TEST(Optimize, MaterialsStayContiguousAndOrdered) {
  const Mesh input = with_materials(shapes::icosphere(2));
  const OptimizeResult r = optimize(input);
  ASSERT_EQ(r.mesh.materials.size(), input.triangle_count());
  EXPECT_TRUE(std::is_sorted(r.mesh.materials.begin(), r.mesh.materials.end()));
  EXPECT_EQ(r.mesh.material_names, input.material_names);
}

TEST(Optimize, OverdrawPassReordersEachMaterialsCacheOrder) {
  // With .overdraw the triangles of each material are the cache order put through overdraw_order:
  // the same triangles and streams, materials still contiguous, and on nested spheres (inner drawn
  // first) less overdraw than the cache order alone, within the threshold's misses.
  const Mesh nested = test::nested_spheres();
  const Mesh three_materials = with_materials(nested);  // the same spheres split into three materials
  for (const Mesh* input : {&nested, &three_materials}) {
    const OptimizeResult cache_only = optimize(*input, {.vertex_fetch = false});
    const OptimizeResult r = optimize(*input, {.overdraw = true, .overdraw_threshold = 1.05f, .vertex_fetch = false});
    EXPECT_EQ(tagged_triangles(r.mesh), tagged_triangles(*input));
    EXPECT_TRUE(std::is_sorted(r.mesh.materials.begin(), r.mesh.materials.end()));
    if (input == &nested) {
      EXPECT_LE(double(r.cache_after.misses), 1.05 * double(cache_only.cache_after.misses));
    }
    // By hand: each material range of the cache order, reordered by overdraw_order.
    std::vector<uint32_t> expected;
    for (size_t begin = 0; begin < cache_only.mesh.triangle_count();) {
      size_t end = begin + 1;
      while (end < cache_only.mesh.triangle_count() && cache_only.mesh.material(end) == cache_only.mesh.material(begin)) ++end;
      const std::vector<uint32_t> range(cache_only.mesh.indices.begin() + long(3 * begin), cache_only.mesh.indices.begin() + long(3 * end));
      for (const uint32_t t : overdraw_order(range, cache_only.mesh.positions, {.cache_size = 16, .threshold = 1.05f}))
        expected.insert(expected.end(), {range[3 * t], range[3 * t + 1], range[3 * t + 2]});
      begin = end;
    }
    EXPECT_EQ(r.mesh.indices, expected);
    EXPECT_GT(r.overdraw_seconds, 0.0);
  }
  const OptimizeResult cache_only = optimize(nested), r = optimize(nested, {.overdraw = true});
  EXPECT_LT(analyze_overdraw(r.mesh.indices, r.mesh.positions).overdraw,
            analyze_overdraw(cache_only.mesh.indices, cache_only.mesh.positions).overdraw - 0.05);
  EXPECT_THROW(optimize(nested, {.strips = true, .overdraw = true}), Error);
}

TEST(Optimize, WeldAndOrientRepairASoup) {
  // An icosphere soup with a third of its faces flipped and its triangles shuffled: after weld and
  // orient it is the sphere again, as a set of position triples with the sphere's own winding.
  const Mesh sphere = shapes::icosphere(3);
  Mesh broken = sphere;
  broken.indices = test::shuffled_triangles(sphere.indices, 4);
  for (size_t t = 0; t < broken.triangle_count(); t += 3) std::swap(broken.indices[3 * t + 1], broken.indices[3 * t + 2]);
  broken = test::triangle_soup(broken);
  const OptimizeResult r = optimize(broken, {.weld = true, .orient = true});
  EXPECT_EQ(r.mesh.vertex_count(), sphere.vertex_count());
  EXPECT_EQ(r.weld.output_vertices, sphere.vertex_count());
  EXPECT_EQ(r.orient.flipped_triangles, (sphere.triangle_count() + 2) / 3);
  EXPECT_EQ(test::position_triangles(r.mesh), test::position_triangles(sphere));
  // Each output vertex names the first soup corner welded into it.
  ASSERT_EQ(r.source_vertices.size(), r.mesh.vertex_count());
  for (size_t v = 0; v < r.mesh.vertex_count(); ++v) {
    const uint32_t s = r.source_vertices[v];
    ASSERT_EQ(broken.positions[s], r.mesh.positions[v]);
    for (uint32_t u = 0; u < s; ++u) ASSERT_NE(broken.positions[u], broken.positions[s]) << v;
  }
  // The cache order makes a real difference on a shuffled soup.
  EXPECT_LT(r.cache_after.acmr, 0.5 * r.cache_before.acmr);
}

TEST(Optimize, ReorderAndRemapByHand) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  m.indices = {0, 1, 2, 2, 1, 3};
  m.materials = {7, 8};
  const Mesh r = reorder_triangles(m, std::vector<uint32_t>{1, 0});
  EXPECT_EQ(r.indices, (std::vector<uint32_t>{2, 1, 3, 0, 1, 2}));
  EXPECT_EQ(r.materials, (std::vector<uint32_t>{8, 7}));
  // New vertex remap[v] is old vertex v.
  const Mesh v = remap_vertices(m, std::vector<uint32_t>{3, 2, 1, 0}, 4);
  EXPECT_EQ(v.indices, (std::vector<uint32_t>{3, 2, 1, 1, 2, 0}));
  EXPECT_EQ(v.positions[3], m.positions[0]);
  EXPECT_EQ(test::position_triangles(v), test::position_triangles(m));
}

}  // namespace
}  // namespace lod
