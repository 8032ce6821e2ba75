// The floor detector's service for any PCL cloud: the supporting plane (a floor or a table) of a
// cloud of any point type with x, y, z, and the points that stand on it and lie behind it.
//
// RANSAC whose candidates are scored by what a camera can see: a point BEHIND a candidate plane
// (on the far side from the viewpoint, farther than the threshold) was seen through it, so it
// counts against the candidate (score = inliers - behind_weight * behind). A plane that slices
// through low boxes holds many points but leaves the table behind it; the table leaves (almost)
// nothing behind.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/types.h>

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <memory>

namespace multislit {

struct PlaneDetectorConfig {
  double threshold = 0.01;        ///< distance from the plane that still counts as the plane [m]
  int max_iterations = 1000;      ///< RANSAC iterations at most (stops earlier when sure) [-]
  double probability = 0.99;      ///< chance that RANSAC drew one clean sample [-]
  int min_points = 50;            ///< fewer finite points: no plane [-]
  double min_inlier_ratio = 0.1;  ///< fewer plane points than this share of the finite: none [-]
  /// Inliers one point behind a candidate plane cancels [-]: with 2, a plane must hold more than
  /// twice the points it hides. 0: plain RANSAC (the most inliers win).
  double behind_weight = 2.0;
  std::uint32_t seed = 1;  ///< seed of the sample draws: the same cloud gives the same plane [-]
  /// Direction that counts as "above" the plane; zero: the side of the cloud's sensor_origin_
  /// (the viewpoint), which then must not lie on the plane (see PlaneResult::viewpoint_on_plane).
  Eigen::Vector3f up = Eigen::Vector3f::Zero();

  void validate() const;  ///< throws std::invalid_argument naming the field
};

struct PlaneResult {
  /// false: too few points, no plane carries enough of them, or the viewpoint lies on the plane.
  bool found = false;
  /// The best plane passes within the threshold of the viewpoint (config `up` zero): its sides
  /// are undefined, so `found` is false; `coefficients` and `inliers` still name that plane.
  bool viewpoint_on_plane = false;
  /// (a, b, c, d) with a x + b y + c z + d = 0, (a, b, c) a unit normal pointing "up" (towards the
  /// viewpoint or along PlaneDetectorConfig::up) [-, -, -, m].
  Eigen::Vector4f coefficients = Eigen::Vector4f::Zero();
  pcl::Indices inliers;  ///< cloud indices of the points within the threshold of the plane
  pcl::Indices above;    ///< cloud indices of the points above the plane, farther than threshold
  pcl::Indices below;    ///< cloud indices of the points behind (below) it, farther than threshold
  std::size_t finite_points = 0;  ///< points considered: finite x, y, z (and in the indices)
};

/// Supporting plane of a cloud (organized or not, NaNs allowed; only finite points take part).
/// PointT: any PCL point type with x, y, z; compiled for pcl::PointXYZ, PointXYZI, PointXYZRGB,
/// PointXYZRGBA, PointXYZRGBL, PointNormal and multislit::PointRDM. With `indices`, only those
/// points are considered; the result's indices index the cloud. Thread-safe.
class PlaneDetector {
 public:
  explicit PlaneDetector(const PlaneDetectorConfig& config = {});  ///< validates `config`

  const PlaneDetectorConfig& config() const { return config_; }

  template <typename PointT>
  PlaneResult detect(const pcl::PointCloud<PointT>& cloud) const;
  template <typename PointT>
  PlaneResult detect(const pcl::PointCloud<PointT>& cloud, const pcl::Indices& indices) const;

  /// PCL's shared pointers (Ptr and ConstPtr); a null cloud: not found.
  template <typename PointT>
  PlaneResult detect(const std::shared_ptr<const pcl::PointCloud<PointT>>& cloud) const {
    return cloud ? detect(*cloud) : PlaneResult{};
  }
  template <typename PointT>
  PlaneResult detect(const std::shared_ptr<pcl::PointCloud<PointT>>& cloud) const {
    return cloud ? detect(*cloud) : PlaneResult{};
  }

 private:
  PlaneDetectorConfig config_;
};

}  // namespace multislit
