// Internal: how large working arrays (the readers' meshes, the simplifier's and the BVH's arrays)
// use the system's memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <type_traits>
#include <vector>
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace lod::core {

// Returns the heap's free pages to the system (glibc's malloc_trim; elsewhere nothing), for a call
// that has just freed large working arrays. glibc raises its mmap threshold whenever a large block is
// freed, so a later call's arrays come from the heap instead, and the heap keeps freed pages
// resident: each simplify call raised the process's peak by about 14 MB (armadillo-s2 -> 83,200:
// 175, 189, 202 MB over three calls; with this, 176 MB after any number).
inline void release_free_memory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

// Arrays from this size up ask for transparent huge pages (below it no aligned 2 MiB page fits
// for sure).
constexpr size_t huge_page_bytes = size_t(2) << 20, huge_array_bytes = 2 * huge_page_bytes;

// Asks the kernel to back the whole 2 MiB pages inside [data, data + bytes) with transparent huge
// pages (Linux's madvise mode, Debian's default). Returns whether it was asked and accepted. Only
// before the pages are first touched does it save anything: then one fault maps 2 MiB instead of
// 4 KiB. In a virtual machine a fault costs microseconds: armadillo-s2 -> 83,200 faulted 38k times
// per simplify call, about 6% of it (bench/README, twenty-fifth session).
inline bool advise_huge_pages(void* data, size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (bytes < huge_array_bytes) return false;
  const uintptr_t begin = (reinterpret_cast<uintptr_t>(data) + huge_page_bytes - 1) & ~(huge_page_bytes - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(data) + bytes) & ~(huge_page_bytes - 1);
  if (end <= begin) return false;
  return madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE) == 0;
#else
  (void)data, (void)bytes;
  return false;
#endif
}

// Makes room for `count` elements in `v` (keeping its elements) and, for a large array, asks for
// huge pages before anything touches the new room. Call it before the assign or resize that fills
// a large working array; it does nothing when `v` already has the room.
template <class T>
void reserve_huge(std::vector<T>& v, size_t count) {
  if (v.capacity() >= count) return;
  if (count * sizeof(T) < huge_array_bytes) return v.reserve(count);
  std::vector<T> room;
  room.reserve(count);  // untouched: operator new does not write the block
  advise_huge_pages(room.data(), count * sizeof(T));
  room.insert(room.end(), std::make_move_iterator(v.begin()), std::make_move_iterator(v.end()));
  v.swap(room);
}

// v.resize(count) and v.assign(count, value), with reserve_huge's advice first.
template <class T>
void resize_huge(std::vector<T>& v, size_t count) {
  reserve_huge(v, count);
  v.resize(count);
}
template <class T>
void assign_huge(std::vector<T>& v, size_t count, const std::type_identity_t<T>& value) {
  reserve_huge(v, count);
  v.assign(count, value);
}
// v = from, with reserve_huge's advice first.
template <class T>
void copy_huge(std::vector<T>& v, const std::vector<T>& from) {
  reserve_huge(v, from.size());
  v.assign(from.begin(), from.end());
}
// A large working array of `count` copies of `value`.
template <class T>
std::vector<T> make_huge(size_t count, const std::type_identity_t<T>& value = T()) {
  std::vector<T> v;
  assign_huge(v, count, value);
  return v;
}

}  // namespace lod::core
