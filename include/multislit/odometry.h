// The robot's odometry from a file, interpolated to each frame's time stamp: how a recording or a
// real walk gives the Pipeline its world-from-robot poses.
//
// The file is CSV with the header `stamp_us,x,y,z,roll,pitch,yaw` and one row per pose: the time
// in microseconds (the frames' clock), the robot's position in the world [m] and its orientation
// [rad] as R = Rz(yaw) Ry(pitch) Rx(roll) (ROS's roll-pitch-yaw). Stamps strictly increase.
#pragma once

#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace multislit {

/// Farthest a pose may be from the world's origin, on each axis [m]: a robot walks kilometres, and
/// beyond this a position is a corrupt file (1e12 m), which no map or figure could hold.
constexpr double kMaxOdometryDistance = 1e5;

/// One pose of the robot at one time: world from robot.
struct OdometrySample {
  std::uint64_t stamp_us = 0;  ///< [us]
  Eigen::Isometry3d world_from_robot = Eigen::Isometry3d::Identity();
};

/// Why a time stamp got no pose.
enum class PoseMiss {
  None,         ///< it got one
  BeforeStart,  ///< earlier than the first sample
  AfterEnd,     ///< later than the last sample
  InGap         ///< between two samples farther apart than max_gap_us
};
const char* poseMissName(PoseMiss miss);

class Odometry {
 public:
  /// `samples` in strictly increasing time, with finite poses within kMaxOdometryDistance and
  /// rotations; two samples farther
  /// apart than `max_gap_us` are not interpolated between. Throws std::invalid_argument naming
  /// the first bad sample.
  explicit Odometry(std::vector<OdometrySample> samples, std::uint64_t max_gap_us = 500000);
  /// Reads the CSV file; throws std::runtime_error "FILE:LINE: what is wrong" (a missing or
  /// wrong header, a short row, a number that is not one or not finite, a position beyond
  /// kMaxOdometryDistance, a stamp that repeats or goes back). A FIFO or pipe is read without
  /// blocking for ever, up to 1 GiB.
  static Odometry load(const std::string& path, std::uint64_t max_gap_us = 500000);

  /// The pose at `stamp_us`: the sample itself at its own stamp, else linear in position and
  /// spherical-linear in orientation between the two samples around it. nullopt, with the reason
  /// in `miss`, outside the samples' span or inside a gap.
  std::optional<Eigen::Isometry3d> at(std::uint64_t stamp_us, PoseMiss* miss = nullptr) const;

  const std::vector<OdometrySample>& samples() const { return samples_; }
  std::uint64_t maxGap() const { return max_gap_us_; }

 private:
  std::vector<OdometrySample> samples_;
  std::uint64_t max_gap_us_;
};

/// roll, pitch, yaw of a rotation (R = Rz(yaw) Ry(pitch) Rx(roll)) [rad].
Eigen::Vector3d rollPitchYaw(const Eigen::Matrix3d& rotation);
Eigen::Matrix3d fromRollPitchYaw(double roll, double pitch, double yaw);

/// Writes the CSV file, every number with 17 significant digits (read back, the same bits);
/// throws std::runtime_error naming the file when it cannot be written completely.
void saveOdometry(const std::string& path, const std::vector<OdometrySample>& samples);

}  // namespace multislit
