#include "recording.h"

#include "common.h"

#include <cstdio>
#include <stdexcept>

namespace multislit::apps {

SequenceRecorder::SequenceRecorder(const std::filesystem::path& folder, const Reference& reference,
                                   const SensorConfig& sensor)
    : folder_(folder) {
  std::filesystem::create_directories(folder);
  reference.save((folder / "calibration.yaml").string());
  sensor.save((folder / "sensor.yaml").string());
  index_.open(folder / "frames.csv");
  if (!index_) throw std::runtime_error("cannot write " + (folder / "frames.csv").string());
  index_ << "frame,file,stamp_us\n";
}

void SequenceRecorder::add(const cv::Mat& image, std::uint64_t stamp_us,
                           const Eigen::Isometry3d& world_from_robot) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%06zu.png", poses_.size());
  writeImage((folder_ / name).string(), image);
  index_ << poses_.size() << ',' << name << ',' << stamp_us << '\n';
  poses_.push_back({stamp_us, world_from_robot});
}

void SequenceRecorder::finish() {
  index_.flush();
  if (!index_)
    throw std::runtime_error("could not write all of " + (folder_ / "frames.csv").string());
  index_.close();
  saveOdometry((folder_ / "odometry.csv").string(), poses_);
}

}  // namespace multislit::apps
