// Internal: the vertex-cache orderers behind lod::vertex_cache_order, exposed for tests and tuning.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "lodkit/optimize.h"

namespace lod::detail {

inline constexpr uint32_t max_cache_size = 64;
inline constexpr uint32_t live_table_size = 16;  // vertices with more triangles left share the last entry

// The greedy walk's vertex score: cache[position in the simulated cache] + live[triangles left].
struct CacheScoring {
  uint32_t cache_size = 16;
  CachePolicy model = CachePolicy::lru;  // how the simulated cache moves
  float cache[max_cache_size + 1] = {};  // [cache_size]: not cached
  float live[live_table_size] = {};      // [0] unused
};
CacheScoring default_scoring(uint32_t cache_size, bool index_codec = false);

// Forsyth-style greedy walk with the given scoring; returns the triangle order.
std::vector<uint32_t> greedy_cache_order(std::span<const uint32_t> indices, size_t vertex_count, const CacheScoring& scoring);

// lodkit's FIFO orderer: fans around one vertex at a time, like Tipsify, but picks the next fan
// centre among all cached vertices by the cost of its fan in the simulated FIFO: its corner misses
// (uncached corners over its remaining triangles, a corner shared by two counting twice) per
// triangle, plus `eviction_weight` per entry among the oldest it would push out (half the corner
// misses) that still has triangles, plus
// `live_weight` per triangle left around the centre (ties go to the oldest entry). Inside a fan, the
// triangle needing the fewest misses goes first, on a tie the one holding the oldest cached corner.
struct FanScoring {
  uint32_t cache_size = 16;
  float eviction_weight = -0.2f;
  float live_weight = 0.02f;
  uint32_t start = 0xFFFFFFFFu;  // the first centre (when it has triangles); else one with the fewest triangles
};
std::vector<uint32_t> fan_cache_order(std::span<const uint32_t> indices, size_t vertex_count, const FanScoring& scoring);

// Extra starts of the fan orderer on small FIFO inputs (lod::vertex_cache_order): n =
// min(max_extra_starts, extra_start_triangles / F) more runs, from the first corner of input
// triangles 0, F/n, ...; at most `extra_start_triangles` triangles of extra work, so inputs of more
// than that run each orderer once. One start (the input's own) on at most 1,024 triangles: each
// fan-orderer run costs 0.7-1x meshoptimizer's whole optimiser, and the target is 2x. When an extra
// start runs, Tipsify does not.
inline constexpr uint32_t max_extra_starts = 1;
inline constexpr uint32_t extra_start_triangles = 1024;

// Tipsify for a FIFO cache of `cache_size`; returns the triangle order.
std::vector<uint32_t> tipsify_order(std::span<const uint32_t> indices, size_t vertex_count, uint32_t cache_size);

}  // namespace lod::detail
