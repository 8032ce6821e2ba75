// Fuzz target: a sensor YAML file (SensorConfig::load, which validates), then the geometry every
// user of a sensor computes from it: slit rows, rays, projections, the mount.
#include "fuzz_support.h"

#include <optional>

#include "multislit/sensor.h"

#include <cmath>
#include <stdexcept>

using namespace multislit;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::optional<SensorConfig> loaded = fuzz::loadInput(
      "sensor.yaml", data, size, [](const std::string& path) { return SensorConfig::load(path); });
  if (!loaded) return 0;  // refused, naming the value or the file
  const SensorConfig& sensor = *loaded;
  sensor.validate();  // load() validated: must not throw
  const SensorGeometry g(sensor);
  const CameraConfig& c = sensor.camera;
  for (int slit = 0; slit < g.slitCount(); ++slit) {
    const auto [first, last] = g.slitRows(slit);
    fuzz::expect(first >= 0 && last <= c.height - 1, "slitRows() inside the image");
    if (first > last) continue;
    const auto t = g.slitParamForRow(slit, 0.5 * (first + last));
    if (t) fuzz::expect(std::abs(*t) <= g.slitTMax(), "slitParamForRow() within the slit");
  }
  const Eigen::Vector3d ray = g.pixelRay(c.width - 1, c.height - 1);
  fuzz::expect(ray.allFinite(), "pixelRay() of a corner finite");
  fuzz::expect(g.project(ray).allFinite(), "project() of a ray finite");
  int slit = -1;
  const double offset = g.nearestSheetOffset(g.toProjector(2.0 * ray), &slit);
  fuzz::expect(slit >= 0 && slit < g.slitCount() && !std::isnan(offset),
               "nearestSheetOffset() names a slit");
  fuzz::expect(g.robotFromCamera().matrix().allFinite(), "robotFromCamera() finite");
  return 0;
}
