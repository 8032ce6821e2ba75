#include "map_input_sim.h"

#include "multislit/sim/simulated_source.h"

#include <memory>
#include <utility>

namespace multislit::apps {

MapInput openSimulatedInput(const MapInputOptions& o, MapInput in) {
  SimulatorSourceConfig config;
  config.scenario = o.simulate;
  config.frames = o.frames;
  if (o.paced) config.fps = o.fps;
  auto simulator = std::make_unique<SimulatorSource>(config);
  if (o.calibration.empty()) in.reference = simulator->makeReference();
  const Scenario scenario = simulator->scenario();
  in.sensor.mount = scenario.mount;
  in.scenario_motion = [scenario](std::uint64_t seq) { return scenario.worldFromRobot(seq); };
  in.description = simulator->name();
  in.source = std::move(simulator);
  return in;
}

}  // namespace multislit::apps
