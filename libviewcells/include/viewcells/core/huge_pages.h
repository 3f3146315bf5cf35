#pragma once
/// An allocator for large arrays read at random (tens of megabytes, one cache line per
/// element): it asks the kernel for 2 MB pages (madvise MADV_HUGEPAGE), so that random reads
/// miss the TLB far less often. Where transparent huge pages are off, or on other systems,
/// the memory is the same, in ordinary pages. Small arrays use the ordinary allocator.
#include <cstddef>
#include <cstdlib>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace viewcells {

template <class T>
class HugePageAllocator {
 public:
  using value_type = T;
  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

  T* allocate(size_t n) {
    const size_t bytes = n * sizeof(T);
    if (n > static_cast<size_t>(-1) / sizeof(T)) throw std::bad_alloc();
    if (!huge(bytes)) return static_cast<T*>(::operator new(bytes, std::align_val_t(alignof(T))));
    void* p = std::aligned_alloc(kPage, rounded(bytes));
    if (!p) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    madvise(p, rounded(bytes), MADV_HUGEPAGE);  // a hint: failure leaves ordinary pages
#endif
    return static_cast<T*>(p);
  }
  void deallocate(T* p, size_t n) noexcept {
    if (huge(n * sizeof(T)))
      std::free(p);
    else
      ::operator delete(p, std::align_val_t(alignof(T)));
  }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const noexcept {
    return true;
  }
  template <class U>
  bool operator!=(const HugePageAllocator<U>&) const noexcept {
    return false;
  }

 private:
  static constexpr size_t kPage = size_t{2} << 20;
  static bool huge(size_t bytes) { return bytes >= 2 * kPage; }
  static size_t rounded(size_t bytes) { return (bytes + kPage - 1) / kPage * kPage; }
};

}  // namespace viewcells
