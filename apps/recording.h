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
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace multislit::apps {

class SequenceRecorder {
 public:
  /// Writes calibration.yaml (when `reference` is given) and sensor.yaml into `folder`
  /// (created), each whole or absent, and frames.csv's header; throws std::runtime_error when the
  /// folder (given by `option`) is one of `inputs` or one of its files would overwrite one of
  /// them (`walk --sensor rec/sensor.yaml --record rec`).
  SequenceRecorder(const std::filesystem::path& folder, const std::string& option,
                   const Reference* reference, const SensorConfig& sensor,
                   const std::vector<NamedInput>& inputs);
  /// One frame: frame_NNNNNN.png (written whole), then its row appended to frames.csv, so that
  /// frames.csv lists exactly the frames whole on disk whenever the process ends (Ctrl-C, a
  /// crash, a lost camera); `clock` names the clock of its stamp ("camera", "host",
  /// "simulated"). Throws std::runtime_error on a write error, frames.csv cut back to its last
  /// whole row.
  void add(const cv::Mat& image, std::uint64_t stamp_us, const std::string& clock);
  /// The same with the robot's pose at the frame, for odometry.csv.
  void add(const cv::Mat& image, std::uint64_t stamp_us, const std::string& clock,
           const Eigen::Isometry3d& world_from_robot);
  std::size_t frames() const { return frames_; }
  /// Closes frames.csv and, when poses were given, writes odometry.csv (whole or absent); throws
  /// std::runtime_error on a write error.
  void finish();

 private:
  std::filesystem::path folder_;
  void appendRow(const std::string& row);

  std::filesystem::path index_path_;  ///< frames.csv
  std::ofstream index_;               ///< frames.csv, opened to append
  std::size_t index_size_ = 0;        ///< its bytes up to the last whole row
  std::size_t frames_ = 0;
  std::vector<OdometrySample> poses_;
};

}  // namespace multislit::apps
