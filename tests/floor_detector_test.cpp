// FloorDetector (Sec. III-B, eq. 1-3) on synthetic RDMaps with exact ground truth: the plane, the
// obstacles, the false obstacles of a noisy floor, and the fail-safe cases.
#include "multislit/floor_detector.h"

#include "multislit/plane_model.h"

#include "test_support.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <algorithm>
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
constexpr double kSigma = 0.3;  // [px], the paper's noise
const Eigen::Vector3d kTruth(0.004, -0.012, 3.0);
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// A synthetic RDMap and, for every point, its true offset from the floor plane [px].
struct Scene {
  Cloud::Ptr cloud;
  std::vector<double> offset;
};

/// The noise of a synthetic RDMap: N(0, sigma), and with probability tail_share a Laplace
/// deviate of scale tail_scale instead (a heavy tail: speckle, another laser).
struct Noise {
  double sigma = kSigma;    ///< [px]
  double tail_share = 0.0;  ///< [-]
  double tail_scale = 0.0;  ///< Laplace scale b, std b sqrt 2 [px]
};

// 15 slits x 300 samples, one per image row, tilted 20 deg from the image rows like the real
// sensor (u = 300 .. 1122 px, v = 50 .. 937 px), dk = A u + B v + C + offset + N(0, 0.3 px), 3 %
// unmeasured (NaN). Obstacles: a 'cable' band across all slits (+2 px, u in [700, 712]) and a
// 'ball' (a cap up to +12 px, 80 px radius).
Scene makeScene(unsigned seed, bool obstacles, const Noise& model = {}) {
  Scene scene{std::make_shared<Cloud>(kSamples, kSlits), {}};
  scene.offset.assign(scene.cloud->size(), 0.0);
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, model.sigma);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::exponential_distribution<double> laplace(1.0 / std::max(model.tail_scale, 1e-9));
  const auto noise = [&](std::mt19937& g) {
    if (model.tail_share > 0.0 && unit(g) < model.tail_share)
      return (unit(g) < 0.5 ? -1.0 : 1.0) * laplace(g);
    return gauss(g);
  };
  for (int s = 0; s < kSlits; ++s) {
    for (int j = 0; j < kSamples; ++j) {
      PointRDM& p = scene.cloud->at(j, s);
      double& offset = scene.offset[static_cast<std::size_t>(s * kSamples + j)];
      p.u = static_cast<float>(300.0 + 2.75 * j);
      p.v = static_cast<float>(50 + 42 * s + j);
      p.slit = s;
      const double rho = std::hypot(p.u - 950.0, p.v - 600.0) / 80.0;
      if (obstacles && p.u >= 700.0f && p.u <= 712.0f) offset = 2.0;
      if (obstacles && rho < 1.0) offset = 12.0 * std::sqrt(1.0 - rho * rho);
      p.dk = static_cast<float>(kTruth.dot(Eigen::Vector3d(p.u, p.v, 1.0)) + offset + noise(rng));
      p.x = p.u * 1e-3f;
      p.y = p.v * 1e-3f;
      p.z = 0.5f;
      if (unit(rng) < 0.03) p.x = p.y = p.z = p.dk = kNaN;
    }
  }
  scene.cloud->is_dense = false;
  return scene;
}

// Standard deviations of the least-squares (A, B, C) of eq. (2) through the floor points of
// `cloud` with noise kSigma: sqrt of the diagonal of sigma^2 (X^T X)^-1.
Eigen::Vector3d planeStd(const Cloud& cloud, const pcl::Indices& floor) {
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  for (const auto i : floor) {
    const Eigen::Vector3d x(cloud[i].u, cloud[i].v, 1.0);
    normal += x * x.transpose();
  }
  return (kSigma * kSigma * normal.inverse()).diagonal().cwiseSqrt();
}

bool contains(const pcl::Indices& sorted, int i) {
  return std::binary_search(sorted.begin(), sorted.end(), i);
}

}  // namespace

TEST(FloorDetector, Eq3GivesThePapersIterations) {
  EXPECT_EQ(ransacIterations(0.99, 0.5), 35);     // the paper's q
  EXPECT_EQ(ransacIterations(0.99, 0.5, 3), 35);  // F = 3
  EXPECT_EQ(ransacIterations(0.99, 0.0), 1);      // no outliers: one sample is clean
  EXPECT_EQ(ransacIterations(0.99, 0.5, 1), 7);   // log(0.01) / log(0.5) = 6.6
  EXPECT_EQ(ransacIterations(0.999, 0.7), 253);   // log(0.001) / log(1 - 0.027) = 252.4
  EXPECT_EQ(FloorDetectorConfig{}.iterations(), 35);
  FloorDetectorConfig fixed;
  fixed.max_iterations = 10;
  EXPECT_EQ(fixed.iterations(), 10);
  EXPECT_DOUBLE_EQ(FloorDetectorConfig{}.threshold(), 0.9);
  EXPECT_THROW(ransacIterations(1.0, 0.5), std::invalid_argument);
  EXPECT_THROW(ransacIterations(0.99, 1.0), std::invalid_argument);
}

TEST(FloorDetector, ValidateNamesTheField) {
  const auto message = [](auto change) { return validationMessage<FloorDetectorConfig>(change); };
  EXPECT_EQ(message([](auto&) {}), "valid");
  EXPECT_NE(message([](auto& c) { c.sigma = 0.0; }).find("sigma"), std::string::npos);
  EXPECT_NE(message([](auto& c) { c.threshold_sigmas = -1.0; }).find("threshold_sigmas"),
            std::string::npos);
  EXPECT_NE(message([](auto& c) { c.probability = 1.0; }).find("probability"), std::string::npos);
  EXPECT_NE(message([](auto& c) { c.outlier_ratio = 1.0; }).find("outlier_ratio"),
            std::string::npos);
  EXPECT_NE(message([](auto& c) { c.max_iterations = -1; }).find("max_iterations"),
            std::string::npos);
  EXPECT_NE(message([](auto& c) { c.min_points = 2; }).find("min_points"), std::string::npos);
  EXPECT_NE(message([](auto& c) { c.min_inlier_ratio = 1.5; }).find("min_inlier_ratio"),
            std::string::npos);
  EXPECT_NE(message([](auto& c) { c.min_sigma = 0.0; }).find("min_sigma"), std::string::npos);
  EXPECT_NE(message([](auto& c) { c.max_sigma = 0.2; }).find("max_sigma"), std::string::npos);
  EXPECT_NE(message([](auto& c) { c.band_sigmas = 0.0; }).find("band_sigmas"), std::string::npos);
  FloorDetectorConfig bad;
  bad.sigma = -0.3;
  EXPECT_THROW(FloorDetector{bad}, std::invalid_argument);
}

TEST(FloorDetector, FindsTheFloorPlaneAndEveryObstaclePoint) {
  const Scene scene = makeScene(11, true);
  const Cloud& cloud = *scene.cloud;
  const FloorResult result = FloorDetector{}.detect(scene.cloud);
  ASSERT_TRUE(result.found);
  EXPECT_EQ(result.iterations, 35);

  std::size_t valid = 0, true_obstacles = 0, large_obstacles = 0;
  pcl::Indices true_floor;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!isValidRDMPoint(cloud[i])) continue;
    ++valid;
    if (scene.offset[i] == 0.0) true_floor.push_back(static_cast<int>(i));
    true_obstacles += scene.offset[i] > 0.0;
    large_obstacles += scene.offset[i] > 1.5;
  }
  EXPECT_EQ(result.valid_points, valid);
  EXPECT_EQ(result.inliers.size() + result.obstacles.size(), valid);
  ASSERT_EQ(result.obstacle_residuals.size(), result.obstacles.size());
  EXPECT_GT(large_obstacles, 150u);

  // The plane: within 4 standard deviations of the least-squares estimate, and |C error| < 0.05.
  const Eigen::Vector3d error = result.plane - kTruth;
  const Eigen::Vector3d tolerance = 4.0 * planeStd(cloud, true_floor);
  EXPECT_LT(std::abs(error[0]), tolerance[0]) << error.transpose();
  EXPECT_LT(std::abs(error[1]), tolerance[1]) << error.transpose();
  EXPECT_LT(std::abs(error[2]), tolerance[2]) << error.transpose();
  EXPECT_LT(std::abs(error[2]), 0.05);
  // The residual std of the floor: sigma, less the 1.3 % that cutting at 3 sigma takes away.
  EXPECT_NEAR(result.residual_std, 0.987 * kSigma, 0.02);

  // Every point more than 1.5 px above the floor is an obstacle, above the floor.
  for (std::size_t k = 0; k < result.obstacles.size(); ++k)
    if (scene.offset[result.obstacles[k]] > 1.5) {
      EXPECT_GT(result.obstacle_residuals[k], 0.9f);
    }
  std::size_t found_large = 0, false_obstacles = 0;
  for (const auto i : result.obstacles) {
    found_large += scene.offset[i] > 1.5;
    false_obstacles += scene.offset[i] == 0.0;
  }
  EXPECT_EQ(found_large, large_obstacles);
  EXPECT_LE(false_obstacles, true_floor.size() * 5 / 1000);  // <= 0.5 %
  EXPECT_TRUE(std::is_sorted(result.inliers.begin(), result.inliers.end()));
  EXPECT_TRUE(std::is_sorted(result.obstacles.begin(), result.obstacles.end()));
}

TEST(FloorDetector, FalseObstaclesOnAPureNoisyFloorStayBelowHalfAPercent) {
  std::size_t false_obstacles = 0, valid = 0;
  for (unsigned seed = 20; seed < 30; ++seed) {
    const Scene scene = makeScene(seed, false);
    const FloorResult result = FloorDetector{}.detect(scene.cloud);
    ASSERT_TRUE(result.found);
    EXPECT_LT(std::abs(result.plane[2] - kTruth[2]), 0.05);
    EXPECT_LE(result.obstacles.size(), result.valid_points * 5 / 1000);
    false_obstacles += result.obstacles.size();
    valid += result.valid_points;
  }
  // 3 sigma leaves 0.27 % of a Gaussian outside.
  EXPECT_NEAR(static_cast<double>(false_obstacles) / static_cast<double>(valid), 0.0027, 0.0012);
}

namespace {

/// Share of the true floor points of `scene` that `result` calls obstacles.
double falseObstacleShare(const Scene& scene, const FloorResult& result) {
  std::size_t floor = 0, wrong = 0;
  for (std::size_t i = 0; i < scene.cloud->size(); ++i)
    floor += isValidRDMPoint((*scene.cloud)[i]) && scene.offset[i] == 0.0;
  for (const auto i : result.obstacles) wrong += scene.offset[i] == 0.0;
  return static_cast<double>(wrong) / static_cast<double>(floor);
}

}  // namespace

TEST(FloorDetector, EstimatesEachFramesSigmaAndTheThresholdFollows) {
  FloorDetectorConfig wide_bounds;  // to see the estimate itself below the default min_sigma
  wide_bounds.min_sigma = 0.05;
  for (const double sigma : {0.15, 0.3, 0.6}) {
    for (unsigned seed = 40; seed < 43; ++seed) {
      const Scene scene = makeScene(seed, true, Noise{sigma});
      const FloorResult r = FloorDetector{wide_bounds}.detect(scene.cloud);
      ASSERT_TRUE(r.found) << sigma;
      EXPECT_NEAR(r.sigma_estimate, sigma, 0.07 * sigma) << "seed " << seed;
      EXPECT_EQ(r.sigma, r.sigma_estimate);
      EXPECT_DOUBLE_EQ(r.threshold, 3.0 * r.sigma);
      // The split follows: 0.27 % of a Gaussian floor lies beyond 3 sigma, at every sigma.
      EXPECT_LT(falseObstacleShare(scene, r), 0.006) << sigma;
      std::printf("sigma %.2f px, seed %u: estimated %.4f px, false obstacles %.3f %%\n", sigma,
                  seed, r.sigma_estimate, 100.0 * falseObstacleShare(scene, r));
    }
  }
}

TEST(FloorDetector, EstimatedSigmaIsClampedToTheConfiguredBounds) {
  const FloorDetectorConfig config;  // [0.3, 1.0] px
  const FloorResult low = FloorDetector{config}.detect(makeScene(44, true, Noise{0.15}).cloud);
  ASSERT_TRUE(low.found);
  EXPECT_NEAR(low.sigma_estimate, 0.15, 0.015);
  EXPECT_EQ(low.sigma, config.min_sigma);  // the paper's 0.9 px is the smallest threshold
  EXPECT_DOUBLE_EQ(low.threshold, 0.9);
  const FloorResult high = FloorDetector{config}.detect(makeScene(45, true, Noise{1.5}).cloud);
  ASSERT_TRUE(high.found);
  EXPECT_GT(high.sigma_estimate, config.max_sigma);
  EXPECT_EQ(high.sigma, config.max_sigma);
  EXPECT_DOUBLE_EQ(high.threshold, 3.0);
}

TEST(FloorDetector, NoisyFrameGetsAWiderThresholdThanTheFixedOne) {
  // 0.6 px of noise: the paper's fixed 0.9 px (1.5 sigma) calls 13 % of the floor obstacles.
  const Scene scene = makeScene(46, true, Noise{0.6});
  FloorDetectorConfig fixed;
  fixed.estimate_sigma = false;
  const FloorResult before = FloorDetector{fixed}.detect(scene.cloud);
  const FloorResult after = FloorDetector{}.detect(scene.cloud);
  ASSERT_TRUE(before.found);
  ASSERT_TRUE(after.found);
  EXPECT_EQ(before.sigma, 0.3);
  EXPECT_DOUBLE_EQ(before.threshold, 0.9);
  EXPECT_TRUE(std::isnan(before.sigma_estimate));
  EXPECT_NEAR(falseObstacleShare(scene, before), 0.134, 0.02);
  EXPECT_NEAR(after.threshold, 1.8, 0.09);
  EXPECT_LT(falseObstacleShare(scene, after), 0.006);
  // The ball's points well above the threshold are all still obstacles.
  std::size_t high = 0, found_high = 0;
  for (std::size_t i = 0; i < scene.cloud->size(); ++i)
    high += isValidRDMPoint((*scene.cloud)[i]) && scene.offset[i] > 4.0;
  for (const auto i : after.obstacles) found_high += scene.offset[i] > 4.0;
  EXPECT_GT(high, 100u);
  EXPECT_EQ(found_high, high);
  std::printf("0.6 px noise: false obstacles %.2f %% at the fixed 0.9 px, %.3f %% at %.3f px\n",
              100.0 * falseObstacleShare(scene, before), 100.0 * falseObstacleShare(scene, after),
              after.threshold);
}

TEST(FloorDetector, HeavyTailedNoiseKeepsTheEstimateNearTheCoreSigma) {
  // 85 % N(0, 0.4 px) and 15 % Laplace of scale 1 px (std 1.41 px): the RMS of all residuals
  // within 3 px is far above the core's 0.4 px; the median-based estimate is not.
  const Noise heavy{0.4, 0.15, 1.0};
  for (unsigned seed = 50; seed < 53; ++seed) {
    const Scene scene = makeScene(seed, false, heavy);
    const FloorResult r = FloorDetector{}.detect(scene.cloud);
    ASSERT_TRUE(r.found);
    double sum_sq = 0.0;
    std::size_t n = 0;
    for (const auto& p : *scene.cloud) {
      if (!isValidRDMPoint(p)) continue;
      const double residual = p.dk - kTruth.dot(Eigen::Vector3d(p.u, p.v, 1.0));
      if (std::abs(residual) > 3.0) continue;
      sum_sq += residual * residual;
      ++n;
    }
    const double rms = std::sqrt(sum_sq / static_cast<double>(n));
    EXPECT_GT(rms, 1.3 * heavy.sigma);
    EXPECT_NEAR(r.sigma, heavy.sigma, 0.12 * heavy.sigma) << "seed " << seed;
    std::printf("heavy tail, seed %u: RMS within 3 px %.3f px, estimated sigma %.4f px\n", seed,
                rms, r.sigma_estimate);
  }
}

TEST(FloorDetector, DeterministicForASeed) {
  const Scene scene = makeScene(12, true);
  FloorDetectorConfig other_seed;
  other_seed.seed = 777;
  const FloorResult a = FloorDetector{}.detect(scene.cloud);
  const FloorResult b = FloorDetector{}.detect(scene.cloud);
  const FloorResult c = FloorDetector{other_seed}.detect(scene.cloud);
  EXPECT_EQ(a.plane, b.plane);
  EXPECT_EQ(a.inliers, b.inliers);
  EXPECT_EQ(a.obstacles, b.obstacles);
  ASSERT_TRUE(c.found);
  EXPECT_LT((a.plane - c.plane).cwiseAbs().maxCoeff(), 0.05);
}

TEST(FloorDetector, UsesOnlyTheGivenIndices) {
  const Scene scene = makeScene(13, true);
  pcl::Indices left;  // u < 650: no cable, no ball
  for (std::size_t i = 0; i < scene.cloud->size(); ++i)
    if ((*scene.cloud)[i].u < 650.0f) left.push_back(static_cast<int>(i));
  const FloorResult result = FloorDetector{}.detect(scene.cloud, left);
  ASSERT_TRUE(result.found);
  EXPECT_EQ(result.inliers.size() + result.obstacles.size(), result.valid_points);
  EXPECT_LT(result.valid_points, left.size());
  for (const auto i : result.inliers) EXPECT_TRUE(contains(left, i));
  for (const auto i : result.obstacles) EXPECT_EQ(scene.offset[i], 0.0);
  EXPECT_LT((result.plane - kTruth).cwiseAbs().maxCoeff(), 0.1);
}

TEST(FloorDetector, FindsTheFloorUnderAFortyPercentObstacle) {
  Scene scene = makeScene(14, false);
  for (auto& p : *scene.cloud)
    if (p.u > 780.0f) p.dk += 5.0f;  // a box 5 px high over 42 % of the view
  const FloorResult result = FloorDetector{}.detect(scene.cloud);
  ASSERT_TRUE(result.found);
  EXPECT_LT(std::abs(result.plane[2] - kTruth[2]), 0.3);  // C extrapolates from u < 780 here
  std::size_t box = 0, false_obstacles = 0;
  for (const auto& p : *scene.cloud) box += isValidRDMPoint(p) && p.u > 780.0f;
  for (const auto i : result.obstacles) false_obstacles += (*scene.cloud)[i].u <= 780.0f;
  EXPECT_GT(box, result.valid_points * 4 / 10);
  EXPECT_EQ(result.obstacles.size() - false_obstacles, box);      // the whole box
  EXPECT_LE(false_obstacles, (result.valid_points - box) / 100);  // 0.27 % expected
}

TEST(FloorDetector, NotFoundOnAnEmptyCloud) {
  const FloorDetector detector;
  const FloorResult empty = detector.detect(std::make_shared<Cloud>());
  EXPECT_FALSE(empty.found);
  EXPECT_EQ(empty.valid_points, 0u);
  EXPECT_EQ(empty.plane, Eigen::Vector3d::Zero());
  EXPECT_FALSE(detector.detect(Cloud::ConstPtr()).found);

  Scene all_nan = makeScene(15, false);
  for (auto& p : *all_nan.cloud) p.dk = kNaN;
  EXPECT_FALSE(detector.detect(all_nan.cloud).found);
}

TEST(FloorDetector, NotFoundWithTwentyValidPoints) {
  Scene scene = makeScene(16, false);
  int kept = 0;
  for (auto& p : *scene.cloud)
    if (isValidRDMPoint(p) && ++kept > 20) p.dk = kNaN;
  const FloorResult result = FloorDetector{}.detect(scene.cloud);
  EXPECT_FALSE(result.found);
  EXPECT_EQ(result.valid_points, 20u);
  EXPECT_TRUE(result.inliers.empty());
  EXPECT_TRUE(result.obstacles.empty());
  EXPECT_EQ(result.plane, Eigen::Vector3d::Zero());
}

TEST(FloorDetector, NotFoundOnRandomOutliers) {
  Scene scene = makeScene(17, false);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> anywhere(-30.0f, 30.0f);
  for (auto& p : *scene.cloud)
    if (isValidRDMPoint(p)) p.dk = anywhere(rng);
  const FloorResult result = FloorDetector{}.detect(scene.cloud);
  EXPECT_FALSE(result.found);
  EXPECT_GT(result.valid_points, 4000u);
  EXPECT_EQ(result.iterations, 35);
  EXPECT_TRUE(result.inliers.empty());
  EXPECT_EQ(result.plane, Eigen::Vector3d::Zero());
}

TEST(FloorDetector, NotFoundWhenOnlyTwoSlitsWereMeasured) {
  Scene scene = makeScene(18, false);
  for (auto& p : *scene.cloud)
    if (p.slit > 1) p.dk = kNaN;
  const FloorResult result = FloorDetector{}.detect(scene.cloud);
  EXPECT_FALSE(result.found);  // no sample of three slits exists
  EXPECT_EQ(result.iterations, 0);
}
