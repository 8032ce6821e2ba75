// PCL filter that keeps the floor of an RDMap, or drops it and keeps the obstacles.
//
//   multislit::FloorFilter filter;
//   filter.setInputCloud(rdmap);
//   filter.setNegative(true);  // keep the obstacles
//   filter.filter(obstacles);
#pragma once

#include "multislit/floor_detector.h"
#include "multislit/point_types.h"

#include <pcl/filters/filter_indices.h>

namespace multislit {

/// Splits the valid points of an RDMap (or of its indices) into floor and obstacles with
/// FloorDetector (RANSAC on eq. 1, refit with eq. 2, threshold 3 sigma). setNegative(false), the
/// default, keeps the floor; setNegative(true) keeps the obstacles. Invalid points (non-finite u, v
/// or dk) are never kept. When no floor is found (FloorResult::found is false) no point is floor,
/// so every valid point counts as an obstacle: nothing is passed off as walkable. With
/// setKeepOrganized(true) the output is the whole input with x, y, z and dk of the removed points
/// set to the user filter value (NaN by default); u, v and slit are kept.
class FloorFilter : public pcl::FilterIndices<PointRDM> {
 public:
  using PointCloud = pcl::PointCloud<PointRDM>;
  using Ptr = std::shared_ptr<FloorFilter>;
  using ConstPtr = std::shared_ptr<const FloorFilter>;

  explicit FloorFilter(bool extract_removed_indices = false);

  /// Standard deviation of the relative disparity [px]: RANSAC's threshold is threshold_sigmas *
  /// sigma; the split uses each input's own measured sigma unless the config's estimate_sigma is
  /// false (getResult().sigma and .threshold: the ones used).
  void setSigma(double sigma);
  double getSigma() const { return config_.sigma; }
  /// Floor / obstacle threshold in sigmas [-] (default 3).
  void setThresholdSigmas(double sigmas);
  double getThresholdSigmas() const { return config_.threshold_sigmas; }
  /// All detector settings at once; throws std::invalid_argument when `config` is invalid.
  void setConfig(const FloorDetectorConfig& config);
  const FloorDetectorConfig& getConfig() const { return config_; }

  /// The floor found by the last call of filter().
  const FloorResult& getResult() const { return result_; }

 protected:
  void applyFilter(pcl::Indices& indices) override;
  void applyFilter(PointCloud& output) override;

 private:
  FloorDetectorConfig config_;
  FloorResult result_;
};

}  // namespace multislit
