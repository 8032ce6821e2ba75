#include "map_evidence.h"

#include "multislit/plane_model.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace multislit::detail {

namespace {

/// The row and column of RDMap indices, without a division while they stay in one row: the floor
/// inliers come row by row.
class RowCursor {
 public:
  explicit RowCursor(std::size_t width) : width_(width) {}
  /// Moves to `index`: row() and column() are its own.
  void to(std::size_t index) {
    if (index - start_ >= width_) {  // another row (below start_, the difference wraps)
      row_ = index / width_;
      start_ = row_ * width_;
    }
    column_ = index - start_;
  }
  std::size_t row() const { return row_; }
  std::size_t column() const { return column_; }

 private:
  std::size_t width_, row_ = 0, start_ = 0, column_ = 0;
};

}  // namespace

void FrameEvidence::sortMarks() {
  if (marks.empty()) return;
  std::uint64_t differ = 0;  // the bits of the voxel in which some mark differs from the first
  for (const std::uint64_t m : marks) differ |= m ^ marks.front();
  differ &= ~std::uint64_t{(1u << kKindBits) - 1};  // the kinds of one voxel stay in any order
  sort_buffer.resize(marks.size());
  constexpr int kDigitBits = 11;  // 2048 counters: in the first level cache
  constexpr std::uint64_t kDigit = (1u << kDigitBits) - 1;
  while (differ != 0) {  // a digit from the lowest bit still differing: each pass is stable
    const int shift = __builtin_ctzll(differ);
    differ &= ~(kDigit << shift);
    std::uint32_t start[kDigit + 2] = {};
    for (const std::uint64_t m : marks) ++start[((m >> shift) & kDigit) + 1];
    for (std::uint64_t d = 0; d <= kDigit; ++d) start[d + 1] += start[d];
    for (const std::uint64_t m : marks) sort_buffer[start[(m >> shift) & kDigit]++] = m;
    marks.swap(sort_buffer);
  }
}

void FrameEvidence::measureSlits(const pcl::PointCloud<PointRDM>& cloud, const FloorResult& floor,
                                 const OccupancyMapConfig& config) {
  const std::size_t rows = cloud.height, width = cloud.width;
  slits.assign(rows, Slit{0.0, 0, static_cast<std::uint32_t>(width), 0, 0.0});
  residual.resize(cloud.size());
  RowCursor at(width);
  for (const auto i : floor.inliers) {
    const auto idx = static_cast<std::size_t>(i);
    at.to(idx);
    Slit& slit = slits[at.row()];
    const auto col = static_cast<std::uint32_t>(at.column());
    const double r = planeResidual(cloud[idx], floor.plane);
    residual[idx] = r;
    slit.sum_sq += r * r;
    ++slit.count;
    slit.first = std::min(slit.first, col);
    slit.last = std::max(slit.last, col);
  }
  for (Slit& slit : slits) {
    const double sigma = slit.count > 1 ? std::sqrt(slit.sum_sq / static_cast<double>(slit.count))
                                        : floor.residual_std;
    slit.weak = config.weak_sigmas * std::max(sigma, config.min_sigma);
  }
}

void FrameEvidence::flagWeakFloorPoints(const pcl::PointCloud<PointRDM>& cloud,
                                        const FloorResult& floor,
                                        const OccupancyMapConfig& config) {
  const std::size_t rows = cloud.height, width = cloud.width;
  const auto end = static_cast<std::uint32_t>(config.weak_end_margin);
  weak_point.assign(cloud.size(), 0);
  RowCursor at(width);
  for (const auto i : floor.inliers) {
    const auto idx = static_cast<std::size_t>(i);
    at.to(idx);
    const Slit& slit = slits[at.row()];
    const auto col = static_cast<std::uint32_t>(at.column());
    if (col < slit.first + end || col + end > slit.last) continue;
    weak_point[idx] = residual[idx] >= slit.weak ? 1 : residual[idx] <= -slit.weak ? -1 : 0;
  }
  // Runs of one sign only.
  const auto run = static_cast<std::size_t>(config.min_weak_run);
  for (std::size_t row = 0; row < rows; ++row) {
    std::int8_t* flags = weak_point.data() + row * width;
    for (std::size_t col = 0; col < width;) {
      if (!flags[col]) {
        ++col;
        continue;
      }
      std::size_t stop = col;
      while (stop < width && flags[stop] == flags[col]) ++stop;
      if (stop - col < run) std::fill(flags + col, flags + stop, std::int8_t{0});
      col = stop;
    }
  }
}

void SlitSweep::begin(std::size_t size) {
  if (seen_.size() != size) seen_.assign(size, Seen{});
  ++frame_;
  first_slit_ = last_slit_ = 0;
  first_count_ = last_count_ = 0;
  now_.clear();
  now_xy_.clear();
}

void SlitSweep::add(std::size_t index, int slit, const Eigen::Vector2d& world) {
  if (now_.empty() || slit < first_slit_) {
    first_slit_ = slit;
    first_sum_.setZero();
    first_count_ = 0;
  }
  if (now_.empty() || slit > last_slit_) {
    last_slit_ = slit;
    last_sum_.setZero();
    last_count_ = 0;
  }
  if (slit == first_slit_) {
    first_sum_ += world;
    ++first_count_;
  }
  if (slit == last_slit_) {
    last_sum_ += world;
    ++last_count_;
  }
  now_.push_back(static_cast<std::uint32_t>(index));
  now_xy_.push_back(world.cast<float>());
}

namespace {

/// The least-squares affine fit move = a + b . (at - centre) over the points whose residual from
/// `previous` is within `keep` [m] (all points when keep is infinite); false when they do not
/// spread over the floor in two directions.
bool fitAffine(const std::vector<float>& moves, const std::vector<Eigen::Vector2f>& at,
               const Eigen::Vector2d& centre, const Eigen::Vector3d& previous, double keep,
               Eigen::Vector3d& fit) {
  // The sums of row * row^T and row * move, each added in the order of the points (the bits of
  // adding the outer products as matrices), in registers rather than in a matrix in memory.
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0, sm = 0, sxm = 0, sym = 0;
  for (std::size_t j = 0; j < moves.size(); ++j) {
    // The row (1, x, y); its dot product with `previous` summed in Eigen's order.
    const double x = at[j].x() - centre.x(), y = at[j].y() - centre.y(), m = moves[j];
    if (!(std::abs(m - (previous[0] + x * previous[1] + y * previous[2])) <= keep)) continue;
    n += 1.0;
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    syy += y * y;
    sm += m;
    sxm += x * m;
    sym += y * m;
  }
  Eigen::Matrix3d normal;
  normal << n, sx, sy, sx, sxx, sxy, sy, sxy, syy;
  const Eigen::Vector3d rhs(sm, sxm, sym);
  constexpr double kMinSpread = 1e-4;  // (1 cm)^2: the points lie along more than a line
  if (normal(0, 0) < 20 || Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(
                               normal.bottomRightCorner<2, 2>() / normal(0, 0))
                                   .eigenvalues()
                                   .minCoeff() < kMinSpread)
    return false;
  fit = normal.ldlt().solve(rhs);
  return fit.allFinite();
}

}  // namespace

float upperMedian(std::vector<float>& values, std::vector<std::uint32_t>& bits) {
  const std::size_t half = values.size() / 2;
  bits.resize(values.size());
  std::uint32_t any = 0;
  for (std::size_t j = 0; j < values.size(); ++j) {
    std::memcpy(&bits[j], &values[j], sizeof(float));
    any |= bits[j] > 0x7f800000u ? 1u : 0u;  // the sign bit, or a NaN
  }
  if (values.empty() || any != 0) {
    const auto mid = values.begin() + static_cast<std::ptrdiff_t>(half);
    std::nth_element(values.begin(), mid, values.end());
    return values.empty() ? 0.0f : *mid;
  }
  std::size_t rank = half;  // of the value sought among those left
  for (const int shift : {21, 10, 0}) {
    constexpr std::uint32_t kDigit = (1u << 11) - 1;
    std::uint32_t count[kDigit + 1] = {};
    for (const std::uint32_t b : bits) ++count[(b >> shift) & kDigit];
    std::uint32_t digit = 0;
    for (; rank >= count[digit]; ++digit) rank -= count[digit];
    // Keep the values with that digit (the digits above are alike in all left).
    bits.erase(std::remove_if(bits.begin(), bits.end(),
                              [&](std::uint32_t b) { return ((b >> shift) & kDigit) != digit; }),
               bits.end());
  }
  float median;
  std::memcpy(&median, &bits.front(), sizeof(float));
  return median;
}

SweepStep SlitSweep::finish(double dead_zone) {
  moves_.clear();
  moved_at_.clear();
  Eigen::Vector2d across = Eigen::Vector2d::Zero();
  if (first_count_ > 0 && last_count_ > 0 && last_slit_ > first_slit_)
    across = last_sum_ / static_cast<double>(last_count_) -
             first_sum_ / static_cast<double>(first_count_);
  const bool has_across = across.norm() > 1e-3;
  if (has_across) across.normalize();
  const Eigen::Vector2f n = across.cast<float>();
  double sum_x = 0.0, sum_y = 0.0;  // of the points that moved: in registers
  for (std::size_t j = 0; j < now_.size(); ++j) {
    Seen& s = seen_[now_[j]];
    if (has_across && s.frame + 1 == frame_) {
      moves_.push_back((now_xy_[j] - Eigen::Vector2f(s.x, s.y)).dot(n));
      moved_at_.push_back(now_xy_[j]);
      sum_x += static_cast<double>(now_xy_[j].x());
      sum_y += static_cast<double>(now_xy_[j].y());
    }
    s = Seen{now_xy_[j].x(), now_xy_[j].y(), frame_};
  }
  SweepStep step;
  if (moves_.size() < 20) return step;
  const auto count = static_cast<double>(moves_.size());
  const Eigen::Vector2d centre(sum_x / count, sum_y / count);
  // Fit all, then again without the points far off the first fit (a point that jumped to another
  // place on its slit: an edge of the view, an object).
  Eigen::Vector3d fit = Eigen::Vector3d::Zero();
  if (!fitAffine(moves_, moved_at_, centre, fit, std::numeric_limits<double>::infinity(), fit))
    return step;
  const auto fitted = [&](const Eigen::Vector2f& at) {  // the fit's move at `at` [m]
    return fit[0] + fit[1] * (at.x() - centre.x()) + fit[2] * (at.y() - centre.y());
  };
  residuals_.clear();
  for (std::size_t j = 0; j < moves_.size(); ++j)
    residuals_.push_back(std::abs(moves_[j] - static_cast<float>(fitted(moved_at_[j]))));
  const float median = upperMedian(residuals_, residual_bits_);
  constexpr double kMinKeep = 2e-4;  // [m]: below the points' own noise, nothing is an outlier
  const double keep = std::max(kMinKeep, 3.0 * 1.4826 * static_cast<double>(median));
  if (!fitAffine(moves_, moved_at_, centre, fit, keep, fit)) return step;
  // The largest move in the view: below the dead zone, the slits did not move.
  double largest = 0.0;
  for (const Eigen::Vector2f& at : moved_at_) largest = std::max(largest, std::abs(fitted(at)));
  if (largest <= dead_zone) return step;
  step.per_x = fit[1];
  step.per_y = fit[2];
  step.offset = fit[0] - fit[1] * centre.x() - fit[2] * centre.y();
  step.middle = fit[0];
  return step;
}

}  // namespace multislit::detail
