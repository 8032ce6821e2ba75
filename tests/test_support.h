// Shared by the tests: sanitizer builds run every test, on fewer frames. The sanitizers check
// memory and undefined behaviour on every code path; the Release build checks the accuracy
// targets on the full frame counts.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif

/// The path of a file `name` in a folder of this test process's own, in the system's temporary
/// folder, removed when the process ends. CTest runs every test in a process of its own, several at
/// once: two tests writing one fixed file name in /tmp read each other's half-written files.
inline std::string tempPath(const std::string& name) {
  static const struct Folder {
    std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("multislit_test_" + std::to_string(::getpid()));
    Folder() { std::filesystem::create_directories(path); }
    ~Folder() {
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  } folder;
  return (folder.path / name).string();
}

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
