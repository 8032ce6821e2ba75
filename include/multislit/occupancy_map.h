// An OctoMap occupancy map of what lies on the floor around the walking robot, updated with every
// frame's floor and obstacles and the robot's odometry. Evidence accumulates over frames, so an
// object too small for one frame (a screw: the paper's future work) is found from sequential data,
// and free-space updates clear an object that has gone (a ball that rolled away).
#pragma once

#include "multislit/feet.h"
#include "multislit/floor_detector.h"
#include "multislit/obstacles.h"
#include "multislit/point_types.h"

#include <octomap/OcTree.h>
#include <pcl/point_cloud.h>

#include <Eigen/Geometry>

#include <array>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace multislit {

/// The map frame: world x, y (the robot's odometry) and z = height above the floor measured in
/// the frame (the metric floor plane), so the floor is at z = 0 whatever the sensor's sway.
///
/// Evidence of one frame, per voxel (each voxel is updated at most once per frame):
/// - hit: the voxel holds points of an obstacle (ObstacleResult::obstacles);
/// - weak hit: the floor-layer voxel (0 <= z < resolution) holds at least min_weak_points points
///   whose residual above the RDMap plane is at least weak_sigmas times their slit's measured
///   floor noise in this frame, while below the frame's obstacle threshold
///   (FloorResult::threshold), and that lie at least weak_end_margin points from their slit's ends;
///   the points of groups rejected as noise count as weak points too;
/// - miss: the floor-layer voxel holds only floor points and no weak point, or a cell above the
///   floor layer lies on the light ray of a floor point below free_height (the projector lit the
///   floor through it); a voxel with fewer weak points than min_weak_points is not updated.
/// A 3 mm screw gives 0.4 to 0.8 px, below the 0.9 px threshold of every frame, but several times
/// the 0.12 px noise of the extractor: each pass of a slit over it is a weak hit, and a few passes
/// make it occupied. Noise makes weak points in one voxel rarely, and never several frames in a
/// row, while the floor around is seen free in every frame. Weak points count only in runs of
/// min_weak_run consecutive points along their slit: in real images the noise of adjacent rows is
/// correlated (lens blur, speckle grain), so noise lifts single rows or pairs, while the screw
/// lifts the 4 or 5 rows that cross it. (On rendered images of a bare floor, 500 frames of walking
/// gave 160 weak voxel updates without the run rule and none of them made a voxel occupied; the
/// run rule removes nearly all of them.)
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
  bool inserted = false;        ///< false: no floor or no metric scale, nothing was learnt
  std::size_t hit_voxels = 0;   ///< voxels updated as hit [-]
  std::size_t weak_voxels = 0;  ///< voxels updated as weak hit [-]
  std::size_t free_voxels = 0;  ///< voxels updated as miss [-]
  bool cropped = false;         ///< the window was applied after this frame
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

  /// Drops the voxels outside the window around `robot_xy` and prunes the tree.
  void crop(const Eigen::Vector2d& robot_xy);
  /// OctoMap's binary format (.bt: occupied / free per voxel), read by octovis and
  /// convert_octree. Throws std::runtime_error when the file cannot be written.
  void save(const std::string& path) const;

 private:
  struct FrameEvidence;
  std::unique_ptr<octomap::OcTree> makeTree() const;
  void collect(const pcl::PointCloud<PointRDM>& cloud, const FloorResult& floor,
               const ObstacleResult& obstacles, const Eigen::Isometry3d& world_from_camera,
               const Eigen::Vector3d& light_origin_camera, FrameEvidence& evidence) const;
  void addFreeRay(const Eigen::Vector3d& floor_point, const Eigen::Vector3d& light,
                  const octomap::OcTreeKey& floor_key, FrameEvidence& evidence) const;
  MapUpdateStats apply(FrameEvidence& evidence);

  OccupancyMapConfig config_;
  std::unique_ptr<octomap::OcTree> tree_;
  std::unique_ptr<FrameEvidence> evidence_;  ///< one frame's, kept to reuse its memory
  float log_hit_ = 0, log_weak_ = 0, log_miss_ = 0;
  std::size_t frames_ = 0;
};

}  // namespace multislit
