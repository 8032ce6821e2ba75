// A picture of what a viewer (rviz, fixed frame base_footprint) shows of the node's messages: the
// RDMap cloud in perspective coloured by height above the floor, the floor's grid, and the
// obstacle groups' boxes and sizes from the markers. For docs/ros.md, and to look at a run.
#pragma once

#include "multislit/point_types.h"

#include <visualization_msgs/MarkerArray.h>

#include <pcl/point_cloud.h>
#include <opencv2/core/mat.hpp>

#include <Eigen/Geometry>

#include <string>

namespace multislit::ros_test {

/// `cloud` in the camera frame, `base_from_camera` from the node's static TF, the markers in the
/// base frame.
cv::Mat renderView(const pcl::PointCloud<PointRDM>& cloud,
                   const visualization_msgs::MarkerArray& markers,
                   const Eigen::Isometry3d& base_from_camera, const std::string& title);

}  // namespace multislit::ros_test
