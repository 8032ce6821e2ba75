// Shared by the tests: sanitizer builds run every test, on fewer frames. The sanitizers check
// memory and undefined behaviour on every code path; the Release build checks the accuracy
// targets on the full frame counts.
#pragma once

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif

/// `release` frames in a normal build, `sanitized` frames under AddressSanitizer.
constexpr int frameCount(int release, int sanitized) { return kSanitized ? sanitized : release; }
