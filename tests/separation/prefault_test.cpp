// Committing pages on a helper thread must never change what the caller reads or writes: the
// helper runs while the caller fills the same buffers, and on regions that share pages with
// other data.
#include "../../src/separation/prefault.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "../test_util.hpp"

using trueaxis::separation::detail::Prefault;

TEST(Prefault, LeavesContentsAsTheCallerWroteThem) {
  constexpr std::size_t n = (std::size_t{24} << 20) / sizeof(std::uint64_t);  // 24 MB
  std::vector<std::uint64_t> a(n / 2, 7);                                     // already written
  std::vector<std::uint64_t> b;
  b.reserve(n);  // new pages, written below while the helper commits them
  {
    // Regions that start and end inside pages (offsets of 1 element), one below the threshold.
    const Prefault prefault({{a.data() + 1, (a.size() - 2) * sizeof(std::uint64_t)},
                             {b.data() + 1, (n - 2) * sizeof(std::uint64_t)},
                             {a.data(), Prefault::kMinBytes - 1},
                             {nullptr, std::size_t{64} << 20}});
    const Prefault none({});
    for (std::size_t i = 0; i < n; ++i) b.push_back(i * 2654435761u);
    for (std::size_t i = 0; i < a.size(); i += 4096) a[i] = i;
  }
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(b[i], i * 2654435761u) << i;
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], i % 4096 == 0 ? i : 7u) << i;
}

// The regions are marked for transparent huge pages ("hg" in the mapping's flags), so that where
// the kernel gives them one fault commits 2 MB instead of 4 KB. Whether it has a huge page to give
// at that moment is the kernel's affair; the mark is ours.
TEST(Prefault, AsksForHugePages) {
  constexpr std::size_t n = (std::size_t{16} << 20) / sizeof(double);  // 16 MB, new memory
  std::vector<double> v;
  v.reserve(n);
  {
    const Prefault prefault({{v.data(), n * sizeof(double)}});
    for (std::size_t i = 0; i < n; ++i) v.push_back(static_cast<double>(i));
  }
  const std::string flags = trueaxis::test::vm_flags_of_mapping(v.data() + n / 2);
  ASSERT_NE(flags, "") << "no mapping holds the buffer in /proc/self/smaps";
  EXPECT_NE(flags.find(" hg"), std::string::npos) << flags;
  for (std::size_t i = 0; i < n; i += 4096) ASSERT_EQ(v[i], static_cast<double>(i));
}
