// Cache-line aligned storage for the vector kernels (a 64-byte load from an array that std::allocator
// placed 16 bytes into a line touches two lines) and for arrays that threads write (State's particle arrays:
// the threads' shares start on whole lines, so no line holds two threads' particles).
#pragma once

#include <cstddef>
#include <new>
#include <vector>

namespace pmfrag::detail {

template <class T>
struct AlignedAllocator {
  using value_type = T;
  static constexpr std::align_val_t alignment{64};
  AlignedAllocator() = default;
  template <class U>
  AlignedAllocator(const AlignedAllocator<U>&) {}
  // Whole lines: an array written by one thread then shares no line with another thread's array (false
  // sharing between this VM's virtual cores costs 150-600 ns a line).
  static std::size_t bytes(std::size_t n) { return (n * sizeof(T) + 63) / 64 * 64; }
  T* allocate(std::size_t n) { return static_cast<T*>(::operator new(bytes(n), alignment)); }
  void deallocate(T* p, std::size_t) { ::operator delete(p, alignment); }
  template <class U>
  bool operator==(const AlignedAllocator<U>&) const {
    return true;
  }
};

}  // namespace pmfrag::detail

namespace pmfrag {
/// A std::vector whose storage starts on a cache line (and ends on one).
template <class T>
using AlignedVector = std::vector<T, detail::AlignedAllocator<T>>;
}  // namespace pmfrag
