// core/heap.h: large working arrays keep their contents and, on Linux, carry the huge-page advice
// the kernel reports back for their memory (/proc/self/smaps, VmFlags "hg").
#include "core/heap.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>

namespace lod {
namespace {

TEST(Heap, ReserveHugeKeepsTheElements) {
  for (const size_t count : {size_t(100), size_t(3) << 20}) {  // below and above the huge-array size
    std::vector<uint32_t> v(1000);
    std::iota(v.begin(), v.end(), 7u);
    core::reserve_huge(v, count);
    ASSERT_GE(v.capacity(), count);
    ASSERT_EQ(v.size(), 1000u);
    for (uint32_t i = 0; i < 1000; ++i) ASSERT_EQ(v[i], i + 7) << count;
  }
}

TEST(Heap, ReserveHugeDoesNothingWithRoom) {
  std::vector<double> v(10, 1.5);
  v.reserve(size_t(1) << 20);
  const double* data = v.data();
  core::reserve_huge(v, size_t(1) << 20);
  EXPECT_EQ(v.data(), data);
  EXPECT_EQ(v.size(), 10u);
}

TEST(Heap, MakeHugeFills) {
  const std::vector<uint32_t> v = core::make_huge<uint32_t>((size_t(5) << 20) / 4 + 3, 0xdeadbeefu);
  ASSERT_EQ(v.size(), (size_t(5) << 20) / 4 + 3);
  for (const uint32_t x : v) ASSERT_EQ(x, 0xdeadbeefu);
  EXPECT_TRUE(core::make_huge<float>(0).empty());
}

TEST(Heap, ResizeAssignCopyAsTheVectorOnesDo) {
  const size_t large = (size_t(3) << 20) / sizeof(uint32_t);  // above the huge-array size
  for (const size_t count : {size_t(10), large}) {
    std::vector<uint32_t> v = {1, 2, 3};
    core::resize_huge(v, count);  // keeps the prefix, zero-fills the rest
    ASSERT_EQ(v.size(), count);
    EXPECT_EQ(v[0], 1u);
    EXPECT_EQ(v[2], 3u);
    EXPECT_EQ(v[count - 1], 0u);
    core::assign_huge(v, count / 2, 9);
    ASSERT_EQ(v.size(), count / 2);
    for (const uint32_t x : v) ASSERT_EQ(x, 9u);
    std::vector<uint32_t> from(count);
    std::iota(from.begin(), from.end(), 0u);
    core::copy_huge(v, from);
    EXPECT_EQ(v, from);
  }
}

#if defined(__linux__)
// The VmFlags line of the mapping holding `address`, or "" if none is listed.
std::string vm_flags_at(uintptr_t address) {
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    uintptr_t lo = 0, hi = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> lo >> dash >> hi && dash == '-' && line.find(':') > line.find(' ')) {
      inside = address >= lo && address < hi;
      continue;
    }
    if (inside && line.rfind("VmFlags:", 0) == 0) return line;
  }
  return "";
}

TEST(Heap, LargeArraysAskForHugePages) {
  std::vector<uint8_t> v;
  core::reserve_huge(v, size_t(8) << 20);
  const uintptr_t inside = (reinterpret_cast<uintptr_t>(v.data()) + core::huge_page_bytes) & ~(core::huge_page_bytes - 1);
  const std::string flags = vm_flags_at(inside);
  if (flags.empty()) GTEST_SKIP() << "no /proc/self/smaps";
  // A kernel without transparent huge pages refuses the advice (EINVAL): then there is no flag to see.
  if (!core::advise_huge_pages(v.data(), v.capacity())) GTEST_SKIP() << "madvise(MADV_HUGEPAGE) refused";
  EXPECT_NE(flags.find(" hg"), std::string::npos) << flags;

  std::vector<uint8_t> small;
  core::reserve_huge(small, 4096);  // below the huge-array size: no advice asked
  EXPECT_FALSE(core::advise_huge_pages(small.data(), small.capacity()));
}
#endif

}  // namespace
}  // namespace lod
