// The RDMap plane model (eq. 1, 2) on synthetic RDMaps with exact ground truth, alone and inside
// PCL's own estimators.
#include "multislit/plane_model.h"

#include <gtest/gtest.h>
#include <pcl/ModelCoefficients.h>
#include <pcl/PointIndices.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/lmeds.h>
#include <pcl/sample_consensus/msac.h>
#include <pcl/sample_consensus/ransac.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <Eigen/QR>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <utility>

using namespace multislit;

namespace {

using Cloud = pcl::PointCloud<PointRDM>;
constexpr int kSlits = 15;
constexpr int kSamples = 300;
const Eigen::Vector3d kTruth(0.004, -0.012, 3.0);  // dk = A u + B v + C
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

double truthDk(double u, double v) { return kTruth[0] * u + kTruth[1] * v + kTruth[2]; }

// 15 slits x 300 samples, one per image row, tilted 20 deg from the image rows like the real
// sensor: u = 300 .. 1122 px, v = 50 .. 937 px. dk = truth + N(0, sigma); a share of the points
// unmeasured (NaN). With `outliers`, a 'ball' (+up to 12 px) and random points (+-20 px) too.
Cloud::Ptr makeRDMap(unsigned seed, double sigma, double nan_share, bool outliers) {
  auto cloud = std::make_shared<Cloud>(kSamples, kSlits);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int s = 0; s < kSlits; ++s) {
    for (int j = 0; j < kSamples; ++j) {
      PointRDM& p = cloud->at(j, s);
      p.u = static_cast<float>(300.0 + 2.75 * j);
      p.v = static_cast<float>(50 + 42 * s + j);
      p.slit = s;
      double dk = truthDk(p.u, p.v) + (sigma > 0.0 ? noise(rng) : 0.0);
      const double rho = std::hypot(p.u - 900.0, p.v - 500.0) / 80.0;
      if (outliers && rho < 1.0) dk += 12.0 * std::sqrt(1.0 - rho * rho);
      if (outliers && unit(rng) < 0.2) dk += 40.0 * (unit(rng) - 0.5);
      p.dk = static_cast<float>(dk);
      p.x = p.u * 1e-3f;
      p.y = p.v * 1e-3f;
      p.z = 0.5f;
      if (unit(rng) < nan_share) p.x = p.y = p.z = p.dk = kNaN;
    }
  }
  cloud->is_dense = false;
  return cloud;
}

Eigen::Vector3d toVector3d(const Eigen::VectorXf& coefficients) {
  return coefficients.head<3>().cast<double>();
}

// Largest |dk difference| of two planes over the area of the synthetic RDMap [px] (the corners of
// the parallelogram the slits cover).
double planeGap(const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  const double u_end = 300.0 + 2.75 * (kSamples - 1), v_end = 50.0 + 42 * (kSlits - 1);
  double gap = 0.0;
  for (const auto& [u, v] : {std::pair{300.0, 50.0}, std::pair{u_end, 50.0 + kSamples - 1},
                             std::pair{300.0, v_end}, std::pair{u_end, v_end + kSamples - 1}})
    gap = std::max(gap, std::abs((p - q).dot(Eigen::Vector3d(u, v, 1.0))));
  return gap;
}

}  // namespace

TEST(PlaneModel, ThreePointsOfThreeSlitsGiveTheirPlane) {
  const auto cloud = makeRDMap(1, 0.0, 0.0, false);
  SampleConsensusModelRDMapPlane model(cloud);
  Eigen::VectorXf coefficients;
  ASSERT_TRUE(
      model.computeModelCoefficients({5, 4 * kSamples + 200, 12 * kSamples + 90}, coefficients));
  ASSERT_EQ(coefficients.size(), 3);
  EXPECT_LT(planeGap(toVector3d(coefficients), kTruth), 1e-4);
  EXPECT_EQ(model.getSampleSize(), 3u);
  EXPECT_EQ(model.getModelSize(), 3u);
  EXPECT_EQ(static_cast<int>(model.getModelType()), kSacModelRDMapPlane);
}

TEST(PlaneModel, RejectsTwoPointsOfOneSlitCollinearAndInvalidSamples) {
  auto cloud = makeRDMap(1, 0.0, 0.0, false);
  (*cloud)[3 * kSamples + 7].dk = kNaN;
  // Three points on one straight line in (u, v) although on three slits: (1,0) (1,42) (1,84).
  (*cloud)[0 * kSamples + 1].u = 500.0f;
  (*cloud)[1 * kSamples + 1].u = 500.0f;
  (*cloud)[2 * kSamples + 1].u = 500.0f;
  SampleConsensusModelRDMapPlane model(cloud);
  Eigen::VectorXf coefficients;
  EXPECT_FALSE(model.computeModelCoefficients({5, 17, 8 * kSamples}, coefficients));  // same slit
  EXPECT_FALSE(model.computeModelCoefficients({1, kSamples + 1, 2 * kSamples + 1}, coefficients));
  EXPECT_FALSE(model.computeModelCoefficients({5, 3 * kSamples + 7, 8 * kSamples}, coefficients));
  EXPECT_FALSE(model.computeModelCoefficients({5, 3 * kSamples}, coefficients));  // two points
  EXPECT_TRUE(model.computeModelCoefficients({5, 3 * kSamples + 8, 8 * kSamples}, coefficients));
}

TEST(PlaneModel, SamplesAreThreeValidPointsOfThreeDifferentSlits) {
  const auto cloud = makeRDMap(2, 0.3, 0.2, true);
  SampleConsensusModelRDMapPlane model(cloud);
  pcl::Indices sample;
  std::set<int> slits_seen;
  for (int k = 0; k < 20000; ++k) {
    int iterations = k;
    model.getSamples(iterations, sample);
    ASSERT_EQ(sample.size(), 3u);
    const PointRDM &p0 = (*cloud)[sample[0]], &p1 = (*cloud)[sample[1]], &p2 = (*cloud)[sample[2]];
    ASSERT_TRUE(isValidRDMPoint(p0) && isValidRDMPoint(p1) && isValidRDMPoint(p2));
    ASSERT_NE(p0.slit, p1.slit);
    ASSERT_NE(p0.slit, p2.slit);
    ASSERT_NE(p1.slit, p2.slit);
    slits_seen.insert({p0.slit, p1.slit, p2.slit});
  }
  EXPECT_EQ(slits_seen.size(), static_cast<std::size_t>(kSlits));
}

TEST(PlaneModel, OnlyValidPointsAreIndicesAndInvalidOnesAreNeverInliers) {
  PointRDM measured;
  measured.u = 500.0f;
  measured.v = 300.0f;
  measured.dk = -2.5f;
  EXPECT_TRUE(isValidRDMPoint(measured));
  for (const float bad :
       {kNaN, std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()}) {
    PointRDM q = measured;
    q.u = bad;
    EXPECT_FALSE(isValidRDMPoint(q));
    q = measured;
    q.v = bad;
    EXPECT_FALSE(isValidRDMPoint(q));
    q = measured;
    q.dk = bad;
    EXPECT_FALSE(isValidRDMPoint(q));
  }

  const auto cloud = makeRDMap(3, 0.0, 0.1, false);
  std::size_t valid = 0;
  for (const auto& p : *cloud) valid += isValidRDMPoint(p);
  ASSERT_GT(valid, 3000u);
  ASSERT_LT(valid, cloud->size());

  SampleConsensusModelRDMapPlane model(cloud);
  EXPECT_EQ(model.getIndices()->size(), valid);
  for (const auto i : *model.getIndices()) EXPECT_TRUE(isValidRDMPoint((*cloud)[i]));

  Eigen::VectorXf truth = kTruth.cast<float>();
  EXPECT_EQ(model.countWithinDistance(truth, 1e-3), valid);

  // Indices given by the user may hold invalid points: they are infinitely far, never inliers.
  pcl::Indices all(cloud->size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  model.setIndices(all);
  std::vector<double> distances;
  model.getDistancesToModel(truth, distances);
  ASSERT_EQ(distances.size(), cloud->size());
  for (std::size_t i = 0; i < all.size(); ++i)
    EXPECT_EQ(std::isinf(distances[i]), !isValidRDMPoint((*cloud)[i])) << i;
  pcl::Indices inliers;
  model.selectWithinDistance(truth, 1e-3, inliers);
  EXPECT_EQ(inliers.size(), valid);
  EXPECT_EQ(model.countWithinDistance(truth, 1e-3), valid);

  // The constructor with indices and setInputCloud keep only the valid ones.
  SampleConsensusModelRDMapPlane with_indices(cloud, all);
  EXPECT_EQ(with_indices.getIndices()->size(), valid);
  with_indices.setInputCloud(makeRDMap(4, 0.0, 0.0, false));
  EXPECT_EQ(with_indices.getIndices()->size(), static_cast<std::size_t>(kSlits * kSamples));
}

TEST(PlaneModel, DistanceIsTheResidualAlongDk) {
  auto cloud = std::make_shared<Cloud>(2, 1);
  (*cloud)[0].u = 100.0f;
  (*cloud)[0].v = 200.0f;
  (*cloud)[0].dk = 2.0f * 100.0f + 1.0f * 200.0f + 5.0f + 1.5f;  // 1.5 px above a steep plane
  (*cloud)[1] = (*cloud)[0];
  (*cloud)[1].dk -= 3.0f;  // 1.5 px below
  SampleConsensusModelRDMapPlane model(cloud);
  Eigen::VectorXf steep(3);
  steep << 2.0f, 1.0f, 5.0f;
  std::vector<double> distances;
  model.getDistancesToModel(steep, distances);
  ASSERT_EQ(distances.size(), 2u);
  EXPECT_NEAR(distances[0], 1.5, 1e-4);  // the orthogonal distance would be 1.5 / sqrt(6)
  EXPECT_NEAR(distances[1], 1.5, 1e-4);
  EXPECT_TRUE(model.doSamplesVerifyModel({0, 1}, steep, 1.6));
  EXPECT_FALSE(model.doSamplesVerifyModel({0, 1}, steep, 1.4));
}

TEST(PlaneModel, OptimizeIsTheLeastSquaresPlaneOfEq2) {
  const auto cloud = makeRDMap(5, 0.3, 0.05, false);
  SampleConsensusModelRDMapPlane model(cloud);
  const pcl::Indices& inliers = *model.getIndices();
  // Reference: the same least-squares problem solved by QR on the design matrix [u v 1].
  Eigen::MatrixXd design(inliers.size(), 3);
  Eigen::VectorXd dk(inliers.size());
  for (std::size_t k = 0; k < inliers.size(); ++k) {
    const PointRDM& p = (*cloud)[inliers[k]];
    design.row(k) << p.u, p.v, 1.0;
    dk[k] = p.dk;
  }
  const Eigen::Vector3d reference = design.colPivHouseholderQr().solve(dk);
  const RDMapPlaneFit fit = fitRDMapPlane(*cloud, inliers);
  ASSERT_TRUE(fit.ok);
  EXPECT_EQ(fit.points, inliers.size());
  EXPECT_LT(planeGap(fit.plane, reference), 1e-9);
  EXPECT_NEAR(fit.residual_std, 0.3, 0.01);

  Eigen::VectorXf refit;
  model.optimizeModelCoefficients(inliers, Eigen::Vector3f(0.0f, 0.0f, 0.0f), refit);
  EXPECT_LT(planeGap(toVector3d(refit), reference), 1e-4);

  // Too few or degenerate points: the coefficients given are kept.
  const Eigen::VectorXf given = Eigen::Vector3f(1.0f, 2.0f, 3.0f);
  model.optimizeModelCoefficients({inliers[0], inliers[1]}, given, refit);
  EXPECT_EQ(refit, given);
  model.optimizeModelCoefficients({0, 1, 2, 3, 4}, given, refit);  // one slit: a line in (u, v)
  EXPECT_EQ(refit, given);
}

TEST(PlaneModel, FitWithinDistanceIsSelectThenFit) {
  const auto cloud = makeRDMap(9, 0.3, 0.05, true);
  SampleConsensusModelRDMapPlane model(cloud);
  Eigen::VectorXf tilted = kTruth.cast<float>();
  tilted[0] += 2e-4f;  // 0.16 px across the map
  pcl::Indices inliers;
  model.selectWithinDistance(tilted, 0.9, inliers);
  const RDMapPlaneFit reference = fitRDMapPlane(*cloud, inliers);
  const RDMapPlaneFit fast = model.fitWithinDistance(tilted, 0.9);
  ASSERT_TRUE(reference.ok && fast.ok);
  EXPECT_EQ(fast.points, inliers.size());
  EXPECT_LT(planeGap(fast.plane, reference.plane), 1e-4);
  EXPECT_NEAR(fast.residual_std, reference.residual_std, 1e-4);

  // The same through the cloud (after setIndices() the cached arrays are not used).
  model.setIndices(*model.getIndices());
  const RDMapPlaneFit uncached = model.fitWithinDistance(tilted, 0.9);
  EXPECT_EQ(uncached.points, inliers.size());
  EXPECT_LT(planeGap(uncached.plane, reference.plane), 1e-9);
}

TEST(PlaneModel, CountIfMoreIsTheCountWhenItBeatsTheBest) {
  const auto cloud = makeRDMap(10, 0.3, 0.05, true);
  SampleConsensusModelRDMapPlane model(cloud);
  const Eigen::VectorXf truth = kTruth.cast<float>();
  const std::size_t count = model.countWithinDistance(truth, 0.9);
  ASSERT_GT(count, 1000u);
  for (std::size_t best : {std::size_t{0}, count / 2, count - 1})
    EXPECT_EQ(model.countWithinDistanceIfMore(truth, 0.9, best), count);
  for (std::size_t best : {count, count + 1, model.getIndices()->size()})
    EXPECT_LE(model.countWithinDistanceIfMore(truth, 0.9, best), best);
}

TEST(PlaneModel, ProjectPointsMovesInliersOntoThePlaneAlongDk) {
  const auto cloud = makeRDMap(6, 0.3, 0.05, false);
  SampleConsensusModelRDMapPlane model(cloud);
  const Eigen::VectorXf truth = kTruth.cast<float>();
  const pcl::Indices inliers(model.getIndices()->begin(), model.getIndices()->begin() + 100);
  Cloud all, only;
  model.projectPoints(inliers, truth, all, true);
  model.projectPoints(inliers, truth, only, false);
  EXPECT_EQ(all.width, cloud->width);
  EXPECT_EQ(all.height, cloud->height);
  ASSERT_EQ(only.size(), inliers.size());
  for (std::size_t k = 0; k < inliers.size(); ++k) {
    const PointRDM& p = (*cloud)[inliers[k]];
    EXPECT_NEAR(only[k].dk, truthDk(p.u, p.v), 1e-4);
    EXPECT_EQ(all[inliers[k]].dk, only[k].dk);
    EXPECT_EQ(only[k].u, p.u);
    EXPECT_EQ(only[k].x, p.x);
  }
  const int outside = model.getIndices()->back();
  EXPECT_EQ(all[outside].dk, (*cloud)[outside].dk);
}

TEST(PlaneModel, PclRansacMsacAndLmedsRecoverThePlane) {
  // 20 % random outliers and a ball, 0.3 px noise.
  const auto cloud = makeRDMap(7, 0.3, 0.05, true);
  auto model = std::make_shared<SampleConsensusModelRDMapPlane>(cloud);
  pcl::RandomSampleConsensus<PointRDM> ransac(model, 0.9);
  pcl::MEstimatorSampleConsensus<PointRDM> msac(model, 0.9);
  pcl::LeastMedianSquares<PointRDM> lmeds(model, 0.9);
  lmeds.setMaxIterations(100);
  const std::pair<const char*, pcl::SampleConsensus<PointRDM>*> estimators[] = {
      {"RANSAC", &ransac}, {"MSAC", &msac}, {"LMedS", &lmeds}};
  for (const auto& [name, sac] : estimators) {
    ASSERT_TRUE(sac->computeModel()) << name;
    pcl::Indices inliers;
    sac->getInliers(inliers);
    Eigen::VectorXf coefficients, refit;
    sac->getModelCoefficients(coefficients);
    model->optimizeModelCoefficients(inliers, coefficients, refit);
    EXPECT_LT(planeGap(toVector3d(refit), kTruth), 0.05) << name;
    EXPECT_GT(inliers.size(), model->getIndices()->size() * 7 / 10) << name;
  }
}

TEST(PlaneModel, SamePlaneAsPclPlaneModelOnANoiseFreeFloor) {
  const auto cloud = makeRDMap(8, 0.0, 0.05, false);
  // PCL's own plane model on the points (u, v, dk): a u + b v + c dk + d = 0.
  auto xyz = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  for (const auto& p : *cloud)
    if (isValidRDMPoint(p)) xyz->push_back(pcl::PointXYZ(p.u, p.v, p.dk));
  pcl::SACSegmentation<pcl::PointXYZ> segmentation;
  segmentation.setOptimizeCoefficients(true);
  segmentation.setModelType(pcl::SACMODEL_PLANE);
  segmentation.setMethodType(pcl::SAC_RANSAC);
  segmentation.setDistanceThreshold(0.01);
  segmentation.setInputCloud(xyz);
  pcl::PointIndices pcl_inliers;
  pcl::ModelCoefficients pcl_plane;
  segmentation.segment(pcl_inliers, pcl_plane);
  ASSERT_EQ(pcl_plane.values.size(), 4u);
  const double a = pcl_plane.values[0], b = pcl_plane.values[1], c = pcl_plane.values[2],
               d = pcl_plane.values[3];
  const Eigen::Vector3d from_pcl(-a / c, -b / c, -d / c);  // dk = -(a u + b v + d) / c

  auto model = std::make_shared<SampleConsensusModelRDMapPlane>(cloud);
  pcl::RandomSampleConsensus<PointRDM> ransac(model, 0.01);
  ASSERT_TRUE(ransac.computeModel());
  pcl::Indices inliers;
  ransac.getInliers(inliers);
  Eigen::VectorXf coefficients, refit;
  ransac.getModelCoefficients(coefficients);
  model->optimizeModelCoefficients(inliers, coefficients, refit);

  EXPECT_EQ(inliers.size(), pcl_inliers.indices.size());
  EXPECT_EQ(inliers.size(), model->getIndices()->size());
  EXPECT_LT(planeGap(toVector3d(refit), from_pcl), 1e-4);
  EXPECT_LT(planeGap(toVector3d(refit), kTruth), 1e-4);
  EXPECT_NEAR(refit[0], from_pcl[0], 1e-4);
  EXPECT_NEAR(refit[1], from_pcl[1], 1e-4);
  EXPECT_NEAR(refit[2], from_pcl[2], 1e-4);
}
