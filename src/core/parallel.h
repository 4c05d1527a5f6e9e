// Internal: deterministic data parallelism. Work is cut into fixed-size blocks whatever the thread
// count, each block's output is kept apart and joined in block order, so results never depend on
// how many threads ran.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace lod::core {

inline unsigned thread_count(unsigned requested) {
  if (requested) return requested;
  const unsigned hardware = std::thread::hardware_concurrency();
  return hardware ? hardware : 1;
}

// Calls fn(block, begin, end) for every block of `block_size` items of [0, count), on up to
// `threads` threads. Blocks are claimed dynamically; fn must only write block-owned outputs.
template <class Fn>
void parallel_blocks(size_t count, size_t block_size, unsigned threads, Fn&& fn) {
  const size_t blocks = (count + block_size - 1) / block_size;
  const size_t workers = std::min<size_t>(thread_count(threads), blocks);
  if (workers <= 1) {
    for (size_t b = 0; b < blocks; ++b) fn(b, b * block_size, std::min(count, (b + 1) * block_size));
    return;
  }
  std::atomic<size_t> next{0};
  auto work = [&] {
    for (size_t b; (b = next.fetch_add(1, std::memory_order_relaxed)) < blocks;)
      fn(b, b * block_size, std::min(count, (b + 1) * block_size));
  };
  std::vector<std::jthread> pool;
  for (size_t k = 1; k < workers; ++k) pool.emplace_back(work);
  work();
}

// parallel_blocks for independent per-item work: fn(i) for every i in [0, count).
template <class Fn>
void parallel_for(size_t count, unsigned threads, Fn&& fn, size_t block_size = 4096) {
  parallel_blocks(count, block_size, threads, [&](size_t, size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) fn(i);
  });
}

}  // namespace lod::core
