// A fixed-size array of floats that starts at zero without writing it: large arrays are fresh anonymous
// pages (zero by the kernel, no memset over them), asked for as transparent huge pages on Linux so a
// 10 MB array costs a handful of page faults instead of 2,500 and its scattered writes miss the TLB less.
// The photon batches' tallies (integrators/photon_tracer.h: 8 copies of a grid per build) are the use:
// their zero-fill and first-touch faults were ~10 % of mfs's set-up on the Disney cloud (issue 12).
#pragma once

#include <cstddef>
#include <cstdlib>
#include <new>
#include <utility>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace nimbus {

class ZeroedFloats {
 public:
  ZeroedFloats() = default;
  explicit ZeroedFloats(size_t n) : size_(n) {
    if (n == 0) return;
    const size_t bytes = n * sizeof(float);
#if defined(__linux__)
    if (bytes >= kMapBytes) {
      // Whole huge pages from a 2 MiB boundary on (THP needs aligned, whole ranges: an array's partial last
      // page, or a 1.4 MB array whole, would fault 4 KiB at a time), so over-allocate by one for the
      // alignment. Pages never touched cost nothing.
      const size_t whole = (bytes + kHugePage - 1) & ~(kHugePage - 1);
      map_bytes_ = whole + kHugePage;
      void* p = mmap(nullptr, map_bytes_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
      if (p == MAP_FAILED) throw std::bad_alloc();
      map_ = p;
      const size_t addr = reinterpret_cast<size_t>(p);
      const size_t aligned = (addr + kHugePage - 1) & ~(kHugePage - 1);
      madvise(reinterpret_cast<void*>(aligned), whole, MADV_HUGEPAGE);  // a hint: ignored where unsupported
      data_ = reinterpret_cast<float*>(aligned);
      return;
    }
#endif
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
#if defined(__linux__)
    if (map_) {
      munmap(map_, map_bytes_);
      return;
    }
#endif
    std::free(data_);
  }

  float* data() { return data_; }
  const float* data() const { return data_; }
  size_t size() const { return size_; }
  float& operator[](size_t i) { return data_[i]; }
  const float& operator[](size_t i) const { return data_[i]; }

 private:
  static constexpr size_t kHugePage = size_t(2) << 20;
  static constexpr size_t kMapBytes = size_t(1) << 20;  // smaller arrays: calloc
  void swap(ZeroedFloats& o) noexcept {
    std::swap(data_, o.data_), std::swap(size_, o.size_), std::swap(map_, o.map_),
        std::swap(map_bytes_, o.map_bytes_);
  }
  float* data_ = nullptr;
  size_t size_ = 0;
  void* map_ = nullptr;  // the mapping data_ lies in (large arrays on Linux), else null
  size_t map_bytes_ = 0;
};

}  // namespace nimbus
