// The ROS node test's options, what it expects from the simulator and the scenario, and the
// decoding of the node's messages (ros_node_test.cpp).
#pragma once

#include "ros_capture.h"

#include "multislit/occupancy_map.h"
#include "multislit/point_types.h"
#include "multislit/sim/scenarios.h"

#include <octomap/OcTree.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace multislit::ros_test {

struct TestOptions {
  std::string scenario = "ball";
  std::size_t frames = 0;
  std::string poses = "tf";                                 ///< tf or odom
  Eigen::Isometry3d robot = Eigen::Isometry3d::Identity();  ///< where the odometry says it is
  std::string node_out;                                     ///< the node's ~out folder
  std::string map_out;                                      ///< `multislit map` on the same frames
  std::string figure;  ///< a PNG of the last frame as a viewer shows it
  double fps = 30.0;   ///< the node's ~fps [Hz]
  double resolution = OccupancyMapConfig{}.resolution;  ///< the node's ~resolution [m]
  /// Not 0: the robot publishes the camera mount on TF (the node's ~publish_mount_tf false), the
  /// sensor's with the camera this much further forward [m].
  double mount_shift = 0.0;
  double timeout = 120.0;  ///< for the whole run [s]
};

/// Reads --scenario, --frames, --poses, --robot X,Y,YAW_DEG, --node-out, --map-out, --figure,
/// --fps, --resolution, --mount-shift and --timeout; false (said on stderr) when they are wrong.
bool parseOptions(int argc, char** argv);
const TestOptions& options();
CaptureOptions captureOptions();

void setCapture(const Capture* capture);
const Capture& capture();

/// What the simulator's reference and the scenario's mount give, independently of the node.
struct Expected {
  std::uint32_t rdmap_width = 0, rdmap_height = 0;  ///< the Extractor's organized RDMap
  Eigen::Isometry3d base_from_camera = Eigen::Isometry3d::Identity();  ///< the mount
};
const Expected& expected();

std::vector<ros::Time> cloudStamps();
/// The rows of a CSV file with a header, each as column -> value.
std::vector<std::map<std::string, std::string>> readCsv(const std::string& path);

pcl::PointCloud<PointRDM> rdmapCloud(const sensor_msgs::PointCloud2& message);
pcl::PointCloud<pcl::PointXYZL> labelledCloud(const sensor_msgs::PointCloud2& message);
pcl::PointCloud<pcl::PointXYZ> xyzCloud(const sensor_msgs::PointCloud2& message);
std::vector<visualization_msgs::Marker> groupBoxes(const visualization_msgs::MarkerArray& array);

/// The scene object whose footprint on the floor (grown by `margin` [m]) holds `p` (a point of
/// the frame `world_from_frame` places in the scenario's world); nullptr for none.
const SceneObject* objectUnder(const Scenario& scenario, const Eigen::Isometry3d& world_from_frame,
                               const Eigen::Vector3d& p, double margin);

/// octomap_msgs' map read back as octomap_msgs' conversions do (readBinaryData, or readData for a
/// full map).
std::unique_ptr<octomap::OcTree> decodeOctomap(const octomap_msgs::Octomap& message);
/// The centres of the occupied leaves, sorted.
std::vector<Eigen::Vector3d> occupiedCentres(const octomap::OcTree& tree);

/// base_footprint -> multislit_optical from /tf_static.
std::optional<Eigen::Isometry3d> baseFromCamera();
/// The last frame's cloud and boxes as a viewer shows them (ros_view.h).
void writeFigure(const std::string& path);

}  // namespace multislit::ros_test
