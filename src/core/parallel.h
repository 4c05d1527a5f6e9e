// Internal: deterministic data parallelism. Work is cut into fixed-size blocks whatever the thread
// count, each block's output is kept apart and joined in block order, so results never depend on
// how many threads ran.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <latch>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include "lodkit/error.h"

namespace lod::core {

inline unsigned thread_count(unsigned requested) {
  if (requested) return requested;
  const unsigned hardware = std::thread::hardware_concurrency();
  return hardware ? hardware : 1;
}

// The number of threads parallel_blocks uses: more workers than cores only adds switching (and
// oneTBB warns), and the result is the same anyway.
inline size_t parallel_workers(size_t count, size_t block_size, unsigned threads) {
  const size_t blocks = (count + block_size - 1) / block_size;
  const size_t cores = size_t(std::max(1, tbb::info::default_concurrency()));
  return std::min({size_t(thread_count(threads)), blocks, cores});
}

// Calls fn(block, begin, end) for every block of `block_size` items of [0, count), on up to
// `threads` threads. Blocks are claimed dynamically; fn must only write block-owned outputs.
// Runs inline (no task overhead) when one thread or one block is enough.
template <class Fn>
void parallel_blocks(size_t count, size_t block_size, unsigned threads, Fn&& fn) {
  const size_t blocks = (count + block_size - 1) / block_size;
  const size_t workers = parallel_workers(count, block_size, threads);
  if (workers <= 1) {
    for (size_t b = 0; b < blocks; ++b) fn(b, b * block_size, std::min(count, (b + 1) * block_size));
    return;
  }
  // oneTBB's persistent workers: callers run many short parallel steps (the simplifier several per
  // pass), where starting threads each time would cost more than the work. (A single arena kept for
  // the process was 1 us per call faster, but its workers outlive main(), and with them the
  // thread-local scratch of the simplifier, which LeakSanitizer reports where its TLS scan is off.)
  tbb::task_arena arena{static_cast<int>(workers)};
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks, 1), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t b = range.begin(); b < range.end(); ++b) fn(b, b * block_size, std::min(count, (b + 1) * block_size));
    });
  });
}

// parallel_blocks for independent per-item work: fn(i) for every i in [0, count).
template <class Fn>
void parallel_for(size_t count, unsigned threads, Fn&& fn, size_t block_size = 4096) {
  parallel_blocks(count, block_size, threads, [&](size_t, size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) fn(i);
  });
}

// Below 2^15 triangles a mesh's simplification gains little from a second thread (lodkit lod
// --threads 1 against 2: 1.0x on elephant's 5.6k, 1.2-1.3x on fandisk's 13k and camel's 20k,
// 1.5-1.6x on armadillo's 52k and bunny00's 75k): a batch's smaller meshes go side by side.
inline constexpr uint64_t small_job_triangles = uint64_t(1) << 15;

// A batch of independent jobs of `sizes[i]` units of work each (meshes, by triangles): run(i,
// job_threads, job_progress) for every i. Jobs under `side_by_side_below` units gain little from a
// second thread, so they run side by side, one thread each (job_progress empty); larger ones first,
// one at a time on all `threads` (job_progress their fraction done). `progress` (may be empty) gets
// the batch's fraction, by units, from the calling thread only. Each job must give the same result
// on any thread count; the batch then does too.
template <class Run>
void parallel_jobs(const std::vector<uint64_t>& sizes, uint64_t side_by_side_below, unsigned threads,
                   const std::function<void(double)>& progress, Run&& run) {
  const unsigned all = thread_count(threads);
  std::vector<size_t> large, small;
  for (size_t i = 0; i < sizes.size(); ++i) (all > 1 && sizes[i] < side_by_side_below ? small : large).push_back(i);
  if (small.size() == 1) large.insert(std::upper_bound(large.begin(), large.end(), small[0]), small[0]), small.clear();
  uint64_t total = 0;
  for (const uint64_t size : sizes) total += std::max<uint64_t>(1, size);
  const auto share = [&](size_t i) { return double(std::max<uint64_t>(1, sizes[i])) / double(total); };
  std::atomic<uint64_t> small_done{0};  // units of the side-by-side jobs finished
  double large_done = 0, reported = 0;
  const std::thread::id caller = std::this_thread::get_id();
  const auto report = [&](double fraction) {
    if (!progress || std::this_thread::get_id() != caller) return;
    reported = std::max(reported, std::min(1.0, fraction));
    progress(reported);
  };
  for (const size_t i : large) {
    const std::function<void(double)> job_progress = [&](double f) {
      report(large_done + f * share(i) + double(small_done.load()) / double(total));
    };
    run(i, threads, job_progress);
    large_done += share(i);
  }
  parallel_for(small.size(), threads, [&](size_t k) {
    const size_t i = small[k];
    run(i, 1u, std::function<void(double)>{});
    small_done += std::max<uint64_t>(1, sizes[i]);
    report(large_done + double(small_done.load()) / double(total));
  }, 1);
  if (progress && !sizes.empty()) progress(1.0);
}

// parallel_jobs over a batch of meshes (anything with triangle_count()), by triangles: run(i,
// job_threads, job_progress) for each. `caller` names the batch in the error a null pointer gets.
template <class M, class Run>
void parallel_meshes(std::span<const M* const> meshes, const char* caller, unsigned threads,
                     const std::function<void(double)>& progress, Run&& run) {
  std::vector<uint64_t> sizes;
  for (const M* mesh : meshes) {
    if (!mesh) throw_usage(std::string(caller) + " needs a mesh behind every pointer");
    sizes.push_back(mesh->triangle_count());
  }
  parallel_jobs(sizes, small_job_triangles, threads, progress, std::forward<Run>(run));
}

// std::sort on up to `threads` threads. Elements that compare equal may end up in any order, so the
// result is the same on any thread count only when they are identical (such as distinct keys).
template <class It>
void parallel_sort(It begin, It end, unsigned threads) {
  const size_t workers = parallel_workers(size_t(end - begin), size_t(1) << 14, threads);
  if (workers <= 1) return std::sort(begin, end);
  tbb::task_arena arena{static_cast<int>(workers)};
  arena.execute([&] { tbb::parallel_sort(begin, end); });
}

// Runs side() on a worker alongside main(), which runs on the calling thread itself (so it may report
// progress there); both may use parallel_blocks inside. Returns when both are done, rethrowing the
// first exception (main's before side's). With one thread, side() runs first.
template <class Side, class Main>
void run_alongside(unsigned threads, Side&& side, Main&& main) {
  const size_t workers = parallel_workers(2, 1, threads);  // two tasks
  if (workers <= 1) {
    side();
    main();
    return;
  }
  std::exception_ptr side_error, main_error;
  std::latch side_done(1);
  // enqueue, not a task group inside execute(): an enqueued task always gets a worker, and main()
  // stays on this thread. The arena goes once side() is done (a worker still leaving it keeps it).
  tbb::task_arena arena{static_cast<int>(workers)};
  arena.enqueue([&] {
    try {
      side();
    } catch (...) {
      side_error = std::current_exception();
    }
    side_done.count_down();
  });
  try {
    main();
  } catch (...) {
    main_error = std::current_exception();
  }
  side_done.wait();
  if (main_error) std::rethrow_exception(main_error);
  if (side_error) std::rethrow_exception(side_error);
}

}  // namespace lod::core
