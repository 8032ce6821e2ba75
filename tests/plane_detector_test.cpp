// PlaneDetector on synthetic table-top clouds with exact counts: the table, the boxes on it, the
// points below it and the NaNs.
#include "multislit/plane_detector.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>

using namespace multislit;

namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

struct Box {
  float x0, y0, x1, y1, height;  // footprint [m] and height [m]
};

/// Counts of what was generated, by kind.
struct TableTop {
  Cloud::Ptr cloud = std::make_shared<Cloud>();
  std::size_t table = 0, boxes = 0, below = 0, nans = 0;
};

// A 1.2 m x 0.8 m table at z = 0 sampled every 1 cm (with +-2 mm noise), three boxes standing on
// it (top faces every 1 cm, side walls every 1 cm from 2 cm above the table up), ten points of the
// floor 0.7 m below, and 37 NaN points; the sensor 1.5 m above the table.
TableTop makeTableTop() {
  TableTop scene;
  Cloud& cloud = *scene.cloud;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> noise(-0.002f, 0.002f);
  for (int i = 0; i < 120; ++i)
    for (int j = 0; j < 80; ++j, ++scene.table)
      cloud.push_back(pcl::PointXYZ(0.01f * i, 0.01f * j, noise(rng)));
  const Box boxes[] = {{0.10f, 0.10f, 0.30f, 0.25f, 0.12f},
                       {0.50f, 0.40f, 0.62f, 0.70f, 0.05f},
                       {0.90f, 0.05f, 1.05f, 0.20f, 0.30f}};
  for (const Box& b : boxes) {
    for (float x = b.x0; x <= b.x1 + 1e-4f; x += 0.01f)
      for (float y = b.y0; y <= b.y1 + 1e-4f; y += 0.01f, ++scene.boxes)
        cloud.push_back(pcl::PointXYZ(x, y, b.height));
    for (float z = 0.02f; z < b.height - 1e-4f; z += 0.01f) {
      for (float x = b.x0; x <= b.x1 + 1e-4f; x += 0.01f, scene.boxes += 2) {
        cloud.push_back(pcl::PointXYZ(x, b.y0, z));
        cloud.push_back(pcl::PointXYZ(x, b.y1, z));
      }
    }
  }
  for (int i = 0; i < 10; ++i, ++scene.below)
    cloud.push_back(pcl::PointXYZ(0.1f * i, -0.2f, -0.7f));
  for (int i = 0; i < 37; ++i, ++scene.nans)
    cloud.insert(cloud.begin() + 97 * i, pcl::PointXYZ(kNaN, kNaN, kNaN));
  cloud.width = static_cast<std::uint32_t>(cloud.size());
  cloud.height = 1;
  cloud.is_dense = false;
  cloud.sensor_origin_ = Eigen::Vector4f(0.6f, 0.4f, 1.5f, 0.0f);
  return scene;
}

}  // namespace

TEST(PlaneDetector, FindsTheTableAndEveryPointStandingOnIt) {
  const TableTop scene = makeTableTop();
  ASSERT_EQ(scene.cloud->size(), scene.table + scene.boxes + scene.below + scene.nans);
  ASSERT_GT(scene.boxes, 1000u);
  const PlaneResult result = PlaneDetector{}.detect(scene.cloud);
  ASSERT_TRUE(result.found);
  EXPECT_EQ(result.finite_points, scene.table + scene.boxes + scene.below);
  EXPECT_EQ(result.inliers.size(), scene.table);
  EXPECT_EQ(result.above.size(), scene.boxes);
  // z = 0 with the normal up, towards the sensor.
  EXPECT_NEAR(result.coefficients[2], 1.0f, 1e-4f);
  EXPECT_NEAR(result.coefficients[3], 0.0f, 1e-3f);
  for (const auto i : result.inliers) EXPECT_LT(std::abs((*scene.cloud)[i].z), 0.003f);
  for (const auto i : result.above) EXPECT_GE((*scene.cloud)[i].z, 0.02f - 1e-4f);
}

TEST(PlaneDetector, OrganizedTiltedCloudWithAnUpDirection) {
  // A 64 x 48 organized cloud of a plane tilted 30 deg about x, every 7th point NaN, and a 10 x 10
  // block of points 5 cm above it along its normal.
  const float angle = 0.5236f;
  const Eigen::Vector3f normal(0.0f, -std::sin(angle), std::cos(angle));
  auto cloud = std::make_shared<Cloud>(64, 48);
  std::size_t nans = 0, above = 0;
  for (int r = 0; r < 48; ++r) {
    for (int c = 0; c < 64; ++c) {
      const Eigen::Vector3f on_plane(0.02f * c, 0.02f * r * std::cos(angle),
                                     0.02f * r * std::sin(angle) + 1.0f);
      const bool block = r >= 20 && r < 30 && c >= 20 && c < 30;
      const Eigen::Vector3f p = on_plane + (block ? 0.05f : 0.0f) * normal;
      (*cloud)(c, r) = pcl::PointXYZ(p.x(), p.y(), p.z());
      if ((r * 64 + c) % 7 == 0) {
        (*cloud)(c, r) = pcl::PointXYZ(kNaN, kNaN, kNaN);
        ++nans;
      } else {
        above += block;
      }
    }
  }
  cloud->is_dense = false;
  PlaneDetectorConfig config;
  config.up = normal;
  const PlaneResult result = PlaneDetector{config}.detect(cloud);
  ASSERT_TRUE(result.found);
  EXPECT_EQ(result.finite_points, cloud->size() - nans);
  EXPECT_EQ(result.above.size(), above);
  EXPECT_EQ(result.inliers.size(), result.finite_points - above);
  EXPECT_NEAR(result.coefficients.head<3>().dot(normal), 1.0f, 1e-4f);

  config.up = -normal;  // the other side is up: the block is below, nothing above
  const PlaneResult flipped = PlaneDetector{config}.detect(cloud);
  ASSERT_TRUE(flipped.found);
  EXPECT_TRUE(flipped.above.empty());
  EXPECT_EQ(flipped.inliers, result.inliers);
}

TEST(PlaneDetector, NotFoundWithTooFewPointsOrNoDominantPlane) {
  const PlaneDetector detector;
  EXPECT_FALSE(detector.detect(std::make_shared<Cloud>()).found);
  EXPECT_FALSE(detector.detect(Cloud::ConstPtr()).found);

  auto few = std::make_shared<Cloud>();
  for (int i = 0; i < 20; ++i) few->push_back(pcl::PointXYZ(0.1f * i, 0.05f * (i % 4), 0.0f));
  const PlaneResult too_few = detector.detect(few);
  EXPECT_FALSE(too_few.found);
  EXPECT_EQ(too_few.finite_points, 20u);

  auto random = std::make_shared<Cloud>();  // points filling a 1 m cube
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (int i = 0; i < 3000; ++i) random->push_back(pcl::PointXYZ(unit(rng), unit(rng), unit(rng)));
  PlaneDetectorConfig config;
  config.min_inlier_ratio = 0.3;
  const PlaneResult none = PlaneDetector{config}.detect(random);
  EXPECT_FALSE(none.found);
  EXPECT_TRUE(none.inliers.empty());
  EXPECT_EQ(none.coefficients, Eigen::Vector4f::Zero());
}

TEST(PlaneDetector, ValidateNamesTheField) {
  PlaneDetectorConfig config;
  config.threshold = 0.0;
  try {
    config.validate();
    FAIL() << "threshold 0 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("threshold"), std::string::npos);
  }
  config = {};
  config.up = Eigen::Vector3f(kNaN, 0.0f, 1.0f);
  EXPECT_THROW(PlaneDetector{config}, std::invalid_argument);
}
