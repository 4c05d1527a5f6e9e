// Internal: hashing of exact float bits, shared by the position-id table and the readers that weld.
#pragma once

#include <cstdint>
#include <cstring>

#include "lodkit/mesh.h"

namespace lod::core {

// Bits of a float with -0.0 folded onto +0.0, so the two zeros weld together.
inline uint32_t float_key(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u == 0x80000000u ? 0u : u;
}

inline uint64_t hash_position(const float3& p) {
  // Multiply-xorshift mix of the three keys: cheap, and good enough for open addressing.
  uint64_t h = float_key(p.x) * 0x9E3779B97F4A7C15ull;
  h ^= (h >> 29) ^ (uint64_t(float_key(p.y)) * 0xC2B2AE3D27D4EB4Full);
  h ^= (h >> 31) ^ (uint64_t(float_key(p.z)) * 0x165667B19E3779F9ull);
  return h ^ (h >> 32);
}

inline bool same_position(const float3& a, const float3& b) {
  return float_key(a.x) == float_key(b.x) && float_key(a.y) == float_key(b.y) && float_key(a.z) == float_key(b.z);
}

// Open-addressing map from exact position to a dense id, in order of first insertion.
class PositionWelder {
 public:
  explicit PositionWelder(size_t expected);
  // Id of `p`; a new id (== count() before the call) when first seen.
  uint32_t insert(const float3& p);
  uint32_t count() const { return uint32_t(unique_.size()); }
  const std::vector<float3>& unique_positions() const { return unique_; }
  std::vector<float3> take_unique_positions() { return std::move(unique_); }

 private:
  void grow();
  std::vector<uint32_t> slots_;  // id + 1, 0 for empty
  std::vector<float3> unique_;
  size_t mask_ = 0;
};

}  // namespace lod::core
