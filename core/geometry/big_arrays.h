// Large arrays filled once per conversion (a model's buffers, the surface check's tables), in
// memory that the kernel maps in 2 MiB pages where it can.
//
// Why (issue 6): on the reference machine a first touch of a fresh 4 KiB page costs about 1.4 us
// (64 MiB: 22 ms of CPU), more than everything the converter computes on a million-triangle
// model; mapped as transparent huge pages the same 64 MiB cost 2.9 ms. Linux maps anonymous
// memory in huge pages only where asked (transparent_hugepage=madvise, Debian's default), so the
// arrays below ask for it. Only the advice changes: contents, sizes and lifetimes are those of an
// ordinary allocation, and on systems without the advice nothing changes at all.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace rdtf::internal {

inline constexpr std::size_t kHugePage = std::size_t{2} << 20;

// Asks for huge pages over the whole 2 MiB pages inside [p, p + bytes) that nothing has touched
// yet (advice on touched pages does no harm either). Ranges that hold no whole huge page are
// left alone.
inline void advise_huge_pages([[maybe_unused]] void* p, [[maybe_unused]] std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (bytes < kHugePage) return;
  const auto begin = (reinterpret_cast<std::uintptr_t>(p) + kHugePage - 1) & ~(kHugePage - 1);
  const auto end = (reinterpret_cast<std::uintptr_t>(p) + bytes) & ~(kHugePage - 1);
  if (end > begin) ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#endif
}

// Gives `v` room for n elements, advised before anything is written to it.
template <typename T>
void reserve_huge(std::vector<T>& v, std::size_t n) {
  if (n <= v.capacity()) return;
  v.reserve(n);
  advise_huge_pages(v.data(), v.capacity() * sizeof(T));
}

// Asks BigArray for all-zero bytes.
struct ZeroFilled {};

// An array of n trivially copyable elements, not initialised (or all bytes zero with
// ZeroFilled). From 1 MiB up it takes whole huge pages (aligned, its size rounded up to them):
// 256 faults of 4 KiB pages already cost more than clearing one 2 MiB page.
template <typename T>
class BigArray {
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);

 public:
  BigArray() = default;
  explicit BigArray(std::size_t n) : size_(n) {
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kHugePage / 2) {
      block_.reset(std::malloc(bytes == 0 ? 1 : bytes));
      data_ = static_cast<T*>(block_.get());
    } else {
      // aligned_alloc needs a size that is a multiple of the alignment.
      const std::size_t rounded = (bytes + kHugePage - 1) & ~(kHugePage - 1);
      block_.reset(std::aligned_alloc(kHugePage, rounded));
      data_ = static_cast<T*>(block_.get());
      if (data_) advise_huge_pages(data_, rounded);
    }
    if (!data_) throw std::bad_alloc();
  }
  // All bytes zero, through calloc: memory fresh from the kernel (a large block is mapped anew,
  // and is always so in a short process) is zero already and calloc writes nothing, where a fill
  // would write every byte once more after the kernel cleared it; reused heap memory calloc
  // clears. The block is one huge page larger than asked, so that the array can start at a huge
  // page boundary without touching anything before it (calloc's own header lies below).
  BigArray(std::size_t n, ZeroFilled) : size_(n) {
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kHugePage / 2) {
      block_.reset(std::calloc(bytes == 0 ? 1 : bytes, 1));
      data_ = static_cast<T*>(block_.get());
    } else {
      const std::size_t rounded = (bytes + kHugePage - 1) & ~(kHugePage - 1);
      block_.reset(std::calloc(rounded + kHugePage, 1));
      if (block_) {
        const auto start = (reinterpret_cast<std::uintptr_t>(block_.get()) + kHugePage - 1) & ~(kHugePage - 1);
        data_ = reinterpret_cast<T*>(start);
        advise_huge_pages(data_, rounded);
      }
    }
    if (!data_) throw std::bad_alloc();
  }
  T* data() { return data_; }
  const T* data() const { return data_; }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  std::size_t size() const { return size_; }

 private:
  struct Free {
    void operator()(void* p) const { std::free(p); }
  };
  std::unique_ptr<void, Free> block_;
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace rdtf::internal
