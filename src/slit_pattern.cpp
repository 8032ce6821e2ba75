#include "slit_pattern.h"

#include <Eigen/Dense>

#include <algorithm>
#include <climits>
#include <cmath>

namespace multislit {

namespace {

constexpr int kSlitDegree = 5;     // of the surface across the slits [-]
constexpr int kRowDegree = 5;      // of the surface along them [-]
constexpr int kPatternPasses = 4;  // fits, each on the centres the one before kept [-]
constexpr double kMinLimit = 0.3;  // a centre this near the surface is on it [px]
constexpr double kMinShare = 0.6;  // of the centres that must fit for the surface to judge [-]

/// The monomials s^a v^b (a <= slit_degree, b <= kRowDegree) of every centre, with s the slit's
/// place across the fan and v its row, both scaled to [-1, 1].
Eigen::MatrixXd basis(const std::vector<Track>& slits, int slit_degree, std::size_t n) {
  int first = INT_MAX, last = INT_MIN;
  for (const Track& t : slits)
    first = std::min(first, t.firstRow()), last = std::max(last, t.lastRow());
  const double mid_row = 0.5 * (first + last), half_rows = std::max(1.0, 0.5 * (last - first));
  const double mid_slit = 0.5 * static_cast<double>(slits.size() - 1);
  Eigen::MatrixXd b(static_cast<Eigen::Index>(n), (slit_degree + 1) * (kRowDegree + 1));
  Eigen::Index i = 0;
  for (std::size_t k = 0; k < slits.size(); ++k) {
    const double s = (static_cast<double>(k) - mid_slit) / mid_slit;
    for (const Centre& c : slits[k].points) {
      const double v = (c.row - mid_row) / half_rows;
      Eigen::Index j = 0;
      double ps = 1;
      for (int a = 0; a <= slit_degree; ++a, ps *= s) {
        double pv = ps;
        for (int d = 0; d <= kRowDegree; ++d, pv *= v) b(i, j++) = pv;
      }
      ++i;
    }
  }
  return b;
}

}  // namespace

std::vector<std::vector<bool>> onPattern(const std::vector<Track>& slits,
                                         const std::vector<std::vector<bool>>& start) {
  std::vector<std::vector<bool>> on(slits.size());
  std::size_t n = 0;
  for (std::size_t k = 0; k < slits.size(); ++k) {
    on[k].assign(slits[k].points.size(), true);
    n += slits[k].points.size();
  }
  const int slit_degree = std::min(kSlitDegree, static_cast<int>(slits.size()) - 1);
  if (slit_degree < 2) return on;
  const Eigen::MatrixXd b = basis(slits, slit_degree, n);
  if (static_cast<Eigen::Index>(n) < 4 * b.cols()) return on;
  Eigen::VectorXd u(static_cast<Eigen::Index>(n));
  Eigen::Index i = 0;
  for (const Track& t : slits)
    for (const Centre& c : t.points) u(i++) = c.u;
  std::vector<bool> kept;
  for (const std::vector<bool>& slit : start) kept.insert(kept.end(), slit.begin(), slit.end());
  Eigen::VectorXd residual;
  for (int pass = 0; pass < kPatternPasses; ++pass) {
    Eigen::MatrixXd a = b;
    Eigen::VectorXd y = u;
    for (Eigen::Index r = 0; r < a.rows(); ++r)
      if (!kept[static_cast<std::size_t>(r)]) a.row(r).setZero(), y(r) = 0;
    residual = u - b * a.colPivHouseholderQr().solve(y);
    std::vector<double> near;
    for (std::size_t r = 0; r < n; ++r)
      if (kept[r]) near.push_back(std::abs(residual(static_cast<Eigen::Index>(r))));
    if (near.empty()) return on;
    const double sigma = 1.4826 * upperMedian(std::move(near));
    const double limit = std::max(kMinLimit, 3.0 * sigma);
    for (std::size_t r = 0; r < n; ++r)
      kept[r] = std::abs(residual(static_cast<Eigen::Index>(r))) <= limit;
  }
  if (static_cast<double>(std::count(kept.begin(), kept.end(), true)) <
      kMinShare * static_cast<double>(n))
    return on;
  std::size_t r = 0;
  for (auto& slit : on)
    for (std::size_t k = 0; k < slit.size(); ++k) slit[k] = kept[r++];
  return on;
}

}  // namespace multislit
