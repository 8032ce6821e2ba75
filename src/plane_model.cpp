#include "multislit/plane_model.h"

#include "plane_kernels.h"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace multislit {

namespace {

constexpr unsigned kSampleSize = 3;  // three points determine dk = A u + B v + C
constexpr unsigned kModelSize = 3;   // (A, B, C)

/// The sums of eq. (2), taken about an origin (u0, v0, dk0) near the points (the first point
/// added, or one given) so that they stay small; solve() shifts C back.
class PlaneSums {
 public:
  PlaneSums() = default;
  /// Sums about a given origin (u0, v0, dk0), to be set().
  PlaneSums(double u0, double v0, double d0) : u0_(u0), v0_(v0), d0_(d0) {}

  void set(double suu, double suv, double su, double svv, double sv, double sud, double svd,
           double sd, double sdd, std::size_t n) {
    suu_ = suu;
    suv_ = suv;
    su_ = su;
    svv_ = svv;
    sv_ = sv;
    sud_ = sud;
    svd_ = svd;
    sd_ = sd;
    sdd_ = sdd;
    n_ = n;
  }

  void add(float u, float v, float dk) {
    if (n_ == 0) {
      u0_ = u;
      v0_ = v;
      d0_ = dk;
    }
    const double du = static_cast<double>(u) - u0_, dv = static_cast<double>(v) - v0_;
    const double dd = static_cast<double>(dk) - d0_;
    suu_ += du * du;
    suv_ += du * dv;
    su_ += du;
    svv_ += dv * dv;
    sv_ += dv;
    sud_ += du * dd;
    svd_ += dv * dd;
    sd_ += dd;
    sdd_ += dd * dd;
    ++n_;
  }

  /// eq. (2): [Σu² Σuv Σu; Σuv Σv² Σv; Σu Σv N] (A B C)ᵀ = (Σu·dk Σv·dk Σdk)ᵀ.
  RDMapPlaneFit solve() const {
    RDMapPlaneFit fit;
    fit.points = n_;
    if (n_ < kSampleSize) return fit;
    Eigen::Matrix3d normal;
    normal << suu_, suv_, su_, suv_, svv_, sv_, su_, sv_, static_cast<double>(n_);
    const Eigen::Vector3d rhs(sud_, svd_, sd_);
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(normal);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive() ||
        ldlt.vectorD().minCoeff() <= 1e-9 * ldlt.vectorD().maxCoeff())
      return fit;  // all points on one line in (u, v)
    const Eigen::Vector3d shifted = ldlt.solve(rhs);
    fit.plane = {shifted[0], shifted[1], shifted[2] + d0_ - shifted[0] * u0_ - shifted[1] * v0_};
    if (!fit.plane.allFinite()) return fit;
    // Σr² = Σdk² - 2 θᵀ rhs + θᵀ N θ, θ the shifted solution: no second pass over the points.
    const double sum_sq = sdd_ - 2.0 * shifted.dot(rhs) + shifted.dot(normal * shifted);
    fit.residual_std = std::sqrt(std::max(0.0, sum_sq) / static_cast<double>(n_));
    fit.ok = true;
    return fit;
  }

 private:
  double u0_ = 0, v0_ = 0, d0_ = 0;
  double suu_ = 0, suv_ = 0, su_ = 0, svv_ = 0, sv_ = 0, sud_ = 0, svd_ = 0, sd_ = 0, sdd_ = 0;
  std::size_t n_ = 0;
};

}  // namespace

RDMapPlaneFit fitRDMapPlane(const pcl::PointCloud<PointRDM>& cloud, const pcl::Indices& indices) {
  PlaneSums sums;
  for (const auto i : indices)
    if (isValidRDMPoint(cloud[i])) sums.add(cloud[i].u, cloud[i].v, cloud[i].dk);
  return sums.solve();
}

RDMapPlaneFit SampleConsensusModelRDMapPlane::fitWithinDistance(
    const Eigen::VectorXf& model_coefficients, double threshold) const {
  if (model_coefficients.size() != kModelSize) return {};
  const float a = model_coefficients[0], b = model_coefficients[1];
  const float t = static_cast<float>(threshold);
  if (!cached()) {
    PlaneSums sums;
    for (const auto i : *indices_) {
      const PointRDM& p = (*input_)[i];
      if (std::abs(planeResidual(p, a, b, model_coefficients[2])) <= t) sums.add(p.u, p.v, p.dk);
    }
    return sums.solve();
  }
  // The sums of eq. (2) over the inliers of the centred arrays, in one vectorized pass (float
  // partial sums; the centring keeps them accurate to ~1e-6).
  const simd::InlierSums in = simd::sumInliers(u_.data(), v_.data(), dk_.data(), u_.size(), a, b,
                                               centredC(model_coefficients), t);
  PlaneSums sums(mean_u_, mean_v_, mean_dk_);
  sums.set(in.uu, in.uv, in.u, in.vv, in.v, in.udk, in.vdk, in.dk, in.dkdk,
           static_cast<std::size_t>(in.n));
  return sums.solve();
}

SampleConsensusModelRDMapPlane::SampleConsensusModelRDMapPlane(const PointCloudConstPtr& cloud,
                                                               bool random)
    : pcl::SampleConsensusModel<PointRDM>(random) {
  model_name_ = "SampleConsensusModelRDMapPlane";
  sample_size_ = kSampleSize;
  model_size_ = kModelSize;
  setInputCloud(cloud);
}

SampleConsensusModelRDMapPlane::SampleConsensusModelRDMapPlane(const PointCloudConstPtr& cloud,
                                                               const pcl::Indices& indices,
                                                               bool random)
    : pcl::SampleConsensusModel<PointRDM>(random) {
  model_name_ = "SampleConsensusModelRDMapPlane";
  sample_size_ = kSampleSize;
  model_size_ = kModelSize;
  setInputCloud(cloud, indices);
}

void SampleConsensusModelRDMapPlane::setInputCloud(const PointCloudConstPtr& cloud) {
  input_ = cloud;
  ownIndices();
  cacheValidPoints(false);
}

void SampleConsensusModelRDMapPlane::setInputCloud(const PointCloudConstPtr& cloud,
                                                   const pcl::Indices& indices) {
  input_ = cloud;
  if (&indices != indices_.get()) {
    ownIndices();
    indices_->assign(indices.begin(), indices.end());
  }
  cacheValidPoints(true);
}

void SampleConsensusModelRDMapPlane::ownIndices() {
  // cached_indices_ is this model's second hold on the cached vector.
  const long held = indices_ && indices_ == cached_indices_ ? 2 : 1;
  if (!indices_ || indices_.use_count() > held) indices_ = std::make_shared<pcl::Indices>();
}

void SampleConsensusModelRDMapPlane::cacheValidPoints(bool among_indices) {
  const std::size_t size = input_ ? input_->size() : 0;
  const std::size_t candidates = size == 0 ? 0 : among_indices ? indices_->size() : size;
  indices_->resize(candidates);
  u_.resize(candidates);
  v_.resize(candidates);
  dk_.resize(candidates);
  // Plain pointers, and the point read (and tested) before the stores: the loop then keeps them in
  // registers and does not read a point again after each store.
  const PointRDM* points = size > 0 ? input_->points.data() : nullptr;
  pcl::index_t* index = indices_->data();
  float* u = u_.data();
  float* v = v_.data();
  float* dk = dk_.data();
  std::size_t kept = 0, k = 0;
  if (!among_indices) {
    k = candidates - candidates % 4;
    kept = simd::gatherValidByFour(points, k, index, u, v, dk);
  }
  for (; k < candidates; ++k) {
    // Branch-free: every point is written at `kept`, which moves on only for a valid one.
    const pcl::index_t i = among_indices ? index[k] : static_cast<pcl::index_t>(k);
    const bool inside = i >= 0 && static_cast<std::size_t>(i) < size;
    const PointRDM& p = points[inside ? i : 0];
    const bool keep = inside && isValidRDMPoint(p);
    const float pu = p.u, pv = p.v, pdk = p.dk;
    index[kept] = i;
    u[kept] = pu;
    v[kept] = pv;
    dk[kept] = pdk;
    kept += keep;
  }
  indices_->resize(kept);
  shuffled_indices_ = *indices_;
  cached_indices_ = indices_;
  u_.resize(kept);
  v_.resize(kept);
  dk_.resize(kept);
  // Centre on the means: any centre near the points keeps the float sums of fitWithinDistance()
  // accurate, so Eigen's vectorized float sums do.
  const auto n = static_cast<Eigen::Index>(kept);
  Eigen::Map<Eigen::ArrayXf> cu(u, n), cv(v, n), cdk(dk, n);
  const float count = kept > 0 ? static_cast<float>(kept) : 1.0f;
  const float mu = cu.sum() / count, mv = cv.sum() / count, md = cdk.sum() / count;
  cu -= mu;
  cv -= mv;
  cdk -= md;
  mean_u_ = mu;
  mean_v_ = mv;
  mean_dk_ = md;
}

float SampleConsensusModelRDMapPlane::centredC(const Eigen::VectorXf& model_coefficients) const {
  return static_cast<float>(model_coefficients[2] + model_coefficients[0] * mean_u_ +
                            model_coefficients[1] * mean_v_ - mean_dk_);
}

void SampleConsensusModelRDMapPlane::setSeed(unsigned seed) {
  rng_alg_.seed(seed);
  shuffled_indices_ = *indices_;  // the draws also depend on the order of the shuffled indices
}

bool SampleConsensusModelRDMapPlane::isSampleGood(const pcl::Indices& samples) const {
  if (samples.size() != kSampleSize) return false;
  const PointRDM& p0 = (*input_)[samples[0]];
  const PointRDM& p1 = (*input_)[samples[1]];
  const PointRDM& p2 = (*input_)[samples[2]];
  if (!isValidRDMPoint(p0) || !isValidRDMPoint(p1) || !isValidRDMPoint(p2)) return false;
  // Sec. III-B: "three points at random in different slits".
  if (p0.slit == p1.slit || p0.slit == p2.slit || p1.slit == p2.slit) return false;
  // Not collinear in (u, v): the sine of the angle at p0 must not vanish.
  const double du1 = p1.u - p0.u, dv1 = p1.v - p0.v;
  const double du2 = p2.u - p0.u, dv2 = p2.v - p0.v;
  const double cross = du1 * dv2 - dv1 * du2;
  const double lengths = std::sqrt((du1 * du1 + dv1 * dv1) * (du2 * du2 + dv2 * dv2));
  return std::abs(cross) > 1e-6 * lengths && lengths > 0.0;
}

bool SampleConsensusModelRDMapPlane::computeModelCoefficients(
    const pcl::Indices& samples, Eigen::VectorXf& model_coefficients) const {
  if (!isSampleGood(samples)) return false;
  const PointRDM& p0 = (*input_)[samples[0]];
  const PointRDM& p1 = (*input_)[samples[1]];
  const PointRDM& p2 = (*input_)[samples[2]];
  // eq. (1) through the three points, relative to p0:
  // A du_i + B dv_i = ddk_i (i = 1, 2), C = dk_0 - A u_0 - B v_0 (Cramer's rule).
  const double du1 = p1.u - p0.u, dv1 = p1.v - p0.v, ddk1 = p1.dk - p0.dk;
  const double du2 = p2.u - p0.u, dv2 = p2.v - p0.v, ddk2 = p2.dk - p0.dk;
  const double det = du1 * dv2 - dv1 * du2;
  const double a = (ddk1 * dv2 - dv1 * ddk2) / det;
  const double b = (du1 * ddk2 - ddk1 * du2) / det;
  const double c = p0.dk - a * p0.u - b * p0.v;
  if (!std::isfinite(a) || !std::isfinite(b) || !std::isfinite(c)) return false;
  model_coefficients.resize(kModelSize);
  model_coefficients << static_cast<float>(a), static_cast<float>(b), static_cast<float>(c);
  return true;
}

void SampleConsensusModelRDMapPlane::optimizeModelCoefficients(
    const pcl::Indices& inliers, const Eigen::VectorXf& model_coefficients,
    Eigen::VectorXf& optimized_coefficients) const {
  optimized_coefficients = model_coefficients;
  if (model_coefficients.size() != kModelSize || !isModelValid(model_coefficients)) return;
  // eq. (2): least-squares plane through the inliers.
  const RDMapPlaneFit fit = fitRDMapPlane(*input_, inliers);
  if (!fit.ok) return;
  const Eigen::VectorXf refit = fit.plane.cast<float>();
  if (isModelValid(refit)) optimized_coefficients = refit;
}

void SampleConsensusModelRDMapPlane::getDistancesToModel(const Eigen::VectorXf& model_coefficients,
                                                         std::vector<double>& distances) const {
  if (model_coefficients.size() != kModelSize || !isModelValid(model_coefficients)) {
    distances.clear();
    return;
  }
  const float a = model_coefficients[0], b = model_coefficients[1], c = model_coefficients[2];
  const std::size_t n = indices_->size();
  distances.resize(n);
  if (cached()) {
    const float cc = centredC(model_coefficients);
    for (std::size_t k = 0; k < n; ++k)
      distances[k] = std::abs(dk_[k] - (a * u_[k] + b * v_[k] + cc));
    return;
  }
  for (std::size_t k = 0; k < n; ++k) {
    const float r = std::abs(planeResidual((*input_)[(*indices_)[k]], a, b, c));
    distances[k] = std::isfinite(r) ? r : std::numeric_limits<double>::infinity();
  }
}

void SampleConsensusModelRDMapPlane::selectWithinDistance(const Eigen::VectorXf& model_coefficients,
                                                          const double threshold,
                                                          pcl::Indices& inliers) {
  inliers.clear();
  error_sqr_dists_.clear();
  if (model_coefficients.size() != kModelSize || !isModelValid(model_coefficients)) return;
  const float a = model_coefficients[0], b = model_coefficients[1], c = model_coefficients[2];
  const float t = static_cast<float>(threshold);
  const std::size_t n = indices_->size();
  const bool in_cache = cached();
  const float cc = centredC(model_coefficients);
  inliers.reserve(n);
  error_sqr_dists_.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const float r = std::abs(in_cache ? dk_[k] - (a * u_[k] + b * v_[k] + cc)
                                      : planeResidual((*input_)[(*indices_)[k]], a, b, c));
    if (r <= t) {  // false for NaN
      inliers.push_back((*indices_)[k]);
      error_sqr_dists_.push_back(static_cast<double>(r) * r);
    }
  }
}

std::size_t SampleConsensusModelRDMapPlane::countWithinDistance(
    const Eigen::VectorXf& model_coefficients, const double threshold) const {
  if (model_coefficients.size() != kModelSize || !isModelValid(model_coefficients)) return 0;
  const float a = model_coefficients[0], b = model_coefficients[1], c = model_coefficients[2];
  const float t = static_cast<float>(threshold);
  if (cached()) {  // the hot loop of RANSAC: contiguous floats, vectorized by the compiler
    const float* u = u_.data();
    const float* v = v_.data();
    const float* dk = dk_.data();
    return simd::countNear(u, v, dk, 0, u_.size(), a, b, centredC(model_coefficients), t);
  }
  std::size_t count = 0;
  for (const auto i : *indices_) count += std::abs(planeResidual((*input_)[i], a, b, c)) <= t;
  return count;
}

std::size_t SampleConsensusModelRDMapPlane::countWithinDistanceIfMore(
    const Eigen::VectorXf& model_coefficients, const double threshold, std::size_t best) const {
  if (!cached()) return countWithinDistance(model_coefficients, threshold);
  if (model_coefficients.size() != kModelSize || !isModelValid(model_coefficients)) return 0;
  const float a = model_coefficients[0], b = model_coefficients[1];
  const float cc = centredC(model_coefficients), t = static_cast<float>(threshold);
  const float* u = u_.data();
  const float* v = v_.data();
  const float* dk = dk_.data();
  const std::size_t n = u_.size();
  constexpr std::size_t kBlock = 256;  // points counted between two checks
  std::size_t count = 0;
  for (std::size_t begin = 0; begin < n; begin += kBlock) {
    const std::size_t end = std::min(n, begin + kBlock);
    count += simd::countNear(u, v, dk, begin, end, a, b, cc, t);
    if (count + (n - end) <= best) return count;  // cannot beat `best` any more
  }
  return count;
}

void SampleConsensusModelRDMapPlane::projectPoints(const pcl::Indices& inliers,
                                                   const Eigen::VectorXf& model_coefficients,
                                                   PointCloud& projected_points,
                                                   bool copy_data_fields) const {
  if (model_coefficients.size() != kModelSize || !isModelValid(model_coefficients)) return;
  const float a = model_coefficients[0], b = model_coefficients[1], c = model_coefficients[2];
  const auto onPlane = [&](PointRDM& p) {
    if (isValidRDMPoint(p)) p.dk = a * p.u + b * p.v + c;
  };
  if (copy_data_fields) {
    projected_points = *input_;
    for (const auto i : inliers) onPlane(projected_points[i]);
    return;
  }
  projected_points.header = input_->header;
  projected_points.resize(inliers.size());
  projected_points.width = static_cast<std::uint32_t>(inliers.size());
  projected_points.height = 1;
  projected_points.is_dense = input_->is_dense;
  for (std::size_t k = 0; k < inliers.size(); ++k) {
    projected_points[k] = (*input_)[inliers[k]];
    onPlane(projected_points[k]);
  }
}

bool SampleConsensusModelRDMapPlane::doSamplesVerifyModel(const std::set<pcl::index_t>& indices,
                                                          const Eigen::VectorXf& model_coefficients,
                                                          const double threshold) const {
  if (model_coefficients.size() != kModelSize || !isModelValid(model_coefficients)) return false;
  const float a = model_coefficients[0], b = model_coefficients[1], c = model_coefficients[2];
  for (const auto i : indices)
    if (!(std::abs(planeResidual((*input_)[i], a, b, c)) <= threshold)) return false;
  return true;
}

}  // namespace multislit
