// frames.csv of a recorded sequence (written by `multislit simulate` and `walk --record`): its
// frames' files and stamps, read strictly (private to the library).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace multislit::detail {

struct FrameIndexRow {
  std::string file;        ///< the frame's file name, in the sequence's folder
  std::uint64_t stamp_us;  ///< [us]
};

/// Largest stamp a frames.csv may give [us] (year 2255): beyond it is a corrupt file.
constexpr std::uint64_t kMaxStampUs = 9000000000000000000ULL;

/// The rows of `folder`/frames.csv in order; std::nullopt when the folder has no frames.csv.
/// Throws std::runtime_error "FILE:LINE: what is wrong" when the file is empty, its header lacks
/// the columns file or stamp_us, a row is short, a stamp is not a whole number of microseconds in
/// [0, kMaxStampUs] (1e308, -5, NaN), or a row names no file of the folder: a path with a folder
/// in it (/etc/passwd), '.', '..', or a file that is missing.
std::optional<std::vector<FrameIndexRow>> readFrameIndex(const std::filesystem::path& folder);

}  // namespace multislit::detail
