#include "recording.h"

#include "common.h"

#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace multislit::apps {

SequenceRecorder::SequenceRecorder(const std::filesystem::path& folder, const std::string& option,
                                   const Reference* reference, const SensorConfig& sensor,
                                   const std::vector<NamedInput>& inputs)
    : folder_(folder) {
  refuseOutputFolder(folder, option,
                     {"calibration.yaml", "sensor.yaml", "frames.csv", "odometry.csv"}, inputs);
  std::filesystem::create_directories(folder);
  if (reference != nullptr)
    writeWhole(
        folder / "calibration.yaml", [reference](const std::string& p) { reference->save(p); },
        [](const std::string& p) { Reference::load(p); });
  writeWhole(
      folder / "sensor.yaml", [&sensor](const std::string& p) { sensor.save(p); },
      [](const std::string& p) { SensorConfig::load(p); });
  // frames.csv whole from the start (its header), then grown a whole row at a time.
  static const std::string kHeader = "frame,file,stamp_us,clock\n";
  index_path_ = folder / "frames.csv";
  writeWhole(
      index_path_, [](const std::string& p) { std::ofstream(p, std::ios::binary) << kHeader; },
      [](const std::string& p) {
        if (std::filesystem::file_size(p) != kHeader.size()) throw std::runtime_error("cut");
      });
  index_size_ = kHeader.size();
  index_.open(index_path_, std::ios::binary | std::ios::app);
  if (!index_) throw std::runtime_error("cannot open " + index_path_.string() + " to append");
}

void SequenceRecorder::appendRow(const std::string& row) {
  index_.write(row.data(), static_cast<std::streamsize>(row.size()));
  index_.flush();
  if (!index_) {  // a full disk: back to the last whole row, which lists every frame before
    index_.close();
    std::error_code ec;
    std::filesystem::resize_file(index_path_, index_size_, ec);
    throw std::runtime_error("could not write all of " + index_path_.string() +
                             " (disk full?): it lists the " + std::to_string(frames_) +
                             " frames before");
  }
  index_size_ += row.size();
}

void SequenceRecorder::add(const cv::Mat& image, std::uint64_t stamp_us, const std::string& clock) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%06zu.png", frames_);
  writeImage((folder_ / name).string(), image);  // whole, before its row lists it
  appendRow(std::to_string(frames_) + ',' + name + ',' + std::to_string(stamp_us) + ',' + clock +
            '\n');
  ++frames_;
}

void SequenceRecorder::add(const cv::Mat& image, std::uint64_t stamp_us, const std::string& clock,
                           const Eigen::Isometry3d& world_from_robot) {
  add(image, stamp_us, clock);
  poses_.push_back({stamp_us, world_from_robot});
}

void SequenceRecorder::finish() {
  index_.close();
  if (index_.fail()) throw std::runtime_error("could not close " + index_path_.string());
  if (!poses_.empty()) writeOdometry(folder_ / "odometry.csv", poses_);
}

}  // namespace multislit::apps
