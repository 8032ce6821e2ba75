#include "multislit/plane_detector.h"

#include "config_check.h"

#include <pcl/ModelCoefficients.h>
#include <pcl/PointIndices.h>
#include <pcl/common/point_tests.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

namespace multislit {

namespace {

constexpr detail::FieldCheck require("PlaneDetectorConfig");

pcl::Indices finiteIndices(const pcl::PointCloud<pcl::PointXYZ>& cloud) {
  pcl::Indices finite;
  finite.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (pcl::isFinite(cloud[i])) finite.push_back(static_cast<pcl::index_t>(i));
  return finite;
}

}  // namespace

void PlaneDetectorConfig::validate() const {
  require(threshold > 0.0 && std::isfinite(threshold), "threshold", "must be > 0 [m]");
  require(max_iterations >= 1, "max_iterations", "must be >= 1");
  require(probability > 0.0 && probability < 1.0, "probability", "must be in (0, 1)");
  require(min_points >= 3, "min_points", "must be >= 3 (a plane needs three points)");
  require(min_inlier_ratio >= 0.0 && min_inlier_ratio <= 1.0, "min_inlier_ratio",
          "must be in [0, 1]");
  require(up.allFinite(), "up", "must be finite (zero: towards the sensor origin)");
}

PlaneDetector::PlaneDetector(const PlaneDetectorConfig& config) : config_(config) {
  config_.validate();
}

PlaneResult PlaneDetector::detect(const pcl::PointCloud<pcl::PointXYZ>::ConstPtr& cloud) const {
  PlaneResult result;
  if (!cloud) return result;
  // 1. Only finite points take part (PCL's plane model would draw samples among NaNs).
  const auto finite = std::make_shared<pcl::Indices>(finiteIndices(*cloud));
  result.finite_points = finite->size();
  if (finite->size() < static_cast<std::size_t>(config_.min_points)) return result;

  // 2. PCL's RANSAC plane with a least-squares refit on its inliers.
  pcl::SACSegmentation<pcl::PointXYZ> segmentation;
  segmentation.setOptimizeCoefficients(true);
  segmentation.setModelType(pcl::SACMODEL_PLANE);
  segmentation.setMethodType(pcl::SAC_RANSAC);
  segmentation.setDistanceThreshold(config_.threshold);
  segmentation.setMaxIterations(config_.max_iterations);
  segmentation.setProbability(config_.probability);
  segmentation.setInputCloud(cloud);
  segmentation.setIndices(finite);
  pcl::PointIndices plane_indices;
  pcl::ModelCoefficients model;
  segmentation.segment(plane_indices, model);
  if (model.values.size() != 4) return result;
  Eigen::Vector4f plane(model.values[0], model.values[1], model.values[2], model.values[3]);
  const float norm = plane.head<3>().norm();
  if (!(norm > 0.0f) || !plane.allFinite()) return result;
  plane /= norm;

  // 3. The normal points up: along `up`, or towards the viewpoint.
  const bool flip = config_.up.isZero()
                        ? plane.head<3>().dot(cloud->sensor_origin_.head<3>()) + plane[3] < 0.0f
                        : plane.head<3>().dot(config_.up) < 0.0f;
  if (flip) plane = -plane;

  // 4. On the plane (|distance| <= threshold), or standing on it (distance > threshold).
  const float threshold = static_cast<float>(config_.threshold);
  for (const auto i : *finite) {
    const float distance = plane.head<3>().dot((*cloud)[i].getVector3fMap()) + plane[3];
    if (std::abs(distance) <= threshold)
      result.inliers.push_back(i);
    else if (distance > threshold)
      result.above.push_back(i);
  }
  if (static_cast<double>(result.inliers.size()) <
      config_.min_inlier_ratio * static_cast<double>(result.finite_points)) {
    result.inliers.clear();
    result.above.clear();
    return result;
  }
  result.coefficients = plane;
  result.found = true;
  return result;
}

}  // namespace multislit
