#include "ros_poses.h"

#include <pcl_conversions/pcl_conversions.h>
#include <ros/console.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <chrono>
#include <vector>

namespace multislit::ros_node {
namespace {

/// Odometry older than this before the newest sample is dropped [us].
constexpr std::uint64_t kKeepOdometryUs = 10000000;

Eigen::Isometry3d toEigen(const geometry_msgs::Point& p, const geometry_msgs::Quaternion& q) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized().toRotationMatrix();
  t.translation() = Eigen::Vector3d(p.x, p.y, p.z);
  return t;
}

}  // namespace

RosPoses::RosPoses(const NodeConfig& config, const apps::MapInput& in,
                   const PipelineConfig& pipeline, ros::NodeHandle& nh)
    : config_(config) {
  if (config.poses.choice == "tf" || !config.publish_mount_tf) {
    tf_buffer_ = std::make_unique<tf2_ros::Buffer>(ros::Duration(30.0));
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh);
  }
  if (config.poses.choice == "odom")
    odometry_subscriber_ = nh.subscribe("odom", 100, &RosPoses::onOdometry, this);
  else if (config.poses.choice != "tf")
    own_.emplace(config.poses, config.input.sequence, in, pipeline);
}

RosPoses::~RosPoses() = default;

std::string RosPoses::description() const {
  if (own_) return own_->description();
  if (config_.poses.choice == "tf") return "TF " + config_.odom_frame + " -> " + config_.base_frame;
  return "nav_msgs/Odometry on " + odometry_subscriber_.getTopic();
}

std::optional<PipelineInput> RosPoses::at(const Frame& frame, std::string& why) {
  why.clear();
  std::optional<PipelineInput> input;
  if (config_.poses.choice == "tf") {
    input = fromTf(frame, why);
  } else if (!own_) {
    input = fromOdometry(frame, why);
  } else {
    PoseMiss miss = PoseMiss::None;
    input = own_->at(frame, miss);
    if (!input) why = poseMissName(miss);
  }
  if (input && !config_.publish_mount_tf)
    mountFromTf(pcl_conversions::fromPCL(frame.stamp_us), *input);
  return input;
}

void RosPoses::mountFromTf(const ros::Time& stamp, PipelineInput& input) {
  const std::string& base = config_.base_frame;
  const std::string& camera = config_.camera_frame;
  try {
    // At the frame's stamp when TF reaches it (a moving head), else its latest (a fixed mount).
    const ros::Time at = tf_buffer_->canTransform(base, camera, stamp) ? stamp : ros::Time(0);
    const geometry_msgs::TransformStamped t = tf_buffer_->lookupTransform(base, camera, at);
    geometry_msgs::Point p;
    p.x = t.transform.translation.x;
    p.y = t.transform.translation.y;
    p.z = t.transform.translation.z;
    input.robot_from_camera = toEigen(p, t.transform.rotation);
    mount_source_ = "TF " + base + " -> " + camera;
  } catch (const tf2::TransformException& e) {
    mount_source_ = "sensor file";
    if (!mount_warned_)
      ROS_WARN_STREAM("no camera mount " << base << " -> " << camera << " on TF yet (" << e.what()
                                         << "): the sensor file's mount meanwhile");
    mount_warned_ = true;
  }
}

bool RosPoses::waitForFirst(double timeout) {
  if (config_.poses.choice == "tf")
    return tf_buffer_->canTransform(config_.odom_frame, config_.base_frame, ros::Time(0),
                                    ros::Duration(timeout));
  if (own_) return true;
  std::unique_lock<std::mutex> lock(mutex_);
  return arrived_.wait_for(lock, std::chrono::duration<double>(timeout), [&] {
    return !samples_.empty() || !ros::ok();
  }) && !samples_.empty();
}

void RosPoses::follow(const WalkerResult& decision) {
  if (own_) own_->follow(decision);
}

std::optional<PipelineInput> RosPoses::fromTf(const Frame& frame, std::string& why) {
  const ros::Time stamp = pcl_conversions::fromPCL(frame.stamp_us);
  try {
    const geometry_msgs::TransformStamped t = tf_buffer_->lookupTransform(
        config_.odom_frame, config_.base_frame, stamp, ros::Duration(config_.pose_timeout));
    const geometry_msgs::Vector3& v = t.transform.translation;
    geometry_msgs::Point p;
    p.x = v.x;
    p.y = v.y;
    p.z = v.z;
    PipelineInput input;
    input.world_from_robot = toEigen(p, t.transform.rotation);
    return input;  // robot_from_camera left empty: the sensor file's mount
  } catch (const tf2::TransformException& e) {
    why = e.what();
    return std::nullopt;
  }
}

void RosPoses::onOdometry(const nav_msgs::Odometry::ConstPtr& m) {
  const std::uint64_t stamp = pcl_conversions::toPCL(m->header.stamp);
  std::lock_guard<std::mutex> lock(mutex_);
  if ((m->header.frame_id != config_.odom_frame || m->child_frame_id != config_.base_frame) &&
      odometry_warning_.empty()) {
    odometry_warning_ = "odometry of " + m->header.frame_id + " -> " + m->child_frame_id +
                        ", not ~odom_frame -> ~base_frame (" + config_.odom_frame + " -> " +
                        config_.base_frame + "): used as it is";
    ROS_WARN_STREAM(odometry_warning_);
  }
  if (!samples_.empty() && stamp <= samples_.back().stamp_us) return;  // out of order: dropped
  samples_.push_back({stamp, toEigen(m->pose.pose.position, m->pose.pose.orientation)});
  while (samples_.size() > 2 && samples_.front().stamp_us + kKeepOdometryUs < stamp)
    samples_.pop_front();
  arrived_.notify_all();
}

std::optional<PipelineInput> RosPoses::fromOdometry(const Frame& frame, std::string& why) {
  std::vector<OdometrySample> samples;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    const auto reached = [&] {
      return !samples_.empty() && samples_.back().stamp_us >= frame.stamp_us;
    };
    arrived_.wait_for(lock, std::chrono::duration<double>(config_.pose_timeout), reached);
    samples.assign(samples_.begin(), samples_.end());
  }
  if (samples.empty()) {
    why = "no odometry received yet";
    return std::nullopt;
  }
  PoseMiss miss = PoseMiss::None;
  const Odometry odometry(std::move(samples),
                          static_cast<std::uint64_t>(config_.poses.max_gap * 1e6));
  const std::optional<Eigen::Isometry3d> pose = odometry.at(frame.stamp_us, &miss);
  if (!pose) {
    why = std::string(poseMissName(miss)) + " of the odometry received";
    return std::nullopt;
  }
  PipelineInput input;
  input.world_from_robot = *pose;
  return input;
}

}  // namespace multislit::ros_node
