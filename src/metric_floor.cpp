// fitMetricFloor (multislit/obstacles.h): the floor's least-squares plane in x, y, z, from sums
// over its inliers taken in float lanes. Two ways to the same bits: four lanes a point (SSE), or
// where the CPU has AVX2 both sets of lanes in one vector.
#include "multislit/obstacles.h"

#include <immintrin.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace multislit {

namespace {

/// The sums over the points with x, y, z among points[indices[0 .. n)] of x, y, z, of their squares
/// (xx, yy, zz) and of their cross products (xy, yz, zx), taken about (x0, y0, z0) so that they
/// stay small.
struct MetricSums {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), squares = Eigen::Vector3d::Zero(),
                  cross = Eigen::Vector3d::Zero();
  std::size_t points = 0;
};

/// Points added in float before the partial sums go to double: keeps the sums accurate to ~1e-7.
constexpr std::size_t kFlushPoints = 64;

/// Adds lanes 0 .. 2 of the partial sums of the even and of the odd points of a block to `total`.
void addLanePairs(Eigen::Vector3d& total, const float* even, const float* odd) {
  for (int axis = 0; axis < 3; ++axis) total[axis] += static_cast<double>(even[axis]) + odd[axis];
}

/// One pass in float with four lanes (x, y, z, 0) per point, added to double every kFlushPoints.
/// Two sets of lanes take the points in turn, so that each add need not wait for the one before.
MetricSums sumAboutOrigin(const PointRDM* points, const pcl::index_t* indices, std::size_t n,
                          float x0, float y0, float z0) {
  typedef float F4 __attribute__((vector_size(16)));
  typedef std::int32_t I4 __attribute__((vector_size(16)));
  const I4 xyz = {-1, -1, -1, 0};
  const F4 origin = {x0, y0, z0, 0.0f};
  struct Lanes {
    F4 sum = {}, squares = {}, cross = {};
    I4 valid = {};
  };
  // p minus the origin, as (x, y, z, 0); (0, 0, 0, 0) when p has no x, y, z, which adds nothing.
  // hasXYZ() without a branch: q - q is 0 in each finite lane, NaN in the others, and a lane of
  // `keep` is set when x, y and z all are.
  const auto add = [&](Lanes& lanes, const PointRDM& p) {
    F4 q;  // (x, y, z, data[3])
    std::memcpy(&q, p.data, sizeof q);
    const I4 finite = q - q == F4{};
    const I4 keep = finite & __builtin_shufflevector(finite, finite, 1, 2, 0, 3) &
                    __builtin_shufflevector(finite, finite, 2, 0, 1, 3) & xyz;
    const F4 d = (F4)((I4)(q - origin) & keep);
    lanes.sum += d;
    lanes.squares += d * d;
    lanes.cross += d * __builtin_shufflevector(d, d, 1, 2, 0, 3);  // (xy, yz, zx, 0)
    lanes.valid -= keep;  // lane 0: 1 per point with x, y, z
  };
  MetricSums out;
  for (std::size_t k = 0; k < n;) {
    Lanes even, odd;
    for (const std::size_t stop = std::min(n, k + kFlushPoints); k < stop; k += 2) {
      add(even, points[indices[k]]);
      if (k + 1 < stop) add(odd, points[indices[k + 1]]);
    }
    const auto lanes = [](const F4& v) { return reinterpret_cast<const float*>(&v); };
    addLanePairs(out.sum, lanes(even.sum), lanes(odd.sum));
    addLanePairs(out.squares, lanes(even.squares), lanes(odd.squares));
    addLanePairs(out.cross, lanes(even.cross), lanes(odd.cross));
    out.points += static_cast<std::size_t>(even.valid[0] + odd.valid[0]);
  }
  return out;
}

/// sumAboutOrigin() with the even points in lanes 0 .. 3 of one AVX vector and the odd ones in
/// lanes 4 .. 7: every lane sees the same float operations in the same order, in half the
/// instructions. Without AVX2's FMA (not enabled here) no product is fused into its sum.
__attribute__((target("avx2"))) MetricSums sumAboutOriginAvx2(const PointRDM* points,
                                                              const pcl::index_t* indices,
                                                              std::size_t n, float x0, float y0,
                                                              float z0) {
  const __m256 origin = _mm256_setr_ps(x0, y0, z0, 0.0f, x0, y0, z0, 0.0f);
  const __m256 xyz = _mm256_castsi256_ps(_mm256_setr_epi32(-1, -1, -1, 0, -1, -1, -1, 0));
  const __m256 zero = _mm256_setzero_ps();
  // The partner of a block's last even point when it has none: not finite, so it adds +0, which
  // leaves every partial sum as it is (they start at +0 and so never hold -0).
  const float none[4] = {std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f, 0.0f};
  constexpr int kRotate = _MM_SHUFFLE(3, 0, 2, 1);  // (y, z, x, w) in each half
  MetricSums out;
  for (std::size_t k = 0; k < n;) {
    __m256 sum = zero, squares = zero, cross = zero;
    for (const std::size_t stop = std::min(n, k + kFlushPoints); k < stop; k += 2) {
      const float* odd = k + 1 < stop ? points[indices[k + 1]].data : none;
      const __m256 q = _mm256_insertf128_ps(
          _mm256_castps128_ps256(_mm_loadu_ps(points[indices[k]].data)), _mm_loadu_ps(odd), 1);
      const __m256 finite = _mm256_cmp_ps(_mm256_sub_ps(q, q), zero, _CMP_EQ_OQ);
      __m256 d = _mm256_sub_ps(q, origin);
      // Nearly always both points have x, y, z: then lanes 0 .. 2 of each half are kept as they
      // are (lanes 3 and 7, data[3], are summed but never read).
      if ((_mm256_movemask_ps(finite) & 0x77) == 0x77) {
        out.points += 2;
      } else {
        const __m256 keep =
            _mm256_and_ps(_mm256_and_ps(finite, _mm256_permute_ps(finite, kRotate)),
                          _mm256_and_ps(_mm256_permute_ps(finite, _MM_SHUFFLE(3, 1, 0, 2)), xyz));
        d = _mm256_and_ps(d, keep);
        out.points += static_cast<std::size_t>(__builtin_popcount(_mm256_movemask_ps(keep)) / 3);
      }
      sum = _mm256_add_ps(sum, d);
      squares = _mm256_add_ps(squares, _mm256_mul_ps(d, d));
      cross = _mm256_add_ps(cross, _mm256_mul_ps(d, _mm256_permute_ps(d, kRotate)));
    }
    alignas(32) float lanes[3][8];
    _mm256_store_ps(lanes[0], sum);
    _mm256_store_ps(lanes[1], squares);
    _mm256_store_ps(lanes[2], cross);
    addLanePairs(out.sum, lanes[0], lanes[0] + 4);
    addLanePairs(out.squares, lanes[1], lanes[1] + 4);
    addLanePairs(out.cross, lanes[2], lanes[2] + 4);
  }
  return out;
}

bool metricSumsHaveAvx2() {
  static const bool yes = __builtin_cpu_supports("avx2");
  return yes;
}

}  // namespace

MetricFloor fitMetricFloor(const pcl::PointCloud<PointRDM>& cloud, const pcl::Indices& inliers) {
  MetricFloor floor;
  const std::size_t n = inliers.size();
  std::size_t first = 0;
  while (first < n && !hasXYZ(cloud[static_cast<std::size_t>(inliers[first])])) ++first;
  if (first == n) return floor;
  // The sums about the first floor point with x, y, z: it lies among the others.
  const PointRDM& o = cloud[static_cast<std::size_t>(inliers[first])];
  const auto sum = metricSumsHaveAvx2() ? sumAboutOriginAvx2 : sumAboutOrigin;
  const MetricSums sums =
      sum(cloud.points.data(), inliers.data() + first, n - first, o.x, o.y, o.z);
  floor.points = sums.points;
  if (floor.points < 3) return floor;
  const Eigen::Vector3d origin(o.x, o.y, o.z);
  const double count = static_cast<double>(floor.points);
  const Eigen::Vector3d mean = sums.sum / count;  // about the origin
  Eigen::Matrix3d covariance;
  covariance << sums.squares[0], sums.cross[0], sums.cross[2], sums.cross[0], sums.squares[1],
      sums.cross[1], sums.cross[2], sums.cross[1], sums.squares[2];
  covariance = covariance / count - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  // The plane's normal is the axis of least spread; the two others must spread (not a line).
  if (eigen.eigenvalues()(1) <= 1e-12) return floor;
  floor.normal = eigen.eigenvectors().col(0).normalized();
  floor.offset = -floor.normal.dot(mean + origin);
  if (floor.offset < 0) {  // the camera (the origin) is above the floor
    floor.normal = -floor.normal;
    floor.offset = -floor.offset;
  }
  floor.valid = true;
  return floor;
}

}  // namespace multislit
