// Obstacle clusters: points off the floor grouped, sized and placed, against the simulator's truth.
#include "multislit/obstacles.h"
#include "default_reference.h"
#include "multislit/extractor.h"
#include "multislit/floor_detector.h"
#include "multislit/sim/rdmap_synth.h"
#include "multislit/sim/scenarios.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

using namespace multislit;

namespace {

const Reference& reference() { return test::defaultReference(); }

const RDMapSynthesizer& synth() {
  static const RDMapSynthesizer s(SensorConfig{}, reference());
  return s;
}

const SensorGeometry& geometry() { return synth().simulator().geometry(); }

struct Seen {
  pcl::PointCloud<PointRDM>::Ptr cloud;
  FloorResult floor;
  ObstacleResult obstacles;
};

/// The robot at the origin of the world, the sensor at the reference mount.
Seen look(const Scene& scene, ClusterMethod method, bool render = false) {
  const MountConfig mount;
  const Eigen::Isometry3d pose = geometry().robotFromCamera(mount);
  Seen s;
  if (render) {
    static const Simulator simulator{SensorConfig{}};
    static const Extractor extractor(reference());
    s.cloud = extractor.extract(simulator.render(scene, pose, 11).image, 0, 11);
  } else {
    s.cloud = synth().synthesize(scene, pose, 11);
  }
  s.floor = FloorDetector().detect(s.cloud);
  ObstacleClustererConfig config;
  config.method = method;
  s.obstacles = ObstacleClusterer(config).cluster(s.cloud, s.floor, pose);
  return s;
}

Scene ballScene() { return makeScenario("ball").scene; }  // 40 mm ball at (0.18, 0.02)

Scene cableScene(double x, double yaw_deg = 0.0) {  // 7 mm cable across the view, x ahead
  Scene scene;
  const double r = 0.0035, half = 0.6, c = std::cos(yaw_deg * M_PI / 180),
               s = std::sin(yaw_deg * M_PI / 180);
  scene.objects.push_back(SceneObject::cylinder("cable",
                                                Eigen::Vector3d(x + half * s, -half * c, r),
                                                Eigen::Vector3d(x - half * s, half * c, r), r));
  scene.objects.back().albedo = 0.35;
  return scene;
}

/// `slack` widens the size tolerances for rendered frames, whose extraction has outliers at
/// the objects' edges.
void expectBall(const ObstacleResult& r, const std::string& what, double slack = 0.0) {
  ASSERT_EQ(r.obstacles.size(), 1u) << what;
  const Obstacle& o = r.obstacles[0];
  EXPECT_GE(o.pointCount(), 20u) << what;
  EXPECT_NEAR(o.height, 0.040, 0.006 + slack) << what;  // the ball's top
  EXPECT_GT(o.width, 0.025) << what;
  EXPECT_LT(o.width, 0.045 + slack) << what;
  EXPECT_LT(o.length, 0.045 + slack) << what;
  // The slits see the side facing the sensor: the centroid lies within the ball's radius.
  EXPECT_LT((o.centroid.head<2>() - Eigen::Vector2d(0.18, 0.02)).norm(), 0.02) << what;
  EXPECT_GE(o.slits, 2) << what;
  // Nearest point about 0.16 m ahead; the feet end 0.0675 m ahead.
  EXPECT_NEAR(o.distance, o.min.x() - 0.0675, 1e-9) << what;
  EXPECT_NEAR(o.distance, 0.16 - 0.0675, 0.015) << what;
}

void expectCable(const ObstacleResult& r, double x, const std::string& what, double slack = 0.0) {
  ASSERT_EQ(r.obstacles.size(), 1u) << what;
  const Obstacle& o = r.obstacles[0];
  EXPECT_GE(o.pointCount(), 100u) << what;  // one slit along many rows
  EXPECT_NEAR(o.height, 0.007, 0.002 + slack) << what;
  EXPECT_GT(o.width, 0.30) << what;  // across the whole view
  EXPECT_LT(o.length, 0.03) << what;
  EXPECT_NEAR(o.centroid.x(), x, 0.01) << what;
}

}  // namespace

TEST(ObstacleClusterer, BallIsOneObstacleSizedAndPlaced) {
  expectBall(look(ballScene(), ClusterMethod::Grid).obstacles, "grid");
  expectBall(look(ballScene(), ClusterMethod::Euclidean).obstacles, "euclidean");
}

TEST(ObstacleClusterer, LanCableIsKeptAndSized) {
  const Seen grid = look(cableScene(0.25), ClusterMethod::Grid);
  expectCable(grid.obstacles, 0.25, "grid");
  EXPECT_EQ(grid.obstacles.obstacles.size(), 1u);
  const Seen euclid = look(cableScene(0.25), ClusterMethod::Euclidean);
  expectCable(euclid.obstacles, 0.25, "euclidean");
  EXPECT_EQ(euclid.obstacles.pointCount(), grid.obstacles.pointCount());
}

TEST(ObstacleClusterer, RenderedFramesGiveTheSameObstacles) {
  expectBall(look(ballScene(), ClusterMethod::Grid, true).obstacles, "rendered ball", 0.005);
  const Seen cable = look(cableScene(0.25), ClusterMethod::Grid, true);
  expectCable(cable.obstacles, 0.25, "rendered cable", 0.002);
  std::printf("rendered cable: %zu obstacles, %zu points, %.1f mm high, %.0f mm across\n",
              cable.obstacles.obstacles.size(), cable.obstacles.pointCount(),
              1e3 * cable.obstacles.obstacles[0].height, 1e3 * cable.obstacles.obstacles[0].width);
}

TEST(ObstacleClusterer, ObliqueCableStaysInFewPieces) {
  // Each slit sees a piece of an oblique cable; at 30 deg and more the pieces are close enough
  // to stay one or two obstacles (at 15 deg they are 50 mm apart: five obstacles).
  for (const double yaw : {30.0, 45.0, 60.0}) {
    const Seen euclid = look(cableScene(0.25, yaw), ClusterMethod::Euclidean);
    const Seen grid = look(cableScene(0.25, yaw), ClusterMethod::Grid);
    EXPECT_LE(euclid.obstacles.obstacles.size(), 2u) << yaw << " deg";
    EXPECT_LE(grid.obstacles.obstacles.size(), 2u) << yaw << " deg";
    EXPECT_EQ(grid.obstacles.pointCount(), euclid.obstacles.pointCount()) << yaw << " deg";
  }
}

TEST(ObstacleClusterer, IsolatedPointsAreRejectedThreeInARowAreKept) {
  Seen s = look(Scene{}, ClusterMethod::Grid);
  ASSERT_TRUE(s.floor.found);
  ASSERT_TRUE(s.obstacles.obstacles.empty());
  // Spikes of +3 px: ten single points and one pair, far apart, then three in a row.
  const int w = static_cast<int>(s.cloud->width);
  const auto spike = [&](int slit, int column) {
    PointRDM& p = s.cloud->at(column, slit);
    ASSERT_TRUE(std::isfinite(p.dk)) << slit << " " << column;
    p.dk += 3.0f;
  };
  for (int k = 0; k < 10; ++k) spike(1 + (k % 5) * 3, w / 4 + (k / 5) * (w / 3));
  spike(7, w / 2);
  spike(7, w / 2 + 1);
  s.floor = FloorDetector().detect(s.cloud);
  const ObstacleClusterer clusterer;
  const Eigen::Isometry3d pose = geometry().robotFromCamera(MountConfig{});
  ObstacleResult r = clusterer.cluster(s.cloud, s.floor, pose);
  EXPECT_TRUE(r.obstacles.empty());
  EXPECT_EQ(r.rejected_groups, 11u);
  EXPECT_EQ(r.rejected.size(), 12u);
  spike(7, w / 2 + 3);  // one cell gap: within max_gap
  s.floor = FloorDetector().detect(s.cloud);
  r = clusterer.cluster(s.cloud, s.floor, pose);
  ASSERT_EQ(r.obstacles.size(), 1u);
  EXPECT_EQ(r.obstacles[0].pointCount(), 3u);
}

TEST(ObstacleClusterer, ARunLiesOnOneSideOfTheFloor) {
  Seen s = look(Scene{}, ClusterMethod::Grid);
  ASSERT_TRUE(s.floor.found);
  ASSERT_TRUE(s.obstacles.obstacles.empty());
  // Three neighbouring rows of one slit off the floor by +3, -3 and +3 px: noise, not a surface.
  const int w = static_cast<int>(s.cloud->width);
  for (int k = 0; k < 3; ++k) {
    PointRDM& p = s.cloud->at(w / 2 + k, 7);
    ASSERT_TRUE(std::isfinite(p.dk)) << k;
    p.dk += k == 1 ? -3.0f : 3.0f;
  }
  s.floor = FloorDetector().detect(s.cloud);
  const Eigen::Isometry3d pose = geometry().robotFromCamera(MountConfig{});
  ObstacleResult r = ObstacleClusterer().cluster(s.cloud, s.floor, pose);
  EXPECT_TRUE(r.obstacles.empty());
  EXPECT_EQ(r.rejected_groups, 1u);
  EXPECT_EQ(r.rejected.size(), 3u);
  ObstacleClustererConfig any_side;
  any_side.run_one_side = false;
  r = ObstacleClusterer(any_side).cluster(s.cloud, s.floor, pose);
  ASSERT_EQ(r.obstacles.size(), 1u);
  EXPECT_EQ(r.obstacles[0].pointCount(), 3u);
  s.cloud->at(w / 2 + 1, 7).dk += 6.0f;  // now +3, +3, +3: a surface
  s.floor = FloorDetector().detect(s.cloud);
  r = ObstacleClusterer().cluster(s.cloud, s.floor, pose);
  ASSERT_EQ(r.obstacles.size(), 1u);
  EXPECT_EQ(r.obstacles[0].pointCount(), 3u);
}

// Points in no run reach at most max_hops links from a run and join one group only.
TEST(ObstacleClusterer, ScatteredPointsNeitherChainGroupsNorSpreadThem) {
  Seen s = look(Scene{}, ClusterMethod::Grid);
  ASSERT_TRUE(s.floor.found);
  ASSERT_TRUE(s.obstacles.obstacles.empty());
  const int w = static_cast<int>(s.cloud->width), at = w / 3;
  const auto lift = [&](int column) {
    PointRDM& p = s.cloud->at(column, 7);
    ASSERT_TRUE(std::isfinite(p.dk)) << column;
    p.dk += 3.0f;
  };
  // A run of 3 rows, then single points 8 rows apart (within max_gap, in no run).
  for (int k = 0; k < 3; ++k) lift(at + k);
  for (int k = 1; k <= 4; ++k) lift(at + 2 + 8 * k);
  s.floor = FloorDetector().detect(s.cloud);
  const Eigen::Isometry3d pose = geometry().robotFromCamera(MountConfig{});
  ObstacleResult r = ObstacleClusterer().cluster(s.cloud, s.floor, pose);
  ASSERT_EQ(r.obstacles.size(), 1u);
  EXPECT_EQ(r.obstacles[0].pointCount(), 5u);  // the run and the 2 singles within 2 hops
  EXPECT_EQ(r.rejected.size(), 2u);            // the 2 beyond, a group of noise
  ObstacleClustererConfig unlimited;
  unlimited.max_hops = 1000;
  r = ObstacleClusterer(unlimited).cluster(s.cloud, s.floor, pose);
  ASSERT_EQ(r.obstacles.size(), 1u);
  EXPECT_EQ(r.obstacles[0].pointCount(), 7u);
  // A second run 8 rows after the last single: the singles no longer chain the two runs into one
  // obstacle (as any number of hops did before max_hops); each joins the run nearer to it.
  for (int k = 0; k < 3; ++k) lift(at + 2 + 8 * 5 + k);
  s.floor = FloorDetector().detect(s.cloud);
  r = ObstacleClusterer(unlimited).cluster(s.cloud, s.floor, pose);
  ASSERT_EQ(r.obstacles.size(), 2u);
  EXPECT_EQ(r.obstacles[0].pointCount(), 5u);
  EXPECT_EQ(r.obstacles[1].pointCount(), 5u);
}

// Where a stripe is lost on dark grout, the region's maximum is speckle: points tens of pixels
// off the floor, jumping from row to row. They join the group of a run beside them, but they are
// no surface, so they do not make it tall (Obstacle::surface).
TEST(ObstacleClusterer, SpeckleJoinsAGroupButIsNoSurface) {
  Seen s = look(Scene{}, ClusterMethod::Grid);
  ASSERT_TRUE(s.floor.found);
  const int w = static_cast<int>(s.cloud->width), at = w / 3;
  // dk raised by `dk`, and x, y, z where the extractor puts such a point.
  const auto lift = [&](int column, float dk) {
    PointRDM& p = s.cloud->at(column, 7);
    ASSERT_TRUE(std::isfinite(p.dk)) << column;
    p.dk += dk;
    const MetricScale& scale = reference().scale;
    const double centre = p.u + p.dk;
    const double depth = scale.disparity_constant /
                         (centre - reference().slits[7].u_inf[static_cast<std::size_t>(column)]);
    p.x = static_cast<float>((centre - scale.cx) * depth / scale.f);
    p.y = static_cast<float>((p.v - scale.cy) * depth / scale.f);
    p.z = static_cast<float>(depth);
  };
  // A run of 6 rows 3 px above the floor (about 8 mm), one row with speckle 40 px above in it,
  // then speckle on the next rows, 40 px above and 35 px below in turn.
  for (int k = 0; k < 6; ++k) lift(at + k, k == 3 ? 40.0f : 3.0f);
  for (int k = 6; k < 9; ++k) lift(at + k, k % 2 == 0 ? 40.0f : -35.0f);
  s.floor = FloorDetector().detect(s.cloud);
  const Eigen::Isometry3d pose = geometry().robotFromCamera(MountConfig{});
  const ObstacleResult r = ObstacleClusterer().cluster(s.cloud, s.floor, pose);
  ASSERT_EQ(r.obstacles.size(), 1u);
  const Obstacle& o = r.obstacles[0];
  EXPECT_EQ(o.pointCount(), 9u);  // the run, the speckle in it and 3 rows after it
  // The surface: the 5 rows of the run, the speckle in it passed over.
  ASSERT_EQ(o.surface.size(), 5u);
  for (const auto i : o.surface)
    EXPECT_LT(std::abs((*s.cloud)[static_cast<std::size_t>(i)].dk - (*s.cloud)[o.surface[0]].dk),
              1.0f);
  ASSERT_EQ(o.surface_heights.size(), 5u);
  for (const float h : o.surface_heights) EXPECT_NEAR(h, 0.008, 0.004);
  EXPECT_GT(o.height, 0.05);  // what the speckle reaches
  EXPECT_EQ(o.surfacePointsAbove(0.025), 0u);
  EXPECT_EQ(o.surfacePointsAbove(0.004), 5u);
  EXPECT_EQ(o.surfacePointsBelow(0.025), 5u);
  EXPECT_EQ(o.surfacePointsBelow(0.0), 0u);  // none below the floor
  // Without the rule every point on one side of the floor in a row is a surface.
  ObstacleClustererConfig any;
  any.max_step = 1000;
  const ObstacleResult all = ObstacleClusterer(any).cluster(s.cloud, s.floor, pose);
  ASSERT_EQ(all.obstacles.size(), 1u);
  EXPECT_GT(all.obstacles[0].surfacePointsAbove(0.025), 0u);
}

TEST(ObstacleClusterer, MetricFloorIsTheFloorUnderTheSensor) {
  const Seen s = look(Scene{}, ClusterMethod::Grid);
  ASSERT_TRUE(s.obstacles.floor.valid);
  // The camera is 445 mm above the floor; the normal is the robot's z axis.
  EXPECT_NEAR(s.obstacles.floor.offset, 0.445, 0.002);
  const Eigen::Vector3d up =
      geometry().robotFromCamera(MountConfig{}).linear() * s.obstacles.floor.normal;
  EXPECT_GT(up.z(), std::cos(0.5 * M_PI / 180));
  EXPECT_GT(s.obstacles.floor.points, 4000u);
}

TEST(ObstacleClusterer, MetricFloorIsThePrincipalAxesPlaneOfTheFloorPoints) {
  // A noisy tilted floor 0.45 m from the camera, with points lacking x, y, z and indices out of
  // order: fitMetricFloor's float pass against the principal axes computed plainly in double.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> across(-0.3f, 0.3f);
  std::normal_distribution<float> noise(0.0f, 0.001f);
  pcl::PointCloud<PointRDM> cloud;
  pcl::Indices inliers;
  for (int k = 0; k < 5000; ++k) {
    PointRDM p;
    p.x = across(rng);
    p.y = 0.2f + across(rng);
    p.z = 0.45f + 0.3f * p.x - 0.5f * p.y + noise(rng);
    if (k % 97 == 0) p.y = std::numeric_limits<float>::quiet_NaN();
    cloud.push_back(p);
    if (k % 5 != 0) inliers.push_back(k);
  }
  std::shuffle(inliers.begin(), inliers.end(), rng);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  std::size_t n = 0;
  for (const auto i : inliers)
    if (std::isfinite(cloud[i].y)) {
      mean += cloud[i].getVector3fMap().cast<double>();
      ++n;
    }
  mean /= static_cast<double>(n);
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const auto i : inliers)
    if (std::isfinite(cloud[i].y)) {
      const Eigen::Vector3d d = cloud[i].getVector3fMap().cast<double>() - mean;
      covariance += d * d.transpose() / static_cast<double>(n);
    }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  Eigen::Vector3d normal = eigen.eigenvectors().col(0);
  double offset = -normal.dot(mean);
  if (offset < 0) {
    normal = -normal;
    offset = -offset;
  }
  const MetricFloor floor = fitMetricFloor(cloud, inliers);
  ASSERT_TRUE(floor.valid);
  EXPECT_EQ(floor.points, n);
  EXPECT_LT((floor.normal - normal).norm(), 1e-6);
  EXPECT_NEAR(floor.offset, offset, 1e-6 * offset);
}

TEST(ObstacleClusterer, NoFloorNoObstacles) {
  Seen s = look(ballScene(), ClusterMethod::Grid);
  s.floor.found = false;
  EXPECT_TRUE(ObstacleClusterer()
                  .cluster(s.cloud, s.floor, Eigen::Isometry3d::Identity())
                  .obstacles.empty());
}

TEST(ObstacleClusterer, ConfigErrorsNameTheField) {
  ObstacleClustererConfig config;
  config.min_points = 0;
  try {
    config.validate();
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("min_points"), std::string::npos);
  }
  config = {};
  config.tolerance = 0;
  EXPECT_THROW(ObstacleClusterer{config}, std::invalid_argument);
}

// The feet are described once (FootConfig): a longer step puts the leading toe farther ahead, so
// the same ball is nearer to the feet by exactly the toe's advance, and the walker's
// sudden-obstacle zone (near_distance from the feet) reaches that much farther ahead.
TEST(Obstacles, TheStepLengthMovesTheFeetTheDistanceIsMeasuredFrom) {
  const Seen s = look(ballScene(), ClusterMethod::Grid);
  const MountConfig mount;
  const Eigen::Isometry3d pose = geometry().robotFromCamera(mount);
  FootConfig shortStep, longStep;
  longStep.step_length = 0.08;
  const ObstacleResult a = ObstacleClusterer({}, shortStep).cluster(s.cloud, s.floor, pose);
  const ObstacleResult b = ObstacleClusterer({}, longStep).cluster(s.cloud, s.floor, pose);
  ASSERT_EQ(a.obstacles.size(), 1u);
  ASSERT_EQ(b.obstacles.size(), 1u);
  EXPECT_GT(a.obstacles[0].distance, 0.03);
  EXPECT_NEAR(a.obstacles[0].distance - b.obstacles[0].distance, longStep.toe() - shortStep.toe(),
              1e-9);
  EXPECT_NEAR(longStep.toe() - shortStep.toe(), 0.02, 1e-12);
}
