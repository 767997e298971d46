// Committing pages on a helper thread must never change what the caller reads or writes: the
// helper runs while the caller fills the same buffers, and on regions that share pages with
// other data.
#include "../../src/separation/prefault.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

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
