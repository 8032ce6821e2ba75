// Named simulated experiments: the poses of Table I and the scenes of the paper's figures.
#pragma once

#include "multislit/sensor.h"
#include "multislit/sim/scene.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <string>
#include <vector>

namespace multislit {

/// The sensor pose of Table I: condition 0 is the reference (theta 66 deg, phi 0, h 445 mm),
/// 1..6 change one parameter. Throws std::out_of_range for other numbers.
MountConfig tableIPose(int condition);

/// A scene, the pose of the sensor while it is filmed, and how the robot moves per frame.
struct Scenario {
  std::string name;
  std::string description;
  Scene scene;
  MountConfig mount;            ///< sensor pose on the robot during the sequence
  MountConfig reference_mount;  ///< pose at which the reference image of the bare floor is taken
  double step = 0.0;            ///< the robot's advance along world x per frame [m]

  /// The robot on the floor at a frame: it starts at the origin facing +x.
  Eigen::Isometry3d worldFromRobot(uint64_t frame) const;
};

/// reference, cond1 .. cond6 (Table I), fig8 (tennis ball and box seen from 50 mm higher),
/// cable (7 mm LAN cable across the path), ball (40 mm ping-pong ball), floor (walk, no object),
/// wall (a wall 0.5 m in front of the level sensor, see makeWallScenario).
std::vector<std::string> scenarioNames();
/// Throws std::invalid_argument listing the known names.
Scenario makeScenario(const std::string& name);
/// A flat wall facing the level sensor at `depth` metres along the optical axis: what a user
/// with a wall and a tape measure films to calibrate the metric scale.
Scenario makeWallScenario(double depth);

}  // namespace multislit
