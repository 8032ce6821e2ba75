// The paper's walking experiment (Sec. V, Fig. 13-15) on the simulator: a HOAP-2 with the sensor
// walks; a ping-pong ball is thrown in just in front of its foot, a LAN cable lies across its path.
// Each frame runs the whole pipeline: RDMap -> floor -> obstacles -> map -> walker -> gait.
#pragma once

#include "multislit/extractor.h"
#include "multislit/floor_detector.h"
#include "multislit/footsteps.h"
#include "multislit/gait.h"
#include "multislit/obstacles.h"
#include "multislit/occupancy_map.h"
#include "multislit/rdmap_synth.h"
#include "multislit/reference.h"
#include "multislit/scene.h"
#include "multislit/simulator.h"
#include "multislit/walker.h"

#include <pcl/point_cloud.h>

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace multislit {

/// The objects of the experiment and when they are there.
struct WalkSceneConfig {
  bool ball = true;      ///< the 40 mm ping-pong ball is thrown in
  int ball_frame = 200;  ///< frame it lands (Fig. 15: the peak around frame 200) [-]
  /// Where it lands, in the robot frame of that frame: just in front of the left foot, where the
  /// nearest slits are.
  Eigen::Vector2d ball_landing = Eigen::Vector2d(0.105, 0.02);  ///< [m]
  int ball_roll_frame = 260;     ///< it rolls away from this frame on [-]
  double ball_roll_speed = 0.5;  ///< sideways, to the robot's left [m/s]
  bool cable = true;             ///< the 7 mm LAN cable lies on the floor across the path
  /// Its axis on the floor, world frame: 0.97 m ahead of the start, reaching 0.05 m to the left
  /// of the path, so that turning left clears it (Fig. 13: the robot turned left).
  Eigen::Vector2d cable_start = Eigen::Vector2d(0.97, -0.70);  ///< [m]
  Eigen::Vector2d cable_end = Eigen::Vector2d(0.97, 0.05);     ///< [m]
  double cable_diameter = 0.007;                               ///< [m]
  std::vector<SceneObject> extra;  ///< more objects, always there (world frame)

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// The scene as it changes: the ball lands relative to the robot, then rolls out of sight.
class WalkWorld {
 public:
  explicit WalkWorld(const WalkSceneConfig& config, double frame_rate = 30.0);  ///< validates
  /// The scene at `frame` with the robot at `body` (frames are asked for in order).
  const Scene& sceneAt(std::uint64_t frame, const Pose2D& body);

 private:
  WalkSceneConfig config_;
  double frame_rate_;
  Scene scene_;
  std::optional<Eigen::Vector3d> ball_landed_;           ///< world
  Eigen::Vector3d ball_roll_ = Eigen::Vector3d::Zero();  ///< unit direction of the roll
};

struct WalkConfig {
  SensorConfig sensor;           ///< its mount is the nominal mount on the robot
  MountConfig reference_mount;   ///< where the reference image of the floor is taken
  bool render = true;            ///< true: render and extract images; false: synthesize
  RenderConfig render_config;    ///< images (render = true)
  RDMapSynthesizerConfig synth;  ///< RDMaps (render = false)
  FloorDetectorConfig floor;
  ObstacleClustererConfig obstacles;
  OccupancyMapConfig map;
  FootConfig foot;
  GaitConfig gait;
  WalkerConfig walker;
  WalkSceneConfig scene;
  /// Within this of an object, an obstacle point is a detection of that object (judging only).
  double truth_radius = 0.01;  ///< [m]

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// One object of the scene in one frame, against the ground truth.
struct ObjectView {
  SceneObject object;        ///< where it is in this frame
  std::size_t lit = 0;       ///< slit points on it at least 3.5 mm high (visible in one frame)
  std::size_t lit_any = 0;   ///< slit points on it, any height
  std::size_t detected = 0;  ///< points of obstacles within truth_radius of it
};

/// Everything one frame did.
struct WalkFrame {
  std::uint64_t frame = 0;
  Pose2D body;        ///< the robot during the frame
  MountConfig mount;  ///< the sensor's mount, sway included
  Eigen::Isometry3d world_from_camera = Eigen::Isometry3d::Identity();
  pcl::PointCloud<PointRDM>::Ptr cloud;  ///< the RDMap
  FloorResult floor;
  ObstacleResult obstacles;
  MapUpdateStats map;
  WalkerResult walker;
  Command motion = Command::Stop;    ///< what the body did (a step under way is finished first)
  std::optional<Footstep> footstep;  ///< landed at the end of the frame
  double footstep_clearance = 0.0;   ///< from the nearest true object (footstep only) [m]
  std::vector<ObjectView> objects;   ///< each object of the scene
  double measure_seconds = 0.0;      ///< rendering and extraction, or synthesis [s]
  double process_seconds = 0.0;      ///< floor, obstacles, map and walker [s]
};

/// The experiment, one frame per step().
class WalkSimulation {
 public:
  /// `reference`: the reference of the bare floor at config.reference_mount; rendered when not
  /// given (renderFloorReference, one rendering).
  explicit WalkSimulation(const WalkConfig& config, std::optional<Reference> reference = {});
  ~WalkSimulation();

  WalkFrame step();
  std::uint64_t frame() const { return frame_; }
  const OccupancyMap& map() const { return map_; }
  const Gait& gait() const { return gait_; }
  const WalkConfig& config() const { return config_; }

 private:
  struct Measurement;
  Measurement measure(const Scene& scene, const Eigen::Isometry3d& world_from_camera);
  void judge(const Scene& scene, const std::vector<SlitCrossing>& truth, WalkFrame& f) const;

  WalkConfig config_;
  SensorGeometry geometry_;
  std::unique_ptr<Simulator> simulator_;
  std::unique_ptr<Extractor> extractor_;
  std::unique_ptr<RDMapSynthesizer> synthesizer_;
  FloorDetector detector_;
  ObstacleClusterer clusterer_;
  OccupancyMap map_;
  Walker walker_;
  Gait gait_;
  WalkWorld world_;
  std::uint64_t frame_ = 0;
};

}  // namespace multislit
