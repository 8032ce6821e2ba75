#include "multislit/pipeline.h"

#include "multislit/odometry.h"

#include <cmath>
#include <ctime>
#include <string>

namespace multislit {

namespace {

/// Seconds since `t0`, and `t0` moved to now.
double lap(double& t0) {
  const double now = threadCpuSeconds();
  const double s = now - t0;
  t0 = now;
  return s;
}

/// Farthest a measured point may lie from the camera [m]: the sensor sees metres, not kilometres.
constexpr float kMaxPointRange = 1000.0f;

bool wild(float value) { return std::isinf(value) || std::abs(value) > kMaxPointRange; }

/// Why nothing may be decided on the frame (PipelineResult::dropped), "" when it may.
std::string unusable(const PipelineInput& in) {
  if (!in.world_from_robot.matrix().allFinite() ||
      in.world_from_robot.translation().cwiseAbs().maxCoeff() > kMaxOdometryDistance)
    return "the robot's pose is not finite or beyond " +
           std::to_string(static_cast<long>(kMaxOdometryDistance)) + " m";
  if (in.robot_from_camera && !in.robot_from_camera->matrix().allFinite())
    return "the camera's mount on the robot is not finite";
  if (!in.cloud) return "";
  for (std::size_t k = 0; k < in.cloud->size(); ++k) {
    const PointRDM& p = (*in.cloud)[k];  // NaN: no point there
    if (wild(p.x) || wild(p.y) || wild(p.z) || std::isinf(p.dk) || std::isinf(p.u) ||
        std::isinf(p.v))
      return "point " + std::to_string(k) + " is infinite or farther than " +
             std::to_string(static_cast<int>(kMaxPointRange)) + " m (is the calibration right?)";
  }
  return "";
}

const PipelineConfig& validated(const PipelineConfig& config) {
  config.validate();
  return config;
}

}  // namespace

double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

void PipelineConfig::validate() const {
  sensor.validate();
  floor.validate();
  obstacles.validate();
  map.validate();
  foot.validate();
  walker.validate();
}

Pipeline::Pipeline(const PipelineConfig& config)
    : config_(validated(config)),
      geometry_(config.sensor),
      detector_(config.floor),
      clusterer_(config.obstacles, config.foot),
      map_(config.map),
      walker_(config.walker, config.foot) {}

PipelineResult Pipeline::process(const PipelineInput& in) {
  PipelineResult r;
  double t0 = threadCpuSeconds();
  const Eigen::Isometry3d robot_from_camera =
      in.robot_from_camera ? *in.robot_from_camera : geometry_.robotFromCamera();
  r.dropped = unusable(in);
  if (!r.dropped.empty()) {  // no decision on bad numbers: the walker stops, as for no floor
    r.walker = walker_.step(map_, r.body, in.next_foot, WalkerObservation{});
    return r;
  }
  r.body = Pose2D::onFloor(in.world_from_robot);
  r.world_from_camera = in.world_from_robot * robot_from_camera;
  // Sec. III-B: the floor by RANSAC (eq. 1-3); points farther than 3 sigma are obstacle points.
  r.floor = detector_.detect(in.cloud);
  r.times.floor = lap(t0);
  // The obstacle points grouped into obstacles, sized and placed in the robot frame.
  if (in.cloud) r.obstacles = clusterer_.cluster(in.cloud, r.floor, robot_from_camera);
  r.times.obstacles = lap(t0);
  // Sec. V: an obstacle seen first very near the feet (judged before the map learns it).
  const WalkerObservation seen{r.floor.found, walker_.findSudden(r.obstacles, map_, r.body)};
  r.times.walker = lap(t0);
  // The map accumulates the frames along the odometry.
  if (in.cloud)
    r.map = map_.insertFrame(*in.cloud, r.floor, r.obstacles, r.world_from_camera,
                             geometry_.projectorCentre());
  r.times.map = lap(t0);
  // The footsteps ahead against the map: walk, turn or stop.
  r.walker = walker_.step(map_, r.body, in.next_foot, seen);
  r.times.walker += lap(t0);
  return r;
}

}  // namespace multislit
