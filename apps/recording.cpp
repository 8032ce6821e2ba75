#include "recording.h"

#include "common.h"

#include <cstdio>
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
  index_ = std::make_unique<OutputFile>(folder / "frames.csv");
  index_->stream() << "frame,file,stamp_us,clock\n";
}

void SequenceRecorder::add(const cv::Mat& image, std::uint64_t stamp_us, const std::string& clock) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%06zu.png", frames_);
  writeImage((folder_ / name).string(), image);
  index_->stream() << frames_ << ',' << name << ',' << stamp_us << ',' << clock << '\n';
  ++frames_;
}

void SequenceRecorder::add(const cv::Mat& image, std::uint64_t stamp_us, const std::string& clock,
                           const Eigen::Isometry3d& world_from_robot) {
  add(image, stamp_us, clock);
  poses_.push_back({stamp_us, world_from_robot});
}

void SequenceRecorder::finish() {
  index_->commit();
  if (!poses_.empty()) writeOdometry(folder_ / "odometry.csv", poses_);
}

}  // namespace multislit::apps
