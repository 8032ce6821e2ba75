// The simulator against its own exact ground truth.
#include "multislit/sim/simulator.h"
#include "multislit/sim/scenarios.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <map>

using namespace multislit;

namespace {

Eigen::Isometry3d cameraPose(const SensorGeometry& g, const Scenario& s, uint64_t frame = 0) {
  return s.worldFromRobot(frame) * g.robotFromCamera(s.mount);
}

// Background-subtracted centroid of row `row` over [u0 - half, u0 + half].
double rowCentroid(const cv::Mat& image, int row, double u0, int half) {
  const int c0 = std::max(0, static_cast<int>(std::lround(u0)) - half);
  const int c1 = std::min(image.cols - 1, static_cast<int>(std::lround(u0)) + half);
  auto at = [&](int c) {
    return image.depth() == CV_8U ? image.at<uint8_t>(row, c) : image.at<uint16_t>(row, c);
  };
  const double background = std::min<double>(at(c0), at(c1));
  double sum = 0, moment = 0;
  for (int c = c0; c <= c1; ++c) {
    const double w = std::max(0.0, at(c) - background);
    sum += w;
    moment += w * c;
  }
  return moment / sum;
}

}  // namespace

TEST(Simulator, GroundTruthPointsProjectOntoTheirImagePosition) {
  const Simulator sim{SensorConfig{}};
  for (const std::string name : {"reference", "cond3", "fig8", "ball", "cable"}) {
    const Scenario s = makeScenario(name);
    const auto truth = sim.groundTruth(s.scene, cameraPose(sim.geometry(), s, 250));
    ASSERT_GT(truth.size(), 4000u) << name;
    double worst = 0;
    for (const SlitCrossing& x : truth) {
      const Eigen::Vector2d uv = sim.geometry().project(x.camera_point);
      worst = std::max({worst, std::abs(uv.x() - x.u), std::abs(uv.y() - x.row)});
      // The point lies on its slit's light sheet, and on the floor or on its object.
      EXPECT_NEAR(sim.geometry().sheetOffset(x.slit, sim.geometry().toProjector(x.camera_point)), 0,
                  1e-9);
      if (x.object == 0) {
        EXPECT_NEAR(x.height, 0.0, 1e-9);
      }
    }
    EXPECT_LT(worst, 1e-6) << name;
  }
}

TEST(Simulator, ObjectsAreHitWhereTheyStand) {
  const Simulator sim{SensorConfig{}};
  const Scenario s = makeScenario("ball");
  const auto truth = sim.groundTruth(s.scene, cameraPose(sim.geometry(), s));
  int on_ball = 0;
  for (const SlitCrossing& x : truth) {
    if (x.object != 1) continue;
    ++on_ball;
    EXPECT_NEAR((x.world_point - s.scene.objects[0].centre).norm(), 0.020, 1e-9);
    EXPECT_GT(x.height, 0.0);
    EXPECT_LE(x.height, 0.040 + 1e-9);
  }
  EXPECT_GT(on_ball, 50);  // a 40 mm ball in front of the foot is crossed by several slits
}

TEST(Simulator, RowsPerSlitAndPointsPerFrameAreWhatTheGeometryPredicts) {
  const Simulator sim{SensorConfig{}};
  const Scenario s = makeScenario("reference");
  const auto truth = sim.groundTruth(s.scene, cameraPose(sim.geometry(), s));
  std::map<int, int> rows;
  for (const SlitCrossing& x : truth) ++rows[x.slit];
  ASSERT_EQ(static_cast<int>(rows.size()), 15);
  std::size_t predicted = 0;
  for (int slit = 0; slit < 15; ++slit) {
    const auto [first, last] = sim.geometry().slitRows(slit);
    EXPECT_EQ(rows[slit], last - first + 1) << "slit " << slit;
    predicted += static_cast<std::size_t>(last - first + 1);
  }
  EXPECT_EQ(truth.size(), predicted);
  // 2 f tan(22.5 deg) cos(70 deg) = 302 rows per slit: 15 slits give 4530 +- 15 points.
  EXPECT_NEAR(static_cast<double>(truth.size()), 4530.0, 15.0);
}

TEST(Simulator, NoiseFreeSlitCentroidMatchesGroundTruth) {
  RenderConfig render;
  render.noise = false;
  render.bit_depth = 16;  // no quantization either
  const Simulator sim{SensorConfig{}, render};
  Scenario s = makeScenario("reference");
  s.scene.floor.texture_amplitude = 0.0;  // a uniform floor: only the optics shape the profile
  const RenderedFrame f = sim.render(s.scene, cameraPose(sim.geometry(), s));
  std::map<int, std::pair<int, int>> ends;
  for (const SlitCrossing& x : f.truth) {
    auto& e = ends.try_emplace(x.slit, x.row, x.row).first->second;
    e.first = std::min(e.first, x.row);
    e.second = std::max(e.second, x.row);
  }
  double worst = 0;
  int measured = 0;
  for (const SlitCrossing& x : f.truth) {
    const auto [first, last] = ends[x.slit];
    // Along a row the profile spans about +-4 rows of the slit: its ends cut the profile there.
    if (x.row < first + 5 || x.row > last - 5) continue;
    const double e = rowCentroid(f.image, x.row, x.u, 20) - x.u;
    worst = std::max(worst, std::abs(e));
    ++measured;
  }
  EXPECT_GT(measured, 4300);
  EXPECT_LT(worst, 0.05);
}

TEST(Simulator, SameSeedSameBytesOtherSeedOtherNoise) {
  RenderConfig render;
  render.seed = 42;
  const Simulator a{SensorConfig{}, render};
  const Scenario s = makeScenario("ball");
  const cv::Mat first = a.render(s.scene, cameraPose(a.geometry(), s), 3).image;
  const cv::Mat again = a.render(s.scene, cameraPose(a.geometry(), s), 3).image;
  ASSERT_EQ(first.size(), again.size());
  EXPECT_EQ(cv::norm(first, again, cv::NORM_L1), 0.0);
  render.seed = 43;
  const Simulator b{SensorConfig{}, render};
  EXPECT_GT(cv::norm(first, b.render(s.scene, cameraPose(b.geometry(), s), 3).image, cv::NORM_L1),
            0.0);
  EXPECT_GT(cv::norm(first, a.render(s.scene, cameraPose(a.geometry(), s), 4).image, cv::NORM_L1),
            0.0);
}

TEST(Simulator, SixteenBitImagesUseTheWholeRange) {
  RenderConfig render;
  render.bit_depth = 16;
  const Simulator sim{SensorConfig{}, render};
  const Scenario s = makeScenario("reference");
  const RenderedFrame f = sim.render(s.scene, cameraPose(sim.geometry(), s));
  EXPECT_EQ(f.image.type(), CV_16UC1);
  double lo = 0, hi = 0;
  cv::minMaxLoc(f.image, &lo, &hi);
  EXPECT_GT(hi, 20000);  // the slits are bright
  // The slit is where the truth says: its row maximum near u is well above the background.
  int bright = 0;
  for (const SlitCrossing& x : f.truth) {
    const int c = static_cast<int>(std::lround(x.u));
    if (f.image.at<uint16_t>(x.row, c) > 4 * f.image.at<uint16_t>(x.row, std::min(c + 30, 1295)))
      ++bright;
  }
  EXPECT_GT(bright, static_cast<int>(0.95 * static_cast<double>(f.truth.size())));
}

TEST(Simulator, ShadowsAndOcclusionHideCrossings) {
  const Simulator sim{SensorConfig{}};
  Scenario s = makeScenario("reference");
  const Eigen::Isometry3d pose = cameraPose(sim.geometry(), s);
  const std::size_t bare = sim.groundTruth(s.scene, pose).size();
  // A tall box in view: it hides floor behind it from the camera and shadows floor from the laser.
  s.scene.objects.push_back(
      SceneObject::box("wall", Eigen::Vector3d(0.2, 0.0, 0.05), Eigen::Vector3d(0.02, 0.2, 0.1)));
  const auto truth = sim.groundTruth(s.scene, pose);
  int on_box = 0;
  for (const SlitCrossing& x : truth) on_box += x.object == 1;
  EXPECT_GT(on_box, 0);
  EXPECT_LT(truth.size(), bare);
}

TEST(Simulator, BadRenderConfigNamesTheField) {
  RenderConfig r;
  r.bit_depth = 12;
  try {
    r.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("bit_depth"), std::string::npos);
  }
}
