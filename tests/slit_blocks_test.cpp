// SlitBlocks (FloorDetector's step 6): the median of every window along a slit, merged from
// sorted blocks in vector lanes, is the median of that window's candidates taken one window at a
// time, bit for bit, at every window length, with ties, missing cells and cut slits.
#include "slit_blocks.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

using multislit::detail::SlitBlocks;

namespace {

// The definition: for each cell k = m stride of a slit that is a candidate (not NaN), the
// candidates of cells [k - stride + 1, k + stride - 1] cut at the slit's ends, when at least
// stride of them; sorted, the value at n / 2, for an even n the mean of it and the one before.
std::vector<float> windowByWindow(const std::vector<float>& cells, std::size_t width,
                                  std::size_t stride) {
  std::vector<float> medians;
  for (std::size_t row = 0; row + width <= cells.size(); row += width)
    for (std::size_t k = 0; k < width; k += stride) {
      if (std::isnan(cells[row + k])) continue;
      std::vector<float> window;
      for (std::size_t j = k + 1 > stride ? k + 1 - stride : 0; j < std::min(width, k + stride);
           ++j)
        if (!std::isnan(cells[row + j])) window.push_back(cells[row + j]);
      const std::size_t n = window.size();
      if (n < stride) continue;
      std::sort(window.begin(), window.end());
      const float mid = window[n / 2];
      medians.push_back(std::abs(n % 2 == 0 ? 0.5f * (mid + window[n / 2 - 1]) : mid));
    }
  return medians;
}

std::uint32_t bitsOf(float x) {
  std::uint32_t b = 0;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

TEST(SlitBlocks, EveryWindowsMedianIsThatOfItsCandidates) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> eighths(-16, 16);  // on a grid of 1/8: many ties
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::size_t compared = 0;
  for (const std::size_t stride : {2u, 3u, 4u, 5u, 8u})
    for (const std::size_t width : {3u, 17u, 64u, 301u}) {
      std::vector<float> cells(5 * width);
      for (float& c : cells)
        c = unit(rng) < 0.2f ? std::nanf("") : static_cast<float>(eighths(rng)) / 8.0f;
      SlitBlocks blocks;
      blocks.start(cells, width, stride);
      std::vector<float> medians;
      for (std::size_t length = stride; length <= 8 * stride; length *= 2) {
        const std::size_t n = blocks.mediansThenDouble(medians);
        const std::vector<float> expected = windowByWindow(cells, width, length);
        ASSERT_EQ(n, expected.size()) << "stride " << length << ", width " << width;
        for (std::size_t i = 0; i < n; ++i)
          ASSERT_EQ(bitsOf(medians[i]), bitsOf(expected[i]))
              << "window " << i << ", stride " << length << ", width " << width;
        compared += n;
      }
    }
  EXPECT_GT(compared, 1500u);  // the windows compared, over all lengths and slits
}

}  // namespace
