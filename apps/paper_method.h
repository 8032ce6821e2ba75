// The yardstick: the paper's method written as plainly as it reads (Sec. II-C and III), to judge
// ours against on the same images. For each reference point, the maximum of the image row inside
// its assigned region; a point when that maximum stands `min_contrast` of full scale above the
// region's minimum; its centre is the centroid of the pixels above half the maximum. The floor:
// RANSAC with q = 35 (eq. 3), least squares on the inliers (eq. 2), 0.9 px (3 x 0.3 px), no
// noise rule. It shares our reference (slits and regions), so the two differ only in how a frame
// is measured and judged. Shared by the robustness tests and `multislit bench`, which times it.
#pragma once

#include "multislit/reference.h"

#include <opencv2/core.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace multislit::paper {

struct PaperPoint {
  int slit = 0, row = 0;
  double u = 0, dk = std::numeric_limits<double>::quiet_NaN();
};

template <typename T>
void paperMeasureRow(const T* row, int columns, double u, double half, double min_contrast,
                     PaperPoint* p) {
  const int first = std::max(0, static_cast<int>(std::ceil(u - half)));
  const int last = std::min(columns - 1, static_cast<int>(std::floor(u + half)));
  if (first > last) return;
  int top = row[first], low = row[first];
  for (int x = first; x <= last; ++x)
    top = std::max<int>(top, row[x]), low = std::min<int>(low, row[x]);
  if (top - low < min_contrast) return;
  // Each pixel above mid = (top + low) / 2 weighted by twice its excess, a whole number without a
  // branch: the centroid is the same number as with the excess itself, and `bench` times the
  // method as fast as it is written simply.
  const int twice_mid = top + low;
  std::int64_t sum = 0, moment = 0;
  for (int x = first; x <= last; ++x) {
    const int w = std::max(2 * static_cast<int>(row[x]) - twice_mid, 0);
    sum += w;
    moment += static_cast<std::int64_t>(w) * x;
  }
  if (sum > 0) p->dk = static_cast<double>(moment) / static_cast<double>(sum) - u;
}

/// Every reference point of `ref` measured in `image` the paper's way (NaN dk: not measured).
inline std::vector<PaperPoint> paperExtract(const Reference& ref, const cv::Mat& image,
                                            double min_contrast_fs = 0.06) {
  const bool bytes = image.depth() == CV_8U;
  const double min_contrast = min_contrast_fs * (bytes ? 255.0 : 65535.0);
  const double half = 0.5 * ref.region_width;
  std::vector<PaperPoint> out;
  for (std::size_t s = 0; s < ref.slits.size(); ++s) {
    const ReferenceSlit& slit = ref.slits[s];
    for (std::size_t k = 0; k < slit.u.size(); ++k) {
      if (!std::isfinite(slit.u[k])) continue;
      PaperPoint p;
      p.slit = static_cast<int>(s);
      p.row = slit.first_row + static_cast<int>(k);
      p.u = slit.u[k];
      if (bytes)
        paperMeasureRow(image.ptr<std::uint8_t>(p.row), image.cols, p.u, half, min_contrast, &p);
      else
        paperMeasureRow(image.ptr<std::uint16_t>(p.row), image.cols, p.u, half, min_contrast, &p);
      out.push_back(p);
    }
  }
  return out;
}

}  // namespace multislit::paper
