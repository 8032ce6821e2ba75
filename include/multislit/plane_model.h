// The plane of an RDMap, dk = A u + B v + C (paper eq. 1), as a PCL sample-consensus model.
// Works with every PCL estimator: RANSAC, LMedS, MSAC, RRANSAC, RMSAC, MLESAC and PROSAC (their
// PointRDM instantiations live in src/pcl_instantiations.cpp; no PCL_NO_PRECOMPILE needed). Give
// RRANSAC and RMSAC a pretest of a few points (setFractionNrPretest, in percent): PCL's 10 % never
// passes on a frame with obstacles, and PCL's RRANSAC then never returns. docs/plane-detector.md.
#pragma once

#include "multislit/point_types.h"

#include <pcl/point_cloud.h>
#include <pcl/sample_consensus/mlesac.h>
#include <pcl/sample_consensus/sac_model.h>
#include <pcl/types.h>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <memory>
#include <set>
#include <vector>

namespace multislit {

/// Model id returned by SampleConsensusModelRDMapPlane::getModelType(). pcl::SacModel has no slot
/// for user models and PCL never dispatches on this value for a model object it is handed, so we
/// use 31: the largest value pcl::SacModel can hold (its enumerators 0 .. 18 need 5 bits), far from
/// PCL's own ids. Never pass it to pcl::SACSegmentation::setModelType.
constexpr int kSacModelRDMapPlane = 31;

/// True when the point was measured: u, v and dk are finite. (x - x is 0 for a finite x and NaN
/// for NaN or infinity: one comparison instead of three branches, which matters in the per-point
/// loops; do not build with -ffinite-math-only, which breaks std::isfinite too.)
inline bool isValidRDMPoint(const PointRDM& p) {
  return (p.u - p.u) + (p.v - p.v) + (p.dk - p.dk) == 0.0f;
}

/// eq. (1): the signed residual dk - (A u + B v + C) of a point against the plane (A, B, C) [px];
/// > 0 above the floor (nearer to the sensor). In float, as the per-point loops compute it.
inline float planeResidual(const PointRDM& p, float a, float b, float c) {
  return p.dk - (a * p.u + b * p.v + c);
}
/// The same in double, for a plane (A, B, C) as FloorResult::plane holds it [px].
inline double planeResidual(const PointRDM& p, const Eigen::Vector3d& plane) {
  return p.dk - (plane[0] * p.u + plane[1] * p.v + plane[2]);
}

/// Least-squares plane of eq. (2) through some points of an RDMap.
struct RDMapPlaneFit {
  bool ok = false;                                  ///< false: fewer than 3 points or degenerate
  Eigen::Vector3d plane = Eigen::Vector3d::Zero();  ///< (A, B, C): dk = A u + B v + C [-, -, px]
  double residual_std = 0.0;  ///< RMS of dk - (A u + B v + C) over the points [px]
  std::size_t points = 0;     ///< points used (invalid points among `indices` are skipped)
};

/// eq. (2): the least-squares plane dk = A u + B v + C through cloud[indices] (invalid points are
/// skipped).
RDMapPlaneFit fitRDMapPlane(const pcl::PointCloud<PointRDM>& cloud, const pcl::Indices& indices);

/// The RDMap plane dk = A u + B v + C as a PCL sample-consensus model. Coefficients: (A, B, C).
/// The distance of a point to the model is its residual along dk, |dk - (A u + B v + C)| [px], not
/// the orthogonal distance. A sample is three valid points of three different slits that are not
/// collinear in (u, v) (paper Sec. III-B). Invalid points (non-finite u, v or dk) are never
/// inliers: setInputCloud() keeps only the valid points as indices, and points given later by
/// setIndices() that are invalid get an infinite distance. As with PCL's models, change the indices
/// through setIndices(), not by writing into the vector getIndices() returns.
class SampleConsensusModelRDMapPlane : public pcl::SampleConsensusModel<PointRDM> {
 public:
  using PointCloud = pcl::PointCloud<PointRDM>;
  using PointCloudConstPtr = PointCloud::ConstPtr;
  using Ptr = std::shared_ptr<SampleConsensusModelRDMapPlane>;
  using ConstPtr = std::shared_ptr<const SampleConsensusModelRDMapPlane>;

  /// Uses all valid points of `cloud`. `random`: seed the sampler from the clock, else with 12345.
  explicit SampleConsensusModelRDMapPlane(const PointCloudConstPtr& cloud, bool random = false);
  /// Uses the valid points among `indices`.
  SampleConsensusModelRDMapPlane(const PointCloudConstPtr& cloud, const pcl::Indices& indices,
                                 bool random = false);

  /// Sets the cloud and makes the indices all of its valid points (any earlier indices are
  /// dropped, unlike PCL's base class, which keeps indices that belong to the previous cloud).
  void setInputCloud(const PointCloudConstPtr& cloud) override;
  /// Sets the cloud and makes the indices the valid points among `indices`. A model kept from
  /// frame to frame and given each frame's cloud by these two reuses its arrays.
  void setInputCloud(const PointCloudConstPtr& cloud, const pcl::Indices& indices);

  /// Restarts the sample draws from `seed`: the same seed and cloud give the same samples.
  void setSeed(unsigned seed);

  /// Solves dk = A u + B v + C through the three samples.
  bool computeModelCoefficients(const pcl::Indices& samples,
                                Eigen::VectorXf& model_coefficients) const override;
  /// eq. (2): least-squares refit on `inliers`; keeps `model_coefficients` when that fails.
  void optimizeModelCoefficients(const pcl::Indices& inliers,
                                 const Eigen::VectorXf& model_coefficients,
                                 Eigen::VectorXf& optimized_coefficients) const override;
  /// |dk - (A u + B v + C)| [px] of every index; +infinity for an invalid point.
  void getDistancesToModel(const Eigen::VectorXf& model_coefficients,
                           std::vector<double>& distances) const override;
  void selectWithinDistance(const Eigen::VectorXf& model_coefficients, double threshold,
                            pcl::Indices& inliers) override;
  std::size_t countWithinDistance(const Eigen::VectorXf& model_coefficients,
                                  double threshold) const override;
  /// Moves the inliers onto the plane along dk (dk = A u + B v + C); x, y, z are left as they are
  /// (the model knows no sensor geometry). With copy_data_fields the whole cloud is copied, so an
  /// organized cloud stays organized; else only the inliers are returned.
  void projectPoints(const pcl::Indices& inliers, const Eigen::VectorXf& model_coefficients,
                     PointCloud& projected_points, bool copy_data_fields = true) const override;
  bool doSamplesVerifyModel(const std::set<pcl::index_t>& indices,
                            const Eigen::VectorXf& model_coefficients,
                            double threshold) const override;

  /// countWithinDistance() when that is more than `best`; else some number <= `best`, found
  /// sooner: the count stops once the points left cannot lift it above `best` (RANSAC's bail-out).
  std::size_t countWithinDistanceIfMore(const Eigen::VectorXf& model_coefficients, double threshold,
                                        std::size_t best) const;
  /// eq. (2) through the points within `threshold` [px] of the model, in one pass (the same
  /// plane as selectWithinDistance() then fitRDMapPlane(), without the index list).
  RDMapPlaneFit fitWithinDistance(const Eigen::VectorXf& model_coefficients,
                                  double threshold) const;

  /// kSacModelRDMapPlane cast to pcl::SacModel (see there).
  pcl::SacModel getModelType() const override {
    return static_cast<pcl::SacModel>(kSacModelRDMapPlane);
  }

 protected:
  /// Three valid points of three different slits, not collinear in (u, v).
  bool isSampleGood(const pcl::Indices& samples) const override;

 private:
  /// Keeps the valid points among indices_ (`among_indices`), else among all points of the cloud,
  /// as indices_, and copies their u, v, dk, centred on their mean, into contiguous arrays: the
  /// residual loops then run over memory in order and vectorize, and float sums of centred values
  /// stay accurate.
  void cacheValidPoints(bool among_indices);
  /// indices_ ready to be rewritten: its vector when no one else holds it, else a new one.
  void ownIndices();
  /// False once setIndices() replaced the cached indices: then the loops read the cloud.
  bool cached() const { return indices_ == cached_indices_; }
  /// C of the model for the centred arrays: dk - mean_dk = A (u - mean_u) + B (v - mean_v) + C'.
  float centredC(const Eigen::VectorXf& model_coefficients) const;

  pcl::IndicesPtr cached_indices_;
  std::vector<float> u_, v_, dk_;  ///< of the points of cached_indices_, minus the means [px]
  double mean_u_ = 0.0, mean_v_ = 0.0, mean_dk_ = 0.0;  ///< [px]
};

}  // namespace multislit

// MLESAC's scale for PointRDM clouds. PCL's MLESAC takes its Gaussian sigma as the threshold times
// the median spread of x, y, z [m] and its outliers as uniform over the bounding box of x, y, z,
// while this model's distances are residuals along dk [px]. With SampleConsensusModelRDMapPlane,
// sigma is threshold / 2 [px], so that MLESAC's inliers (within 2 sigma) are the points within the
// threshold, as for the other estimators, and the outliers are uniform over the span of dk (at
// least 2 x threshold). Any other model keeps PCL's formulas. Defined in
// src/pcl_instantiations.cpp.
template <>
double pcl::MaximumLikelihoodSampleConsensus<multislit::PointRDM>::computeMedianAbsoluteDeviation(
    const PointCloudConstPtr& cloud, const IndicesPtr& indices, double sigma) const;
template <>
void pcl::MaximumLikelihoodSampleConsensus<multislit::PointRDM>::getMinMax(
    const PointCloudConstPtr& cloud, const IndicesPtr& indices, Eigen::Vector4f& min_p,
    Eigen::Vector4f& max_p) const;
