// Internal: disjoint sets with path halving and union by index (the smaller root wins, so results are
// deterministic and roots are the first element of each set).
#pragma once

#include <cstdint>
#include <numeric>
#include <vector>

namespace lod::core {

// Follows `next` (~0u ends a chain) from x to its end, pointing every visited entry straight at the
// end (chains are shortened once, whatever their length).
inline uint32_t chain_end(std::vector<uint32_t>& next, uint32_t x) {
  uint32_t end = x;
  while (next[end] != ~0u) end = next[end];
  while (x != end) {
    const uint32_t n = next[x];
    next[x] = end;
    x = n;
  }
  return end;
}

class UnionFind {
 public:
  explicit UnionFind(size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0u); }
  uint32_t find(uint32_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (a < b) parent_[b] = a;
    else parent_[a] = b;
  }

 private:
  std::vector<uint32_t> parent_;
};

}  // namespace lod::core
