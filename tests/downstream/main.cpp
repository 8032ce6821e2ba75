// Uses the installed library: the ground truth of the reference scenario has the paper's
// ~4500 slit points (more than 4000), and the installed FloorFilter (multislit::filters) keeps
// the one point that stands 2 px off a plane of 15 slits. Exits non-zero otherwise.
#include <multislit/floor_filter.h>
#include <multislit/sim/scenarios.h>
#include <multislit/sim/simulator.h>

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

  // An RDMap of a plane dk = 0.002 u - 0.001 v + 0.5: 15 slits of 40 points, one point lifted.
  auto rdmap = pcl::make_shared<pcl::PointCloud<multislit::PointRDM>>(40, 15);
  for (std::uint32_t s = 0; s < 15; ++s)
    for (std::uint32_t j = 0; j < 40; ++j) {
      multislit::PointRDM& p = rdmap->at(j, s);
      p.x = p.y = p.z = 0.0f;
      p.u = 100.0f + 40.0f * static_cast<float>(s) + 0.5f * static_cast<float>(j);
      p.v = 200.0f + 10.0f * static_cast<float>(j);
      p.dk = 0.002f * p.u - 0.001f * p.v + 0.5f + (s == 7 && j == 20 ? 2.0f : 0.0f);
      p.slit = static_cast<std::int32_t>(s);
    }
  multislit::FloorFilter filter;
  filter.setInputCloud(rdmap);
  filter.setNegative(true);  // keep the obstacles
  pcl::PointCloud<multislit::PointRDM> obstacles;
  filter.filter(obstacles);
  std::printf("FloorFilter: %zu obstacle point(s) of %zu\n", obstacles.size(), rdmap->size());
  return truth.size() > 4000 && obstacles.size() == 1 ? 0 : 1;
}
