#include "slit_scale.h"

#include "multislit/plane_model.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

namespace multislit::detail {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr std::size_t kMinMedians = 50;  // fewer windows: the scale's noise is not measured

/// The window of 2 half + 1 cells about cell k of one slit (`cells`, `width` of them), cut at the
/// slit's ends: [first, last).
struct Window {
  std::size_t first = 0, last = 0;
};
Window windowAt(std::size_t k, std::size_t half, std::size_t width) {
  return {k > half ? k - half : 0, std::min(width, k + half + 1)};
}

/// The noise of the window medians of 2 half + 1 cells: 1.4826 x the median |median| of the
/// windows centred on every (half + 1)-th cell of a slit, when a candidate, that hold at least
/// half + 1 candidates: windows overlapping by half, not all (neighbouring windows share nearly all
/// their cells, and the nth_element of every one took 0.5 to 1 ms a frame). NaN with fewer than
/// kMinMedians windows.
double windowNoise(const std::vector<float>& r, std::size_t width, std::size_t half) {
  const std::size_t stride = half + 1;
  std::vector<float> medians, window;
  for (std::size_t row = 0; row + width <= r.size(); row += width) {
    const float* cells = r.data() + row;
    for (std::size_t k = 0; k < width; k += stride) {
      if (std::isnan(cells[k])) continue;
      const Window w = windowAt(k, half, width);
      window.clear();
      for (std::size_t j = w.first; j < w.last; ++j)
        if (!std::isnan(cells[j])) window.push_back(cells[j]);
      if (window.size() <= half) continue;
      const std::size_t n = window.size();
      const auto mid = window.begin() + static_cast<std::ptrdiff_t>(n / 2);
      std::nth_element(window.begin(), mid, window.end());
      float median = *mid;
      if (n % 2 == 0) median = 0.5f * (median + *std::max_element(window.begin(), mid));
      medians.push_back(std::abs(median));
    }
  }
  if (medians.size() < kMinMedians) return std::numeric_limits<double>::quiet_NaN();
  const auto mid = medians.begin() + static_cast<std::ptrdiff_t>(medians.size() / 2);
  std::nth_element(medians.begin(), mid, medians.end());
  return 1.4826 * static_cast<double>(*mid);
}

/// Marks in `off` the candidates whose window of 2 half + 1 cells holds at least half + 1
/// candidates, more than half of them beyond `limit` on the side of the cell's own residual
/// (the window's median beyond it). Running counts along each slit: one pass per window length.
void markOff(const std::vector<float>& r, std::size_t width, std::size_t half, float limit,
             std::vector<char>& off) {
  // count[j]: candidates, above +limit, below -limit among the first j cells of the slit.
  std::vector<std::int32_t> valid(width + 1), above(width + 1), below(width + 1);
  for (std::size_t row = 0; row + width <= r.size(); row += width) {
    const float* cells = r.data() + row;
    for (std::size_t k = 0; k < width; ++k) {
      const float v = cells[k];
      valid[k + 1] = valid[k] + !std::isnan(v);
      above[k + 1] = above[k] + (v > limit);
      below[k + 1] = below[k] + (v < -limit);
    }
    for (std::size_t k = 0; k < width; ++k) {
      const float v = cells[k];
      if (std::isnan(v)) continue;
      const Window w = windowAt(k, half, width);
      const std::int32_t n = valid[w.last] - valid[w.first];
      if (n <= static_cast<std::int32_t>(half)) continue;
      const std::int32_t side =
          v > 0.0f ? above[w.last] - above[w.first] : below[w.last] - below[w.first];
      off[row + k] |= 2 * side > n;
    }
  }
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
    r[static_cast<std::size_t>(i)] = planeResidual(p, a, b, c);
  }
  std::vector<char> off(cloud.size(), 0);
  for (int w = min_window; w <= max_window; w = 2 * w + 1) {
    const auto half = static_cast<std::size_t>(w / 2);
    const double sigma = windowNoise(r, cloud.width, half);
    out.sigmas.push_back(sigma);
    if (std::isnan(sigma)) continue;
    markOff(r, cloud.width, half, static_cast<float>(std::max(sigmas * sigma, min_shift)), off);
  }
  for (const auto i : candidates) {
    if (!off[static_cast<std::size_t>(i)]) continue;
    out.points.push_back(i);
    out.residuals.push_back(r[static_cast<std::size_t>(i)]);
  }
  return out;
}

}  // namespace multislit::detail
