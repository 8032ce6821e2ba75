// An OctoMap occupancy map of what lies on the floor around the walking robot, updated with every
// frame's floor and obstacles and the robot's odometry. Evidence accumulates over frames, so an
// object too small for one frame (a screw: the paper's future work) is found from sequential data,
// and free-space updates clear an object that has gone (a ball that rolled away).
#pragma once

#include "multislit/feet.h"
#include "multislit/floor_detector.h"
#include "multislit/obstacles.h"
#include "multislit/point_types.h"
#include "multislit/sweep_evidence.h"

#include <octomap/OcTree.h>
#include <pcl/point_cloud.h>

#include <Eigen/Geometry>

#include <array>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace multislit {

namespace detail {
struct FrameEvidence;
class RayKeys;
class SlitSweep;
}  // namespace detail

/// The map frame: world x, y (the robot's odometry) and z = height above the floor measured in
/// the frame (the metric floor plane), so the floor is at z = 0 whatever the sensor's sway.
///
/// Evidence of one frame, per voxel (each voxel is updated at most once per frame):
/// - evidence points: the points of obstacle groups (strong), and weak points: points of groups
///   rejected as noise, and floor points whose residual is at least weak_sigmas times their
///   slit's floor noise (in runs of min_weak_run points of one sign, away from the slit's ends);
/// - the evidence is judged over the sweep of the slits (SweepEvidence, config `sweep`): where it
///   is consistent, a voxel holding strong points above the floor is a hit, one holding
///   min_weak_points weak points a weak hit, and a floor-layer voxel under strong points below the
///   floor a hit (a hole); where it is not yet consistent (a texture lobe, an object seen once),
///   the voxel is not updated: unknown;
/// - miss: the floor-layer voxel holds only floor points, or a cell above the floor layer lies on
///   the light ray of a floor point below free_height (the projector lit the floor through it).
///
/// In frames, with the defaults and the paper's gait (1.7 mm of sweep a frame): a place is occupied
/// when two slits one after the other each gave it 3 consecutive frames of one sign over 3 mm of
/// sweep (an object on the floor: a 7 mm cable is occupied 28 to 113 frames after the slits first
/// reach it, by floor), or 2 consecutive moving frames with 3 surface points (Obstacle::surface)
/// higher than 25 mm in the column and no line below the floor beside it (a ball), or 6 passes of
/// weak evidence above the floor (a screw); a robot that stands occupies nothing; a hit saturates
/// the voxel (prob_hit 0.85: +1.73 in log-odds against a threshold of +1.10), and 48 frames of
/// clear floor free it again (prob_miss -0.05 each, from clamp_max 0.97 down to the threshold).
///
/// Free space is discretized: one light ray per slit and floor voxel, cast from the floor up to
/// free_height only (not to the sensor), which is where an object on the floor can be. Cells the
/// robot has left far behind are dropped: every crop_interval frames the map keeps only a window
/// around the robot, so its memory stays flat on long walks.
struct OccupancyMapConfig {
  double resolution = 0.01;           ///< voxel edge [m]
  double prob_hit = 0.85;             ///< update of a voxel holding obstacle points [-]
  double prob_weak_hit = 0.7;         ///< update of a voxel with weak evidence [-]
  double prob_miss = 0.4875;          ///< update of a voxel seen free [-]
  double occupancy_threshold = 0.75;  ///< occupied above: one hit, or two net weak hits [-]
  double clamp_min = 0.12;            ///< lower clamping of a voxel's probability [-]
  double clamp_max = 0.97;            ///< upper clamping: 12 misses clear a saturated voxel [-]
  double weak_sigmas = 3.0;  ///< weak point: residual over its slit's floor std this frame [-]
  double min_sigma = 0.05;   ///< the floor std used is at least this [px]
  int min_weak_points = 2;   ///< weak points that make a weak hit in one voxel [-]
  int min_weak_run = 3;      ///< consecutive weak points along a slit for any of them to count [-]
  /// Floor points this close to either end of their slit's measured run are never weak: where a
  /// slit ends, its profile is cut and its centre biased (12 mm on the floor).
  int weak_end_margin = 10;       ///< [points]
  double free_height = 0.06;      ///< free-space rays go up to this height [m]
  double max_height = 0.3;        ///< points higher are not mapped; window top [m]
  double window_half_size = 1.0;  ///< voxels farther along x or y from the robot are dropped [m]
  int crop_interval = 90;         ///< frames between two crops of the window (3 s) [-]
  SweepEvidenceConfig sweep;      ///< when evidence is consistent over the sweep

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// One occupied voxel.
struct MapCell {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< map frame [m]
  double size = 0.0;                                 ///< edge [m]
  double probability = 0.0;                          ///< occupancy [-]
};

/// What one frame changed.
struct MapUpdateStats {
  bool inserted = false;           ///< false: no floor or no metric scale, nothing was learnt
  std::size_t hit_voxels = 0;      ///< voxels updated as hit [-]
  std::size_t weak_voxels = 0;     ///< voxels updated as weak hit [-]
  std::size_t free_voxels = 0;     ///< voxels updated as miss [-]
  std::size_t pending_voxels = 0;  ///< voxels with evidence not consistent over the sweep [-]
  double sweep = 0.0;  ///< the slits' travel across themselves so far (SweepEvidence) [m]
  std::vector<SweepPass> passes;  ///< passes ended (OccupancyMapConfig::sweep.record_passes)
  bool cropped = false;           ///< the window was applied after this frame
};

class OccupancyMap {
 public:
  explicit OccupancyMap(const OccupancyMapConfig& config = {});  ///< validates
  OccupancyMap(OccupancyMap&&) noexcept;
  OccupancyMap& operator=(OccupancyMap&&) noexcept;
  ~OccupancyMap();

  const OccupancyMapConfig& config() const { return config_; }
  const octomap::OcTree& tree() const { return *tree_; }

  /// Learns one frame: its RDMap, floor and obstacles, the camera's pose in the world
  /// (odometry, sway included) and the light's origin (the projector centre) in the camera frame.
  /// Every crop_interval frames, crops the map to the window around the camera.
  MapUpdateStats insertFrame(const pcl::PointCloud<PointRDM>& cloud, const FloorResult& floor,
                             const ObstacleResult& obstacles,
                             const Eigen::Isometry3d& world_from_camera,
                             const Eigen::Vector3d& light_origin_camera);

  /// Occupied voxels overlapping the box [min, max] (map frame).
  std::vector<MapCell> occupiedInBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max) const;
  /// Occupied voxels between the two heights whose square overlaps the footprint.
  std::vector<MapCell> occupiedUnder(const Footprint& footprint, double min_height,
                                     double max_height) const;
  std::size_t occupiedCount() const;
  std::size_t leafCount() const { return tree_->getNumLeafNodes(); }
  std::size_t memoryUsage() const { return tree_->memoryUsage(); }  ///< [bytes]
  const SweepEvidence& sweepEvidence() const { return *sweep_; }

  /// Drops the voxels outside the window around `robot_xy` and prunes the tree.
  void crop(const Eigen::Vector2d& robot_xy);
  /// OctoMap's binary format (.bt: occupied / free per voxel), read by octovis and
  /// convert_octree. Throws std::runtime_error when the file cannot be written.
  void save(const std::string& path) const;

 private:
  using FrameEvidence = detail::FrameEvidence;
  std::unique_ptr<octomap::OcTree> makeTree() const;
  void collect(const pcl::PointCloud<PointRDM>& cloud, const FloorResult& floor,
               const ObstacleResult& obstacles, const Eigen::Isometry3d& world_from_camera,
               const Eigen::Vector3d& light_origin_camera, FrameEvidence& evidence);
  void markEvidence(FrameEvidence& evidence);
  void addFreeRay(const Eigen::Vector3d& floor_point, const Eigen::Vector3d& light,
                  const octomap::OcTreeKey& floor_key, const detail::RayKeys& rays,
                  FrameEvidence& evidence) const;
  MapUpdateStats apply(FrameEvidence& evidence);

  OccupancyMapConfig config_;
  std::unique_ptr<octomap::OcTree> tree_;
  std::unique_ptr<FrameEvidence> evidence_;        ///< one frame's, kept to reuse its memory
  std::unique_ptr<detail::SlitSweep> slit_sweep_;  ///< the slits' move between frames
  std::unique_ptr<SweepEvidence> sweep_;           ///< evidence over the sweep
  float log_hit_ = 0, log_weak_ = 0, log_miss_ = 0;
  std::size_t frames_ = 0;
};

}  // namespace multislit
