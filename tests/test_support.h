// Shared by the tests: sanitizer builds run every test, on fewer frames. The sanitizers check
// memory and undefined behaviour on every code path; the Release build checks the accuracy
// targets on the full frame counts.
#pragma once

#include <stdexcept>
#include <string>

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif

/// `release` frames in a normal build, `sanitized` frames under AddressSanitizer.
constexpr int frameCount(int release, int sanitized) { return kSanitized ? sanitized : release; }

/// What validate() says of a default `Config` after `change(config)`: its message, or "valid".
template <typename Config, typename Change>
std::string validationMessage(Change change) {
  Config config;
  change(config);
  try {
    config.validate();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "valid";
}
