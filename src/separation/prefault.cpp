#include "prefault.hpp"

#include <cstdint>
#include <system_error>

#include "../common/memory.hpp"

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace trueaxis::separation::detail {

namespace {

#if defined(__linux__)
#ifndef MADV_POPULATE_WRITE
#define MADV_POPULATE_WRITE 23  // Linux 5.14 uapi value; older kernels answer EINVAL
#endif

bool worth_a_thread() {
  static const bool multi = std::thread::hardware_concurrency() > 1;
  return multi;
}

std::uintptr_t page_size() {
  static const std::uintptr_t page = static_cast<std::uintptr_t>(sysconf(_SC_PAGESIZE));
  return page;
}

// Huge pages where the kernel allows them: one fault commits 512 pages, and the later passes over
// them miss the TLB less.
void advise_huge(const std::vector<Prefault::Region>& regions) {
  for (const auto& r : regions) trueaxis::detail::advise_huge_pages(r.data, r.bytes);
}

void populate(const std::vector<Prefault::Region>& regions) {
  const std::uintptr_t page = page_size();
  for (const auto& r : regions) {
    // Whole pages inside the region only: the pages at its ends may belong to other data.
    const auto b = reinterpret_cast<std::uintptr_t>(r.data);
    const std::uintptr_t first = (b + page - 1) / page * page;
    const std::uintptr_t last = (b + r.bytes) / page * page;
    if (last <= first) continue;
    // Chunks of 1 MB, so that the caller, writing the same region from its start, finds the
    // helper ahead of it rather than both waiting on one long call.
    constexpr std::uintptr_t kChunk = std::uintptr_t{1} << 20;
    for (std::uintptr_t p = first; p < last; p += kChunk) {
      const std::uintptr_t e = p + kChunk < last ? p + kChunk : last;
      if (madvise(reinterpret_cast<void*>(p), e - p, MADV_POPULATE_WRITE) != 0)
        return;  // not supported here (or no memory to commit now): the caller's faults remain
    }
  }
}
#endif

}  // namespace

Prefault::Prefault(std::vector<Region> regions) {
#if defined(__linux__)
  std::vector<Region> big;
  for (const Region& r : regions)
    if (r.data && r.bytes >= kMinBytes) big.push_back(r);
  if (big.empty()) return;
  advise_huge(big);
  if (!worth_a_thread()) return;
  try {
    thread_ = std::thread([big = std::move(big)] { populate(big); });
  } catch (const std::system_error&) {
    // No thread to spare: the caller takes the faults itself.
  }
#else
  (void)regions;
#endif
}

Prefault::~Prefault() {
  if (thread_.joinable()) thread_.join();
}

}  // namespace trueaxis::separation::detail
