// The allocator for large scratch buffers: big blocks start on a 2 MB boundary and are marked for
// transparent huge pages before anything is written to them; small ones are plain; contents are
// whatever the caller writes.
#include "../../src/common/memory.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "../test_util.hpp"

using trueaxis::detail::HugePageAllocator;
using trueaxis::detail::kHugePageBytes;

TEST(HugePageAllocator, AlignsAndMarksLargeBlocks) {
  constexpr std::size_t n = (std::size_t{12} << 20) / sizeof(double) + 3;  // 12 MB and a bit
  std::vector<double, HugePageAllocator<double>> v;
  v.resize(n);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(v.data()) % kHugePageBytes, 0u);
  const std::string flags = trueaxis::test::vm_flags_of_mapping(v.data() + n / 2);
  ASSERT_NE(flags, "") << "no mapping holds the buffer in /proc/self/smaps";
  EXPECT_NE(flags.find(" hg"), std::string::npos) << flags;
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<double>(i);
  v.resize(2 * n);  // reallocation keeps what was written
  for (std::size_t i = 0; i < n; i += 1000) ASSERT_EQ(v[i], static_cast<double>(i)) << i;
  EXPECT_EQ(v[n - 1], static_cast<double>(n - 1));
}

TEST(HugePageAllocator, SmallBlocksAndValuesAreOrdinary) {
  std::vector<int, HugePageAllocator<int>> small(5, 7);  // an explicit value is still written
  for (int x : small) EXPECT_EQ(x, 7);
  small.push_back(9);
  EXPECT_EQ(small.back(), 9);
  const std::vector<unsigned char, HugePageAllocator<unsigned char>> bytes(kHugePageBytes - 1, 1);
  EXPECT_EQ(bytes.front() + bytes.back(), 2);
}
