// ImageSequenceSource: recorded PNG images, replayed at a rate, as fast as taken, or stepped.
#include "multislit/sources.h"

#include "multislit/image_file.h"

#include "frame_index.h"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace multislit {

namespace fs = std::filesystem;

namespace {

std::uint64_t wallClockMicros() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}

// Days since 1970-01-01 of a proleptic Gregorian date (H. Hinnant's days_from_civil).
long long daysFromCivil(long long y, unsigned m, unsigned d) {
  y -= m <= 2;
  const long long era = (y >= 0 ? y : y - 399) / 400;
  const auto yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<long long>(doe) - 719468;
}

// frames.csv of `folder` (written by `multislit simulate` and `walk --record`): file name ->
// stamp_us, and the files in its order into `files`. Empty when there is none; throws naming
// the line when it is wrong (detail::readFrameIndex).
std::map<std::string, std::uint64_t> readIndexStamps(const fs::path& folder,
                                                     std::vector<std::string>* files = nullptr) {
  std::map<std::string, std::uint64_t> stamps;
  const auto rows = detail::readFrameIndex(folder);
  if (!rows) return stamps;
  for (const detail::FrameIndexRow& row : *rows) {
    if (files) files->push_back((folder / row.file).string());
    stamps[row.file] = row.stamp_us;
  }
  return stamps;
}

}  // namespace

std::optional<std::uint64_t> stampFromFileName(const std::string& file_name) {
  // The first YYYYMMDDThhmmss[.ffffff] in the name.
  const std::string name = fs::path(file_name).filename().string();
  const auto digits = [&name](std::size_t from, std::size_t count) {
    if (from + count > name.size()) return false;
    return std::all_of(name.begin() + static_cast<std::ptrdiff_t>(from),
                       name.begin() + static_cast<std::ptrdiff_t>(from + count),
                       [](char c) { return c >= '0' && c <= '9'; });
  };
  std::size_t at = 0;
  while (at < name.size() && !(digits(at, 8) && name[at + 8] == 'T' && digits(at + 9, 6))) ++at;
  if (at == name.size()) return std::nullopt;
  const auto number = [&name, at](std::size_t offset, std::size_t count) {
    return std::stoi(name.substr(at + offset, count));
  };
  const int year = number(0, 4), month = number(4, 2), day = number(6, 2);
  const int hour = number(9, 2), minute = number(11, 2), second = number(13, 2);
  if (year < 1970 || month < 1 || month > 12 || day < 1 || day > 31 || hour > 23 || minute > 59 ||
      second > 60)
    return std::nullopt;
  std::string fraction;
  if (at + 15 < name.size() && name[at + 15] == '.')
    for (std::size_t k = at + 16; k < name.size() && fraction.size() < 6 && digits(k, 1); ++k)
      fraction += name[k];
  fraction.resize(6, '0');
  const long long days =
      daysFromCivil(year, static_cast<unsigned>(month), static_cast<unsigned>(day));
  const long long seconds = days * 86400LL + hour * 3600LL + minute * 60LL + second;
  return static_cast<std::uint64_t>(seconds) * 1000000ULL + std::stoull(fraction);
}

void ImageSequenceConfig::validate() const {
  auto fail = [](const std::string& field, const std::string& what) {
    throw std::invalid_argument("ImageSequenceConfig." + field + " " + what);
  };
  if (folder.empty() && files.empty()) fail("folder", "or files must be given");
  if (!(fps >= 0)) fail("fps", "must be >= 0");
  if (!(stamp_rate > 0)) fail("stamp_rate", "must be > 0");
}

ImageSequenceSource::ImageSequenceSource(const ImageSequenceConfig& config) : config_(config) {
  config_.validate();
}

std::string ImageSequenceSource::name() const {
  return "image sequence " +
         (config_.files.empty() ? config_.folder : std::to_string(config_.files.size()) + " files");
}

SourceStats ImageSequenceSource::stats() const {
  SourceStats s;
  s.frames = frames_;
  s.read_errors = read_errors_;
  return s;
}

void ImageSequenceSource::listFiles() {
  files_ = config_.files;
  if (!files_.empty()) return;
  const fs::path folder = config_.folder;
  if (!fs::is_directory(folder))
    throw std::runtime_error("image folder '" + config_.folder + "' does not exist");
  readIndexStamps(folder, &files_);
  if (files_.empty()) {
    for (const fs::directory_entry& e : fs::directory_iterator(folder)) {
      std::string ext = e.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(),
                     [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      if (e.is_regular_file() && ext == ".png" && e.path().filename() != "reference.png")
        files_.push_back(e.path().string());
    }
    std::sort(files_.begin(), files_.end());
  }
  if (files_.empty()) throw std::runtime_error("no PNG images in '" + config_.folder + "'");
}

// Per file: the stamp in its name, else frames.csv's stamp_us, else start + index / stamp_rate.
void ImageSequenceSource::assignStamps() {
  std::map<std::string, std::map<std::string, std::uint64_t>> index_by_folder;
  const std::uint64_t start = wallClockMicros();
  stamps_.clear();
  for (std::size_t i = 0; i < files_.size(); ++i) {
    const fs::path path = files_[i];
    std::optional<std::uint64_t> stamp = stampFromFileName(path.filename().string());
    if (!stamp) {
      const std::string folder = path.parent_path().string();
      auto it = index_by_folder.find(folder);
      if (it == index_by_folder.end())
        it = index_by_folder.emplace(folder, readIndexStamps(path.parent_path())).first;
      const auto found = it->second.find(path.filename().string());
      if (found != it->second.end()) stamp = found->second;
    }
    stamps_.push_back(stamp ? *stamp
                            : start + static_cast<std::uint64_t>(static_cast<double>(i) * 1e6 /
                                                                 config_.stamp_rate));
  }
}

void ImageSequenceSource::start() {
  resetWaits();
  listFiles();
  assignStamps();
  position_ = 0;
  finished_ = false;
  started_ = Clock::now();
}

void ImageSequenceSource::stop() {}

std::optional<Frame> ImageSequenceSource::next(std::chrono::milliseconds timeout) {
  const std::uint64_t n = files_.size();
  if (finished_ || n == 0) return std::nullopt;
  const Clock::time_point deadline = Clock::now() + timeout;
  if (config_.triggered) {
    if (!takeTrigger(deadline)) return std::nullopt;
  } else if (config_.fps > 0) {
    if (!waitUntilDue(started_, position_, config_.fps, deadline)) return std::nullopt;
  } else if (interrupted()) {
    return std::nullopt;
  }
  if (!config_.repeat && position_ >= n) {
    finished_ = true;
    return std::nullopt;
  }

  const std::uint64_t seq = position_++;
  const std::string& file = files_[seq % n];
  cv::Mat image;
  try {
    image = readMonoImage(file);
  } catch (const std::runtime_error& e) {
    ++read_errors_;  // missing, corrupt, too large, or not a one-channel 8- or 16-bit image
    setLastError(e.what());
    return std::nullopt;
  }
  // A repeated sequence goes on in time: each loop is shifted by the span of the sequence.
  const std::uint64_t loop = seq / n;
  const std::uint64_t period = static_cast<std::uint64_t>(1e6 / config_.stamp_rate);
  const std::uint64_t span = stamps_.back() - std::min(stamps_.front(), stamps_.back()) + period;
  ++frames_;
  return Frame{image, stamps_[seq % n] + loop * span, seq, Clock::now()};
}

}  // namespace multislit
