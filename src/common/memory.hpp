// Private: hints to the kernel about large new buffers.
//
// The first write to each 4 KB page of new memory is a page fault, which on the virtual machines
// we measure costs several times the writing of the page itself; a run that parses, separates and
// writes 10⁶ stations touches a few hundred megabytes of new memory. Transparent huge pages commit
// 2 MB per fault instead; with the kernel's usual setting ("madvise") only where the program asks.
#pragma once

#include <cstddef>
#include <new>
#include <utility>

namespace trueaxis::detail {

// Buffers smaller than this gain nothing from the hint (no 2 MB block fits inside them).
inline constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;

// Asks for transparent huge pages over [data, data + bytes), rounded out to whole pages (a page
// shared with other data gets the hint too, harmlessly). Only a hint, which changes no data and
// never fails: where the kernel does not offer huge pages, or for the pages already written,
// nothing changes. Call it before the buffer is first written. Does nothing below kHugePageBytes.
void advise_huge_pages(const void* data, std::size_t bytes) noexcept;

// Resizes an Eigen vector or matrix to rows × cols (its contents then unset) and asks for its new
// storage in huge pages before anything is written to it.
template <class Array>
void resize_in_huge_pages(Array& a, std::ptrdiff_t rows, std::ptrdiff_t cols) {
  a.resize(rows, cols);
  advise_huge_pages(a.data(), static_cast<std::size_t>(a.size()) * sizeof(typename Array::Scalar));
}

// A new Eigen vector of n zeros, asked for in huge pages before the zeros are written.
template <class Vector>
Vector huge_page_zeros(std::ptrdiff_t n) {
  Vector v;
  resize_in_huge_pages(v, n, 1);
  v.setZero();
  return v;
}

// An allocator for large scratch buffers that are written before they are read:
//   - resize leaves new elements uninitialised (no zeroing pass; pages never written are never
//     committed);
//   - a block of kHugePageBytes or more starts on a 2 MB boundary, is rounded up to whole 2 MB
//     pages, and is marked for huge pages before anything is written to it. A block that merely
//     follows malloc's layout shares its first and last 2 MB with other data (or malloc's own
//     header, written first), so those stay in 4 KB pages: on the virtual machines we measure,
//     ~3 µs per 4 KB fault, i.e. up to ~3 ms per buffer.
template <class T>
struct HugePageAllocator {
  using value_type = T;
  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}  // NOLINT: rebinding
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const noexcept {
    return true;
  }

  static constexpr std::size_t kAlign = kHugePageBytes;

  T* allocate(std::size_t n) {
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kHugePageBytes) return static_cast<T*>(::operator new(bytes));
    const std::size_t whole = (bytes + kAlign - 1) / kAlign * kAlign;
    void* p = ::operator new (whole, std::align_val_t{kAlign});
    advise_huge_pages(p, whole);
    return static_cast<T*>(p);
  }
  void deallocate(T* p, std::size_t n) noexcept {
    if (n * sizeof(T) < kHugePageBytes)
      ::operator delete(p);
    else
      ::operator delete (p, std::align_val_t{kAlign});
  }
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

}  // namespace trueaxis::detail
