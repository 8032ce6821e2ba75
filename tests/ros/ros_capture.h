// What the ROS node test (ros_node_test.cpp) receives from multislit_ros: every message of the
// node's topics with its time of receipt and the MD5 its publisher announced, while it plays the
// robot that the node asks for poses (odom -> base_footprint on TF, or nav_msgs/Odometry).
#pragma once

#include <diagnostic_msgs/DiagnosticArray.h>
#include <multislit_ros/Decision.h>
#include <multislit_ros/Floor.h>
#include <nav_msgs/OccupancyGrid.h>
#include <octomap_msgs/Octomap.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>
#include <visualization_msgs/MarkerArray.h>

#include <Eigen/Geometry>

#include <atomic>
#include <cstddef>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace multislit::ros_test {

/// The messages of one topic as they came.
template <typename M>
struct Inbox {
  struct Item {
    boost::shared_ptr<const M> message;
    double received = 0.0;  ///< ROS time of receipt (the host's clock) [s]
    std::string md5;        ///< the MD5 announced by the publisher's connection
  };
  std::string topic;
  std::vector<Item> items;
};

struct CaptureOptions {
  std::string ns = "/multislit";  ///< the node's namespace
  std::size_t frames = 0;         ///< the frames the node processes
  /// "tf": publish odom -> base_footprint; "odom": publish nav_msgs/Odometry on /odom; else
  /// nothing.
  std::string poses = "tf";
  Eigen::Isometry3d robot = Eigen::Isometry3d::Identity();  ///< the robot in odom, standing
  /// The camera mount the robot publishes on /tf_static (base_footprint -> multislit_optical).
  std::optional<Eigen::Isometry3d> mount;
  double timeout = 120.0;  ///< for all of the node's messages [s]
};

class Capture {
 public:
  explicit Capture(const CaptureOptions& options);
  ~Capture();

  /// Waits until the node has published every frame and finished; false at the deadline, with
  /// what is missing in `missing`. Stops listening either way.
  bool wait(std::string& missing);

  Inbox<sensor_msgs::PointCloud2> rdmap, obstacles, occupied;
  Inbox<multislit_ros::Floor> floor;
  Inbox<visualization_msgs::MarkerArray> markers;
  Inbox<octomap_msgs::Octomap> octomap, octomap_full;
  Inbox<nav_msgs::OccupancyGrid> projected;
  Inbox<multislit_ros::Decision> decision;
  Inbox<diagnostic_msgs::DiagnosticArray> diagnostics;
  Inbox<tf2_msgs::TFMessage> tf_static;

 private:
  template <typename M>
  void listen(Inbox<M>& inbox, const std::string& topic);
  std::string missing() const;
  void playRobot();

  CaptureOptions options_;
  ros::NodeHandle nh_;
  ros::CallbackQueue queue_;
  ros::AsyncSpinner spinner_;
  std::vector<ros::Subscriber> subscribers_;
  mutable std::mutex mutex_;
  std::atomic<bool> stop_{false};
  std::thread robot_;
};

/// The value of `key` in the status, "" when it has none.
std::string diagnosticValue(const diagnostic_msgs::DiagnosticStatus& status,
                            const std::string& key);

}  // namespace multislit::ros_test
