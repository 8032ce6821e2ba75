// The first largest pixel of a region (firstMax in src/slit_profile_simd.h), where each profile's
// measure starts: its vector forms for 8- and 16-bit rows (AVX2 where the CPU has it, their last
// load overlapping the one before) against std::max_element, at every length from 1 to 100 and
// with the maximum repeated, at the ends and nowhere near them.
#include "slit_profile_simd.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace {

template <typename T>
void expectFirstMaxAsMaxElement() {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> pixel(0, std::numeric_limits<T>::max());
  std::uniform_int_distribution<int> few(0, 3);  // many ties
  std::size_t checked = 0;
  for (int n = 1; n <= 100; ++n)
    for (int trial = 0; trial < 40; ++trial) {
      // One element of padding each side: the loads must stay inside [p, p + n).
      std::vector<T> row(static_cast<std::size_t>(n) + 2, std::numeric_limits<T>::max());
      T* p = row.data() + 1;
      for (int i = 0; i < n; ++i) p[i] = static_cast<T>(trial % 2 ? few(rng) : pixel(rng));
      if (trial % 5 == 0) p[n - 1] = std::numeric_limits<T>::max() - 1;  // the last, largest
      if (trial % 7 == 0) p[0] = std::numeric_limits<T>::max() - 1;      // then the first wins
      const auto expected = static_cast<int>(std::max_element(p, p + n) - p);
      ASSERT_EQ(multislit::profile::firstMax(p, n), expected) << "n " << n << " trial " << trial;
      ++checked;
    }
  EXPECT_EQ(checked, 4000u);
}

TEST(FirstMax, EightBitRowsAsMaxElement) { expectFirstMaxAsMaxElement<std::uint8_t>(); }

TEST(FirstMax, SixteenBitRowsAsMaxElement) { expectFirstMaxAsMaxElement<std::uint16_t>(); }

}  // namespace
