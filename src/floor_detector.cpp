#include "multislit/floor_detector.h"

#include "multislit/plane_model.h"

#include "config_check.h"
#include "rdm_simd.h"
#include "slit_scale.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

namespace multislit {

namespace {

/// Sec. III-B: q planes through three points of three different slits; the plane with the most
/// points within `threshold` wins. With `local_refit`, each new best plane is replaced by the
/// least-squares plane (eq. 2) of its inliers when that holds more points (LO-RANSAC): a plane
/// through three noisy points is tilted, and the tilt grows with the distance from them. Returns
/// false when no plane could be drawn.
bool ransac(SampleConsensusModelRDMapPlane& model, int q, double threshold, bool local_refit,
            Eigen::VectorXf& best, int& iterations) {
  std::size_t best_count = 0;
  Eigen::VectorXf candidate(3);
  pcl::Indices sample;
  for (iterations = 0; iterations < q; ++iterations) {
    int unused = iterations;
    model.getSamples(unused, sample);
    if (sample.empty()) break;  // not three valid points on three slits
    if (!model.computeModelCoefficients(sample, candidate)) continue;
    const std::size_t count = model.countWithinDistanceIfMore(candidate, threshold, best_count);
    if (count <= best_count) continue;
    best_count = count;
    best = candidate;
    if (!local_refit) continue;
    const RDMapPlaneFit fit = model.fitWithinDistance(candidate, threshold);
    if (!fit.ok) continue;
    const Eigen::VectorXf refit = fit.plane.cast<float>();
    const std::size_t refit_count = model.countWithinDistanceIfMore(refit, threshold, best_count);
    if (refit_count > best_count) {
      best_count = refit_count;
      best = refit;
    }
  }
  return best_count > 0;
}

/// Every valid point of the model is floor (|residual| <= threshold) or obstacle.
void split(const pcl::PointCloud<PointRDM>& cloud, const pcl::Indices& valid, double threshold,
           FloorResult& result) {
  const float a = static_cast<float>(result.plane[0]);
  const float b = static_cast<float>(result.plane[1]);
  const float c = static_cast<float>(result.plane[2]);
  const float t = static_cast<float>(threshold);
  const std::size_t n = valid.size();
  result.inliers.resize(n);
  // The obstacles, a few of the points, first into buffers kept from frame to frame (one per
  // thread): full-length lists of the result would be allocated, zeroed and cut on every frame.
  thread_local std::vector<pcl::index_t> obstacle_buffer;
  thread_local std::vector<float> residual_buffer;
  if (obstacle_buffer.size() < n) obstacle_buffer.resize(n);
  if (residual_buffer.size() < n) residual_buffer.resize(n);
  const PointRDM* points = cloud.points.data();
  pcl::index_t* inliers = result.inliers.data();
  pcl::index_t* obstacles = obstacle_buffer.data();
  float* residuals = residual_buffer.data();
  std::size_t floor = 0, off = 0;
  double sum_sq = 0.0;
  // Branch-free: each point is written to both lists, and the one it belongs to moves on.
  const auto place = [&](pcl::index_t i, float r) {
    const bool in = std::abs(r) <= t;
    inliers[floor] = i;
    obstacles[off] = i;
    residuals[off] = r;
    const double r_in = r * static_cast<float>(in);  // 0 for an obstacle, without a branch
    sum_sq += r_in * r_in;
    floor += in;
    off += !in;
  };
  // Four points at a time, with the float operations of the one-point residual below: when all
  // four are floor (nearly always), their indices go to the floor in one store.
  const __m128 va = _mm_set1_ps(a), vb = _mm_set1_ps(b), vc = _mm_set1_ps(c), vt = _mm_set1_ps(t);
  const __m128 sign = _mm_set1_ps(-0.0f);
  std::size_t k = 0;
  for (; k + 4 <= n; k += 4) {
    const pcl::index_t* ids = valid.data() + k;
    const simd::UVDK4 p =
        simd::loadUVDK(points[ids[0]], points[ids[1]], points[ids[2]], points[ids[3]]);
    const __m128 r = simd::planeResiduals(p, va, vb, vc);
    const int in = _mm_movemask_ps(_mm_cmple_ps(_mm_andnot_ps(sign, r), vt));
    alignas(16) float lr[4];
    _mm_store_ps(lr, r);
    if (in != 0xf) {
      for (int j = 0; j < 4; ++j) place(ids[j], lr[j]);
      continue;
    }
    std::memcpy(inliers + floor, ids, 4 * sizeof *ids);
    floor += 4;
    for (int j = 0; j < 4; ++j) sum_sq += static_cast<double>(lr[j]) * lr[j];  // in order
  }
  for (; k < n; ++k) {
    const PointRDM& p = points[valid[k]];
    place(valid[k], planeResidual(p, a, b, c));
  }
  // Before any call, which would make the compiler keep the sum in memory throughout the loop.
  if (floor > 0) result.residual_std = std::sqrt(sum_sq / static_cast<double>(floor));
  result.inliers.resize(floor);
  result.obstacles.assign(obstacles, obstacles + off);
  result.obstacle_residuals.assign(residuals, residuals + off);
}

/// |dk - (A u + B v + C)| of the valid points below `band`, counted in kBins equal bins: the
/// medians below any cut come from it without sorting. The estimate adds 12 to 19 us to the
/// 36 to 42 us of a 4476-point rendered frame's detect(); two nth_element passes added 50 to 60.
struct ResidualHistogram {
  static constexpr std::size_t kBins = 4096;  // 0.73e-3 px wide for the default 3 px band
  double width = 0.0;                         ///< [px]
  std::array<std::uint32_t, kBins> counts{};
};

ResidualHistogram residualHistogram(const pcl::PointCloud<PointRDM>& cloud,
                                    const pcl::Indices& valid, const Eigen::Vector3d& plane,
                                    double band) {
  ResidualHistogram h;
  h.width = band / static_cast<double>(ResidualHistogram::kBins);
  const float a = static_cast<float>(plane[0]), b = static_cast<float>(plane[1]),
              c = static_cast<float>(plane[2]), scale = static_cast<float>(1.0 / h.width);
  const auto bins = static_cast<float>(ResidualHistogram::kBins);
  const PointRDM* points = cloud.points.data();
  const pcl::index_t* ids = valid.data();
  const std::size_t n = valid.size();
  // Four points at a time with the float operations of the one-point bin below (float like
  // split()); a lane beyond the band adds to bin 0 nothing.
  const __m128 va = _mm_set1_ps(a), vb = _mm_set1_ps(b), vc = _mm_set1_ps(c);
  const __m128 vscale = _mm_set1_ps(scale), vbins = _mm_set1_ps(bins), sign = _mm_set1_ps(-0.0f);
  std::size_t k = 0;
  for (; k + 4 <= n; k += 4) {
    const simd::UVDK4 p =
        simd::loadUVDK(points[ids[k]], points[ids[k + 1]], points[ids[k + 2]], points[ids[k + 3]]);
    const __m128 bin = _mm_mul_ps(_mm_andnot_ps(sign, simd::planeResiduals(p, va, vb, vc)), vscale);
    const int in = _mm_movemask_ps(_mm_cmplt_ps(bin, vbins));
    alignas(16) std::int32_t at[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(at), _mm_cvttps_epi32(bin));
    for (int j = 0; j < 4; ++j) {
      const bool inside = (in >> j) & 1;
      h.counts[inside ? static_cast<std::size_t>(at[j]) : 0] += inside;
    }
  }
  for (; k < n; ++k) {
    const float bin = std::abs(planeResidual(points[ids[k]], a, b, c)) * scale;
    if (bin < bins) ++h.counts[static_cast<std::size_t>(bin)];
  }
  return h;
}

/// The sigma of a zero-mean Gaussian whose |values| cut at `band` have the median `mad`: solves
/// erf(mad / (sigma sqrt 2)) = erf(band / (sigma sqrt 2)) / 2 by bisection. Without the cut,
/// sigma = 1.4826 mad; the cut makes the median smaller, so the root lies above that.
/// Returns infinity when mad >= band / 2 (as uniform as the band allows, or wider).
double sigmaFromCutMad(double mad, double band) {
  if (!(mad < 0.5 * band)) return std::numeric_limits<double>::infinity();
  if (mad <= 0.0) return 0.0;
  const double sqrt2 = std::sqrt(2.0);
  const auto median_share = [&](double sigma) {  // decreasing in sigma, from 1 to mad / band
    return std::erf(mad / (sigma * sqrt2)) / std::erf(band / (sigma * sqrt2));
  };
  double lo = 1.4826 * mad, hi = lo;
  if (median_share(lo) < 0.5 + 1e-9) return lo;  // the cut is too far out to matter
  while (median_share(hi) > 0.5) hi *= 2.0;
  for (int i = 0; i < 40; ++i) {  // to 1e-12 of sigma
    const double mid = 0.5 * (lo + hi);
    (median_share(mid) > 0.5 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

/// Robust sigma of the |residuals| below `cut` (taken down to a bin edge): their median,
/// interpolated within its bin, corrected for the cut. NaN with fewer than 3 of them.
double bandSigma(const ResidualHistogram& h, double cut) {
  const std::size_t bins =
      std::min(ResidualHistogram::kBins, static_cast<std::size_t>(cut / h.width));
  const auto total = static_cast<double>(std::accumulate(
      h.counts.begin(), h.counts.begin() + static_cast<std::ptrdiff_t>(bins), std::uint64_t{0}));
  if (total < 3.0) return std::numeric_limits<double>::quiet_NaN();
  double below = 0.0;
  std::size_t k = 0;
  while (below + h.counts[k] < 0.5 * total) below += h.counts[k++];
  const double median = (static_cast<double>(k) + (0.5 * total - below) / h.counts[k]) * h.width;
  return sigmaFromCutMad(median, static_cast<double>(bins) * h.width);
}

/// This frame's floor noise from its residuals about `plane`: first within band_sigmas *
/// max_sigma, which leaves out the gross obstacles, then within band_sigmas times that first
/// estimate, which leaves out most of a heavy tail. NaN when too few points lie near the plane.
double estimateSigma(const pcl::PointCloud<PointRDM>& cloud, const pcl::Indices& valid,
                     const Eigen::Vector3d& plane, const FloorDetectorConfig& config) {
  const double band = config.band_sigmas * config.max_sigma;
  const ResidualHistogram h = residualHistogram(cloud, valid, plane, band);
  const double wide = bandSigma(h, band);
  if (!std::isfinite(wide)) return wide;
  const double narrow = bandSigma(h, std::min(band, config.band_sigmas * wide));
  return std::isnan(narrow) ? wide : narrow;
}

/// The sigma and threshold of this frame into `result` (the configured sigma when estimate_sigma is
/// false), and `fit` (eq. 2 with the configured threshold) refit on the points within the frame's
/// threshold when that differs.
void adoptFrameNoise(SampleConsensusModelRDMapPlane& model, const FloorDetectorConfig& config,
                     RDMapPlaneFit& fit, FloorResult& result) {
  result.sigma = config.sigma;
  if (config.estimate_sigma) {
    result.sigma_estimate =
        estimateSigma(*model.getInputCloud(), *model.getIndices(), fit.plane, config);
    if (!std::isnan(result.sigma_estimate))
      result.sigma = std::clamp(result.sigma_estimate, config.min_sigma, config.max_sigma);
  }
  result.threshold = config.threshold_sigmas * result.sigma;
  if (result.threshold == config.threshold()) return;
  const RDMapPlaneFit refit = model.fitWithinDistance(fit.plane.cast<float>(), result.threshold);
  if (refit.ok) fit = refit;
}

/// Step 6: the floor points that their windows of rows put off the floor become obstacles.
void addRunObstacles(const pcl::PointCloud<PointRDM>& cloud, const FloorDetectorConfig& config,
                     FloorResult& result) {
  detail::SlitScaleOff off =
      detail::offFloorAtScales(cloud, result.inliers, result.plane, config.min_window,
                               config.max_window, config.window_sigmas, config.min_window_shift);
  result.window_noise = std::move(off.sigmas);
  if (off.points.empty()) return;
  // Both lists in the order of the inliers: one pass takes them out, the inliers between two of
  // them moved as one block.
  pcl::index_t* inliers = result.inliers.data();
  const std::size_t n = result.inliers.size();
  std::size_t from = 0, kept = 0;
  double removed_sq = 0.0;
  for (std::size_t next = 0; next < off.points.size(); ++next) {
    const std::size_t at = static_cast<std::size_t>(
        std::find(inliers + from, inliers + n, off.points[next]) - inliers);
    if (at == n) break;  // not an inlier (cannot happen: they are taken from the inliers)
    std::memmove(inliers + kept, inliers + from, (at - from) * sizeof *inliers);
    kept += at - from;
    from = at + 1;
    removed_sq += static_cast<double>(off.residuals[next]) * off.residuals[next];
  }
  std::memmove(inliers + kept, inliers + from, (n - from) * sizeof *inliers);
  kept += n - from;
  const double floor_sq =
      result.residual_std * result.residual_std * static_cast<double>(result.inliers.size());
  result.inliers.resize(kept);
  if (kept > 0)
    result.residual_std =
        std::sqrt(std::max(0.0, floor_sq - removed_sq) / static_cast<double>(kept));
  result.obstacles.insert(result.obstacles.end(), off.points.begin(), off.points.end());
  result.obstacle_residuals.insert(result.obstacle_residuals.end(), off.residuals.begin(),
                                   off.residuals.end());
  result.run_obstacles = off.points.size();
}

FloorResult detectWith(SampleConsensusModelRDMapPlane& model, const FloorDetectorConfig& config,
                       int q) {
  FloorResult result;
  const pcl::Indices& valid = *model.getIndices();
  result.valid_points = valid.size();
  if (result.valid_points < static_cast<std::size_t>(config.min_points)) return result;
  model.setSeed(config.seed);

  // 1. RANSAC with q iterations (eq. 3) and the configured threshold, 3 sigma.
  Eigen::VectorXf best;
  if (!ransac(model, q, config.threshold(), config.local_refit, best, result.iterations))
    return result;

  // 2. eq. (2): least-squares refit on the inliers of the best plane.
  RDMapPlaneFit fit = model.fitWithinDistance(best, config.threshold());
  if (!fit.ok) return result;

  // 3. This frame's noise and threshold; eq. (2) again on the points within that threshold.
  adoptFrameNoise(model, config, fit, result);
  result.plane = fit.plane;

  // 4. Floor or obstacle, for every valid point, against the refit plane.
  split(*model.getInputCloud(), valid, result.threshold, result);

  // 5. Fail safe: a plane carrying too few of the points is no floor.
  if (static_cast<double>(result.inliers.size()) <
      config.min_inlier_ratio * static_cast<double>(result.valid_points)) {
    FloorResult not_found;
    not_found.valid_points = result.valid_points;
    not_found.iterations = result.iterations;
    return not_found;
  }
  result.found = true;

  // 6. Runs along the slits: floor points whose window of rows lies off the floor.
  if (config.multiscale) addRunObstacles(*model.getInputCloud(), config, result);
  return result;
}

/// detectWith() on the model of this thread, given `cloud` (and `indices`) for this call only. The
/// model is kept from frame to frame: building one per frame (PCL's sampler and its seeding, the
/// index and point arrays) took about a tenth of the stage. detectWith() reseeds its draws, so
/// each frame's result is that of a new model.
FloorResult detectOnThreadModel(const pcl::PointCloud<PointRDM>::ConstPtr& cloud,
                                const pcl::Indices* indices, const FloorDetectorConfig& config,
                                int q) {
  thread_local SampleConsensusModelRDMapPlane model{pcl::PointCloud<PointRDM>::ConstPtr()};
  struct Release {  // the model holds no cloud between calls, also when one throws
    SampleConsensusModelRDMapPlane& model;
    ~Release() { model.setInputCloud(nullptr); }
  } release{model};
  if (indices)
    model.setInputCloud(cloud, *indices);
  else
    model.setInputCloud(cloud);
  return detectWith(model, config, q);
}

}  // namespace

int ransacIterations(double probability, double outlier_ratio, int sample_size) {
  if (!(probability > 0.0 && probability < 1.0))
    throw std::invalid_argument("ransacIterations: probability must be in (0, 1)");
  if (!(outlier_ratio >= 0.0 && outlier_ratio < 1.0))
    throw std::invalid_argument("ransacIterations: outlier_ratio must be in [0, 1)");
  if (sample_size < 1) throw std::invalid_argument("ransacIterations: sample_size must be >= 1");
  const double clean_sample = std::pow(1.0 - outlier_ratio, sample_size);
  if (clean_sample >= 1.0) return 1;
  const double q = std::ceil(std::log(1.0 - probability) / std::log(1.0 - clean_sample));
  return static_cast<int>(std::clamp(q, 1.0, 1e9));
}

int FloorDetectorConfig::iterations() const {
  return max_iterations > 0 ? max_iterations : ransacIterations(probability, outlier_ratio);
}

void FloorDetectorConfig::validate() const {
  constexpr detail::FieldCheck require("FloorDetectorConfig");
  require(sigma > 0.0 && std::isfinite(sigma), "sigma", "must be > 0 [px]");
  require(threshold_sigmas > 0.0 && std::isfinite(threshold_sigmas), "threshold_sigmas",
          "must be > 0");
  require(min_sigma > 0.0 && std::isfinite(min_sigma), "min_sigma", "must be > 0 [px]");
  require(max_sigma >= min_sigma && std::isfinite(max_sigma), "max_sigma",
          "must be >= min_sigma [px]");
  require(band_sigmas > 0.0 && std::isfinite(band_sigmas), "band_sigmas", "must be > 0");
  require(probability > 0.0 && probability < 1.0, "probability", "must be in (0, 1)");
  require(outlier_ratio >= 0.0 && outlier_ratio < 1.0, "outlier_ratio", "must be in [0, 1)");
  require(max_iterations >= 0 && max_iterations <= 1000000, "max_iterations",
          "must be in [0, 1000000] (0: from eq. 3)");
  require(min_points >= 3, "min_points", "must be >= 3 (a plane needs three points)");
  require(min_window >= 3 && min_window % 2 == 1, "min_window", "must be odd and >= 3 rows");
  require(max_window >= min_window, "max_window", "must be >= min_window rows");
  require(window_sigmas > 0.0 && std::isfinite(window_sigmas), "window_sigmas", "must be > 0");
  require(min_window_shift >= 0.0 && std::isfinite(min_window_shift), "min_window_shift",
          "must be >= 0 [px]");
  require(min_inlier_ratio >= 0.0 && min_inlier_ratio <= 1.0, "min_inlier_ratio",
          "must be in [0, 1]");
}

FloorDetector::FloorDetector(const FloorDetectorConfig& config) : config_(config) {
  config_.validate();
  iterations_ = config_.iterations();
}

FloorResult FloorDetector::detect(const pcl::PointCloud<PointRDM>::ConstPtr& cloud) const {
  if (!cloud) return {};
  return detectOnThreadModel(cloud, nullptr, config_, iterations_);
}

FloorResult FloorDetector::detect(const pcl::PointCloud<PointRDM>::ConstPtr& cloud,
                                  const pcl::Indices& indices) const {
  if (!cloud) return {};
  return detectOnThreadModel(cloud, &indices, config_, iterations_);
}

}  // namespace multislit
