#include "node_config.h"

#include <ros/node_handle.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <stdexcept>

namespace multislit::ros_node {
namespace {

const std::vector<std::string> kParameters = {"camera",
                                              "sequence",
                                              "simulate",
                                              "calibration",
                                              "sensor",
                                              "poses",
                                              "max_gap",
                                              "frames",
                                              "fps",
                                              "out",
                                              "realtime",
                                              "odom_frame",
                                              "base_frame",
                                              "camera_frame",
                                              "publish_mount_tf",
                                              "map_every",
                                              "pose_timeout",
                                              "wait_for_subscribers",
                                              "wait_timeout",
                                              "diagnostics_period"};

/// The map's fields under octomap_server's parameter names, where they mean the same.
struct MapParameter {
  const char* name;   ///< the parameter, octomap_server's
  const char* field;  ///< OccupancyMapConfig's, as its validate() names it
  double OccupancyMapConfig::*value;
};
const MapParameter kMapParameters[] = {
    {"resolution", "resolution", &OccupancyMapConfig::resolution},
    {"sensor_model/hit", "prob_hit", &OccupancyMapConfig::prob_hit},
    {"sensor_model/miss", "prob_miss", &OccupancyMapConfig::prob_miss},
    {"sensor_model/min", "clamp_min", &OccupancyMapConfig::clamp_min},
    {"sensor_model/max", "clamp_max", &OccupancyMapConfig::clamp_max},
    {"pointcloud_max_z", "max_height", &OccupancyMapConfig::max_height}};

bool isKnown(const std::string& name) {
  if (std::find(kParameters.begin(), kParameters.end(), name) != kParameters.end()) return true;
  return std::any_of(std::begin(kMapParameters), std::end(kMapParameters),
                     [&](const MapParameter& p) { return name == p.name; });
}

void require(bool ok, const std::string& name, const std::string& rule) {
  if (!ok) throw std::invalid_argument("~" + name + " " + rule);
}

/// The parameter when set (else `value` is kept); a value of another type is an error, never
/// silently replaced by the default.
template <typename T>
void read(const ros::NodeHandle& nh, const std::string& name, T& value, const char* type) {
  if (!nh.hasParam(name)) return;
  T got{};
  require(nh.getParam(name, got), name, std::string("must be ") + type);
  value = got;
}

}  // namespace

void NodeConfig::validate() const {
  require(frames >= 0, "frames", "must be >= 0");
  require(std::isfinite(input.fps) && input.fps >= 0.1 && input.fps <= 1000, "fps",
          "must be in [0.1, 1000] Hz");
  require(std::isfinite(poses.max_gap) && poses.max_gap > 0, "max_gap", "must be > 0 s");
  require(!odom_frame.empty(), "odom_frame", "must not be empty");
  require(!base_frame.empty(), "base_frame", "must not be empty");
  require(!camera_frame.empty(), "camera_frame", "must not be empty");
  require(odom_frame != base_frame && base_frame != camera_frame && odom_frame != camera_frame,
          "camera_frame", "and ~odom_frame and ~base_frame must be three different frames");
  require(map_every >= 1, "map_every", "must be >= 1");
  require(std::isfinite(pose_timeout) && pose_timeout >= 0, "pose_timeout", "must be >= 0 s");
  require(wait_for_subscribers >= 0, "wait_for_subscribers", "must be >= 0");
  require(std::isfinite(wait_timeout) && wait_timeout > 0, "wait_timeout", "must be > 0 s");
  require(std::isfinite(diagnostics_period) && diagnostics_period > 0, "diagnostics_period",
          "must be > 0 s");
  try {
    map.validate();
  } catch (const std::invalid_argument& e) {  // "OccupancyMapConfig.<field> <rule>"
    const std::string message = e.what();
    for (const MapParameter& p : kMapParameters)
      if (message.find(std::string(".") + p.field + " ") != std::string::npos)
        throw std::invalid_argument("~" + std::string(p.name) + ": " + message);
    throw;
  }
}

NodeConfig readNodeConfig(const ros::NodeHandle& nh) {
  NodeConfig c;
  c.input.prefix = c.poses.prefix = "~";
  c.poses.max_gap_name = "max_gap";
  read(nh, "camera", c.input.camera, "a string");
  read(nh, "sequence", c.input.sequence, "a string");
  read(nh, "simulate", c.input.simulate, "a string");
  read(nh, "calibration", c.input.calibration, "a string");
  read(nh, "sensor", c.input.sensor, "a string");
  read(nh, "fps", c.input.fps, "a number");
  read(nh, "poses", c.poses.choice, "a string");
  read(nh, "max_gap", c.poses.max_gap, "a number");
  read(nh, "frames", c.frames, "an integer");
  read(nh, "out", c.out, "a string");
  read(nh, "realtime", c.realtime, "true or false");
  read(nh, "odom_frame", c.odom_frame, "a string");
  read(nh, "base_frame", c.base_frame, "a string");
  read(nh, "camera_frame", c.camera_frame, "a string");
  read(nh, "publish_mount_tf", c.publish_mount_tf, "true or false");
  read(nh, "map_every", c.map_every, "an integer");
  read(nh, "pose_timeout", c.pose_timeout, "a number");
  read(nh, "wait_for_subscribers", c.wait_for_subscribers, "an integer");
  read(nh, "wait_timeout", c.wait_timeout, "a number");
  read(nh, "diagnostics_period", c.diagnostics_period, "a number");
  for (const MapParameter& p : kMapParameters) read(nh, p.name, c.map.*p.value, "a number");
  c.validate();
  c.input.frames = static_cast<std::uint64_t>(c.frames);
  c.input.paced = c.realtime;
  return c;
}

std::vector<std::string> unknownParameters(const ros::NodeHandle& nh) {
  std::vector<std::string> names, unknown;
  nh.getParamNames(names);
  const std::string prefix = nh.getNamespace() + "/";
  for (const std::string& name : names) {
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string own = name.substr(prefix.size());
    if (!isKnown(own)) unknown.push_back("~" + own);
  }
  return unknown;
}

}  // namespace multislit::ros_node
