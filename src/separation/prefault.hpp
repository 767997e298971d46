// Private: commits the pages of large new buffers on another core while the caller goes on.
//
// The first write to a page of new memory costs a page fault (about 1.2 µs per 4 KB page on the
// machines we measure, several times the cost of writing the page itself). For buffers that a
// sequential pass is about to fill, a helper thread asks the kernel to commit their pages ahead of
// it: madvise(MADV_POPULATE_WRITE) (Linux 5.14 and later) makes pages present and writable without
// changing their contents, so the caller may write them at the same time. Where that is not
// available, or on one core, it does nothing and the caller takes the faults as before. The regions
// are also marked for transparent huge pages (madvise(MADV_HUGEPAGE)), so that where the kernel
// allows them one fault commits 2 MB instead of 4 KB, on whichever core touches the page first.
#pragma once

#include <cstddef>
#include <thread>
#include <vector>

namespace trueaxis::separation::detail {

class Prefault {
 public:
  struct Region {
    const void* data;
    std::size_t bytes;
  };
  // Marks the regions for huge pages and starts committing them, in order, on a helper thread.
  // (Pages already written keep their size: the hint helps only where nothing was written yet.)
  // Regions smaller than a few megabytes are left alone (the thread would cost more than their
  // faults).
  explicit Prefault(std::vector<Region> regions);
  Prefault(const Prefault&) = delete;
  Prefault& operator=(const Prefault&) = delete;
  // Waits for the helper: the regions must stay allocated until then.
  ~Prefault();

  static constexpr std::size_t kMinBytes = std::size_t{2} << 20;

 private:
  std::thread thread_;
};

}  // namespace trueaxis::separation::detail
