// A recording that `multislit map --sequence` replays: PNG frames, frames.csv (file, stamp_us),
// odometry.csv (the robot's pose at each stamp, see odometry.h), calibration.yaml and sensor.yaml.
#pragma once

#include "output_file.h"

#include "multislit/odometry.h"
#include "multislit/reference.h"
#include "multislit/sensor.h"

#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace multislit::apps {

class SequenceRecorder {
 public:
  /// Writes calibration.yaml and sensor.yaml into `folder` (created), each whole or absent, and
  /// begins frames.csv; throws std::runtime_error when one of them would overwrite one of
  /// `inputs` (`walk --sensor rec/sensor.yaml --record rec`).
  SequenceRecorder(const std::filesystem::path& folder, const Reference& reference,
                   const SensorConfig& sensor, const std::vector<std::string>& inputs);
  /// One frame: frame_NNNNNN.png, its row of frames.csv and its pose.
  void add(const cv::Mat& image, std::uint64_t stamp_us, const Eigen::Isometry3d& world_from_robot);
  /// Completes frames.csv and writes odometry.csv; throws std::runtime_error on a write error
  /// (then neither is left behind, cut).
  void finish();

 private:
  std::filesystem::path folder_;
  std::unique_ptr<OutputFile> index_;  ///< frames.csv, renamed into place by finish()
  std::vector<OdometrySample> poses_;
};

}  // namespace multislit::apps
