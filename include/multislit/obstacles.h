// Obstacles: the points off the floor of one RDMap (FloorResult::obstacles) grouped into objects,
// each sized and placed in the robot frame. Two groupings: neighbours in the organized RDMap (along
// a slit and across adjacent slits), or metric neighbours found with PCL's
// EuclideanClusterExtraction on a FLANN k-d tree.
#pragma once

#include "multislit/feet.h"
#include "multislit/floor_detector.h"
#include "multislit/point_types.h"

#include <pcl/point_cloud.h>
#include <pcl/types.h>

#include <Eigen/Geometry>

#include <cstddef>
#include <vector>

namespace multislit {

enum class ClusterMethod {
  Grid,      ///< neighbours in the organized RDMap: along a slit and across adjacent slits
  Euclidean  ///< metric neighbours (pcl::EuclideanClusterExtraction, pcl::search::KdTree)
};

struct ObstacleClustererConfig {
  ClusterMethod method = ClusterMethod::Grid;
  /// Grid: two obstacle points of one slit are neighbours when at most this many cells (image
  /// rows, 1.2 mm each on the floor) lie between them: points the extractor lost on an object's
  /// texture or edge do not split it.
  int max_gap = 10;  ///< [points]
  /// Grid: points of adjacent slits are neighbours when their reference positions (u, v) are this
  /// close in the image: about two slit spacings (43 px, f tan 2.3 deg, for the default sensor),
  /// so that the pieces of an oblique cable on adjacent slits stay one obstacle.
  double slit_link_radius = 90.0;  ///< [px]
  /// Euclidean: largest gap inside one obstacle. The slits are 20 to 30 mm apart on the floor, so
  /// an oblique cable is seen in pieces up to about 35 mm apart.
  double tolerance = 0.04;  ///< [m]
  /// Rejection rule: a group with fewer points is noise. A slit has one point per image row, so 3
  /// points are 3 rows of one slit or parts of 2 or more slits; isolated noisy points (the 3 sigma
  /// threshold lets 0.27% of a Gaussian floor through) almost never come in 3 connected ones. The
  /// 7 mm LAN cable crosses each slit along dozens of rows, the 40 mm ball along a hundred.
  int min_points = 3;  ///< [-]
  /// And it must hold this many points of one slit on neighbouring rows (a gap of one row
  /// allowed): an object lifts a run of rows, while noise that passes the threshold is scattered,
  /// and the grid grouping's gaps of up to max_gap rows would otherwise chain it into groups.
  /// 1: no such rule.
  int min_run = 3;  ///< [points]
  /// The run of min_run rows must lie on one side of the floor: an object lifts (or a hole sinks)
  /// every point of its run, while noise that passes the threshold above and below the floor on
  /// neighbouring rows is no surface.
  bool run_one_side = true;
  /// Grid: an obstacle point in no such run joins the group of a run at most this many links
  /// (max_gap along a slit, slit_link_radius across) away, the first group to reach it and that
  /// one only. Scattered points that pass the threshold (speckle, a stripe lost on dark grout)
  /// then neither chain two groups together nor spread one over the floor. Over the 80 frames of
  /// robustness_test, 0 hops (the points in runs only) gives 1.11 % false points and a recall of
  /// >= 5 mm crossings of 0.857, 1 hop 1.33 % and 0.884, 2 hops 1.42 % and 0.891, 3 hops 1.46 % and
  /// 0.892, 5 hops 1.48 % and 0.892; chaining through any number of points in no run gave 1.49 %
  /// and 0.892. With min_run 1 every point is in a run.
  int max_hops = 2;
  /// An obstacle's surface (Obstacle::surface): runs of min_run points of one slit whose dk
  /// changes by at most this much from one point to the next. A surface changes dk by at most
  /// 3.5 px from one image row to the next (the simulator's truth on the ball, the box and the
  /// tennis ball); where a stripe is lost on dark grout, the row's profile finds speckle anywhere
  /// in the assigned region, tens of pixels apart on neighbouring rows.
  double max_step = 8.0;  ///< [px]

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// One obstacle. Positions in the robot frame (x forward, y left, z up, origin on the floor midway
/// between the feet) [m].
struct Obstacle {
  pcl::Indices indices;                                ///< its points (indices into the cloud)
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< mean of its points [m]
  Eigen::Vector3d min = Eigen::Vector3d::Zero();       ///< bounding box, robot frame [m]
  Eigen::Vector3d max = Eigen::Vector3d::Zero();       ///< bounding box, robot frame [m]
  double length = 0.0;                                 ///< size along the walking direction (x) [m]
  double width = 0.0;         ///< size across the walking direction (y) [m]
  double height = 0.0;        ///< highest point above the floor plane [m]
  double distance = 0.0;      ///< nearest point to the feet (FootConfig::toe, halfWidth) [m]
  double max_residual = 0.0;  ///< largest |dk - plane| of its points [px]
  int slits = 0;              ///< slits it lies on [-]
  /// Its points on a surface (ObstacleClustererConfig::max_step), in ascending order, and their
  /// heights above the floor [m] (where they have x, y, z). Only these tell how tall it is for
  /// the walker's sudden stop and the map's tall evidence: points where a stripe was lost join
  /// groups and reach any height.
  pcl::Indices surface;
  std::vector<float> surface_heights;
  /// Surface points at least `least` [m] above the floor.
  std::size_t surfacePointsAbove(double least) const;
  /// Surface points less than `most` [m] above the floor (below it: `most` 0).
  std::size_t surfacePointsBelow(double most) const;
  std::size_t pointCount() const { return indices.size(); }
};

/// The floor as a metric plane in the camera frame: n . p + d = height above the floor [m], n a
/// unit normal pointing to the camera.
struct MetricFloor {
  bool valid = false;  ///< false: too few floor points with x, y, z (no metric scale)
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double offset = 0.0;
  std::size_t points = 0;  ///< floor points fitted
  double height(const Eigen::Vector3d& p_camera) const { return normal.dot(p_camera) + offset; }
};

struct ObstacleResult {
  std::vector<Obstacle> obstacles;  ///< nearest to the feet first
  MetricFloor floor;                ///< the plane heights are measured from
  std::size_t rejected_groups = 0;  ///< groups below min_points (noise)
  pcl::Indices rejected;            ///< their points
  std::size_t pointCount() const;   ///< points in all obstacles
};

/// The floor of an RDMap in metric space: the least-squares plane through the x, y, z of the
/// floor inliers (principal axes), its normal turned to the camera.
MetricFloor fitMetricFloor(const pcl::PointCloud<PointRDM>& cloud, const pcl::Indices& inliers);

/// Groups the obstacle points of a FloorResult into obstacles. Thread-safe: a result depends only
/// on the arguments (scratch buffers are per thread).
class ObstacleClusterer {
 public:
  /// `feet`: the robot's feet, which Obstacle::distance is measured from. Validates both.
  explicit ObstacleClusterer(const ObstacleClustererConfig& config = {},
                             const FootConfig& feet = {});

  const ObstacleClustererConfig& config() const { return config_; }
  const FootConfig& feet() const { return feet_; }

  /// The obstacles of `cloud` (an organized RDMap with metric x, y, z) given its floor.
  /// `robot_from_camera` places them in the robot frame (SensorGeometry::robotFromCamera of the
  /// sensor's current mount); heights come from the metric floor plane, so a wrong mount height
  /// or roll does not change them. Empty when the floor was not found.
  ObstacleResult cluster(const pcl::PointCloud<PointRDM>::ConstPtr& cloud, const FloorResult& floor,
                         const Eigen::Isometry3d& robot_from_camera) const;

 private:
  std::vector<pcl::Indices> gridGroups(const pcl::PointCloud<PointRDM>& cloud,
                                       const pcl::Indices& points,
                                       const Eigen::Vector3d* plane) const;
  std::vector<pcl::Indices> euclideanGroups(const pcl::PointCloud<PointRDM>& cloud,
                                            const pcl::Indices& points) const;
  Obstacle describe(const pcl::PointCloud<PointRDM>& cloud, const FloorResult& floor,
                    const MetricFloor& metric, pcl::Indices indices,
                    const Eigen::Isometry3d& robot_from_camera) const;

  ObstacleClustererConfig config_;
  FootConfig feet_;
};

}  // namespace multislit
