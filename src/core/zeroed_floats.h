// A fixed-size array of floats that starts at zero without writing it: large arrays are fresh anonymous
// pages (zero by the kernel, no memset over them), asked for as transparent huge pages on Linux so a
// 10 MB array costs a handful of page faults instead of 2,500 and its scattered writes miss the TLB less.
// The photon batches' tallies (integrators/photon_tracer.h: 8 copies of a grid per build) are the use:
// their zero-fill and first-touch faults were ~10 % of mfs's set-up on the Disney cloud (issue 12).
// HugePageAllocator / FloatArray give the grids built from them (sums, shadow maps) the same pages.
#pragma once

#include <cstddef>
#include <cstdlib>
#include <new>
#include <utility>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace nimbus {

namespace huge_pages {

inline constexpr size_t kHugePage = size_t(2) << 20;
inline constexpr size_t kMapBytes = size_t(1) << 20;  // smaller blocks: the C heap

// Whole huge pages from a 2 MiB boundary on (THP needs aligned, whole ranges: an array's partial last page,
// or a 1.4 MB array whole, would fault 4 KiB at a time): `bytes` rounded up to whole huge pages.
inline size_t whole(size_t bytes) { return (bytes + kHugePage - 1) & ~(kHugePage - 1); }

// Fresh zero pages for `bytes`, asked for as transparent huge pages; only where mapped(bytes) (Linux, and
// at least kMapBytes: the callers take smaller blocks from the heap). Pages never touched cost nothing.
inline void* map(size_t bytes) {
#if defined(__linux__)
  const size_t w = whole(bytes);
  // Over-allocate by one huge page for the alignment, then give back the head and the tail.
  void* p = mmap(nullptr, w + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) throw std::bad_alloc();
  const size_t addr = reinterpret_cast<size_t>(p);
  const size_t aligned = (addr + kHugePage - 1) & ~(kHugePage - 1);
  if (aligned > addr) munmap(p, aligned - addr);
  if (addr + kHugePage > aligned) munmap(reinterpret_cast<void*>(aligned + w), addr + kHugePage - aligned);
  madvise(reinterpret_cast<void*>(aligned), w, MADV_HUGEPAGE);  // a hint: ignored where unsupported
  return reinterpret_cast<void*>(aligned);
#else
  (void)bytes;
  return nullptr;
#endif
}

inline void unmap(void* p, size_t bytes) {
#if defined(__linux__)
  munmap(p, whole(bytes));
#else
  (void)p, (void)bytes;
#endif
}

inline bool mapped(size_t bytes) {
#if defined(__linux__)
  return bytes >= kMapBytes;
#else
  (void)bytes;
  return false;
#endif
}

}  // namespace huge_pages

class ZeroedFloats {
 public:
  ZeroedFloats() = default;
  explicit ZeroedFloats(size_t n) : size_(n) {
    if (n == 0) return;
    if (huge_pages::mapped(n * sizeof(float))) {
      data_ = static_cast<float*>(huge_pages::map(n * sizeof(float)));
      mapped_ = true;
      return;
    }
    data_ = static_cast<float*>(std::calloc(n, sizeof(float)));
    if (!data_) throw std::bad_alloc();
  }
  ZeroedFloats(ZeroedFloats&& o) noexcept { swap(o); }
  ZeroedFloats& operator=(ZeroedFloats&& o) noexcept {
    ZeroedFloats(std::move(o)).swap(*this);
    return *this;
  }
  ZeroedFloats(const ZeroedFloats&) = delete;
  ZeroedFloats& operator=(const ZeroedFloats&) = delete;
  ~ZeroedFloats() {
    if (mapped_)
      huge_pages::unmap(data_, size_ * sizeof(float));
    else
      std::free(data_);
  }

  float* data() { return data_; }
  const float* data() const { return data_; }
  size_t size() const { return size_; }
  float& operator[](size_t i) { return data_[i]; }
  const float& operator[](size_t i) const { return data_[i]; }

 private:
  void swap(ZeroedFloats& o) noexcept {
    std::swap(data_, o.data_), std::swap(size_, o.size_), std::swap(mapped_, o.mapped_);
  }
  float* data_ = nullptr;
  size_t size_ = 0;
  bool mapped_ = false;  // data_ is a huge-page mapping (large arrays on Linux), else from calloc
};

// A std::allocator whose large blocks are whole transparent huge pages (huge_pages::map), for the grids
// that are filled once and read many times (photon sums, shadow maps): a 4 MB grid's fill costs two page
// faults instead of a thousand (each ~10 us on a virtual machine).
template <typename T>
struct HugePageAllocator {
  using value_type = T;
  HugePageAllocator() = default;
  template <typename U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}
  T* allocate(size_t n) {
    const size_t bytes = n * sizeof(T);
    if (huge_pages::mapped(bytes)) return static_cast<T*>(huge_pages::map(bytes));
    return std::allocator<T>().allocate(n);
  }
  void deallocate(T* p, size_t n) noexcept {
    if (huge_pages::mapped(n * sizeof(T)))
      huge_pages::unmap(p, n * sizeof(T));
    else
      std::allocator<T>().deallocate(p, n);
  }
  template <typename U>
  bool operator==(const HugePageAllocator<U>&) const noexcept {
    return true;
  }
};

// A float array of a grid (see HugePageAllocator).
using FloatArray = std::vector<float, HugePageAllocator<float>>;

}  // namespace nimbus
