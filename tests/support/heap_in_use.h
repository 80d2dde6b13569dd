// The heap a test program holds, for tests that bound what a structure keeps per item.
#pragma once

#include <cstddef>

#if defined(__SANITIZE_ADDRESS__)
#define RDTF_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define RDTF_TEST_ASAN 1
#endif
#endif

#ifdef RDTF_TEST_ASAN
#include <sanitizer/allocator_interface.h>
#else
#include <malloc.h>
#endif

namespace rdtf::testing {

// Bytes the program has allocated and not freed (ASan counts its own allocations; glibc's
// counters sum every arena, and blocks it mapped on their own).
inline std::size_t heap_in_use() {
#ifdef RDTF_TEST_ASAN
  return __sanitizer_get_current_allocated_bytes();
#else
  const struct mallinfo2 info = mallinfo2();
  return info.uordblks + info.hblkhd;
#endif
}

}  // namespace rdtf::testing
