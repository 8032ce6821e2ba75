#include "multislit/plane_detector.h"

#include "config_check.h"
#include "multislit/point_types.h"

#include <pcl/common/point_tests.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace multislit {

namespace {

/// The points taking part, copied once into a contiguous array, and their cloud indices.
struct Points {
  std::vector<Eigen::Vector3f> xyz;
  pcl::Indices ids;
};

/// Which side of a plane is up: along `up`, or else towards `viewpoint`.
struct Side {
  bool use_up = false;
  Eigen::Vector3f up = Eigen::Vector3f::Zero();
  Eigen::Vector3f viewpoint = Eigen::Vector3f::Zero();
};

constexpr double kLowest = -std::numeric_limits<double>::infinity();

float signedDistance(const Eigen::Vector4f& plane, const Eigen::Vector3f& p) {
  return plane[0] * p[0] + plane[1] * p[1] + plane[2] * p[2] + plane[3];
}

template <typename PointT>
Points gather(const pcl::PointCloud<PointT>& cloud, const pcl::Indices* indices) {
  Points points;
  const std::size_t n = indices ? indices->size() : cloud.size();
  points.xyz.reserve(n);
  points.ids.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const pcl::index_t i = indices ? (*indices)[k] : static_cast<pcl::index_t>(k);
    if (i < 0 || static_cast<std::size_t>(i) >= cloud.size())
      throw std::invalid_argument("PlaneDetector::detect: indices: " + std::to_string(i) +
                                  " is outside the cloud of " + std::to_string(cloud.size()));
    if (!pcl::isFinite(cloud[i])) continue;
    points.xyz.emplace_back(cloud[i].x, cloud[i].y, cloud[i].z);
    points.ids.push_back(i);
  }
  return points;
}

/// The plane through three points, unit normal; zero when they are (nearly) on a line.
Eigen::Vector4f planeThrough(const Eigen::Vector3f& a, const Eigen::Vector3f& b,
                             const Eigen::Vector3f& c) {
  Eigen::Vector3f normal = (b - a).cross(c - a);
  const float norm = normal.norm();
  if (!(norm > 1e-12f)) return Eigen::Vector4f::Zero();
  normal /= norm;
  return Eigen::Vector4f(normal[0], normal[1], normal[2], -normal.dot(a));
}

/// Turns the normal up; false when the sides are undefined (the viewpoint on the plane).
bool orient(Eigen::Vector4f& plane, const Side& side, float threshold) {
  const float s =
      side.use_up ? plane.head<3>().dot(side.up) : signedDistance(plane, side.viewpoint);
  if (s < 0.0f) plane = -plane;
  return side.use_up || std::abs(s) > threshold;
}

/// score = inliers - w * behind. Gives up (returns the lowest score) as soon as even all the
/// remaining points as inliers could not beat `best`: most candidates end after a block or two.
double score(const std::vector<Eigen::Vector3f>& xyz, const Eigen::Vector4f& plane, float threshold,
             double w, double best) {
  constexpr std::size_t kBlock = 4096;
  std::size_t inliers = 0, behind = 0;
  for (std::size_t start = 0; start < xyz.size(); start += kBlock) {
    const std::size_t end = std::min(xyz.size(), start + kBlock);
    for (std::size_t i = start; i < end; ++i) {
      const float d = signedDistance(plane, xyz[i]);
      inliers += std::abs(d) <= threshold;
      behind += d < -threshold;
    }
    const double so_far = static_cast<double>(inliers) - w * static_cast<double>(behind);
    if (so_far + static_cast<double>(xyz.size() - end) <= best) return kLowest;
  }
  return static_cast<double>(inliers) - w * static_cast<double>(behind);
}

/// Iterations for `probability` of one all-inlier sample when a share `ratio` are inliers.
double iterationsFor(double ratio, double probability) {
  const double clean = ratio * ratio * ratio;
  if (clean >= 1.0) return 1.0;
  if (clean <= 0.0) return std::numeric_limits<double>::infinity();
  return std::log(1.0 - probability) / std::log(1.0 - clean);
}

/// RANSAC: the candidate through three drawn points with the best score, its normal up.
Eigen::Vector4f bestCandidate(const std::vector<Eigen::Vector3f>& xyz,
                              const PlaneDetectorConfig& config, const Side& side) {
  std::mt19937 rng(config.seed);
  std::uniform_int_distribution<std::size_t> pick(0, xyz.size() - 1);
  const auto threshold = static_cast<float>(config.threshold);
  Eigen::Vector4f best = Eigen::Vector4f::Zero();
  double best_score = kLowest;
  double needed = config.max_iterations;
  for (int iteration = 0; iteration < config.max_iterations && iteration < needed; ++iteration) {
    const std::size_t a = pick(rng), b = pick(rng), c = pick(rng);
    Eigen::Vector4f plane = planeThrough(xyz[a], xyz[b], xyz[c]);
    if (plane.isZero()) continue;
    // A candidate through the viewpoint has no "behind": only its inliers count.
    const double w = orient(plane, side, threshold) ? config.behind_weight : 0.0;
    const double s = score(xyz, plane, threshold, w, best_score);
    if (s <= best_score) continue;
    best_score = s;
    best = plane;
    // A better plane holds more inliers than this score: enough draws to catch such a plane.
    needed = iterationsFor(std::max(0.0, s) / static_cast<double>(xyz.size()), config.probability);
  }
  return best;
}

/// Least-squares plane of the points within `threshold` of `plane` (the normal: the least
/// eigenvector of their covariance), on the same side as `plane`; `plane` if too few.
Eigen::Vector4f refit(const std::vector<Eigen::Vector3f>& xyz, const Eigen::Vector4f& plane,
                      float threshold) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  std::size_t n = 0;
  for (const Eigen::Vector3f& p : xyz)
    if (std::abs(signedDistance(plane, p)) <= threshold) {
      mean += p.cast<double>();
      ++n;
    }
  if (n < 3) return plane;
  mean /= static_cast<double>(n);
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3f& p : xyz)
    if (std::abs(signedDistance(plane, p)) <= threshold) {
      const Eigen::Vector3d q = p.cast<double>() - mean;
      covariance += q * q.transpose();
    }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  Eigen::Vector3d normal = solver.eigenvectors().col(0);
  if (normal.dot(plane.head<3>().cast<double>()) < 0.0) normal = -normal;
  return Eigen::Vector4d(normal[0], normal[1], normal[2], -normal.dot(mean)).cast<float>();
}

/// Inliers, above and below of `plane` into `result`.
void classify(const Points& points, const Eigen::Vector4f& plane, float threshold,
              PlaneResult& result) {
  for (std::size_t k = 0; k < points.xyz.size(); ++k) {
    const float d = signedDistance(plane, points.xyz[k]);
    if (std::abs(d) <= threshold)
      result.inliers.push_back(points.ids[k]);
    else if (d > threshold)
      result.above.push_back(points.ids[k]);
    else
      result.below.push_back(points.ids[k]);
  }
}

template <typename PointT>
PlaneResult detectPlane(const PlaneDetectorConfig& config, const pcl::PointCloud<PointT>& cloud,
                        const pcl::Indices* indices) {
  PlaneResult result;
  // 1. Only finite points (of the indices) take part.
  const Points points = gather(cloud, indices);
  result.finite_points = points.xyz.size();
  if (points.xyz.size() < static_cast<std::size_t>(config.min_points)) return result;
  const Side side{!config.up.isZero(), config.up, cloud.sensor_origin_.template head<3>()};
  const auto threshold = static_cast<float>(config.threshold);

  // 2. RANSAC scored by inliers and points behind, then two least-squares refits on the inliers.
  Eigen::Vector4f plane = bestCandidate(points.xyz, config, side);
  if (plane.isZero()) return result;
  for (int round = 0; round < 2; ++round) plane = refit(points.xyz, plane, threshold);
  const bool sides_defined = orient(plane, side, threshold);

  // 3. On the plane, above it, or behind it; a plane carrying too few points is no plane.
  classify(points, plane, threshold, result);
  if (static_cast<double>(result.inliers.size()) <
      config.min_inlier_ratio * static_cast<double>(result.finite_points)) {
    result = PlaneResult{};
    result.finite_points = points.xyz.size();
    return result;
  }
  result.coefficients = plane;
  // 4. Seen from a viewpoint on the plane, nothing is above or below it: say so, find nothing.
  if (!sides_defined) {
    result.viewpoint_on_plane = true;
    result.above.clear();
    result.below.clear();
    return result;
  }
  result.found = true;
  return result;
}

}  // namespace

void PlaneDetectorConfig::validate() const {
  constexpr detail::FieldCheck require("PlaneDetectorConfig");
  require(threshold > 0.0 && std::isfinite(threshold), "threshold", "must be > 0 [m]");
  require(max_iterations >= 1, "max_iterations", "must be >= 1");
  require(probability > 0.0 && probability < 1.0, "probability", "must be in (0, 1)");
  require(min_points >= 3, "min_points", "must be >= 3 (a plane needs three points)");
  require(min_inlier_ratio >= 0.0 && min_inlier_ratio <= 1.0, "min_inlier_ratio",
          "must be in [0, 1]");
  require(behind_weight >= 0.0 && std::isfinite(behind_weight), "behind_weight",
          "must be finite and >= 0 (0: plain RANSAC)");
  require(up.allFinite(), "up", "must be finite (zero: towards the sensor origin)");
}

PlaneDetector::PlaneDetector(const PlaneDetectorConfig& config) : config_(config) {
  config_.validate();
}

template <typename PointT>
PlaneResult PlaneDetector::detect(const pcl::PointCloud<PointT>& cloud) const {
  return detectPlane(config_, cloud, nullptr);
}

template <typename PointT>
PlaneResult PlaneDetector::detect(const pcl::PointCloud<PointT>& cloud,
                                  const pcl::Indices& indices) const {
  return detectPlane(config_, cloud, &indices);
}

// The point types users link against without PCL_NO_PRECOMPILE.
#define MULTISLIT_PLANE_DETECTOR_INSTANTIATE(PointT)                                        \
  template PlaneResult PlaneDetector::detect<PointT>(const pcl::PointCloud<PointT>&) const; \
  template PlaneResult PlaneDetector::detect<PointT>(const pcl::PointCloud<PointT>&,        \
                                                     const pcl::Indices&) const;
MULTISLIT_PLANE_DETECTOR_INSTANTIATE(pcl::PointXYZ)
MULTISLIT_PLANE_DETECTOR_INSTANTIATE(pcl::PointXYZI)
MULTISLIT_PLANE_DETECTOR_INSTANTIATE(pcl::PointXYZRGB)
MULTISLIT_PLANE_DETECTOR_INSTANTIATE(pcl::PointXYZRGBA)
MULTISLIT_PLANE_DETECTOR_INSTANTIATE(pcl::PointXYZRGBL)
MULTISLIT_PLANE_DETECTOR_INSTANTIATE(pcl::PointNormal)
MULTISLIT_PLANE_DETECTOR_INSTANTIATE(PointRDM)
#undef MULTISLIT_PLANE_DETECTOR_INSTANTIATE

}  // namespace multislit
