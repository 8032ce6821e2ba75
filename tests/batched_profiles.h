// measurePeaks() (eight profiles at a time in float lanes where the CPU has AVX2 and FMA, else
// four in double) against measurePeak() one by one in double, over every slit's region of a frame:
// shared by the 8-bit test (extractor_test.cpp) and the 16-bit one (bit_depth_test.cpp).
#pragma once

#include "multislit/reference.h"
#include "multislit/slit_profile.h"

#include <gtest/gtest.h>
#include <opencv2/core/mat.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <memory>
#include <vector>

namespace multislit {

struct BatchedAgreement {
  std::size_t regions = 0, found = 0, differ = 0;  ///< found by both; by one only
  double worst = 0;                                ///< largest centre difference [px]
};

/// Adds the regions of `image` (pixels of T) to `a`, each profile's contrast checked within 1e-3.
template <typename T>
void addBatchedAgreement(const Reference& ref, const cv::Mat& image, const ProfileParams& p,
                         BatchedAgreement& a) {
  std::vector<PeakRegion<T>> regions;
  for (const ReferenceSlit& slit : ref.slits)
    for (std::size_t k = 0; k < slit.u.size(); ++k) {
      if (!std::isfinite(slit.u[k])) continue;
      const double half = 0.5 * ref.region_width;
      regions.push_back({image.ptr<T>(slit.first_row + static_cast<int>(k)),
                         static_cast<int>(std::ceil(slit.u[k] - half)),
                         static_cast<int>(std::floor(slit.u[k] + half))});
    }
  std::vector<Peak> peaks(regions.size());
  std::unique_ptr<bool[]> batched(new bool[regions.size()]);
  measurePeaks(regions.data(), regions.size(), image.cols, p, peaks.data(), batched.get());
  for (std::size_t i = 0; i < regions.size(); ++i) {
    Peak one;
    const bool alone =
        measurePeak(regions[i].row, image.cols, regions[i].first, regions[i].last, p, &one);
    ++a.regions;
    a.differ += alone != batched[i];
    if (!alone || !batched[i]) continue;
    ++a.found;
    a.worst = std::max(a.worst, std::abs(one.centre - peaks[i].centre));
    EXPECT_NEAR(one.contrast, peaks[i].contrast, 1e-3 * one.contrast);
  }
}

/// Prints `a` and expects nine in ten regions found, by both or by neither, within 1e-3 px.
inline void expectBatchedAgreement(const BatchedAgreement& a) {
  std::printf(
      "%zu regions: %zu profiles found by both, %zu found by one only; largest centre "
      "difference %.2e px\n",
      a.regions, a.found, a.differ, a.worst);
  EXPECT_GT(a.found, a.regions * 9 / 10);
  EXPECT_EQ(a.differ, 0u);
  EXPECT_LT(a.worst, 1e-3);
}

}  // namespace multislit
