// The laser's light on each pixel (the renderer's second step, sim/laser_integral.h) against rays
// traced at 16 x 16 positions of every pixel, where a slit's end crosses the pixels: the linear
// model of the sheet's offset and of the position along the slit is no worse there than the 4 x 4
// traced rays it replaced.
#include "sim/laser_integral.h"
#include "sim/object_bounds.h"
#include "sim/pixel_centres.h"
#include "sim/shader.h"

#include "multislit/sim/scenarios.h"

#include "test_support.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <string>

using namespace multislit;

namespace {

struct EndErrors {
  int pixels = 0;                         // lit pixels within 3 px of a slit's end
  double integrated = 0, traced_4x4 = 0;  // mean |error| against 16 x 16 rays [of the peak]
  double worst_integrated = 0, worst_4x4 = 0;
};

EndErrors endErrors(const Scenario& s, std::uint64_t frame) {
  const SensorGeometry geometry{SensorConfig{}};
  RenderConfig render;
  const Eigen::Isometry3d pose = s.worldFromRobot(frame) * geometry.robotFromCamera(s.mount);
  const double sigma = geometry.config().projector.sheet_sigma * render.stripe_width,
               pixel = 1.0 / geometry.config().camera.f();
  Shader shader{s.scene, geometry,           render,
                pose,    pose.translation(), pose * geometry.projectorCentre(),
                sigma};
  const std::vector<ShadowBox> casters = shadowBoxes(shader);
  shader.casters = &casters;
  const FloorAlbedo albedo(s.scene.floor, floorInView(shader));
  shader.floor_albedo = &albedo;
  const double reach = sheetReach(s.scene, sigma, pixel);
  CentreSamples centre;
  traceCentres(shader, reach, pixel, RenderMethod::Culled, centre);
  cv::Mat laser;
  integrateLaser(shader, centre, reach, laser);
  double peak = 0;
  cv::minMaxLoc(laser, nullptr, &peak);
  EndErrors e;
  const double t_max = geometry.slitTMax();
  for (int r = 1; r + 1 < centre.height; ++r)
    for (int c = 1; c + 1 < centre.width; ++c) {
      const Shader::Sample& m = centre.at(r, c);
      if (!centre.near.at<uchar>(r, c) || std::abs(std::abs(m.t) - t_max) > 3 * pixel) continue;
      const double truth = tracedPixelMean(shader, m, c, r, reach, 16);
      if (truth < 1e-3 * peak && laser.at<float>(r, c) < 1e-3 * peak) continue;
      const double ours = std::abs(laser.at<float>(r, c) - truth) / peak,
                   old = std::abs(tracedPixelMean(shader, m, c, r, reach, 4) - truth) / peak;
      ++e.pixels;
      e.integrated += ours, e.traced_4x4 += old;
      e.worst_integrated = std::max(e.worst_integrated, ours);
      e.worst_4x4 = std::max(e.worst_4x4, old);
    }
  e.integrated /= std::max(1, e.pixels), e.traced_4x4 /= std::max(1, e.pixels);
  return e;
}

}  // namespace

TEST(LaserIntegral, SlitEndsAgreeWithRaysTracedFinely) {
  for (const char* name : {"reference", "ball", "cable"}) {
    if (kSanitized && std::string(name) != "ball") continue;
    SCOPED_TRACE(name);
    const EndErrors e = endErrors(makeScenario(name), 3);
    std::printf(
        "%s: %d lit pixels at slit ends; |error| against 16x16 rays, of the frame's peak: "
        "mean %.2e (4x4 rays %.2e), worst %.2e (4x4 rays %.2e)\n",
        name, e.pixels, e.integrated, e.traced_4x4, e.worst_integrated, e.worst_4x4);
    EXPECT_GT(e.pixels, 300);
    EXPECT_LE(e.integrated, 1.1 * e.traced_4x4);
    EXPECT_LE(e.worst_integrated, 1.1 * e.worst_4x4);
  }
}
