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

/// The candidates of one block of `stride` cells along a slit (its residuals without NaN), in
/// ascending order (insertion sort: a block holds 4 to 16 cells).
void sortedBlock(const float* cells, std::size_t first, std::size_t last, std::vector<float>& out) {
  out.clear();
  for (std::size_t j = first; j < last; ++j) {
    const float x = cells[j];
    if (std::isnan(x)) continue;
    out.push_back(x);
    std::size_t i = out.size() - 1;
    for (; i > 0 && out[i - 1] > x; --i) out[i] = out[i - 1];
    out[i] = x;
  }
}

/// The median of the union of ascending `a` (with one value equal to `skip` left out, unless
/// NaN) and ascending `b`: the value at position n / 2 of the union, for an even n the mean of it
/// and the one before; what any exact selection of the window's median gives. `n`: its size.
float mergedMedian(const std::vector<float>& a, float skip, const std::vector<float>& b,
                   std::size_t n) {
  bool skipped = std::isnan(skip);
  std::size_t i = 0, j = 0;
  float before = 0.0f, at = 0.0f;
  for (std::size_t p = 0; p <= n / 2; ++p) {
    if (!skipped && i < a.size() && a[i] == skip) skipped = true, ++i;
    const bool from_a = j >= b.size() || (i < a.size() && a[i] <= b[j]);
    before = at;
    at = from_a ? a[i++] : b[j++];
  }
  return n % 2 == 0 ? 0.5f * (at + before) : at;
}

/// The noise of the window medians of 2 half + 1 cells: 1.4826 x the median |median| of the
/// windows centred on every (half + 1)-th cell of a slit, when a candidate, that hold at least
/// half + 1 candidates: windows overlapping by half, not all (neighbouring windows share nearly all
/// their cells). NaN with fewer than kMinMedians windows. The window about cell m (half + 1) is
/// block m of half + 1 cells and block m - 1 without its first cell: each block is sorted once and
/// the window's median merged from two (a selection per window took most of the floor's time).
double windowNoise(const std::vector<float>& r, std::size_t width, std::size_t half) {
  const std::size_t stride = half + 1;
  std::vector<float> medians, previous, block;
  for (std::size_t row = 0; row + width <= r.size(); row += width) {
    const float* cells = r.data() + row;
    previous.clear();
    for (std::size_t k = 0; k < width; k += stride) {
      sortedBlock(cells, k, std::min(width, k + stride), block);
      // Block m - 1 lies in the window but for its first cell (half + 1 cells before k).
      const float skip = k > 0 ? cells[k - stride] : std::nanf("");
      const std::size_t n = previous.size() - (std::isnan(skip) ? 0 : 1) + block.size();
      if (!std::isnan(cells[k]) && n > half)
        medians.push_back(std::abs(mergedMedian(previous, skip, block, n)));
      std::swap(previous, block);
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
