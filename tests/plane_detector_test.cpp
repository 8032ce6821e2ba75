// PlaneDetector on synthetic table-top clouds with exact counts (the table, the boxes on it, the
// points below it and the NaNs), on the table-top trap that plain RANSAC falls into, and on four
// labelled Kinect scenes of the mOSD (data/mosd/).
#include "multislit/plane_detector.h"

#include "multislit/point_types.h"

#include <gtest/gtest.h>
#include <pcl/common/io.h>
#include <pcl/common/point_tests.h>
#include <pcl/io/pcd_io.h>

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
  EXPECT_EQ(result.below.size(), scene.below);
  EXPECT_FALSE(result.viewpoint_on_plane);
  // z = 0 with the normal up, towards the sensor.
  EXPECT_NEAR(result.coefficients[2], 1.0f, 1e-4f);
  EXPECT_NEAR(result.coefficients[3], 0.0f, 1e-3f);
  for (const auto i : result.inliers) EXPECT_LT(std::abs((*scene.cloud)[i].z), 0.003f);
  for (const auto i : result.above) EXPECT_GE((*scene.cloud)[i].z, 0.02f - 1e-4f);
  for (const auto i : result.below) EXPECT_EQ((*scene.cloud)[i].z, -0.7f);
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
  EXPECT_EQ(flipped.below, result.above);
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

TEST(PlaneDetector, ValidateRejectsANegativeBehindWeight) {
  PlaneDetectorConfig config;
  config.behind_weight = -1.0;
  EXPECT_THROW(config.validate(), std::invalid_argument);
}

// --- the trap: a plane through the tops of low boxes holds more points than the table ----------

namespace {

/// A 1.2 m x 1.0 m table (1 cm grid, +-2 mm noise) under six low wide boxes 30 to 40 mm tall
/// whose tops together hold three times the table's visible points: the table holds 25 % of all.
/// The scene is turned and moved to lie 1 m in front of a camera at the origin.
struct Trap {
  Cloud::Ptr cloud = std::make_shared<Cloud>();
  Eigen::Vector4f truth;   ///< the table plane, normal towards the camera
  Eigen::Vector3f centre;  ///< the table's centre
  std::size_t table = 0;
};

Trap makeTrap() {
  Trap trap;
  const Eigen::Affine3f pose = Eigen::Translation3f(0.1f, -0.2f, 1.0f) *
                               Eigen::AngleAxisf(2.4f, Eigen::Vector3f(1, 0.2f, 0.1f).normalized());
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> noise(-0.002f, 0.002f);
  const float heights[] = {0.030f, 0.034f, 0.038f, 0.032f, 0.036f, 0.040f};
  const auto add = [&](float x, float y, float z) {
    const Eigen::Vector3f p = pose * Eigen::Vector3f(x - 0.6f, y - 0.5f, z + noise(rng));
    trap.cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  };
  for (int i = 0; i < 120; ++i) {
    for (int j = 0; j < 100; ++j) {
      const int box = (i % 40 < 34 && j % 50 < 42) ? (i / 40) * 2 + j / 50 : -1;
      add(0.01f * i, 0.01f * j, box < 0 ? 0.0f : heights[box]);  // the table or a top
      trap.table += box < 0;
      const bool edge = box >= 0 && (i % 40 == 0 || i % 40 == 33 || j % 50 == 0 || j % 50 == 41);
      if (edge)
        for (const float z : {0.015f, 0.025f}) add(0.01f * i, 0.01f * j, z);  // the side walls
    }
  }
  trap.cloud->width = static_cast<std::uint32_t>(trap.cloud->size());
  trap.cloud->height = 1;
  Eigen::Vector3f normal = pose.linear() * Eigen::Vector3f::UnitZ();
  trap.centre = pose * Eigen::Vector3f::Zero();
  if (normal.dot(-trap.centre) < 0.0f) normal = -normal;  // towards the camera at the origin
  trap.truth = Eigen::Vector4f(normal.x(), normal.y(), normal.z(), -normal.dot(trap.centre));
  return trap;
}

double angleDeg(const Eigen::Vector4f& a, const Eigen::Vector4f& b) {
  const double c = std::min(1.0f, std::abs(a.head<3>().dot(b.head<3>())));
  return std::acos(c) * 180.0 / M_PI;
}

/// How far `plane` passes from the true table's centre [m].
double offset(const Eigen::Vector4f& plane, const Eigen::Vector3f& centre) {
  return std::abs(plane.head<3>().dot(centre) + plane[3]);
}

}  // namespace

TEST(PlaneDetector, PointsBehindACandidateCountAgainstIt) {
  const Trap trap = makeTrap();
  const double table_share =
      static_cast<double>(trap.table) / static_cast<double>(trap.cloud->size());
  ASSERT_GT(table_share, 0.23);
  ASSERT_LT(table_share, 0.26);

  // Plain RANSAC (nothing behind counts) takes the tops: more points, the table behind them.
  PlaneDetectorConfig plain;
  plain.behind_weight = 0.0;
  const PlaneResult trapped = PlaneDetector{plain}.detect(trap.cloud);
  ASSERT_TRUE(trapped.found);
  EXPECT_GT(offset(trapped.coefficients, trap.centre), 0.02);
  EXPECT_GT(trapped.below.size(), trap.table / 2);

  // Seen from the camera, the table leaves nothing behind it: it wins.
  const PlaneResult result = PlaneDetector{}.detect(trap.cloud);
  ASSERT_TRUE(result.found);
  EXPECT_LT(angleDeg(result.coefficients, trap.truth), 1.0);
  EXPECT_LT(offset(result.coefficients, trap.centre), 0.005);
  EXPECT_GT(result.coefficients.head<3>().dot(trap.truth.head<3>()), 0.0f);  // up: the camera
  EXPECT_EQ(result.inliers.size(), trap.table);
  EXPECT_EQ(result.above.size(), trap.cloud->size() - trap.table);
  EXPECT_TRUE(result.below.empty());
}

// --- any point type, indices, the viewpoint ----------------------------------------------------

template <typename PointT>
class PlaneDetectorPointTypes : public testing::Test {};
using PointTypes = testing::Types<pcl::PointXYZRGB, pcl::PointXYZI, pcl::PointNormal, PointRDM>;
TYPED_TEST_SUITE(PlaneDetectorPointTypes, PointTypes);

TYPED_TEST(PlaneDetectorPointTypes, SameResultAsPointXYZ) {
  const TableTop scene = makeTableTop();
  pcl::PointCloud<TypeParam> cloud;
  pcl::copyPointCloud(*scene.cloud, cloud);
  cloud.sensor_origin_ = scene.cloud->sensor_origin_;
  const PlaneResult expected = PlaneDetector{}.detect(scene.cloud);
  const PlaneResult result = PlaneDetector{}.detect(cloud);
  ASSERT_TRUE(result.found);
  EXPECT_EQ(result.inliers.size(), scene.table);
  EXPECT_EQ(result.inliers, expected.inliers);
  EXPECT_EQ(result.above, expected.above);
  EXPECT_EQ(result.below, expected.below);
  EXPECT_EQ(result.coefficients, expected.coefficients);
}

TEST(PlaneDetector, OnlyTheGivenIndicesTakePart) {
  const TableTop scene = makeTableTop();
  const Cloud& cloud = *scene.cloud;
  pcl::Indices even;  // every other point, NaNs among them
  std::size_t finite = 0, table = 0, boxes = 0;
  for (std::size_t i = 0; i < cloud.size(); i += 2) {
    even.push_back(static_cast<pcl::index_t>(i));
    if (!std::isfinite(cloud[i].z)) continue;
    ++finite;
    table += std::abs(cloud[i].z) < 0.003f;
    boxes += cloud[i].z > 0.01f;
  }
  const PlaneResult result = PlaneDetector{}.detect(cloud, even);
  ASSERT_TRUE(result.found);
  EXPECT_EQ(result.finite_points, finite);
  EXPECT_EQ(result.inliers.size(), table);
  EXPECT_EQ(result.above.size(), boxes);
  for (const auto i : result.inliers) {  // cloud indices, all among the given
    EXPECT_EQ(i % 2, 0);
    EXPECT_LT(std::abs(cloud[i].z), 0.003f);
  }
  for (const auto i : result.above) EXPECT_EQ(i % 2, 0);

  const pcl::Indices outside = {0, static_cast<pcl::index_t>(cloud.size())};
  EXPECT_THROW(PlaneDetector{}.detect(cloud, outside), std::invalid_argument);
}

TEST(PlaneDetector, ViewpointOnThePlaneIsReportedNotGuessed) {
  // A 1 m x 1 m floor at z = 0 with a 20 cm cube of points 5 cm above it.
  Cloud cloud;
  for (int i = 0; i < 100; ++i)
    for (int j = 0; j < 100; ++j) {
      const bool cube = i >= 40 && i < 60 && j >= 40 && j < 60;
      cloud.push_back(pcl::PointXYZ(0.01f * i, 0.01f * j, cube ? 0.05f : 0.0f));
    }
  cloud.sensor_origin_ = Eigen::Vector4f(-0.5f, 0.3f, 0.004f, 0.0f);  // 4 mm: on the plane
  const PlaneResult on = PlaneDetector{}.detect(cloud);
  EXPECT_FALSE(on.found);
  EXPECT_TRUE(on.viewpoint_on_plane);
  EXPECT_EQ(on.inliers.size(), 9600u);  // which plane it was
  EXPECT_NEAR(std::abs(on.coefficients[2]), 1.0f, 1e-4f);
  EXPECT_TRUE(on.above.empty());
  EXPECT_TRUE(on.below.empty());

  PlaneDetectorConfig config;  // an explicit up direction defines the sides
  config.up = Eigen::Vector3f::UnitZ();
  const PlaneResult up = PlaneDetector{config}.detect(cloud);
  EXPECT_TRUE(up.found);
  EXPECT_FALSE(up.viewpoint_on_plane);
  EXPECT_EQ(up.above.size(), 400u);

  cloud.sensor_origin_ = Eigen::Vector4f(-0.5f, 0.3f, -0.8f, 0.0f);  // seen from below
  const PlaneResult below = PlaneDetector{}.detect(cloud);
  ASSERT_TRUE(below.found);
  EXPECT_NEAR(below.coefficients[2], -1.0f, 1e-4f);
  EXPECT_EQ(below.below.size(), 400u);
}

// --- real depth data: four labelled Kinect scenes of the mOSD (data/mosd/README.md) ------------

namespace {

/// Against the labels (0: NaN, 1-9: the table, >= 20: objects), over the finite points.
struct LabelScore {
  double object_f1 = 0;     ///< F1 of `above` as the objects (truth: label >= 20)
  double table_recall = 0;  ///< share of the table's points among the inliers
  double behind_share = 0;  ///< share of the finite points in `below`
};

LabelScore scoreAgainstLabels(const pcl::PointCloud<pcl::PointXYZRGBL>& cloud,
                              const PlaneResult& result) {
  std::vector<char> above(cloud.size(), 0), inlier(cloud.size(), 0);
  for (const auto i : result.above) above[static_cast<std::size_t>(i)] = 1;
  for (const auto i : result.inliers) inlier[static_cast<std::size_t>(i)] = 1;
  std::size_t finite = 0, tp = 0, fp = 0, fn = 0, table = 0, table_found = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!pcl::isFinite(cloud[i])) continue;
    ++finite;
    const bool object = cloud[i].label >= 20;
    tp += object && above[i];
    fp += !object && above[i];
    fn += object && !above[i];
    if (cloud[i].label >= 1 && cloud[i].label <= 9) {
      ++table;
      table_found += inlier[i];
    }
  }
  LabelScore s;
  s.object_f1 = 2.0 * static_cast<double>(tp) / static_cast<double>(2 * tp + fp + fn);
  s.table_recall = static_cast<double>(table_found) / static_cast<double>(table);
  s.behind_share = static_cast<double>(result.below.size()) / static_cast<double>(finite);
  return s;
}

class MosdScene : public testing::TestWithParam<const char*> {};

}  // namespace

TEST_P(MosdScene, FindsTheTableAndTheObjectsOnIt) {
  const std::string path = std::string(MULTISLIT_DATA_DIR) + "/mosd/" + GetParam() + ".pcd";
  pcl::PointCloud<pcl::PointXYZRGBL> cloud;
  ASSERT_EQ(pcl::io::loadPCDFile<pcl::PointXYZRGBL>(path, cloud), 0) << path;
  ASSERT_EQ(cloud.width * cloud.height, 640u * 480u);
  const PlaneResult result = PlaneDetector{}.detect(cloud);
  ASSERT_TRUE(result.found);
  const LabelScore s = scoreAgainstLabels(cloud, result);
  EXPECT_GE(s.object_f1, 0.95);
  EXPECT_GE(s.table_recall, 0.95);
  EXPECT_LE(s.behind_share, 0.005);
  RecordProperty("object_f1", std::to_string(s.object_f1));
}

INSTANTIATE_TEST_SUITE_P(Kinect, MosdScene,
                         testing::Values("learn0", "learn20", "learn28", "learn40"));
