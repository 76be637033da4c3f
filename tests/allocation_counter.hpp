#pragma once
// Counts every heap allocation of the process: malloc and its relatives are interposed (operator
// new and Eigen both end there), and Eigen's own check (EIGEN_RUNTIME_NO_MALLOC, defined for the
// no-allocation test binaries) is armed while counting. The interposition is per binary: include
// this header in exactly one source file of a test executable.
// Under AddressSanitizer, which owns malloc (an interposed one would hand it blocks it did not
// allocate), the count comes from its allocation hook instead: every malloc, operator new,
// aligned or reallocated block goes through it.

#include <Eigen/Core>
#include <atomic>
#include <cstdlib>

#include "sanitizers.hpp"

namespace stride::testing::detail {
inline std::atomic<bool> g_counting{false};
inline std::atomic<long> g_allocations{0};
inline void count() {
  if (g_counting) ++g_allocations;
}
}  // namespace stride::testing::detail

#ifdef STRIDE_ADDRESS_SANITIZER
namespace stride::testing::detail {
inline void allocated(const volatile void*, size_t) {
  count();
}
inline void freed(const volatile void*) {}
// Static, not inline: the header is in one source file of a binary, and the hook must be installed.
[[maybe_unused]] static const int g_hooks_installed =
    __sanitizer_install_malloc_and_free_hooks(allocated, freed);
}  // namespace stride::testing::detail
#else
extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void* __libc_memalign(size_t, size_t);

void* malloc(size_t n) {
  stride::testing::detail::count();
  return __libc_malloc(n);
}
void* calloc(size_t n, size_t s) {
  stride::testing::detail::count();
  return __libc_calloc(n, s);
}
void* realloc(void* p, size_t n) {
  stride::testing::detail::count();
  return __libc_realloc(p, n);
}
void* memalign(size_t a, size_t n) {
  stride::testing::detail::count();
  return __libc_memalign(a, n);
}
void* aligned_alloc(size_t a, size_t n) {
  stride::testing::detail::count();
  return __libc_memalign(a, n);
}
int posix_memalign(void** p, size_t a, size_t n) {
  stride::testing::detail::count();
  *p = __libc_memalign(a, n);
  return *p ? 0 : 12;
}
}
#endif

namespace stride::testing {

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

}  // namespace stride::testing
