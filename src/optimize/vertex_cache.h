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
CacheScoring default_scoring(uint32_t cache_size);

// Forsyth-style greedy walk with the given scoring; returns the triangle order.
std::vector<uint32_t> greedy_cache_order(std::span<const uint32_t> indices, size_t vertex_count, const CacheScoring& scoring);

// Tipsify for a FIFO cache of `cache_size`; returns the triangle order.
std::vector<uint32_t> tipsify_order(std::span<const uint32_t> indices, size_t vertex_count, uint32_t cache_size);

}  // namespace lod::detail
