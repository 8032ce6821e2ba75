// Footsteps of the HOAP-2: where its soles land when it walks straight or turns in place, checked
// against the occupancy map, and measured against the true objects of a simulated scene.
#pragma once

#include "multislit/occupancy_map.h"
#include "multislit/scene.h"

#include <Eigen/Geometry>

#include <vector>

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
  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// The robot on the floor: origin midway between the feet, yaw from world x (counter-clockwise).
struct Pose2D {
  double x = 0.0;    ///< [m]
  double y = 0.0;    ///< [m]
  double yaw = 0.0;  ///< [rad]

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

struct Footstep {
  Foot foot = Foot::Left;
  Pose2D body;     ///< the body when the foot is down
  Footprint sole;  ///< where the sole is, world frame
};

/// The sole of `foot` with the body at `body`, the foot `ahead` metres in front of the body (half
/// a step when walking, 0 when turning in place).
Footprint soleAt(const Pose2D& body, Foot foot, double ahead, const FootConfig& config);

/// The next `count` footsteps of walking straight from `body`, `first` foot first.
std::vector<Footstep> planStraight(const Pose2D& body, Foot first, int count,
                                   const FootConfig& config);

/// Occupied voxels under planned footsteps (each sole grown by a margin).
struct FootstepCheck {
  bool free = true;            ///< no footstep touches an occupied voxel
  int first_blocked = -1;      ///< index of the first footstep that does
  std::vector<MapCell> cells;  ///< the occupied voxels under that footstep
};

/// Checks footsteps against the map: voxels between min_height and max_height (map frame, the
/// floor at 0) under each sole grown by `margin` [m].
FootstepCheck checkFootsteps(const std::vector<Footstep>& steps, const OccupancyMap& map,
                             double margin, double min_height, double max_height);

/// Horizontal clearance between a sole and an object seen from above (sphere: a disc; cylinder:
/// a capsule around its axis; box: a rectangle): 0 when they overlap [m].
double clearance(const Footprint& sole, const SceneObject& object);

}  // namespace multislit
