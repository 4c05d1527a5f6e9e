#pragma once
// Items grouped by a small integer key in one array (compressed rows), by a counting sort: the
// vertex -> triangles lists, half-edges by vertex and the like, without a vector per key.

#include <cstddef>
#include <cstdint>
#include <numeric>
#include <span>
#include <vector>

#include "core/heap.h"

namespace lod::core {

template <class T>
struct Buckets {
  std::vector<uint32_t> first;  // key k's items are items[first[k], first[k + 1])
  std::vector<T> items;

  size_t size() const { return first.empty() ? 0 : first.size() - 1; }
  std::span<const T> operator[](size_t key) const { return {items.data() + first[key], items.data() + first[key + 1]}; }
  std::span<T> operator[](size_t key) { return {items.data() + first[key], items.data() + first[key + 1]}; }
};

// `each(emit)` calls emit(key, item) for every item, key < keys. It is run twice (to count, then to
// fill) and must emit the same sequence both times; within a key, items keep that order, so the
// result depends on nothing but the input.
template <class T, class Each>
Buckets<T> bucket(size_t keys, Each&& each) {
  Buckets<T> b;
  b.first.assign(keys + 1, 0);
  each([&](size_t key, const T&) { ++b.first[key + 1]; });
  std::partial_sum(b.first.begin(), b.first.end(), b.first.begin());
  resize_huge(b.items, b.first[keys]);  // (large ones ask for huge pages)
  std::vector<uint32_t> fill(b.first.begin(), b.first.end() - 1);
  each([&](size_t key, const T& item) { b.items[fill[key]++] = item; });
  return b;
}

}  // namespace lod::core
