// A recording that `multislit map --sequence` replays: PNG frames, frames.csv (file, stamp_us and
// the clock of each stamp), odometry.csv (the robot's pose at each stamp, see odometry.h) when
// poses are given, calibration.yaml when there is one, and sensor.yaml. Written by `walk --record`
// (the simulator) and `multislit record` (a live camera).
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
  /// Writes calibration.yaml (when `reference` is given) and sensor.yaml into `folder`
  /// (created), each whole or absent, and begins frames.csv; throws std::runtime_error when the
  /// folder (given by `option`) is one of `inputs` or one of its files would overwrite one of
  /// them (`walk --sensor rec/sensor.yaml --record rec`).
  SequenceRecorder(const std::filesystem::path& folder, const std::string& option,
                   const Reference* reference, const SensorConfig& sensor,
                   const std::vector<NamedInput>& inputs);
  /// One frame: frame_NNNNNN.png (written whole) and its row of frames.csv; `clock` names the
  /// clock of its stamp ("camera", "host", "simulated").
  void add(const cv::Mat& image, std::uint64_t stamp_us, const std::string& clock);
  /// The same with the robot's pose at the frame, for odometry.csv.
  void add(const cv::Mat& image, std::uint64_t stamp_us, const std::string& clock,
           const Eigen::Isometry3d& world_from_robot);
  std::size_t frames() const { return frames_; }
  /// Completes frames.csv and, when poses were given, writes odometry.csv; throws
  /// std::runtime_error on a write error (then neither is left behind, cut).
  void finish();

 private:
  std::filesystem::path folder_;
  std::unique_ptr<OutputFile> index_;  ///< frames.csv, renamed into place by finish()
  std::size_t frames_ = 0;
  std::vector<OdometrySample> poses_;
};

}  // namespace multislit::apps
