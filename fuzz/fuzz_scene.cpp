// Fuzz target: a scene file (Scene::load, which validates), then one render of it and its ground
// truth by a 1/60-size sensor (21 x 16 px, the paper's field of view) on the robot at the origin:
// 336 pixels, so that a render costs about a millisecond.
#include "fuzz_support.h"

#include <optional>

#include "multislit/sim/scene.h"
#include "multislit/sim/simulator.h"

#include <opencv2/core/utility.hpp>

#include <cmath>
#include <stdexcept>

using namespace multislit;

namespace {

const Simulator& smallSimulator() {
  static const Simulator simulator = [] {
    cv::setNumThreads(0);  // the render's parallel_for on this thread: waking others costs more
    SensorConfig sensor;
    sensor.camera.width /= 60;
    sensor.camera.height /= 60;
    sensor.camera.pixel_size *= 60;
    RenderConfig render;
    render.supersample = 1;
    return Simulator(sensor, render);
  }();
  return simulator;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const Simulator& simulator = smallSimulator();
  const std::optional<Scene> loaded = fuzz::loadInput(
      "scene.yaml", data, size, [](const std::string& path) { return Scene::load(path); });
  if (!loaded) return 0;  // refused, naming the value or the file
  const Scene& scene = *loaded;
  const CameraConfig& camera = simulator.geometry().config().camera;
  const RenderedFrame frame = simulator.render(scene, simulator.geometry().robotFromCamera());
  fuzz::expect(frame.image.cols == camera.width && frame.image.rows == camera.height,
               "an image of the camera's size");
  for (const SlitCrossing& c : frame.truth)
    fuzz::expect(c.row >= 0 && c.row < camera.height && c.u > -1 && c.u < camera.width &&
                     c.object >= 0 && c.object <= static_cast<int>(scene.objects.size()),
                 "a crossing seen in the image, on the floor or an object");
  return 0;
}
