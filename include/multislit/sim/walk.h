// The paper's walking experiment (Sec. V, Fig. 13-15) on the simulator: a HOAP-2 with the sensor
// walks; a ping-pong ball is thrown in just in front of its foot, a LAN cable lies across its path.
// Each frame runs the whole pipeline: RDMap -> floor -> obstacles -> map -> walker -> gait.
#pragma once

#include "multislit/extractor.h"
#include "multislit/gait.h"
#include "multislit/pipeline.h"
#include "multislit/reference.h"
#include "multislit/sim/photometry.h"
#include "multislit/sim/rdmap_synth.h"
#include "multislit/sim/scene.h"
#include "multislit/sim/simulator.h"
#include "multislit/sim/truth.h"

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
  FloorConfig floor;               ///< the floor's albedo, texture and gloss (a photometry's)
  /// Every object's albedo, as a photometry sets it; < 0: each keeps its own (the ball 0.85, the
  /// cable 0.35).
  double object_albedo = -1.0;
  /// Factor on the sheet's width on every object; < 0: each keeps its own [-].
  double object_stripe_width = -1.0;

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// The scene as it changes: the ball lands relative to the robot, then rolls out of sight.
class WalkWorld {
 public:
  explicit WalkWorld(const WalkSceneConfig& config, double frame_rate = 30.0);  ///< validates
  /// The scene at `frame` with the robot at `body` (frames are asked for in order).
  const Scene& sceneAt(std::uint64_t frame, const Pose2D& body);

 private:
  const Scene& withSurfaces();  ///< the objects' albedo and stripe width set as configured

  WalkSceneConfig config_;
  double frame_rate_;
  Scene scene_;
  std::optional<Eigen::Vector3d> ball_landed_;           ///< world
  Eigen::Vector3d ball_roll_ = Eigen::Vector3d::Zero();  ///< unit direction of the roll
};

struct WalkConfig {
  /// The robot's chain: its sensor (whose mount is the nominal mount on the robot), floor,
  /// obstacles, map, feet and walker.
  PipelineConfig pipeline;
  MountConfig reference_mount;   ///< where the reference image of the floor is taken
  bool render = true;            ///< true: render and extract images; false: synthesize
  RenderConfig render_config;    ///< images (render = true)
  RDMapSynthesizerConfig synth;  ///< RDMaps (render = false)
  GaitConfig gait;
  WalkSceneConfig scene;
  /// Within this of an object, an obstacle point is a detection of that object (judging only).
  double truth_radius = 0.01;  ///< [m]

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// A walk under `photometry`: its floor and object surfaces into config.scene, its light, speckle,
/// stripes, noise and bit depth into config.render_config (config's noise seed is kept).
void applyPhotometry(const Photometry& photometry, WalkConfig& config);

/// One object of the scene in one frame, against the ground truth.
struct ObjectView {
  SceneObject object;        ///< where it is in this frame
  std::size_t lit = 0;       ///< slit points on it at least 3.5 mm high (visible in one frame)
  std::size_t lit_any = 0;   ///< slit points on it, any height
  std::size_t detected = 0;  ///< points of obstacles within truth_radius of it
};

/// Everything one frame did: the pipeline's result (body, floor, obstacles, map update, decision)
/// and what the simulated robot and the ground truth add to it.
struct WalkFrame : PipelineResult {
  std::uint64_t frame = 0;
  std::uint64_t stamp_us = 0;  ///< the frame's time from the start of the walk [us]
  MountConfig mount;           ///< the sensor's mount, sway included
  /// The torso's pose, world from robot with the sway: with the sensor's nominal mount it gives
  /// world_from_camera. What odometry of this walk records (a replay sees the same camera poses).
  Eigen::Isometry3d world_from_torso = Eigen::Isometry3d::Identity();
  pcl::PointCloud<PointRDM>::Ptr cloud;  ///< the RDMap
  cv::Mat image;                         ///< the rendered image (render = true)
  Command motion = Command::Stop;        ///< what the body did (a step under way is finished first)
  std::optional<Footstep> footstep;      ///< landed at the end of the frame
  double footstep_clearance = 0.0;       ///< from the nearest true object (footstep only) [m]
  std::vector<ObjectView> objects;       ///< each object of the scene
  double measure_seconds = 0.0;          ///< rendering and extraction, or synthesis [s]
  double process_seconds = 0.0;          ///< floor, obstacles, map and walker (times.total()) [s]
};

/// The experiment, one frame per step().
class WalkSimulation {
 public:
  /// `reference`: the reference of the bare floor at config.reference_mount; rendered when not
  /// given (renderFloorReference, one rendering).
  explicit WalkSimulation(const WalkConfig& config, std::optional<Reference> reference = {});
  ~WalkSimulation();

  WalkFrame step();
  /// A frame in which the body does `forced` (a turn: to the left) whatever the walker decided:
  /// to try the map on a turn in place or on standing still.
  WalkFrame step(Command forced);
  std::uint64_t frame() const { return frame_; }
  const OccupancyMap& map() const { return pipeline_.map(); }
  const Pipeline& pipeline() const { return pipeline_; }
  /// The reference the images are measured with; throws std::logic_error when RDMaps are
  /// synthesized (render = false).
  const Reference& reference() const;
  const Gait& gait() const { return gait_; }
  const WalkConfig& config() const { return config_; }

 private:
  struct Measurement;
  WalkFrame step(const std::optional<Command>& forced);
  std::uint64_t stamp() const;  ///< of the frame now [us]
  Measurement measure(const Scene& scene, const Eigen::Isometry3d& world_from_camera);
  void judge(const Scene& scene, const std::vector<SlitCrossing>& truth, WalkFrame& f) const;

  WalkConfig config_;
  Pipeline pipeline_;
  std::unique_ptr<Simulator> simulator_;
  std::unique_ptr<Extractor> extractor_;
  std::unique_ptr<RDMapSynthesizer> synthesizer_;
  Gait gait_;
  WalkWorld world_;
  std::uint64_t frame_ = 0;
};

}  // namespace multislit
