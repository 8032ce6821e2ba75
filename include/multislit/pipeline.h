// The whole chain for one frame of any source (camera, recording, simulator), as the paper's steps:
// the RDMap's floor by RANSAC (Sec. III-B, eq. 1-3), the points off it grouped into obstacles, an
// obstacle appearing suddenly near the feet (Sec. V), the occupancy map along the robot's
// odometry, and the footsteps ahead checked against it: walk, turn or stop.
#pragma once

#include "multislit/feet.h"
#include "multislit/floor_detector.h"
#include "multislit/footsteps.h"
#include "multislit/obstacles.h"
#include "multislit/occupancy_map.h"
#include "multislit/point_types.h"
#include "multislit/sensor.h"
#include "multislit/walker.h"

#include <pcl/point_cloud.h>

#include <Eigen/Geometry>

#include <optional>

namespace multislit {

/// Every stage's configuration, and the robot the sensor is mounted on.
struct PipelineConfig {
  SensorConfig sensor;  ///< its mount places the camera on the robot; its projector lights rays
  FloorDetectorConfig floor;
  ObstacleClustererConfig obstacles;
  OccupancyMapConfig map;
  FootConfig foot;  ///< the feet: obstacles' distance, footsteps, the walker's checks
  WalkerConfig walker;

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// One frame into the pipeline.
struct PipelineInput {
  pcl::PointCloud<PointRDM>::ConstPtr cloud;  ///< the RDMap (Extractor, MultiSlitGrabber)
  /// The robot at the frame's time stamp (odometry, TF, the gait model): world from robot, x
  /// forward, y left, z up, the origin on the floor midway between the feet.
  Eigen::Isometry3d world_from_robot = Eigen::Isometry3d::Identity();
  /// The camera on the robot; not given: the sensor's fixed mount (PipelineConfig::sensor).
  std::optional<Eigen::Isometry3d> robot_from_camera;
  Foot next_foot = Foot::Left;  ///< the foot that swings next (for the footsteps ahead)
};

/// CPU time of the calling thread [s]: the clock of PipelineTimes. Other processes on the same
/// core do not inflate it (a busy 2-core robot computer, a CI machine).
double threadCpuSeconds();

/// Time of each stage of one frame: CPU time of the calling thread (threadCpuSeconds) [s].
struct PipelineTimes {
  double floor = 0.0;      ///< RANSAC, eq. (2) refit, noise, split
  double obstacles = 0.0;  ///< noise rule, groups, sizes
  double map = 0.0;        ///< the OctoMap update
  double walker = 0.0;     ///< sudden obstacles, footsteps, decision
  double total() const { return floor + obstacles + map + walker; }
};

/// What one frame gave.
struct PipelineResult {
  Pose2D body;  ///< the robot on the floor (from world_from_robot)
  Eigen::Isometry3d world_from_camera = Eigen::Isometry3d::Identity();
  FloorResult floor;         ///< plane, inliers, obstacle points, the frame's sigma
  ObstacleResult obstacles;  ///< groups, nearest to the feet first
  MapUpdateStats map;        ///< what the map update did
  /// The decision (walker.command: walk, turn or stop, and why), the footsteps checked and the
  /// sudden obstacle that made it stop, if any.
  WalkerResult walker;
  PipelineTimes times;
  /// Why the frame was dropped, "" when it was used: a pose or a point that is infinite or beyond
  /// any range (a corrupt calibration or odometry). A dropped frame finds no floor, changes
  /// nothing, and the walker stops as for no floor.
  std::string dropped;
};

/// The chain, frame after frame: it keeps the map and the walker's state (a stop lasts its
/// frames). Not thread-safe; one Pipeline per robot.
class Pipeline {
 public:
  explicit Pipeline(const PipelineConfig& config = {});  ///< validates

  PipelineResult process(const PipelineInput& input);

  const PipelineConfig& config() const { return config_; }
  const SensorGeometry& geometry() const { return geometry_; }
  const OccupancyMap& map() const { return map_; }

 private:
  PipelineConfig config_;
  SensorGeometry geometry_;
  FloorDetector detector_;
  ObstacleClusterer clusterer_;
  OccupancyMap map_;
  Walker walker_;
};

}  // namespace multislit
