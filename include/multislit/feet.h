// The robot's feet, described once: the HOAP-2's soles, their separation and its step (sensor.md),
// a sole as a rectangle on the floor, and the body's pose on the floor. The footsteps, the
// obstacles' distance to the feet, the walker and the gait all derive from FootConfig.
#pragma once

#include <Eigen/Geometry>

#include <array>

namespace multislit {

/// The feet and the step of the HOAP-2 (sensor.md). The step length is not published: 40 mm, a
/// short step for a 50 cm robot that walks slowly while it looks at the floor just ahead.
struct FootConfig {
  double foot_length = 0.095;      ///< sole along the walking direction [m]
  double foot_width = 0.065;       ///< sole across it [m]
  double foot_separation = 0.078;  ///< between the feet's centres [m]
  double step_length = 0.040;      ///< the body's advance per step (a foot moves twice it) [m]
  double turn_step = 10.0;         ///< yaw per step when turning in place [deg]

  double toe() const { return 0.5 * step_length + 0.5 * foot_length; }  ///< leading toe, x [m]
  /// The rectangle both feet stand in, seen from above in the robot frame: |x| <= toe(), |y| <=
  /// halfWidth() (the leading foot half a step ahead). Obstacle::distance is measured from it.
  double halfWidth() const { return 0.5 * (foot_separation + foot_width); }  ///< [m]

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// The robot on the floor: origin midway between the feet, yaw from world x (counter-clockwise).
struct Pose2D {
  double x = 0.0;    ///< [m]
  double y = 0.0;    ///< [m]
  double yaw = 0.0;  ///< [rad]

  /// The pose on the floor of a 3D world-from-robot pose (odometry): its x, y and heading.
  static Pose2D onFloor(const Eigen::Isometry3d& world_from_robot);
  Eigen::Vector2d position() const { return {x, y}; }
  /// A point given in the robot frame (x forward, y left), in the world.
  Eigen::Vector2d toWorld(const Eigen::Vector2d& robot) const;
  Pose2D movedForward(double distance) const;
  Pose2D turned(double angle) const;   ///< [rad], positive to the left
  Eigen::Isometry3d isometry() const;  ///< world from robot, z = 0 on the floor
};

enum class Foot { Left, Right };
inline Foot otherFoot(Foot f) { return f == Foot::Left ? Foot::Right : Foot::Left; }
inline const char* footName(Foot f) { return f == Foot::Left ? "left" : "right"; }

/// A rectangle on the floor (a foot's sole), world frame.
struct Footprint {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  ///< [m]
  double yaw = 0.0;                                  ///< direction of its length from world x [rad]
  double length = 0.0;                               ///< along yaw [m]
  double width = 0.0;                                ///< across [m]

  Footprint inflated(double margin) const;  ///< grown by `margin` on every side
  std::array<Eigen::Vector2d, 4> corners() const;
  bool contains(const Eigen::Vector2d& p) const;
};

}  // namespace multislit
