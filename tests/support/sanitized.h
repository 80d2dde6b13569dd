// RDTF_SANITIZED: 1 in the sanitizer build (CI's clang AddressSanitizer + UndefinedBehaviorSanitizer,
// which always come together there), else 0. Tests that starve the process of descriptors while
// vptr-checked code runs are left out of that build: docs/notes/ubsan-descriptors.md.
#pragma once

#if defined(__SANITIZE_ADDRESS__)
#define RDTF_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define RDTF_SANITIZED 1
#endif
#endif
#ifndef RDTF_SANITIZED
#define RDTF_SANITIZED 0
#endif
