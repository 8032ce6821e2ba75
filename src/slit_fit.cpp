#include "slit_fit.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

namespace multislit {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

struct RowScale {  // a track's rows scaled to [-1, 1]
  double mid, half;
  explicit RowScale(const Track& t)
      : mid(0.5 * (t.firstRow() + t.lastRow())),
        half(std::max(1.0, 0.5 * (t.lastRow() - t.firstRow()))) {}
  double operator()(int row) const { return (row - mid) / half; }
};

/// The polynomial sum of coef(d) s^d for d <= `degree`.
double polynomialAt(const Eigen::VectorXd& coef, int degree, double s) {
  double p = 1, u = 0;
  for (int d = 0; d <= degree; ++d, p *= s) u += coef(d) * p;
  return u;
}

}  // namespace

Eigen::VectorXd fitSlit(const Track& t, const std::vector<bool>& on_pattern, int degree,
                        std::vector<bool>* inlier) {
  const std::vector<Centre>& pts = t.points;
  const RowScale scale(t);
  const int n = static_cast<int>(pts.size());
  constexpr std::size_t kFewest = 16;  // a shorter track starts from all of its centres
  inlier->assign(pts.size(), pts.size() < kFewest);
  for (std::size_t k = pts.size() / 4; k < pts.size() - pts.size() / 4; ++k) (*inlier)[k] = true;
  for (std::size_t k = 0; k < pts.size(); ++k) (*inlier)[k] = (*inlier)[k] && on_pattern[k];
  // Where the pattern has judged the middle half mostly off it, its centres elsewhere start.
  if (static_cast<std::size_t>(std::count(inlier->begin(), inlier->end(), true)) < kFewest)
    *inlier = on_pattern;
  Eigen::VectorXd coef = Eigen::VectorXd::Zero(degree + 1);
  std::vector<double> res(pts.size());
  constexpr int kPasses = 6;
  for (int pass = 0; pass < kPasses; ++pass) {
    const int d_max = pass == 0 ? std::min(degree, 2) : degree;
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, degree + 1);
    Eigen::VectorXd b(n);
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const double s = scale(pts[k].row);
      const double w = (*inlier)[k] ? 1.0 : 0.0;
      double p = 1;
      for (int d = 0; d <= d_max; ++d, p *= s) a(i, d) = w * p;
      b(i) = w * pts[k].u;
    }
    coef = a.colPivHouseholderQr().solve(b);
    std::vector<double> kept;
    for (std::size_t k = 0; k < pts.size(); ++k) {
      res[k] = pts[k].u - polynomialAt(coef, degree, scale(pts[k].row));
      if ((*inlier)[k]) kept.push_back(std::abs(res[k]));
    }
    const double sigma = kept.empty() ? 0.0 : 1.4826 * upperMedian(kept);
    // After the parabola, a generous limit: the full curve is not fitted yet.
    const double limit = pass == 0 ? std::max(3.0, 6.0 * sigma) : std::max(0.3, 3.0 * sigma);
    for (std::size_t k = 0; k < pts.size(); ++k)
      (*inlier)[k] = on_pattern[k] && std::abs(res[k]) <= limit;
  }
  return coef;
}

bool toSlit(const Track& t, const std::vector<bool>& on_pattern, const ReferenceConfig& config,
            ReferenceSlit* slit, double* ss, std::size_t* m) {
  slit->first_row = t.firstRow();
  slit->u.assign(static_cast<std::size_t>(t.lastRow() - slit->first_row + 1), kNaN);
  if (config.smoothing_degree == 0) {
    for (const Centre& c : t.points)
      slit->u[static_cast<std::size_t>(c.row - slit->first_row)] = static_cast<float>(c.u);
    return true;
  }
  // Near its ends a slit is cut inside the row profile, which narrows the profile (as the raw
  // image shows it) and pulls its centre inwards: such rows are dropped until the slit runs clean.
  // The width changes slowly along a slit: each end is judged by the rows next to it.
  const std::size_t n = t.points.size(), near = std::min<std::size_t>(n / 2, 40);
  auto narrowness = [&](std::size_t from) {
    std::vector<double> w;
    for (std::size_t i = from; i < from + near; ++i) w.push_back(t.points[i].width);
    return 0.85 * upperMedian(w);
  };
  const double narrow_first = narrowness(0), narrow_last = narrowness(n - near);
  std::vector<bool> inlier;
  const Eigen::VectorXd coef = fitSlit(t, on_pattern, config.smoothing_degree, &inlier);
  auto clean = [&](std::size_t i) {
    return inlier[i] && t.points[i].width >= (i < n / 2 ? narrow_first : narrow_last);
  };
  std::size_t begin = 0, end = t.points.size();
  while (begin < end && !clean(begin)) ++begin;
  while (end > begin && !clean(end - 1)) --end;
  if (end - begin < static_cast<std::size_t>(config.min_rows)) return false;
  slit->first_row = t.points[begin].row;
  const int kept_last = t.points[end - 1].row;
  slit->u.assign(static_cast<std::size_t>(kept_last - slit->first_row + 1), kNaN);
  const RowScale scale(t);
  for (int r = slit->first_row; r <= kept_last; ++r)
    slit->u[static_cast<std::size_t>(r - slit->first_row)] =
        static_cast<float>(polynomialAt(coef, config.smoothing_degree, scale(r)));
  for (std::size_t i = begin; i < end; ++i) {
    if (!inlier[i]) continue;
    const double d =
        t.points[i].u - slit->u[static_cast<std::size_t>(t.points[i].row - slit->first_row)];
    *ss += d * d;
    ++*m;
  }
  return true;
}

}  // namespace multislit
