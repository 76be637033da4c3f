#pragma once
// Counts every heap allocation of the process: malloc and its relatives are interposed (operator
// new and Eigen both end there; allocation_counter.cpp, linked once into each test executable that
// counts: tests/CMakeLists.txt), and Eigen's own check (EIGEN_RUNTIME_NO_MALLOC, defined for those
// executables) is armed while counting.
// Under AddressSanitizer, which owns malloc (an interposed one would hand it blocks it did not
// allocate), the count comes from its allocation hook instead: every malloc, operator new,
// aligned or reallocated block goes through it.

#include <Eigen/Core>
#include <atomic>
#include <cstdlib>

#include "sanitizers.hpp"

namespace stride::test_support::detail {
inline std::atomic<bool> g_counting{false};
inline std::atomic<long> g_allocations{0};
inline void count() {
  if (g_counting) ++g_allocations;
}
}  // namespace stride::test_support::detail

namespace stride::test_support {

// Counts from construction to stop() (or destruction).
class AllocationCounter {
 public:
  AllocationCounter() {
    detail::g_allocations = 0;
    Eigen::internal::set_is_malloc_allowed(false);
    detail::g_counting = true;
  }
  ~AllocationCounter() { stop(); }
  long stop() {
    detail::g_counting = false;
    Eigen::internal::set_is_malloc_allowed(true);
    return detail::g_allocations;
  }
};

// The number of allocations f() makes.
template <typename F>
long allocations(F&& f) {
  AllocationCounter counter;
  f();
  return counter.stop();
}

}  // namespace stride::test_support
