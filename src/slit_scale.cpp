#include "slit_scale.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace multislit::detail {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr std::size_t kMinMedians = 50;  // fewer windows: the scale's noise is not measured

/// The median of `sorted` (ascending, not empty).
float medianOf(const std::vector<float>& sorted) {
  const std::size_t n = sorted.size();
  return n % 2 ? sorted[n / 2] : 0.5f * (sorted[n / 2 - 1] + sorted[n / 2]);
}

/// For each cell of `r` (NaN: no candidate), the median of the candidates among the `half` cells
/// on either side along its slit and itself, when at least half + 1 of them are candidates; NaN
/// otherwise. A sorted window slides along each slit.
std::vector<float> movingMedians(const std::vector<float>& r, std::size_t width, std::size_t half) {
  std::vector<float> m(r.size(), kNaN), window;
  window.reserve(2 * half + 1);
  const auto add = [&](float v) {
    window.insert(std::upper_bound(window.begin(), window.end(), v), v);
  };
  const auto remove = [&](float v) {
    window.erase(std::lower_bound(window.begin(), window.end(), v));
  };
  for (std::size_t row = 0; row + width <= r.size(); row += width) {
    const float* cells = r.data() + row;
    window.clear();
    for (std::size_t k = 0; k < std::min(half, width); ++k)
      if (!std::isnan(cells[k])) add(cells[k]);
    for (std::size_t k = 0; k < width; ++k) {
      if (k + half < width && !std::isnan(cells[k + half])) add(cells[k + half]);
      if (k > half && !std::isnan(cells[k - half - 1])) remove(cells[k - half - 1]);
      if (!std::isnan(cells[k]) && window.size() > half) m[row + k] = medianOf(window);
    }
  }
  return m;
}

/// 1.4826 x the median |m| of the cells where m is known; NaN with too few of them.
double robustSigma(const std::vector<float>& m) {
  std::vector<float> a;
  a.reserve(m.size());
  for (const float v : m)
    if (!std::isnan(v)) a.push_back(std::abs(v));
  if (a.size() < kMinMedians) return std::numeric_limits<double>::quiet_NaN();
  const auto mid = a.begin() + static_cast<std::ptrdiff_t>(a.size() / 2);
  std::nth_element(a.begin(), mid, a.end());
  return 1.4826 * static_cast<double>(*mid);
}

}  // namespace

SlitScaleOff offFloorAtScales(const pcl::PointCloud<PointRDM>& cloud,
                              const pcl::Indices& candidates, const Eigen::Vector3d& plane,
                              int min_window, int max_window, double sigmas, double min_shift) {
  SlitScaleOff out;
  if (!cloud.isOrganized() || cloud.width < 3) return out;
  std::vector<float> r(cloud.size(), kNaN);
  const float a = static_cast<float>(plane[0]), b = static_cast<float>(plane[1]),
              c = static_cast<float>(plane[2]);
  for (const auto i : candidates) {
    const PointRDM& p = cloud[static_cast<std::size_t>(i)];
    r[static_cast<std::size_t>(i)] = p.dk - (a * p.u + b * p.v + c);
  }
  std::vector<char> off(cloud.size(), 0);
  for (int w = min_window; w <= max_window; w = 2 * w + 1) {
    const std::vector<float> m = movingMedians(r, cloud.width, static_cast<std::size_t>(w / 2));
    const double sigma = robustSigma(m);
    out.sigmas.push_back(sigma);
    if (std::isnan(sigma)) continue;
    const float limit = static_cast<float>(std::max(sigmas * sigma, min_shift));
    for (const auto i : candidates) {
      const auto k = static_cast<std::size_t>(i);
      off[k] |= std::abs(m[k]) > limit && m[k] * r[k] > 0.0f;
    }
  }
  for (const auto i : candidates) {
    if (!off[static_cast<std::size_t>(i)]) continue;
    out.points.push_back(i);
    out.residuals.push_back(r[static_cast<std::size_t>(i)]);
  }
  return out;
}

}  // namespace multislit::detail
