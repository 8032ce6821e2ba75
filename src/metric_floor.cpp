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

/// The float partial sums of one block of up to kFlushPoints points, in AVX lanes: the even points
/// in lanes 0 .. 3, the odd ones in lanes 4 .. 7 (lanes 3 and 7, data[3], are summed but never
/// read).
struct BlockLanes {
  __m256 sum, squares, cross;
};

/// Adds the points `even` and `odd` (two floats a point's x, y, z, data[3]) about `origin` to
/// `lanes`, as sumAboutOrigin() does; returns how many of the two have x, y, z.
__attribute__((target("avx2"), always_inline)) inline std::size_t addPair(BlockLanes& lanes,
                                                                          const float* even,
                                                                          const float* odd,
                                                                          const __m256& origin) {
  const __m256 xyz = _mm256_castsi256_ps(_mm256_setr_epi32(-1, -1, -1, 0, -1, -1, -1, 0));
  const __m256 zero = _mm256_setzero_ps();
  constexpr int kRotate = _MM_SHUFFLE(3, 0, 2, 1);  // (y, z, x, w) in each half
  const __m256 q =
      _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(even)), _mm_loadu_ps(odd), 1);
  const __m256 finite = _mm256_cmp_ps(_mm256_sub_ps(q, q), zero, _CMP_EQ_OQ);
  __m256 d = _mm256_sub_ps(q, origin);
  std::size_t points = 2;  // nearly always both points have x, y, z: lanes 0 .. 2 kept as they are
  if ((_mm256_movemask_ps(finite) & 0x77) != 0x77) {
    const __m256 keep =
        _mm256_and_ps(_mm256_and_ps(finite, _mm256_permute_ps(finite, kRotate)),
                      _mm256_and_ps(_mm256_permute_ps(finite, _MM_SHUFFLE(3, 1, 0, 2)), xyz));
    d = _mm256_and_ps(d, keep);
    points = static_cast<std::size_t>(__builtin_popcount(_mm256_movemask_ps(keep)) / 3);
  }
  lanes.sum = _mm256_add_ps(lanes.sum, d);
  lanes.squares = _mm256_add_ps(lanes.squares, _mm256_mul_ps(d, d));
  lanes.cross = _mm256_add_ps(lanes.cross, _mm256_mul_ps(d, _mm256_permute_ps(d, kRotate)));
  return points;
}

/// Adds a block's partial sums to the double totals, the even points' lanes with the odd ones'.
__attribute__((target("avx2"))) void flushBlock(MetricSums& out, const BlockLanes& lanes) {
  alignas(32) float l[3][8];
  _mm256_store_ps(l[0], lanes.sum);
  _mm256_store_ps(l[1], lanes.squares);
  _mm256_store_ps(l[2], lanes.cross);
  addLanePairs(out.sum, l[0], l[0] + 4);
  addLanePairs(out.squares, l[1], l[1] + 4);
  addLanePairs(out.cross, l[2], l[2] + 4);
}

/// sumAboutOrigin() with the even points in lanes 0 .. 3 of one AVX vector and the odd ones in
/// lanes 4 .. 7: every lane sees the same float operations in the same order, in half the
/// instructions. Two full blocks are summed side by side, each in its own lanes, and flushed in
/// their order: the same bits, with twice the adds in flight. Without AVX2's FMA (not enabled
/// here) no product is fused into its sum.
__attribute__((target("avx2"))) MetricSums sumAboutOriginAvx2(const PointRDM* points,
                                                              const pcl::index_t* indices,
                                                              std::size_t n, float x0, float y0,
                                                              float z0) {
  const __m256 origin = _mm256_setr_ps(x0, y0, z0, 0.0f, x0, y0, z0, 0.0f);
  const __m256 zero = _mm256_setzero_ps();
  // The partner of a block's last even point when it has none: not finite, so it adds +0, which
  // leaves every partial sum as it is (they start at +0 and so never hold -0).
  const float none[4] = {std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f, 0.0f};
  const auto at = [&](std::size_t k) { return points[indices[k]].data; };
  MetricSums out;
  std::size_t counted = 0, k = 0;  // counted in a register, not in `out`
  for (; k + 2 * kFlushPoints <= n; k += 2 * kFlushPoints) {
    BlockLanes first{zero, zero, zero}, second{zero, zero, zero};
    for (std::size_t j = k; j < k + kFlushPoints; j += 2) {
      counted += addPair(first, at(j), at(j + 1), origin);
      counted += addPair(second, at(j + kFlushPoints), at(j + kFlushPoints + 1), origin);
    }
    flushBlock(out, first);
    flushBlock(out, second);
  }
  while (k < n) {
    BlockLanes lanes{zero, zero, zero};
    for (const std::size_t stop = std::min(n, k + kFlushPoints); k < stop; k += 2)
      counted += addPair(lanes, at(k), k + 1 < stop ? at(k + 1) : none, origin);
    flushBlock(out, lanes);
  }
  out.points = counted;
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
