#include "node.h"

#include "ros_messages.h"
#include "simulated_input.h"

#include <diagnostic_msgs/DiagnosticArray.h>
#include <nav_msgs/Odometry.h>
#include <pcl_conversions/pcl_conversions.h>
#include <ros/ros.h>

#include <chrono>
#include <sstream>
#include <stdexcept>

namespace multislit::ros_node {
namespace {

PipelineConfig pipelineConfig(const apps::MapInput& in, const NodeConfig& node) {
  PipelineConfig config;
  config.sensor = in.sensor;
  config.map = node.map;
  return config;
}

diagnostic_msgs::KeyValue entry(const std::string& key, const std::string& value) {
  diagnostic_msgs::KeyValue kv;
  kv.key = key;
  kv.value = value;
  return kv;
}

template <typename T>
std::string str(const T& value) {
  std::ostringstream s;
  s << value;
  return s.str();
}

}  // namespace

Node::Node(const NodeConfig& config, ros::NodeHandle& nh, ros::NodeHandle& pnh)
    : config_(config),
      in_(apps::openMapInput(config.input, simulatedInput())),
      pipeline_(pipelineConfig(in_, config)),
      extractor_(in_.reference),
      poses_(config_, in_, pipeline_.config(), nh) {
  if (!config_.out.empty())
    recorder_.emplace(config_.out, config_.input.prefix + "out", apps::inputFiles(config_.input));
  rdmap_ = pnh.advertise<sensor_msgs::PointCloud2>("rdmap", 5);
  // The floor and the decision are latched as the map is: who subscribes late (a controller,
  // rostopic echo) gets the last frame's at once.
  floor_ = pnh.advertise<multislit_ros::Floor>("floor", 10, true);
  obstacles_ = pnh.advertise<sensor_msgs::PointCloud2>("obstacles", 5);
  markers_ = pnh.advertise<visualization_msgs::MarkerArray>("obstacle_markers", 5);
  octomap_ = pnh.advertise<octomap_msgs::Octomap>("octomap_binary", 1, true);  // latched
  octomap_full_ = pnh.advertise<octomap_msgs::Octomap>("octomap_full", 1, true);
  projected_ = pnh.advertise<nav_msgs::OccupancyGrid>("projected_map", 1, true);
  occupied_ = pnh.advertise<sensor_msgs::PointCloud2>("octomap_point_cloud_centers", 1, true);
  decision_ = pnh.advertise<multislit_ros::Decision>("decision", 10, true);
  diagnostics_ = nh.advertise<diagnostic_msgs::DiagnosticArray>("/diagnostics", 10);
  if (config_.publish_mount_tf)  // the sensor file's mount: base_frame -> camera_frame
    static_tf_.sendTransform(transformMessage(pipeline_.geometry().robotFromCamera(),
                                              header(ros::Time::now(), config_.base_frame),
                                              config_.camera_frame));
  ROS_INFO_STREAM("multislit: " << in_.description << ", poses from " << poses_.description()
                                << "; publishing on " << pnh.getNamespace() << "/");
}

std_msgs::Header Node::header(const ros::Time& stamp, const std::string& frame) const {
  std_msgs::Header h;
  h.stamp = stamp;
  h.frame_id = frame;
  h.seq = static_cast<std::uint32_t>(counts_.last_seq.value_or(0));
  return h;
}

void Node::waitForSubscribers() const {
  if (config_.wait_for_subscribers == 0) return;
  const std::vector<const ros::Publisher*> topics = {
      &rdmap_,        &floor_,     &obstacles_, &markers_,  &octomap_,
      &octomap_full_, &projected_, &occupied_,  &decision_, &diagnostics_};
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(config_.wait_timeout);
  const auto missing = [&] {
    std::string names;
    for (const ros::Publisher* p : topics)
      if (p->getNumSubscribers() < static_cast<std::uint32_t>(config_.wait_for_subscribers))
        names += " " + p->getTopic();
    return names;
  };
  for (std::string names = missing(); !names.empty(); names = missing()) {
    if (!ros::ok()) return;
    if (ros::WallTime::now() > deadline)
      throw std::runtime_error("~wait_for_subscribers: fewer than " +
                               std::to_string(config_.wait_for_subscribers) +
                               " subscribers after " + str(config_.wait_timeout) + " s on" + names);
    ros::WallDuration(0.01).sleep();
  }
}

void Node::run() {
  waitForSubscribers();
  // The first frames would have no pose before the robot's odometry or TF comes.
  if (!poses_.own() && !poses_.waitForFirst(config_.wait_timeout))
    ROS_WARN_STREAM("no pose from " << poses_.description() << " after " << config_.wait_timeout
                                    << " s: frames without a pose are skipped");
  const std::size_t max_frames = static_cast<std::size_t>(config_.frames);
  const auto t0 = std::chrono::steady_clock::now();
  last_diagnostics_ = ros::WallTime::now();
  in_.source->start();
  while (ros::ok() && (max_frames == 0 || counts_.processed < max_frames)) {
    const std::optional<Frame> frame = in_.source->next(std::chrono::milliseconds(200));
    publishDiagnostics(false, "running");
    if (!frame) {
      if (in_.source->finished()) break;
      continue;
    }
    processFrame(*frame);
  }
  in_.source->stop();
  if (counts_.last_stamp_us && map_published_at_ != counts_.processed)
    publishMap(pcl_conversions::fromPCL(*counts_.last_stamp_us));
  publishDiagnostics(true, ros::ok() ? "finished" : "shut down");
  if (recorder_) {
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    recorder_->finish(pipeline_,
                      "multislit_ros: " + in_.description + ", poses from " + poses_.description(),
                      seconds, !ros::ok());
  }
  ROS_INFO_STREAM("multislit: " << counts_.processed << " frames processed (" << counts_.no_pose
                                << " without a pose, " << counts_.bad_frames << " refused, "
                                << counts_.seq_gaps << " lost)");
}

void Node::processFrame(const Frame& frame) {
  if (counts_.last_seq && frame.seq > *counts_.last_seq + 1)
    counts_.seq_gaps += frame.seq - *counts_.last_seq - 1;
  counts_.last_seq = frame.seq;
  std::string why;
  std::optional<PipelineInput> input = poses_.at(frame, why);
  if (!input) {
    ++counts_.no_pose;
    if (recorder_) recorder_->skip();
    if (why != last_miss_)
      ROS_WARN_STREAM("frame " << frame.seq << " has no pose (" << why << "): skipped");
    last_miss_ = why;
    return;
  }
  const double start = threadCpuSeconds();
  try {
    input->cloud =
        extractor_.extract(frame.image, frame.stamp_us, static_cast<std::uint32_t>(frame.seq));
  } catch (const std::exception& e) {  // a frame of another size or kind: said, counted
    if (counts_.bad_frames++ == 0) ROS_ERROR_STREAM("frame " << frame.seq << ": " << e.what());
    return;
  }
  const double extract_seconds = threadCpuSeconds() - start;
  const PipelineResult r = pipeline_.process(*input);
  counts_.processing_sum += threadCpuSeconds() - start;
  poses_.follow(r.walker);
  ++counts_.processed;
  counts_.no_floor += !r.floor.found;
  counts_.last_stamp_us = frame.stamp_us;
  counts_.last_floor = r.floor.found;
  counts_.last_sigma = r.floor.sigma;
  counts_.last_groups = r.obstacles.obstacles.size();
  counts_.last_decision = commandName(r.walker.command);
  publishFrame(frame, *input->cloud, r, *input);
  if (recorder_)
    recorder_->record(frame.seq, frame.stamp_us, extract_seconds, *input->cloud, r,
                      pipeline_.map());
}

void Node::publishFrame(const Frame& frame, const pcl::PointCloud<PointRDM>& cloud,
                        const PipelineResult& r, const PipelineInput& input) {
  const ros::Time stamp = pcl_conversions::fromPCL(frame.stamp_us);
  if (poses_.own())  // the robot's pose is the node's own: it tells TF
    tf_.sendTransform(transformMessage(input.world_from_robot, header(stamp, config_.odom_frame),
                                       config_.base_frame));
  const std_msgs::Header camera = header(stamp, config_.camera_frame);
  const std_msgs::Header base = header(stamp, config_.base_frame);
  rdmap_.publish(rdmapMessage(cloud, camera));
  counts_.latency_sum += (ros::Time::now() - stamp).toSec();
  counts_.node_latency_sum +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - frame.arrival).count();
  ++counts_.published;
  floor_.publish(floorMessage(r.floor, r.obstacles.floor, camera));
  obstacles_.publish(obstacleCloudMessage(cloud, r.obstacles, camera));
  markers_.publish(obstacleMarkers(r.obstacles, base));
  decision_.publish(decisionMessage(r.walker, base));
  if (counts_.processed - map_published_at_ >= static_cast<std::size_t>(config_.map_every) ||
      (config_.frames > 0 && counts_.processed == static_cast<std::size_t>(config_.frames)))
    publishMap(stamp);
}

void Node::publishMap(const ros::Time& stamp) {
  const std_msgs::Header odom = header(stamp, config_.odom_frame);
  octomap_.publish(octomapMessage(pipeline_.map().tree(), odom));
  octomap_full_.publish(octomapFullMessage(pipeline_.map().tree(), odom));
  projected_.publish(projectedMapMessage(pipeline_.map().tree(), odom));
  occupied_.publish(occupiedCellsMessage(pipeline_.map().tree(), odom));
  map_published_at_ = counts_.processed;
}

void Node::publishDiagnostics(bool now, const std::string& state) {
  const ros::WallTime t = ros::WallTime::now();
  const double elapsed = (t - last_diagnostics_).toSec();
  if (!now && elapsed < config_.diagnostics_period) return;
  const SourceStats source = in_.source->stats();
  const std::size_t dropped = counts_.seq_gaps + counts_.no_pose + counts_.bad_frames +
                              static_cast<std::size_t>(source.bad_buffers);
  diagnostic_msgs::DiagnosticStatus s;
  s.name = "multislit: sensor";
  s.hardware_id = in_.description;
  const bool lost = !in_.source->connected();
  s.level = lost ? diagnostic_msgs::DiagnosticStatus::ERROR
            : (counts_.processed > 0 && !counts_.last_floor) || dropped > dropped_at_diagnostics_
                ? diagnostic_msgs::DiagnosticStatus::WARN
                : diagnostic_msgs::DiagnosticStatus::OK;
  s.message = lost                                           ? "camera lost"
              : counts_.processed > 0 && !counts_.last_floor ? "no floor"
                                                             : state;
  const double fps =
      static_cast<double>(counts_.processed - processed_at_diagnostics_) / std::max(elapsed, 1e-9);
  const double n = static_cast<double>(std::max<std::size_t>(counts_.published, 1));
  s.values = {
      entry("state", state),
      entry("fps", str(fps)),
      entry("frames processed", str(counts_.processed)),
      entry("dropped frames", str(dropped)),
      entry("frames lost by the source (seq gaps)", str(counts_.seq_gaps)),
      entry("frames without a pose", str(counts_.no_pose)),
      entry("frames refused by the extractor", str(counts_.bad_frames)),
      entry("bad camera buffers", str(source.bad_buffers)),
      entry("found floor", counts_.last_floor ? "true" : "false"),
      entry("frames without a floor", str(counts_.no_floor)),
      entry("sigma [px]", str(counts_.last_sigma)),
      entry("obstacle groups", str(counts_.last_groups)),
      entry("decision", counts_.last_decision),
      entry("camera mount", poses_.mountSource()),
      entry("occupied voxels", str(pipeline_.map().occupiedCount())),
      entry("mean latency, stamp to cloud published [ms]", str(1e3 * counts_.latency_sum / n)),
      entry("mean latency, frame arrival to cloud published [ms]",
            str(1e3 * counts_.node_latency_sum / n)),
      entry("mean CPU time per frame [ms]", str(1e3 * counts_.processing_sum / n))};
  diagnostic_msgs::DiagnosticArray array;
  array.header.stamp = ros::Time::now();
  array.status.push_back(s);
  diagnostics_.publish(array);
  last_diagnostics_ = t;
  processed_at_diagnostics_ = counts_.processed;
  dropped_at_diagnostics_ = dropped;
}

}  // namespace multislit::ros_node
