// The floor detector's service for any PCL cloud: the dominant plane (a floor or a table) of a
// pcl::PointXYZ cloud, found with PCL's own SACSegmentation (SACMODEL_PLANE, RANSAC), and the
// points that stand on it.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/types.h>

#include <Eigen/Core>

#include <cstddef>

namespace multislit {

struct PlaneDetectorConfig {
  double threshold = 0.01;        ///< distance from the plane that still counts as the plane [m]
  int max_iterations = 1000;      ///< RANSAC iterations at most (PCL stops earlier when sure) [-]
  double probability = 0.99;      ///< chance that RANSAC drew one clean sample [-]
  int min_points = 50;            ///< fewer finite points: no plane [-]
  double min_inlier_ratio = 0.1;  ///< fewer plane points than this share of the finite: none [-]
  /// Direction that counts as "above" the plane; zero: the side of the cloud's sensor_origin_
  /// (which then must not lie on the plane).
  Eigen::Vector3f up = Eigen::Vector3f::Zero();

  void validate() const;  ///< throws std::invalid_argument naming the field
};

struct PlaneResult {
  bool found = false;  ///< false: too few points, or no plane carries enough of them
  /// (a, b, c, d) with a x + b y + c z + d = 0, (a, b, c) a unit normal pointing "up" (towards the
  /// viewpoint or along PlaneDetectorConfig::up) [-, -, -, m].
  Eigen::Vector4f coefficients = Eigen::Vector4f::Zero();
  pcl::Indices inliers;  ///< cloud indices of the points within the threshold of the plane
  pcl::Indices above;    ///< cloud indices of the points above the plane, farther than threshold
  std::size_t finite_points = 0;  ///< points with finite x, y, z
};

/// Dominant plane of a pcl::PointXYZ cloud (organized or not, NaNs allowed). Thread-safe.
class PlaneDetector {
 public:
  explicit PlaneDetector(const PlaneDetectorConfig& config = {});  ///< validates `config`

  const PlaneDetectorConfig& config() const { return config_; }

  PlaneResult detect(const pcl::PointCloud<pcl::PointXYZ>::ConstPtr& cloud) const;

 private:
  PlaneDetectorConfig config_;
};

}  // namespace multislit
