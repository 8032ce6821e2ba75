#include "ros_capture.h"

#include <nav_msgs/Odometry.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include <chrono>

namespace multislit::ros_test {

std::string diagnosticValue(const diagnostic_msgs::DiagnosticStatus& status,
                            const std::string& key) {
  for (const diagnostic_msgs::KeyValue& kv : status.values)
    if (kv.key == key) return kv.value;
  return "";
}

Capture::Capture(const CaptureOptions& options) : options_(options), spinner_(1, &queue_) {
  nh_.setCallbackQueue(&queue_);
  const std::string& ns = options_.ns;
  listen(rdmap, ns + "/rdmap");
  listen(obstacles, ns + "/obstacles");
  listen(occupied, ns + "/octomap_point_cloud_centers");
  listen(floor, ns + "/floor");
  listen(markers, ns + "/obstacle_markers");
  listen(octomap, ns + "/octomap_binary");
  listen(octomap_full, ns + "/octomap_full");
  listen(projected, ns + "/projected_map");
  listen(decision, ns + "/decision");
  listen(diagnostics, "/diagnostics");
  listen(tf_static, "/tf_static");
  spinner_.start();
  robot_ = std::thread([this] { playRobot(); });
}

Capture::~Capture() {
  stop_ = true;
  robot_.join();
  spinner_.stop();
}

template <typename M>
void Capture::listen(Inbox<M>& inbox, const std::string& topic) {
  inbox.topic = topic;
  const boost::function<void(const ros::MessageEvent<M const>&)> store =
      [this, &inbox](const ros::MessageEvent<M const>& event) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (stop_) return;
        inbox.items.push_back({event.getMessage(), event.getReceiptTime().toSec(),
                               event.getConnectionHeader()["md5sum"]});
      };
  ros::SubscribeOptions ops;
  ops.template initByFullCallbackType<const ros::MessageEvent<M const>&>(topic, 1000, store);
  ops.transport_hints = ros::TransportHints().tcpNoDelay();
  subscribers_.push_back(nh_.subscribe(ops));
}

/// The robot standing at options_.robot, 100 times a second, on the node's clock (now).
void Capture::playRobot() {
  tf2_ros::TransformBroadcaster tf;
  tf2_ros::StaticTransformBroadcaster static_tf;
  if (options_.mount) {
    const Eigen::Quaterniond r(options_.mount->rotation());
    geometry_msgs::TransformStamped t;
    t.header.stamp = ros::Time::now();
    t.header.frame_id = "base_footprint";
    t.child_frame_id = "multislit_optical";
    t.transform.translation.x = options_.mount->translation().x();
    t.transform.translation.y = options_.mount->translation().y();
    t.transform.translation.z = options_.mount->translation().z();
    t.transform.rotation.x = r.x();
    t.transform.rotation.y = r.y();
    t.transform.rotation.z = r.z();
    t.transform.rotation.w = r.w();
    static_tf.sendTransform(t);
  }
  ros::Publisher odometry;
  if (options_.poses == "odom") odometry = nh_.advertise<nav_msgs::Odometry>("/odom", 100);
  const Eigen::Vector3d p = options_.robot.translation();
  const Eigen::Quaterniond q(options_.robot.rotation());
  geometry_msgs::Quaternion rotation;
  rotation.x = q.x();
  rotation.y = q.y();
  rotation.z = q.z();
  rotation.w = q.w();
  ros::WallRate rate(100.0);
  for (; !stop_ && ros::ok(); rate.sleep()) {
    if (options_.poses == "tf") {
      geometry_msgs::TransformStamped t;
      t.header.stamp = ros::Time::now();
      t.header.frame_id = "odom";
      t.child_frame_id = "base_footprint";
      t.transform.translation.x = p.x();
      t.transform.translation.y = p.y();
      t.transform.translation.z = p.z();
      t.transform.rotation = rotation;
      tf.sendTransform(t);
    } else if (options_.poses == "odom") {
      nav_msgs::Odometry m;
      m.header.stamp = ros::Time::now();
      m.header.frame_id = "odom";
      m.child_frame_id = "base_footprint";
      m.pose.pose.position.x = p.x();
      m.pose.pose.position.y = p.y();
      m.pose.pose.position.z = p.z();
      m.pose.pose.orientation = rotation;
      odometry.publish(m);
    }
  }
}

std::string Capture::missing() const {
  const std::size_t n = options_.frames;
  std::string what;
  const auto need = [&](const std::string& topic, std::size_t got, std::size_t want) {
    if (got < want)
      what += " " + topic + " " + std::to_string(got) + " of " + std::to_string(want) + ";";
  };
  need(rdmap.topic, rdmap.items.size(), n);
  need(obstacles.topic, obstacles.items.size(), n);
  need(floor.topic, floor.items.size(), n);
  need(markers.topic, markers.items.size(), n);
  need(decision.topic, decision.items.size(), n);
  need(tf_static.topic, tf_static.items.size(), 1);
  // The map of the last frame, and the diagnostics said after it.
  const auto last = [&](const auto& inbox) {
    return !rdmap.items.empty() && !inbox.items.empty() &&
           inbox.items.back().message->header.stamp == rdmap.items.back().message->header.stamp;
  };
  const bool last_map = last(octomap) && last(octomap_full) && last(projected) && last(occupied);
  if (!last_map) what += " the map of the last frame;";
  bool finished = false;
  for (const auto& d : diagnostics.items)
    for (const auto& s : d.message->status)
      finished = finished || diagnosticValue(s, "state") == "finished";
  if (!finished) what += " diagnostics with state finished;";
  return what;
}

bool Capture::wait(std::string& what) {
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(options_.timeout);
  for (;;) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      what = missing();
      if (what.empty() || std::chrono::steady_clock::now() > deadline || !ros::ok()) {
        stop_ = true;  // the inboxes stay as they are from now on
        return what.empty();
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

}  // namespace multislit::ros_test
