// FloorDetector's step 6 (FloorDetectorConfig::multiscale) on synthetic RDMaps whose noise is
// correlated along each slit like speckle grains: a low run of rows that no single point shows
// above the frame's noise is found, and an empty floor of the same noise gives no run.
#include "multislit/floor_detector.h"

#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

using namespace multislit;

namespace {

using Cloud = pcl::PointCloud<PointRDM>;
constexpr int kSlits = 15;
constexpr int kSamples = 300;
const Eigen::Vector3d kPlane(0.004, -0.012, 3.0);

struct Scene {
  Cloud::Ptr cloud;
  std::vector<bool> lifted;  // per cell: on the run
};

// 15 slits x 300 rows; along each slit the noise is white noise of std `sigma` smoothed over a
// grain of 2 rows (a moving mean, rescaled to std `sigma`), 3 % unmeasured. With `lift`, rows 100
// to 139 of slits 4 to 9 are raised by `lift` px: a cable lying along the slits.
Scene makeScene(unsigned seed, double sigma, double lift) {
  Scene scene{std::make_shared<Cloud>(kSamples, kSlits), {}};
  scene.lifted.assign(scene.cloud->size(), false);
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  constexpr int kGrain = 2;
  for (int s = 0; s < kSlits; ++s) {
    std::vector<double> white(kSamples + kGrain);
    for (double& w : white) w = gauss(rng);
    for (int j = 0; j < kSamples; ++j) {
      double grain = 0.0;
      for (int g = 0; g < kGrain; ++g) grain += white[static_cast<std::size_t>(j + g)];
      const bool on_run = lift > 0.0 && s >= 4 && s <= 9 && j >= 100 && j < 140;
      PointRDM& p = scene.cloud->at(j, s);
      p.u = static_cast<float>(300.0 + 2.75 * j);
      p.v = static_cast<float>(50 + 42 * s + j);
      p.slit = s;
      p.dk = static_cast<float>(kPlane.dot(Eigen::Vector3d(p.u, p.v, 1.0)) + (on_run ? lift : 0.0) +
                                sigma * grain / std::sqrt(kGrain));
      p.x = p.u * 1e-3f, p.y = p.v * 1e-3f, p.z = 0.5f;
      scene.lifted[static_cast<std::size_t>(s * kSamples + j)] = on_run;
      if (unit(rng) < 0.03) p.x = p.y = p.z = p.dk = std::numeric_limits<float>::quiet_NaN();
    }
  }
  scene.cloud->is_dense = false;
  return scene;
}

struct Count {
  std::size_t lifted = 0, found = 0, false_points = 0;
};

Count count(const Scene& scene, const FloorResult& r) {
  Count c;
  for (std::size_t i = 0; i < scene.cloud->size(); ++i)
    c.lifted += scene.lifted[i] && std::isfinite((*scene.cloud)[i].dk);
  for (const auto i : r.obstacles) {
    const bool lifted = scene.lifted[static_cast<std::size_t>(i)];
    c.found += lifted;
    c.false_points += !lifted;
  }
  return c;
}

}  // namespace

// 1 px of grainy noise (the estimate's upper bound, a 3 px threshold) hides a 2.5 px run (a 10 mm
// object) point by point; its windows of 7 to 31 rows show it.
TEST(SlitScale, FindsALowRunHiddenInGrainyNoise) {
  FloorDetectorConfig single;
  single.multiscale = false;
  Count with_runs, without;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const Scene scene = makeScene(seed, 1.0, 2.5);
    const FloorResult a = FloorDetector().detect(scene.cloud);
    const FloorResult b = FloorDetector(single).detect(scene.cloud);
    ASSERT_TRUE(a.found && b.found);
    EXPECT_DOUBLE_EQ(a.sigma, 1.0);        // the bound: the point threshold is 3 px
    ASSERT_EQ(a.window_noise.size(), 3u);  // 7, 15, 31 rows
    EXPECT_LT(a.window_noise[2], 0.7 * a.window_noise[0]);  // longer windows, less noise
    EXPECT_EQ(a.obstacles.size(), a.obstacle_residuals.size());
    EXPECT_EQ(a.inliers.size() + a.obstacles.size(), a.valid_points);
    EXPECT_EQ(b.run_obstacles, 0u);
    const Count ca = count(scene, a), cb = count(scene, b);
    std::printf("seed %u: run points %zu, found %zu (%zu false) with windows, %zu (%zu) without\n",
                seed, ca.lifted, ca.found, ca.false_points, cb.found, cb.false_points);
    with_runs.lifted += ca.lifted, with_runs.found += ca.found;
    with_runs.false_points += ca.false_points;
    without.found += cb.found, without.false_points += cb.false_points;
  }
  // 593 of 1160 run points with the windows (51 %), 340 (29 %) by the point rule alone; the
  // windows add no false point (56 and 56).
  EXPECT_GE(with_runs.found * 100, with_runs.lifted * 48);
  EXPECT_LE(without.found * 100, with_runs.lifted * 35);
  EXPECT_LE(with_runs.false_points, without.false_points + 5);
}

// The same noise without the run: the windows add (nearly) nothing to the point rule.
TEST(SlitScale, AnEmptyGrainyFloorGivesNoRun) {
  for (const double sigma : {0.3, 0.6, 1.0}) {
    for (unsigned seed = 11; seed <= 15; ++seed) {
      const Scene scene = makeScene(seed, sigma, 0.0);
      const FloorResult r = FloorDetector().detect(scene.cloud);
      ASSERT_TRUE(r.found);
      EXPECT_LE(r.run_obstacles, 10u) << sigma << " " << seed;
    }
  }
}

// Unorganized clouds have no slits to run along: step 6 does nothing.
TEST(SlitScale, NothingOnAnUnorganizedCloud) {
  const Scene scene = makeScene(21, 1.0, 2.5);
  auto flat = std::make_shared<Cloud>(*scene.cloud);
  flat->width = static_cast<std::uint32_t>(flat->size());
  flat->height = 1;
  const FloorResult r = FloorDetector().detect(flat);
  ASSERT_TRUE(r.found);
  EXPECT_EQ(r.run_obstacles, 0u);
  EXPECT_TRUE(r.window_noise.empty());
}

TEST(SlitScale, ValidateNamesTheField) {
  const auto message = [](auto change) { return validationMessage<FloorDetectorConfig>(change); };
  EXPECT_EQ(message([](auto&) {}), "valid");
  EXPECT_EQ(message([](auto& c) { c.min_window = 4; }),
            "FloorDetectorConfig.min_window must be odd and >= 3 rows");
  EXPECT_NE(message([](auto& c) { c.max_window = 5; }).find("max_window"), std::string::npos);
  EXPECT_NE(message([](auto& c) { c.window_sigmas = 0.0; }).find("window_sigmas"),
            std::string::npos);
  EXPECT_NE(message([](auto& c) { c.min_window_shift = -1.0; }).find("min_window_shift"),
            std::string::npos);
}
