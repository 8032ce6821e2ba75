// A recording that `multislit map --sequence` replays: PNG frames, frames.csv (file, stamp_us),
// odometry.csv (the robot's pose at each stamp, see odometry.h), calibration.yaml and sensor.yaml.
#pragma once

#include "multislit/odometry.h"
#include "multislit/reference.h"
#include "multislit/sensor.h"

#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <vector>

namespace multislit::apps {

class SequenceRecorder {
 public:
  /// Writes calibration.yaml and sensor.yaml into `folder` (created) and opens frames.csv.
  SequenceRecorder(const std::filesystem::path& folder, const Reference& reference,
                   const SensorConfig& sensor);
  /// One frame: frame_NNNNNN.png, its row of frames.csv and its pose.
  void add(const cv::Mat& image, std::uint64_t stamp_us, const Eigen::Isometry3d& world_from_robot);
  /// Closes frames.csv and writes odometry.csv; throws std::runtime_error on a write error.
  void finish();

 private:
  std::filesystem::path folder_;
  std::ofstream index_;
  std::vector<OdometrySample> poses_;
};

}  // namespace multislit::apps
