// The simulator as a FrameSource: a scenario rendered frame by frame while the robot walks.
#pragma once

#include "multislit/reference.h"
#include "multislit/sim/scenarios.h"
#include "multislit/sim/simulator.h"
#include "multislit/sources.h"

#include <atomic>
#include <cstdint>
#include <string>

namespace multislit {

struct SimulatorSourceConfig {
  std::string scenario = "ball";  ///< named scenario (scenarioNames())
  SensorConfig sensor;            ///< the simulated sensor (its mount is the scenario's)
  RenderConfig render;            ///< radiometry and noise
  double fps = 0.0;               ///< frame rate [Hz]; 0: as fast as frames render
  std::uint64_t first_frame = 0;  ///< walk frame of the first image
  std::uint64_t frames = 0;       ///< frames to render; 0: endless

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// Renders a scenario frame by frame while the robot walks (Scenario::worldFromRobot(frame)).
class SimulatorSource : public FrameSource {
 public:
  explicit SimulatorSource(const SimulatorSourceConfig& config = {});

  void start() override;
  std::optional<Frame> next(std::chrono::milliseconds timeout) override;
  void stop() override {}
  std::string name() const override { return "simulator (" + scenario_.name + ")"; }
  SourceStats stats() const override;
  bool live() const override { return config_.fps > 0; }
  bool finished() const override;

  /// The reference for these images: the bare floor at the scenario's reference pose, with the
  /// nominal metric scale.
  Reference makeReference(const ReferenceConfig& config = {}) const;
  const Scenario& scenario() const { return scenario_; }
  const Simulator& simulator() const { return simulator_; }

 private:
  SimulatorSourceConfig config_;
  Scenario scenario_;
  Simulator simulator_;
  std::atomic<std::uint64_t> rendered_{0};
  Clock::time_point started_{};
};

}  // namespace multislit
