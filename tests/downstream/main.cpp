// Uses the installed library: the ground truth of the reference scenario has the paper's
// ~4900 slit points (more than 4000). Exits non-zero otherwise.
#include <multislit/scenarios.h>
#include <multislit/simulator.h>

#include <cstdio>

int main() {
  const multislit::SensorConfig sensor;  // the paper's sensor (Sec. II)
  const multislit::SensorGeometry geometry(sensor);
  const multislit::Simulator simulator(sensor);
  const multislit::Scenario scenario = multislit::makeScenario("reference");
  const auto truth = simulator.groundTruth(
      scenario.scene, scenario.worldFromRobot(0) * geometry.robotFromCamera(scenario.mount));
  std::printf("%d slits, %zu crossings in the reference image\n", geometry.slitCount(),
              truth.size());
  return truth.size() > 4000 ? 0 : 1;
}
