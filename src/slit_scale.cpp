#include "slit_scale.h"

#include "multislit/plane_model.h"

#include "rdm_simd.h"
#include "slit_blocks.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

namespace multislit::detail {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr std::size_t kMinMedians = 50;  // fewer windows: the scale's noise is not measured

/// The buffers of one call, kept from frame to frame: the stage runs on every frame, so they are
/// allocated once. One per thread, so that detectors may run on several threads at once.
struct Workspace {
  std::vector<float> r;            ///< per cell: the candidate's residual, NaN for the others
  std::vector<std::uint8_t> off;   ///< per cell: off the floor at some scale
  std::vector<float> medians;      ///< |window median| of one scale
  SlitBlocks blocks;               ///< the sorted blocks of the current and the next scale
  std::vector<std::int32_t> runs;  ///< running counts of one slit (markOff)
};

Workspace& workspace() {
  thread_local Workspace w;
  return w;
}

/// The value std::nth_element would place at position n / 2 of values[0, n) (n > 0, every one
/// >= 0 and not NaN; reordered). The values are counted in 256 bins of equal
/// width up to the largest, an order-keeping map; the middle then lies among the few of one bin.
/// Three passes without a branch on the values, where a selection by comparisons over all of
/// them mispredicts half of its branches.
float middleOf(float* values, std::size_t n) {
  std::size_t k = n / 2;
  float top = 0.0f;
  for (std::size_t i = 0; i < n; ++i) top = std::max(top, values[i]);
  if (!(top < std::numeric_limits<float>::infinity()) || top == 0.0f) {
    std::nth_element(values, values + k, values + n);
    return values[k];
  }
  const float scale = 255.0f / top;  // v * scale rises with v and stays below 256
  const auto bin = [scale](float v) { return static_cast<std::size_t>(v * scale); };
  std::array<std::uint32_t, 256> counts{};
  for (std::size_t i = 0; i < n; ++i) ++counts[bin(values[i])];
  std::size_t middle_bin = 0;
  while (k >= counts[middle_bin]) k -= counts[middle_bin++];
  std::size_t kept = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const float v = values[i];
    values[kept] = v;
    kept += bin(v) == middle_bin;
  }
  std::nth_element(values, values + k, values + kept);
  return values[k];
}

/// The noise of the window medians of 2 half + 1 cells: 1.4826 x the median |median| of the
/// windows centred on every (half + 1)-th cell of a slit, when a candidate, that hold at least
/// half + 1 candidates: windows overlapping by half, not all (neighbouring windows share nearly all
/// their cells). NaN with fewer than kMinMedians windows. `blocks` holds this scale's sorted
/// blocks of half + 1 cells; each window is two of them. Leaves `blocks` at the next length.
double windowNoise(SlitBlocks& blocks, std::vector<float>& medians) {
  const std::size_t n = blocks.mediansThenDouble(medians);
  if (n < kMinMedians) return std::numeric_limits<double>::quiet_NaN();
  return 1.4826 * static_cast<double>(middleOf(medians.data(), n));
}

/// Marks in `off` the candidates among cells [first_k, end_k) of one slit (`cells`, `width` of
/// them) whose window of 2 half + 1 cells, cut at the slit's ends, holds at least half + 1
/// candidates, more than half of them beyond the limit on the side of the cell's own residual.
/// `runs`: the running counts of candidates, of cells above +limit and of cells below -limit
/// (width + 1 each). `kCut`: whether a window may reach past an end of the slit.
template <bool kCut>
void markWindows(const float* cells, std::size_t first_k, std::size_t end_k, std::size_t width,
                 std::size_t half, const std::int32_t* runs, std::uint8_t* off) {
  const std::int32_t* valid = runs;
  const std::int32_t* above = runs + (width + 1);
  const std::int32_t* below = runs + 2 * (width + 1);
  const auto min_n = static_cast<std::int32_t>(half);
  for (std::size_t k = first_k; k < end_k; ++k) {
    const std::size_t first = !kCut || k > half ? k - half : 0;
    const std::size_t last = kCut ? std::min(width, k + half + 1) : k + half + 1;
    const float v = cells[k];
    const std::int32_t n = valid[last] - valid[first];
    const std::int32_t up = above[last] - above[first], down = below[last] - below[first];
    const std::int32_t side = v > 0.0f ? up : down;
    // Branch-free, so that the loop is vectorized: a NaN cell (no candidate) is never marked.
    off[k] |= static_cast<std::uint8_t>((v == v) & (n > min_n) & (2 * side > n));
  }
}

/// Cells above +limit and below -limit in cells[0, width).
struct Beyond {
  std::int32_t up = 0, down = 0;
};
Beyond countBeyond(const float* cells, std::size_t width, float limit) {
  Beyond b;
  for (std::size_t k = 0; k < width; ++k) {
    b.up += cells[k] > limit;
    b.down += cells[k] < -limit;
  }
  return b;
}

/// Marks in `off` the candidates whose window of 2 half + 1 cells holds at least half + 1
/// candidates, more than half of them beyond `limit` on the side of the cell's own residual
/// (the window's median beyond it). Running counts along each slit: one pass per window length.
/// Returns whether it looked at any slit: a slit with fewer than (half + 2) / 2 cells beyond the
/// limit on either side has no window with more than half of its candidates there (nearly every
/// slit of a plain floor).
bool markOff(const std::vector<float>& r, std::size_t width, std::size_t half, float limit,
             std::vector<std::int32_t>& runs, std::vector<std::uint8_t>& off) {
  runs.resize(3 * (width + 1));
  std::int32_t* valid = runs.data();
  std::int32_t* above = valid + (width + 1);
  std::int32_t* below = above + (width + 1);
  valid[0] = above[0] = below[0] = 0;
  bool any = false;
  for (std::size_t row = 0; row + width <= r.size(); row += width) {
    const float* cells = r.data() + row;
    const Beyond beyond = countBeyond(cells, width, limit);
    if (2 * static_cast<std::size_t>(std::max(beyond.up, beyond.down)) < half + 2) continue;
    any = true;
    std::int32_t n = 0, up = 0, down = 0;  // in registers: the arrays may alias for the compiler
    for (std::size_t k = 0; k < width; ++k) {
      const float v = cells[k];
      valid[k + 1] = n += (v == v);
      above[k + 1] = up += (v > limit);
      below[k + 1] = down += (v < -limit);
    }
    // The cells whose window is not cut by the slit's ends take the vectorized loop alone.
    const std::size_t inner_begin = std::min(half, width);
    const std::size_t inner_end = std::max(inner_begin, width > half ? width - half : 0);
    std::uint8_t* row_off = off.data() + row;
    markWindows<true>(cells, 0, inner_begin, width, half, runs.data(), row_off);
    markWindows<false>(cells, inner_begin, inner_end, width, half, runs.data(), row_off);
    markWindows<true>(cells, inner_end, width, width, half, runs.data(), row_off);
  }
  return any;
}

/// r[i] = planeResidual() of each candidate i in float, NaN for the other cells; four points at
/// a time with the same float operations.
void residualsAt(const pcl::PointCloud<PointRDM>& cloud, const pcl::Indices& candidates,
                 const Eigen::Vector3d& plane, std::vector<float>& r) {
  r.assign(cloud.size(), kNaN);
  const float a = static_cast<float>(plane[0]), b = static_cast<float>(plane[1]),
              c = static_cast<float>(plane[2]);
  const __m128 va = _mm_set1_ps(a), vb = _mm_set1_ps(b), vc = _mm_set1_ps(c);
  const PointRDM* points = cloud.points.data();
  const pcl::index_t* ids = candidates.data();
  const std::size_t n = candidates.size();
  std::size_t k = 0;
  for (; k + 4 <= n; k += 4) {
    const simd::UVDK4 p =
        simd::loadUVDK(points[ids[k]], points[ids[k + 1]], points[ids[k + 2]], points[ids[k + 3]]);
    alignas(16) float lr[4];
    _mm_store_ps(lr, simd::planeResiduals(p, va, vb, vc));
    for (std::size_t j = 0; j < 4; ++j) r[static_cast<std::size_t>(ids[k + j])] = lr[j];
  }
  for (; k < n; ++k) r[static_cast<std::size_t>(ids[k])] = planeResidual(points[ids[k]], a, b, c);
}

}  // namespace

SlitScaleOff offFloorAtScales(const pcl::PointCloud<PointRDM>& cloud,
                              const pcl::Indices& candidates, const Eigen::Vector3d& plane,
                              int min_window, int max_window, double sigmas, double min_shift) {
  SlitScaleOff out;
  if (!cloud.isOrganized() || cloud.width < 3) return out;
  Workspace& ws = workspace();
  std::vector<float>& r = ws.r;
  residualsAt(cloud, candidates, plane, r);
  ws.off.assign(cloud.size(), 0);
  bool looked = false;  // whether any slit could hold a window off the floor
  ws.blocks.start(r, cloud.width, static_cast<std::size_t>(min_window / 2 + 1));
  for (int w = min_window; w <= max_window; w = 2 * w + 1) {
    const auto half = static_cast<std::size_t>(w / 2);
    const double sigma = windowNoise(ws.blocks, ws.medians);  // then blocks for 2 w + 1
    out.sigmas.push_back(sigma);
    if (std::isnan(sigma)) continue;
    const auto limit = static_cast<float>(std::max(sigmas * sigma, min_shift));
    looked |= markOff(r, cloud.width, half, limit, ws.runs, ws.off);
  }
  if (!looked) return out;
  // Counted first: the lists are then allocated once, and written only where marked (rarely).
  // Only candidate cells are marked (the others' residuals are NaN), so the cells are counted in
  // order, without reading them through the candidates' indices.
  const std::uint8_t* off = ws.off.data();
  const float* residuals = r.data();
  std::size_t marked = 0;
  for (std::size_t k = 0; k < ws.off.size(); ++k) marked += off[k];
  if (marked == 0) return out;
  out.points.reserve(marked);
  out.residuals.reserve(marked);
  for (const auto i : candidates) {
    if (!off[static_cast<std::size_t>(i)]) continue;
    out.points.push_back(i);
    out.residuals.push_back(residuals[static_cast<std::size_t>(i)]);
  }
  return out;
}

}  // namespace multislit::detail
