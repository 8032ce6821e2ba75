// SimulatorSource: the simulated sensor filming a scenario while the robot walks.
#include "multislit/sim/simulated_source.h"

#include <stdexcept>

namespace multislit {

void SimulatorSourceConfig::validate() const {
  if (!(fps >= 0)) throw std::invalid_argument("SimulatorSourceConfig.fps must be >= 0");
  sensor.validate();
  render.validate();
}

namespace {

const SimulatorSourceConfig& validated(const SimulatorSourceConfig& config) {
  config.validate();
  return config;
}

}  // namespace

SimulatorSource::SimulatorSource(const SimulatorSourceConfig& config)
    : config_(validated(config)),
      scenario_(makeScenario(config.scenario)),
      simulator_(config.sensor, config.render) {}

SourceStats SimulatorSource::stats() const {
  SourceStats s;
  s.frames = rendered_;
  return s;
}

bool SimulatorSource::finished() const { return config_.frames > 0 && rendered_ >= config_.frames; }

void SimulatorSource::start() {
  resetWaits();
  rendered_ = 0;
  started_ = Clock::now();
}

std::optional<Frame> SimulatorSource::next(std::chrono::milliseconds timeout) {
  if (finished()) return std::nullopt;
  if (config_.fps > 0) {
    if (!waitUntilDue(started_, rendered_, config_.fps, Clock::now() + timeout))
      return std::nullopt;
  } else if (interrupted()) {
    return std::nullopt;
  }
  // The robot's pose on the walk, then the camera on the robot (scenarios.h).
  const std::uint64_t frame = config_.first_frame + rendered_;
  const Eigen::Isometry3d world_from_camera =
      scenario_.worldFromRobot(frame) * simulator_.geometry().robotFromCamera(scenario_.mount);
  const auto stamp = std::chrono::duration_cast<std::chrono::microseconds>(
                         std::chrono::system_clock::now().time_since_epoch())
                         .count();
  cv::Mat image = simulator_.render(scenario_.scene, world_from_camera, frame).image;
  ++rendered_;
  return Frame{std::move(image), static_cast<std::uint64_t>(stamp), frame, Clock::now()};
}

Reference SimulatorSource::makeReference(const ReferenceConfig& config) const {
  // The bare floor seen from the reference pose (paper Sec. II-C).
  const Scenario reference = makeScenario("reference");
  ReferenceConfig c = config;
  c.expected_slits = simulator_.geometry().config().projector.slit_count;  // what it renders
  Reference ref = Reference::fromImage(
      simulator_.renderReference(reference.scene, scenario_.reference_mount).image, c);
  ref.setNominalScale(simulator_.geometry().config(), scenario_.reference_mount);
  return ref;
}

}  // namespace multislit
