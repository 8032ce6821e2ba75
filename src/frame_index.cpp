#include "frame_index.h"

#include "file_read.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace multislit::detail {

namespace fs = std::filesystem;

namespace {

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

/// A stamp: decimal digits only, at most kMaxStampUs; nullopt otherwise.
std::optional<std::uint64_t> parseStamp(const std::string& text) {
  if (text.empty() || text.size() > 19 ||
      !std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return std::nullopt;
  const std::uint64_t v = std::stoull(text);
  return v <= kMaxStampUs ? std::optional<std::uint64_t>(v) : std::nullopt;
}

/// Throws unless `file` names a file of `folder` itself that exists (a broken link counts: it is
/// a frame that cannot be read, told when it is read).
void checkFrameName(const fs::path& folder, const std::string& file, const std::string& at) {
  if (file.empty() || file == "." || file == ".." || file.find('/') != std::string::npos)
    throw std::runtime_error(at + ": file '" + file +
                             "' is not a file name of the sequence's folder");
  std::error_code error;
  if (!fs::exists(fs::symlink_status(folder / file, error)))
    throw std::runtime_error(at + ": file '" + file + "' is missing from " + folder.string());
}

}  // namespace

std::optional<std::vector<FrameIndexRow>> readFrameIndex(const fs::path& folder) {
  const fs::path path = folder / "frames.csv";
  std::error_code error;
  if (!fs::exists(fs::symlink_status(path, error))) return std::nullopt;
  constexpr std::size_t kMaxBytes = std::size_t{1} << 30;
  std::istringstream in(readWholeFile(path.string(), "frame index", kMaxBytes));
  std::string line;
  std::getline(in, line);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const std::vector<std::string> header = splitCsv(line);
  const auto column = [&header](const char* name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  const std::size_t file_col = column("file"), stamp_col = column("stamp_us");
  if (file_col >= header.size() || stamp_col >= header.size())
    throw std::runtime_error(path.string() + ":1: the header must name the columns file and " +
                             "stamp_us, not '" + line.substr(0, 80) + "'");
  std::vector<FrameIndexRow> rows;
  for (std::size_t number = 2; std::getline(in, line); ++number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const std::string at = path.string() + ":" + std::to_string(number);
    const std::vector<std::string> cells = splitCsv(line);
    if (cells.size() != header.size())
      throw std::runtime_error(at + ": " + std::to_string(cells.size()) + " values, expected " +
                               std::to_string(header.size()) + " as in the header");
    const std::optional<std::uint64_t> stamp = parseStamp(cells[stamp_col]);
    if (!stamp)
      throw std::runtime_error(at + ": stamp_us '" + cells[stamp_col].substr(0, 40) +
                               "' is not a whole number of microseconds in [0, " +
                               std::to_string(kMaxStampUs) + "]");
    checkFrameName(folder, cells[file_col], at);
    rows.push_back({cells[file_col], *stamp});
  }
  if (rows.empty()) throw std::runtime_error(path.string() + ": no frames after the header");
  return rows;
}

}  // namespace multislit::detail
