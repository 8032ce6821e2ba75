// Shared by the fuzz targets: the loaders read files, so each input is written to a file of this
// process first; and a finding that is not a crash (a broken promise of the API) aborts.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <string>

namespace multislit::fuzz {

/// A folder of this process, removed when the process exits: in /dev/shm (memory) when there is
/// one, else in the temporary directory. (On ext4 a file truncated and written again is flushed
/// to the disk when closed: in /tmp the targets waited for the disk more than they ran.)
inline const std::filesystem::path& scratchDir() {
  struct Dir {
    std::filesystem::path path;
    Dir() {
      const std::string name = "multislit_fuzz_" + std::to_string(::getpid());
      std::error_code failed;
      path = std::filesystem::path("/dev/shm") / name;
      std::filesystem::create_directories(path, failed);
      if (failed) {
        path = std::filesystem::temp_directory_path() / name;
        std::filesystem::create_directories(path);
      }
    }
    ~Dir() {
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  };
  static const Dir dir;
  return dir.path;
}

/// Writes the fuzz input to `name` in scratchDir() and returns the file's path.
inline std::string writeInput(const std::string& name, const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path path = scratchDir() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  if (!out) {
    std::fprintf(stderr, "fuzz: cannot write %s\n", path.c_str());
    std::abort();
  }
  return path.string();
}

/// Aborts with `what` unless `ok`: the library broke a promise of its API on this input.
inline void expect(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "fuzz: broken promise: %s\n", what);
  std::abort();
}

/// The input written as `name` and read by `load` (a loader taking a path): nothing when the loader
/// refuses it, as it must a bad value (std::invalid_argument) or a file that is not YAML, too large
/// or too deep (std::runtime_error); any other exception is a finding.
template <typename Load>
auto loadInput(const std::string& name, const std::uint8_t* data, std::size_t size, Load load)
    -> std::optional<decltype(load(std::string()))> {
  const std::string path = writeInput(name, data, size);
  try {
    return load(path);
  } catch (const std::invalid_argument&) {
    return std::nullopt;
  } catch (const std::runtime_error&) {
    return std::nullopt;
  }
}

}  // namespace multislit::fuzz
