// The ROS node's configuration: the `multislit map` command's options as private parameters
// (~camera, ~sequence, ~simulate, ~calibration, ~sensor, ~poses, ~max_gap, ~frames, ~fps, ~out)
// and what only a ROS graph needs: frame names, the TF it publishes, rates and waits.
#pragma once

#include "map_input.h"

#include "multislit/occupancy_map.h"

#include <string>
#include <vector>

namespace ros {
class NodeHandle;
}

namespace multislit::ros_node {

struct NodeConfig {
  apps::MapInputOptions input;  ///< ~camera, ~sequence, ~simulate, ~calibration, ~sensor, ~fps
  /// ~poses: "tf" (odom_frame -> base_frame at each frame's stamp), "odom" (nav_msgs/Odometry
  /// on the topic `odom`), an odometry CSV file, "still", "gait" or "scenario"; "": as `map`.
  apps::MapPoseOptions poses;
  int frames = 0;   ///< stop after this many frames; 0: all, or until shut down [-]
  std::string out;  ///< also write `multislit map`'s files (decisions.csv, map.bt, ...) here
  /// Recorded and simulated frames come at ~fps, as from the camera; false: as fast as they are
  /// processed.
  bool realtime = true;

  std::string odom_frame = "odom";  ///< the map's and the odometry's frame
  /// The robot on the floor midway between its feet, x forward, z up: REP 120's base_footprint
  /// (base_link is the torso, the robot's to publish).
  std::string base_frame = "base_footprint";
  std::string camera_frame = "multislit_optical";  ///< x right, y down, z forward
  /// Publish base_frame -> camera_frame (static) from the sensor's mount; false when the robot's
  /// own description already does.
  bool publish_mount_tf = true;

  /// The map under octomap_server's parameter names: ~resolution, ~sensor_model/hit, ~miss, ~min,
  /// ~max (prob_hit, prob_miss, clamp_min, clamp_max) and ~pointcloud_max_z (max_height).
  OccupancyMapConfig map;

  int map_every = 10;         ///< frames between two map messages (the last frame has one too) [-]
  double pose_timeout = 0.1;  ///< wait at most this for TF or odometry at a frame's stamp [s]
  /// Before the first frame, wait until every topic of the node has this many subscribers (a
  /// recorder, a test) so that none of its frames is lost; 0: start at once.
  int wait_for_subscribers = 0;  ///< [-]
  /// ... for at most this long, else the node fails; also the wait for the first pose from TF or
  /// odometry (then the node warns and goes on) [s]
  double wait_timeout = 30.0;
  double diagnostics_period = 1.0;  ///< between two diagnostics messages [s]

  bool posesFromRos() const { return poses.choice == "tf" || poses.choice == "odom"; }
  void validate() const;  ///< throws std::invalid_argument naming the ~parameter
};

/// The private parameters of the node (`private_nh`: "~"). Throws std::invalid_argument naming
/// a parameter given with the wrong type or out of range.
NodeConfig readNodeConfig(const ros::NodeHandle& private_nh);

/// The private parameters set that the node does not know (typos, like ~camra).
std::vector<std::string> unknownParameters(const ros::NodeHandle& private_nh);

}  // namespace multislit::ros_node
