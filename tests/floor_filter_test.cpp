// FloorFilter used like pcl::PassThrough: it keeps exactly the floor points (or the obstacles) that
// FloorDetector finds, organized or not, and its removed indices are the rest.
#include "multislit/floor_filter.h"

#include "multislit/plane_model.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>

using namespace multislit;

namespace {

using Cloud = pcl::PointCloud<PointRDM>;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// 15 slits x 300 samples tilted 20 deg like the real sensor, dk = 0.004 u - 0.012 v + 3 + N(0, 0.3
// px), 3 % NaN, a 'cable' (+2 px across all slits) and a 'ball' (up to +12 px).
Cloud::Ptr makeRDMap(unsigned seed) {
  auto cloud = std::make_shared<Cloud>(300, 15);
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, 0.3f);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (int s = 0; s < 15; ++s) {
    for (int j = 0; j < 300; ++j) {
      PointRDM& p = cloud->at(j, s);
      p.u = 300.0f + 2.75f * j;
      p.v = 50.0f + 42.0f * s + j;
      p.slit = s;
      const float rho = std::hypot(p.u - 950.0f, p.v - 600.0f) / 80.0f;
      const float cable = p.u >= 700.0f && p.u <= 712.0f ? 2.0f : 0.0f;
      const float ball = rho < 1.0f ? 12.0f * std::sqrt(1.0f - rho * rho) : 0.0f;
      p.dk = 0.004f * p.u - 0.012f * p.v + 3.0f + std::max(cable, ball) + noise(rng);
      p.x = p.u * 1e-3f;
      p.y = p.v * 1e-3f;
      p.z = 0.5f;
      if (unit(rng) < 0.03f) p.x = p.y = p.z = p.dk = kNaN;
    }
  }
  cloud->is_dense = false;
  return cloud;
}

bool samePoint(const PointRDM& a, const PointRDM& b) {
  return a.x == b.x && a.y == b.y && a.z == b.z && a.u == b.u && a.v == b.v && a.dk == b.dk &&
         a.slit == b.slit;
}

}  // namespace

TEST(FloorFilter, KeepsExactlyTheFloorOrTheObstacles) {
  const auto cloud = makeRDMap(1);
  const FloorResult truth = FloorDetector{}.detect(cloud);
  ASSERT_TRUE(truth.found);
  ASSERT_GT(truth.obstacles.size(), 100u);

  FloorFilter filter;
  filter.setInputCloud(cloud);
  Cloud floor, obstacles;
  filter.filter(floor);
  EXPECT_TRUE(filter.getResult().found);
  EXPECT_EQ(filter.getResult().plane, truth.plane);
  filter.setNegative(true);
  filter.filter(obstacles);

  ASSERT_EQ(floor.size(), truth.inliers.size());
  ASSERT_EQ(obstacles.size(), truth.obstacles.size());
  EXPECT_EQ(floor.height, 1u);
  EXPECT_EQ(floor.width, floor.size());
  EXPECT_TRUE(floor.is_dense);
  EXPECT_EQ(obstacles.header.frame_id, cloud->header.frame_id);
  for (std::size_t k = 0; k < floor.size(); ++k)
    EXPECT_TRUE(samePoint(floor[k], (*cloud)[truth.inliers[k]])) << k;
  for (std::size_t k = 0; k < obstacles.size(); ++k)
    EXPECT_TRUE(samePoint(obstacles[k], (*cloud)[truth.obstacles[k]])) << k;
}

TEST(FloorFilter, FilterIndicesAndRemovedIndices) {
  const auto cloud = makeRDMap(2);
  const FloorResult truth = FloorDetector{}.detect(cloud);
  FloorFilter filter(true);  // extract the removed indices
  filter.setInputCloud(cloud);
  pcl::Indices kept;
  filter.filter(kept);
  EXPECT_EQ(kept, truth.inliers);
  const pcl::Indices removed = *filter.getRemovedIndices();
  EXPECT_EQ(kept.size() + removed.size(), cloud->size());  // obstacles and NaNs are removed
  pcl::Indices all;
  std::merge(kept.begin(), kept.end(), removed.begin(), removed.end(), std::back_inserter(all));
  for (std::size_t i = 0; i < all.size(); ++i) ASSERT_EQ(all[i], static_cast<int>(i));

  filter.setNegative(true);
  filter.filter(kept);
  EXPECT_EQ(kept, truth.obstacles);
  EXPECT_EQ(filter.getRemovedIndices()->size(), cloud->size() - truth.obstacles.size());
}

TEST(FloorFilter, KeepOrganizedNaNsTheRemovedPoints) {
  const auto cloud = makeRDMap(3);
  const FloorResult truth = FloorDetector{}.detect(cloud);
  FloorFilter filter;
  filter.setInputCloud(cloud);
  filter.setKeepOrganized(true);
  filter.setNegative(true);
  Cloud obstacles;
  filter.filter(obstacles);
  ASSERT_EQ(obstacles.width, cloud->width);
  ASSERT_EQ(obstacles.height, cloud->height);
  EXPECT_FALSE(obstacles.is_dense);
  std::vector<bool> is_obstacle(cloud->size(), false);
  for (const auto i : truth.obstacles) is_obstacle[i] = true;
  std::size_t finite = 0;
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const PointRDM& p = obstacles[i];
    finite += std::isfinite(p.dk);
    EXPECT_EQ(std::isfinite(p.dk), is_obstacle[i]) << i;
    EXPECT_EQ(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z), is_obstacle[i]);
    EXPECT_EQ(p.u, (*cloud)[i].u);  // u, v and slit stay
    EXPECT_EQ(p.slit, (*cloud)[i].slit);
    if (is_obstacle[i]) {
      EXPECT_TRUE(samePoint(p, (*cloud)[i]));
    }
  }
  EXPECT_EQ(finite, truth.obstacles.size());
}

TEST(FloorFilter, OnlyTheGivenIndicesTakePart) {
  const auto cloud = makeRDMap(4);
  auto left = std::make_shared<pcl::Indices>();  // u < 650: no cable, no ball
  for (std::size_t i = 0; i < cloud->size(); ++i)
    if ((*cloud)[i].u < 650.0f) left->push_back(static_cast<int>(i));
  const FloorResult truth = FloorDetector{}.detect(cloud, *left);
  FloorFilter filter;
  filter.setInputCloud(cloud);
  filter.setIndices(left);
  pcl::Indices kept;
  filter.filter(kept);
  EXPECT_EQ(kept, truth.inliers);
  for (const auto i : kept) EXPECT_LT((*cloud)[i].u, 650.0f);

  filter.setKeepOrganized(true);  // everything outside the kept points is NaN, also outside left
  Cloud organized;
  filter.filter(organized);
  std::size_t finite = 0;
  for (const auto& p : organized) finite += std::isfinite(p.dk);
  EXPECT_EQ(finite, truth.inliers.size());
}

TEST(FloorFilter, WithoutAFloorEveryValidPointIsAnObstacle) {
  auto cloud = makeRDMap(5);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> anywhere(-30.0f, 30.0f);
  std::size_t valid = 0;
  for (auto& p : *cloud) {
    if (!isValidRDMPoint(p)) continue;
    p.dk = anywhere(rng);
    ++valid;
  }
  FloorFilter filter;
  filter.setInputCloud(cloud);
  Cloud floor, obstacles;
  filter.filter(floor);
  EXPECT_FALSE(filter.getResult().found);
  EXPECT_EQ(floor.size(), 0u);
  filter.setNegative(true);
  filter.filter(obstacles);
  EXPECT_EQ(obstacles.size(), valid);
}

TEST(FloorFilter, SettersChangeTheThresholdAndValidate) {
  const auto cloud = makeRDMap(6);
  FloorFilter filter;
  filter.setInputCloud(cloud);
  filter.setNegative(true);
  pcl::Indices at_3_sigma, at_5_sigma;
  filter.filter(at_3_sigma);
  filter.setThresholdSigmas(5.0);
  EXPECT_DOUBLE_EQ(filter.getConfig().threshold(), 1.5);
  filter.filter(at_5_sigma);
  EXPECT_LT(at_5_sigma.size(), at_3_sigma.size());
  for (const auto i : at_5_sigma)
    EXPECT_TRUE(std::binary_search(at_3_sigma.begin(), at_3_sigma.end(), i));
  filter.setSigma(0.1);
  EXPECT_DOUBLE_EQ(filter.getSigma(), 0.1);
  EXPECT_THROW(filter.setSigma(-1.0), std::invalid_argument);
  EXPECT_THROW(filter.setThresholdSigmas(0.0), std::invalid_argument);
  EXPECT_DOUBLE_EQ(filter.getSigma(), 0.1);  // unchanged by a rejected value
}
