// Vertex-cache and vertex-fetch order, and the analyzers, against values worked out by hand.
#include <gtest/gtest.h>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/optimize.h"
#include "optimize/vertex_cache.h"
#include "optimize_test_support.h"

namespace lod {
namespace {

TEST(Analyze, CacheMissesByHandFifoAndLru) {
  // Cache of 3 entries; triangles (0,1,2), (0,3,4), (0,1,2).
  //   FIFO: 0 1 2 miss [0 1 2]; 0 hit; 3 miss, 0 leaves [1 2 3]; 4 miss, 1 leaves [2 3 4];
  //         0 miss [3 4 0]; 1 miss [4 0 1]; 2 miss [0 1 2]               -> 8 misses
  //   LRU:  0 1 2 miss (recent first) [2 1 0]; 0 hit [0 2 1]; 3 miss, 1 leaves [3 0 2]; 4 miss, 2 leaves
  //         [4 3 0]; 0 hit [0 4 3]; 1 miss, 3 leaves [1 0 4]; 2 miss, 4 leaves [2 1 0] -> 7 misses
  const std::vector<uint32_t> indices = {0, 1, 2, 0, 3, 4, 0, 1, 2};
  const VertexCacheStats fifo = analyze_vertex_cache(indices, 5, {.cache_size = 3, .policy = CachePolicy::fifo});
  EXPECT_EQ(fifo.misses, 8u);
  EXPECT_EQ(fifo.triangles, 3u);
  EXPECT_EQ(fifo.referenced_vertices, 5u);
  EXPECT_DOUBLE_EQ(fifo.acmr, 8.0 / 3.0);
  EXPECT_DOUBLE_EQ(fifo.atvr, 8.0 / 5.0);
  const VertexCacheStats lru = analyze_vertex_cache(indices, 5, {.cache_size = 3, .policy = CachePolicy::lru});
  EXPECT_EQ(lru.misses, 7u);
  EXPECT_DOUBLE_EQ(lru.acmr, 7.0 / 3.0);
  // A cache of 5 holds everything: one miss per vertex.
  EXPECT_EQ(analyze_vertex_cache(indices, 5, {.cache_size = 5}).misses, 5u);
}

TEST(Analyze, QuadStripByHand) {
  // Two triangles of a quad share two vertices: 4 misses for 2 triangles with any cache of 3 or more.
  const std::vector<uint32_t> quad = {0, 1, 2, 2, 1, 3};
  for (const CachePolicy p : {CachePolicy::fifo, CachePolicy::lru}) {
    const VertexCacheStats s = analyze_vertex_cache(quad, 4, {.cache_size = 3, .policy = p});
    EXPECT_DOUBLE_EQ(s.acmr, 2.0);
    EXPECT_DOUBLE_EQ(s.atvr, 1.0);
  }
}

TEST(Analyze, FetchByHand) {
  // 64-byte vertices on 64-byte lines: each vertex is one line. Vertices 0 1 2 then 3 1 2 with a big
  // vertex cache: 4 misses, 4 lines, overfetch 1. With 16-byte vertices four share a line: one line
  // read for 4 vertices of 16 bytes each = 64 / 64 -> overfetch 1 too, and 64 bytes fetched.
  const std::vector<uint32_t> idx = {0, 1, 2, 3, 1, 2};
  const VertexFetchStats a = analyze_vertex_fetch(idx, 4, {.vertex_size = 64});
  EXPECT_EQ(a.bytes_fetched, 4u * 64u);
  EXPECT_DOUBLE_EQ(a.overfetch, 1.0);
  const VertexFetchStats b = analyze_vertex_fetch(idx, 4, {.vertex_size = 16});
  EXPECT_EQ(b.bytes_fetched, 64u);
  EXPECT_DOUBLE_EQ(b.overfetch, 1.0);
  // Vertices 0 and 100 (16 bytes each) sit on different lines: two lines for 32 bytes -> overfetch 4.
  const VertexFetchStats c = analyze_vertex_fetch(std::vector<uint32_t>{0, 100, 0}, 101, {.vertex_size = 16});
  EXPECT_EQ(c.bytes_fetched, 128u);
  EXPECT_DOUBLE_EQ(c.overfetch, 4.0);
}

TEST(VertexCache, KeepsEveryTriangleAndItsCornerOrder) {
  for (const Mesh& m : {shapes::icosphere(3), shapes::torus(), shapes::cylinder(), shapes::fin()})
    for (const CachePolicy policy : {CachePolicy::fifo, CachePolicy::lru})
      for (const uint32_t size : {3u, 16u, 32u}) {
        const std::vector<uint32_t> out = optimize_vertex_cache(m.indices, m.vertex_count(), {.cache_size = size, .policy = policy});
        // Corner order kept exactly, not just up to rotation: each output triple is an input triple.
        std::vector<std::array<uint32_t, 3>> a, b;
        for (size_t k = 0; k < m.indices.size(); k += 3) {
          a.push_back({m.indices[k], m.indices[k + 1], m.indices[k + 2]});
          b.push_back({out[k], out[k + 1], out[k + 2]});
        }
        std::sort(a.begin(), a.end());
        std::sort(b.begin(), b.end());
        EXPECT_EQ(a, b);
      }
}

TEST(VertexCache, ShuffledGridGetsNearOneLoadPerVertex) {
  // A 40 x 40 grid in random triangle order loads almost every vertex once per triangle corner it
  // touches. Any cache-aware order of a regular grid needs each vertex about once, plus the vertices
  // of a band boundary a second time; a FIFO of 16 allows bands of more than ten vertices, so fewer
  // than 1.4 loads per vertex on average (ATVR), well below the shuffled input.
  const Mesh grid = shapes::grid(40, 40);
  const std::vector<uint32_t> shuffled = test::shuffled_triangles(grid.indices, 1);
  const VertexCacheOptions fifo16{.cache_size = 16};
  const VertexCacheStats before = analyze_vertex_cache(shuffled, grid.vertex_count(), fifo16);
  const VertexCacheStats after = analyze_vertex_cache(optimize_vertex_cache(shuffled, grid.vertex_count(), fifo16), grid.vertex_count(), fifo16);
  EXPECT_GT(before.atvr, 4.0);
  EXPECT_LT(after.atvr, 1.4);
  // A larger cache never needs more loads on this grid.
  const VertexCacheOptions fifo32{.cache_size = 32};
  const VertexCacheStats big = analyze_vertex_cache(optimize_vertex_cache(shuffled, grid.vertex_count(), fifo32), grid.vertex_count(), fifo32);
  EXPECT_LE(big.misses, after.misses);
}

TEST(VertexCache, NeverWorseThanTheOrderersItChoosesFromOrTheInput) {
  // The result is the best of the input order, Tipsify and, for a FIFO, the fan orderer (for an LRU,
  // the Forsyth-style walk), measured on the caller's cache.
  const Mesh m = shapes::torus(1.0f, 0.3f, 40, 20);
  const std::vector<uint32_t> shuffled = test::shuffled_triangles(m.indices, 2);
  for (const CachePolicy policy : {CachePolicy::fifo, CachePolicy::lru})
    for (const uint32_t size : {8u, 16u, 32u}) {
      const VertexCacheOptions o{.cache_size = size, .policy = policy};
      auto misses_of = [&](const std::vector<uint32_t>& order) {
        EXPECT_EQ(order.size(), shuffled.size() / 3);
        std::vector<uint32_t> list;
        for (const uint32_t t : order) list.insert(list.end(), {shuffled[3 * t], shuffled[3 * t + 1], shuffled[3 * t + 2]});
        return analyze_vertex_cache(list, m.vertex_count(), o).misses;
      };
      const uint64_t chosen = analyze_vertex_cache(optimize_vertex_cache(shuffled, m.vertex_count(), o), m.vertex_count(), o).misses;
      EXPECT_LE(chosen, analyze_vertex_cache(shuffled, m.vertex_count(), o).misses);
      EXPECT_LE(chosen, misses_of(detail::tipsify_order(shuffled, m.vertex_count(), size)));
      if (policy == CachePolicy::fifo)
        EXPECT_LE(chosen, misses_of(detail::fan_cache_order(shuffled, m.vertex_count(), {.cache_size = size})));
      else
        EXPECT_LE(chosen, misses_of(detail::greedy_cache_order(shuffled, m.vertex_count(), detail::default_scoring(size))));
    }
}

TEST(VertexCache, FanOrdererFinishesVerticesOneAtATime) {
  // On a closed, regular mesh the fan orderer loads most vertices once: every fan finishes its
  // centre, and a centre is picked from the cache, so few vertices are loaded again after eviction.
  // Each vertex is loaded at least once (ATVR >= 1); an order that loaded every vertex twice would be
  // no better than strips of quads.
  const Mesh sphere = shapes::icosphere(4);
  const std::vector<uint32_t> shuffled = test::shuffled_triangles(sphere.indices, 3);
  const std::vector<uint32_t> order = detail::fan_cache_order(shuffled, sphere.vertex_count(), {.cache_size = 16});
  std::vector<uint32_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (uint32_t t = 0; t < sorted.size(); ++t) ASSERT_EQ(sorted[t], t);
  std::vector<uint32_t> list;
  for (const uint32_t t : order) list.insert(list.end(), {shuffled[3 * t], shuffled[3 * t + 1], shuffled[3 * t + 2]});
  const VertexCacheStats s = analyze_vertex_cache(list, sphere.vertex_count(), {.cache_size = 16});
  EXPECT_GE(s.atvr, 1.0);
  EXPECT_LT(s.atvr, 1.5);
}

TEST(VertexCache, DeterministicAndChecksItsInput) {
  const Mesh m = shapes::icosphere(2);
  EXPECT_EQ(optimize_vertex_cache(m.indices, m.vertex_count()), optimize_vertex_cache(m.indices, m.vertex_count()));
  EXPECT_THROW(optimize_vertex_cache(m.indices, m.vertex_count(), {.cache_size = 2}), Error);
  EXPECT_THROW(optimize_vertex_cache(m.indices, 3), Error);
  EXPECT_TRUE(optimize_vertex_cache(std::vector<uint32_t>{}, 0).empty());
}

TEST(VertexFetch, FirstUseOrderByHand) {
  // Indices 5 2 5 0 2 3 over 6 vertices: first uses 5, 2, 0, 3; then the unused 1 and 4 in order.
  const std::vector<uint32_t> remap = vertex_fetch_remap(std::vector<uint32_t>{5, 2, 5, 0, 2, 3}, 6);
  EXPECT_EQ(remap, (std::vector<uint32_t>{2, 4, 1, 3, 5, 0}));
}

}  // namespace
}  // namespace lod
