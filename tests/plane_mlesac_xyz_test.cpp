// MLESAC on PointRDM clouds keeps PCL's own scale for every model but the RDMap plane: with PCL's
// plane model on x, y, z it finds what MLESAC finds on the same points as pcl::PointXYZ. This
// file compiles PCL's templates itself (PCL_NO_PRECOMPILE), as a user's program may, and so also
// checks that the library's MLESAC specializations are declared where such a program sees them.
#define PCL_NO_PRECOMPILE
#include "multislit/plane_model.h"

#include <gtest/gtest.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/mlesac.h>
#include <pcl/sample_consensus/sac_model_plane.h>

#include <memory>
#include <random>

using namespace multislit;

TEST(PlaneMlesacXyz, OtherModelsKeepPclsScale) {
  // A tilted plane of 2000 points with 1 mm noise and 25 % outliers, as PointRDM and PointXYZ.
  auto rdm = std::make_shared<pcl::PointCloud<PointRDM>>();
  auto xyz = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::normal_distribution<float> noise(0.0f, 0.001f);
  for (int i = 0; i < 2000; ++i) {
    const float x = unit(rng), y = unit(rng);
    const float z = i % 4 == 0 ? 0.5f * unit(rng) : 0.1f * x - 0.05f * y + 0.3f + noise(rng);
    PointRDM p;
    p.x = x, p.y = y, p.z = z, p.u = p.v = p.dk = 0.0f, p.slit = 0;
    rdm->push_back(p);
    xyz->push_back(pcl::PointXYZ(x, y, z));
  }
  auto rdm_model = std::make_shared<pcl::SampleConsensusModelPlane<PointRDM>>(rdm);
  auto xyz_model = std::make_shared<pcl::SampleConsensusModelPlane<pcl::PointXYZ>>(xyz);
  // PCL's threshold for MLESAC: a multiple of the median spread of x, y, z.
  pcl::MaximumLikelihoodSampleConsensus<PointRDM> rdm_sac(rdm_model, 0.01);
  pcl::MaximumLikelihoodSampleConsensus<pcl::PointXYZ> xyz_sac(xyz_model, 0.01);
  ASSERT_TRUE(rdm_sac.computeModel());
  ASSERT_TRUE(xyz_sac.computeModel());
  pcl::Indices rdm_inliers, xyz_inliers;
  rdm_sac.getInliers(rdm_inliers);
  xyz_sac.getInliers(xyz_inliers);
  EXPECT_EQ(rdm_inliers, xyz_inliers);
  EXPECT_GT(rdm_inliers.size(), 1000u);
  EXPECT_LT(rdm_inliers.size(), 1600u);  // the outliers off the plane are not inliers
}
