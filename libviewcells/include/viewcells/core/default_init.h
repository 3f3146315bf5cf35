#pragma once
/// std::vector whose resize() leaves new elements of trivial types uninitialised, for large
/// outputs that are written before being read (saves a memset pass over hundreds of megabytes).
#include <memory>
#include <type_traits>
#include <vector>

namespace viewcells {

template <class T, class A = std::allocator<T>>
class DefaultInitAllocator : public A {
  using Traits = std::allocator_traits<A>;

 public:
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U, typename Traits::template rebind_alloc<U>>;
  };
  using A::A;
  DefaultInitAllocator() = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U, typename Traits::template rebind_alloc<U>>& other) noexcept
      : A(other) {}

  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;  // default-init: no zeroing for trivial types
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    Traits::construct(static_cast<A&>(*this), p, std::forward<Args>(args)...);
  }
};

/// A vector of trivially copyable values with uninitialised growth.
template <class T>
using RawVector = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace viewcells
