// The robot's pose at each frame's stamp for the ROS node: from TF (odom_frame -> base_frame),
// from nav_msgs/Odometry messages (interpolated as an odometry file is), or the node's own poses
// as `multislit map` makes them (a file, standing still, the gait model, the scenario's motion).
// With ~publish_mount_tf false the robot publishes the camera's mount (base_frame ->
// camera_frame): it is looked up in TF at each frame, the sensor file's mount while TF has none.
#pragma once

#include "map_input.h"
#include "node_config.h"

#include "multislit/odometry.h"
#include "multislit/pipeline.h"

#include <nav_msgs/Odometry.h>
#include <ros/node_handle.h>
#include <ros/subscriber.h>

#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

namespace tf2_ros {
class Buffer;
class TransformListener;
}  // namespace tf2_ros

namespace multislit::ros_node {

class RosPoses {
 public:
  /// `nh`: the node's namespace (the odometry topic `odom` is resolved there).
  RosPoses(const NodeConfig& config, const apps::MapInput& in, const PipelineConfig& pipeline,
           ros::NodeHandle& nh);
  ~RosPoses();

  /// The frame's pipeline input (no cloud yet), waiting at most ~pose_timeout for TF or odometry
  /// to reach the frame's stamp; nullopt with the reason in `why` when there is no pose.
  std::optional<PipelineInput> at(const Frame& frame, std::string& why);
  /// With TF or odometry, waits until the robot's first pose has come, at most `timeout` [s];
  /// false when none came. True at once for the node's own poses.
  bool waitForFirst(double timeout);
  /// The gait model takes the decision.
  void follow(const WalkerResult& decision);
  /// True when the poses are the node's own (not TF or odometry): it publishes them on TF.
  bool own() const { return own_.has_value(); }
  std::string description() const;
  /// Where the last frame's camera mount came from: "TF <base> -> <camera>" or "sensor file".
  const std::string& mountSource() const { return mount_source_; }

 private:
  std::optional<PipelineInput> fromTf(const Frame& frame, std::string& why);
  std::optional<PipelineInput> fromOdometry(const Frame& frame, std::string& why);
  void onOdometry(const nav_msgs::Odometry::ConstPtr& message);
  /// input.robot_from_camera from TF at `stamp` (else the latest), when the robot publishes it.
  void mountFromTf(const ros::Time& stamp, PipelineInput& input);

  NodeConfig config_;
  std::optional<apps::MapPoses> own_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  ros::Subscriber odometry_subscriber_;
  std::mutex mutex_;
  std::condition_variable arrived_;
  std::deque<OdometrySample> samples_;  ///< the latest odometry, in increasing time
  std::string odometry_warning_;        ///< said once
  std::string mount_source_ = "sensor file";
  bool mount_warned_ = false;  ///< that TF has no mount yet, said once
};

}  // namespace multislit::ros_node
