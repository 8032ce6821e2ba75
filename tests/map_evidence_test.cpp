// Parts of the map's evidence (src/map_evidence.h) against the standard library: the median of the
// slits' move residuals by radix select is the value std::nth_element gives.
#include "map_evidence.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace {

using multislit::detail::upperMedian;

/// nth_element's value at size / 2.
float stockMedian(std::vector<float> values) {
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

TEST(UpperMedian, IsNthElementsValue) {
  std::mt19937 rng(17);
  std::uniform_int_distribution<int> size(1, 5000), kind(0, 3);
  std::uniform_real_distribution<float> residual(0.0f, 0.004f);
  std::vector<float> values;
  std::vector<std::uint32_t> bits;
  std::size_t with_ties = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    values.resize(static_cast<std::size_t>(size(rng)));
    const int k = kind(rng);
    for (float& v : values) {
      v = residual(rng);
      if (k == 1) v = std::round(v * 2000.0f) / 2000.0f;  // few values: many ties
      if (k == 2 && v < 0.001f) v = 0.0f;                 // zeros
      if (k == 3 && v > 0.0039f) v = std::numeric_limits<float>::infinity();
    }
    with_ties += k == 1;
    const float expected = stockMedian(values);
    ASSERT_EQ(upperMedian(values, bits), expected) << "trial " << trial;
  }
  EXPECT_GT(with_ties, 400u);
}

TEST(UpperMedian, FallsBackOnNegativeZeroAndSmallSizes) {
  std::vector<std::uint32_t> bits;
  std::vector<float> values{0.3f, -0.2f, 0.1f, -0.0f, 0.5f};
  EXPECT_EQ(upperMedian(values, bits), 0.1f);
  values = {0.0f, -0.0f, 0.0f};
  EXPECT_EQ(upperMedian(values, bits), 0.0f);
  values = {};
  EXPECT_EQ(upperMedian(values, bits), 0.0f);
  values = {0.25f};
  EXPECT_EQ(upperMedian(values, bits), 0.25f);
  values = {0.2f, 0.7f};
  EXPECT_EQ(upperMedian(values, bits), 0.7f);
}

}  // namespace
