// The interposition behind allocation_counter.hpp, once per test executable: malloc and its
// relatives count while a counter runs. Under AddressSanitizer, which owns malloc (an interposed
// one would hand it blocks it did not allocate), its allocation hook counts instead: every malloc,
// operator new, aligned or reallocated block goes through it.
#include "allocation_counter.hpp"

#ifdef STRIDE_ADDRESS_SANITIZER
namespace stride::test_support::detail {
inline void allocated(const volatile void*, size_t) {
  count();
}
inline void freed(const volatile void*) {}
[[maybe_unused]] const int g_hooks_installed =
    __sanitizer_install_malloc_and_free_hooks(allocated, freed);
}  // namespace stride::test_support::detail
#else
extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void* __libc_memalign(size_t, size_t);

void* malloc(size_t n) {
  stride::test_support::detail::count();
  return __libc_malloc(n);
}
void* calloc(size_t n, size_t s) {
  stride::test_support::detail::count();
  return __libc_calloc(n, s);
}
void* realloc(void* p, size_t n) {
  stride::test_support::detail::count();
  return __libc_realloc(p, n);
}
void* memalign(size_t a, size_t n) {
  stride::test_support::detail::count();
  return __libc_memalign(a, n);
}
void* aligned_alloc(size_t a, size_t n) {
  stride::test_support::detail::count();
  return __libc_memalign(a, n);
}
int posix_memalign(void** p, size_t a, size_t n) {
  stride::test_support::detail::count();
  *p = __libc_memalign(a, n);
  return *p ? 0 : 12;
}
}
#endif
