#pragma once
// What a test needs to know of the sanitizers it may run under (tools/test.sh --sanitize builds
// the suite with AddressSanitizer and UndefinedBehaviorSanitizer).

#if defined(__SANITIZE_ADDRESS__)  // gcc
#define STRIDE_ADDRESS_SANITIZER 1
#elif defined(__has_feature)  // clang
#if __has_feature(address_sanitizer)
#define STRIDE_ADDRESS_SANITIZER 1
#endif
#endif

#ifdef STRIDE_ADDRESS_SANITIZER
#include <sanitizer/allocator_interface.h>
#endif

namespace stride::test_support {

#ifdef STRIDE_ADDRESS_SANITIZER
constexpr bool kAddressSanitizer = true;
// How much longer a wall-clock budget of a test (a tick's deadline, a state's age) is under the
// sanitizers: the controller's tick runs 3-10x slower there (tests/README.md, "Sanitizers").
constexpr int kSanitizerSlowdown = 20;
#else
constexpr bool kAddressSanitizer = false;
constexpr int kSanitizerSlowdown = 1;
#endif

// The memory a process holds: its resident size, except under AddressSanitizer, where that says
// little (freed blocks wait in a quarantine of up to 256 MB before reuse, and the shadow memory
// grows with them): there, the bytes its allocator has handed out and not taken back.
inline long heldMemoryKb(long resident_kb) {
#ifdef STRIDE_ADDRESS_SANITIZER
  (void)resident_kb;
  return static_cast<long>(__sanitizer_get_current_allocated_bytes() / 1024);
#else
  return resident_kb;
#endif
}
constexpr const char* kHeldMemory = kAddressSanitizer ? "heap in use" : "VmRSS";

}  // namespace stride::test_support
