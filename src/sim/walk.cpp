#include "multislit/sim/walk.h"

#include "config_check.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace multislit {

namespace {

// Objects lower than this give less than the 3 sigma threshold (0.9 px) in one frame.
constexpr double kVisibleHeight = 0.0035;  // [m]
constexpr double kBallRadius = 0.020;      // ping-pong ball [m]

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

void WalkSceneConfig::validate() const {
  constexpr detail::FieldCheck require("WalkSceneConfig");
  require(ball_frame >= 0, "ball_frame", "must be >= 0");
  require(ball_roll_frame >= ball_frame, "ball_roll_frame", "must be >= ball_frame");
  require(ball_roll_speed >= 0, "ball_roll_speed", "must be >= 0 m/s");
  require(cable_diameter > 0 && cable_diameter < 0.1, "cable_diameter", "must be in (0, 0.1) m");
  require((cable_end - cable_start).norm() > cable_diameter, "cable_end",
          "must be apart from cable_start");
  for (const SceneObject& o : extra) o.validate();
  floor.validate();
  require(object_albedo <= 1, "object_albedo", "must be <= 1 (< 0: each object's own)");
  require(object_stripe_width < 0 || (object_stripe_width >= 0.25 && object_stripe_width <= 4),
          "object_stripe_width", "must be in [0.25, 4] (< 0: each object's own)");
}

void applyPhotometry(const Photometry& photometry, WalkConfig& config) {
  photometry.validate();
  const std::uint64_t seed = config.render_config.seed;
  config.render_config = photometry.render;
  config.render_config.seed = seed;
  config.scene.floor = photometry.floor;
  config.scene.object_albedo = photometry.object_albedo;
  config.scene.object_stripe_width = photometry.object_stripe_width;
  if (photometry.distortion.any()) config.pipeline.sensor.camera.distortion = photometry.distortion;
}

WalkWorld::WalkWorld(const WalkSceneConfig& config, double frame_rate)
    : config_(config), frame_rate_(frame_rate) {
  config_.validate();
  detail::require(frame_rate > 0, "WalkWorld frame_rate", "must be > 0 Hz");
  scene_.floor = config_.floor;
}

const Scene& WalkWorld::sceneAt(std::uint64_t frame, const Pose2D& body) {
  scene_.objects = config_.extra;
  if (config_.cable) {
    const double r = 0.5 * config_.cable_diameter;
    scene_.objects.push_back(SceneObject::cylinder(
        "lan_cable", Eigen::Vector3d(config_.cable_start.x(), config_.cable_start.y(), r),
        Eigen::Vector3d(config_.cable_end.x(), config_.cable_end.y(), r), r));
    scene_.objects.back().albedo = 0.35;
  }
  if (!config_.ball || frame < static_cast<std::uint64_t>(config_.ball_frame))
    return withSurfaces();
  if (!ball_landed_) {  // thrown in just in front of the foot, it rolls away to the left later
    const Eigen::Vector2d at = body.toWorld(config_.ball_landing);
    ball_landed_ = Eigen::Vector3d(at.x(), at.y(), kBallRadius);
    ball_roll_ = Eigen::Vector3d(-std::sin(body.yaw), std::cos(body.yaw), 0.0);
  }
  const double rolled = frame > static_cast<std::uint64_t>(config_.ball_roll_frame)
                            ? config_.ball_roll_speed *
                                  static_cast<double>(frame - config_.ball_roll_frame) / frame_rate_
                            : 0.0;
  if (rolled < 1.0) {  // a metre away it is out of sight for good
    scene_.objects.push_back(
        SceneObject::sphere("pingpong_ball", *ball_landed_ + rolled * ball_roll_, kBallRadius));
    scene_.objects.back().albedo = 0.85;
  }
  return withSurfaces();
}

const Scene& WalkWorld::withSurfaces() {
  setObjectSurfaces(scene_.objects, config_.object_albedo, config_.object_stripe_width);
  return scene_;
}

void WalkConfig::validate() const {
  pipeline.validate();
  render_config.validate();
  synth.validate();
  gait.validate();
  scene.validate();
  constexpr detail::FieldCheck require("WalkConfig");
  require(truth_radius > 0, "truth_radius", "must be > 0 m");
}

struct WalkSimulation::Measurement {
  pcl::PointCloud<PointRDM>::Ptr cloud;
  std::vector<SlitCrossing> truth;
  cv::Mat image;
};

WalkSimulation::WalkSimulation(const WalkConfig& config, std::optional<Reference> reference)
    : config_(config),
      pipeline_(config.pipeline),
      gait_(config.gait, config.pipeline.foot, config.pipeline.sensor.mount),
      world_(config.scene, config.gait.frame_rate) {
  config_.validate();
  if (!reference)
    reference = renderFloorReference(config_.pipeline.sensor, config_.reference_mount,
                                     config_.render_config, config_.scene.floor);
  if (config_.render) {
    simulator_ = std::make_unique<Simulator>(config_.pipeline.sensor, config_.render_config);
    extractor_ = std::make_unique<Extractor>(std::move(*reference));
  } else {
    synthesizer_ = std::make_unique<RDMapSynthesizer>(config_.pipeline.sensor,
                                                      std::move(*reference), config_.synth);
  }
}

WalkSimulation::~WalkSimulation() = default;

const Reference& WalkSimulation::reference() const {
  if (!extractor_) throw std::logic_error("WalkSimulation::reference: RDMaps are synthesized");
  return extractor_->reference();
}

WalkSimulation::Measurement WalkSimulation::measure(const Scene& scene,
                                                    const Eigen::Isometry3d& world_from_camera) {
  Measurement m;
  if (synthesizer_) {
    m.cloud = synthesizer_->synthesize(scene, world_from_camera, frame_, &m.truth);
    return m;
  }
  RenderedFrame rendered = simulator_->render(scene, world_from_camera, frame_);
  m.cloud = extractor_->extract(rendered.image, stamp(), static_cast<std::uint32_t>(frame_));
  m.truth = std::move(rendered.truth);
  m.image = rendered.image;
  return m;
}

std::uint64_t WalkSimulation::stamp() const {
  return static_cast<std::uint64_t>(static_cast<double>(frame_) * 1e6 / config_.gait.frame_rate);
}

WalkFrame WalkSimulation::step() { return step(std::optional<Command>{}); }

WalkFrame WalkSimulation::step(Command forced) { return step(std::optional<Command>(forced)); }

WalkFrame WalkSimulation::step(const std::optional<Command>& forced) {
  WalkFrame f;
  f.frame = frame_;
  f.stamp_us = stamp();
  f.mount = gait_.mount();
  const Scene& scene = world_.sceneAt(frame_, gait_.pose());  // the ball may land, roll, be gone
  const Eigen::Isometry3d robot_from_camera = pipeline_.geometry().robotFromCamera(f.mount);
  f.world_from_torso =
      gait_.worldFromRobot() * robot_from_camera * pipeline_.geometry().robotFromCamera().inverse();
  // Sec. III-A: the relative disparity map of this frame.
  const auto t0 = std::chrono::steady_clock::now();
  Measurement m = measure(scene, gait_.worldFromRobot() * robot_from_camera);
  f.cloud = m.cloud;
  f.image = m.image;
  f.measure_seconds = secondsSince(t0);
  // Sec. III-B to V: floor, obstacles, map, footsteps and the decision.
  static_cast<PipelineResult&>(f) =
      pipeline_.process({m.cloud, gait_.worldFromRobot(), robot_from_camera, gait_.nextFoot()});
  f.process_seconds = f.times.total();
  // The robot moves: its pose integrates its own commands.
  f.footstep =
      forced ? gait_.advance(*forced, 1) : gait_.advance(f.walker.command, f.walker.turn_direction);
  f.motion = gait_.command();
  judge(scene, m.truth, f);
  ++frame_;
  return f;
}

void WalkSimulation::judge(const Scene& scene, const std::vector<SlitCrossing>& truth,
                           WalkFrame& f) const {
  f.objects.resize(scene.objects.size());
  for (std::size_t k = 0; k < scene.objects.size(); ++k) f.objects[k].object = scene.objects[k];
  for (const SlitCrossing& c : truth) {
    if (c.object <= 0) continue;
    ObjectView& v = f.objects[static_cast<std::size_t>(c.object - 1)];
    ++v.lit_any;
    v.lit += c.height >= kVisibleHeight;
  }
  // An obstacle point detects the objects within truth_radius of it (seen from above).
  for (const Obstacle& o : f.obstacles.obstacles)
    for (const auto i : o.indices) {
      const PointRDM& p = (*f.cloud)[static_cast<std::size_t>(i)];
      if (!std::isfinite(p.x)) continue;
      Footprint point;
      point.centre = (f.world_from_camera * Eigen::Vector3d(p.x, p.y, p.z)).head<2>();
      for (std::size_t k = 0; k < scene.objects.size(); ++k)
        f.objects[k].detected += clearance(point, scene.objects[k]) <= config_.truth_radius;
    }
  if (!f.footstep) return;
  f.footstep_clearance = std::numeric_limits<double>::infinity();
  for (const SceneObject& object : scene.objects)
    f.footstep_clearance = std::min(f.footstep_clearance, clearance(f.footstep->sole, object));
}

}  // namespace multislit
