// The simulator's gamma levels (src/sim/gamma_levels.h): the level of every exposed value found
// from the table of each level's least value is the level std::pow gives, for gammas below and
// above 1 and 8- and 16-bit cameras: at every level's edge (the float there and its neighbours)
// and on floats spread over [0, 1].
#include "sim/gamma_levels.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <vector>

namespace {

using multislit::GammaLevels;

float floatOf(std::uint32_t bits) {
  float v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

std::uint32_t bitsOf(float v) {
  std::uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  return bits;
}

/// quantize() of `values` against exact() of each; returns how many were checked.
template <typename T>
std::size_t expectExact(const GammaLevels& levels, const std::vector<float>& values) {
  std::vector<T> out(values.size());
  levels.quantize(values.data(), out.data(), static_cast<int>(values.size()));
  for (std::size_t i = 0; i < values.size(); ++i)
    if (out[i] != levels.exact(values[i])) {
      ADD_FAILURE() << "value " << values[i] << ": level " << out[i] << ", std::pow "
                    << levels.exact(values[i]);
      return i;
    }
  return values.size();
}

/// Every level's edge (found by bisection on exact()) and the floats each side of it, then
/// every 257th float of [0, 1].
template <typename T>
void expectEveryLevelExact(double gamma, float full) {
  const GammaLevels levels(gamma, full);
  const std::uint32_t one = bitsOf(1.0f);
  std::vector<float> values;
  std::uint32_t lo = 0;
  for (int level = 1; level <= levels.exact(1.0f); ++level) {
    std::uint32_t hi = one;  // exact(lo) < level <= exact(hi)
    while (hi - lo > 1) {
      const std::uint32_t mid = lo + (hi - lo) / 2;
      (levels.exact(floatOf(mid)) < level ? lo : hi) = mid;
    }
    for (std::uint32_t b = hi > 3 ? hi - 3 : 0; b <= hi + 3 && b <= one; ++b)
      values.push_back(floatOf(b));
  }
  const std::size_t edges = values.size();
  EXPECT_GT(edges, static_cast<std::size_t>(6 * full));
  for (std::uint32_t b = 0; b <= one; b += 257) values.push_back(floatOf(b));
  values.push_back(0.0f);
  values.push_back(1.0f);
  EXPECT_EQ(expectExact<T>(levels, values), values.size()) << "gamma " << gamma;
}

TEST(GammaLevels, EightBitLevelsAreThoseOfStdPow) {
  for (const double gamma : {0.8, 1.02, 1.65, 2.2}) expectEveryLevelExact<std::uint8_t>(gamma, 255);
}

TEST(GammaLevels, SixteenBitLevelsAreThoseOfStdPow) {
  for (const double gamma : {0.8, 1.89, 2.2}) expectEveryLevelExact<std::uint16_t>(gamma, 65535);
}

TEST(GammaLevels, OneTablePerGammaAndDepthIsKept) {
  const auto a = GammaLevels::cached(1.7, 255), b = GammaLevels::cached(1.7, 255);
  EXPECT_EQ(a.get(), b.get());
  EXPECT_NE(GammaLevels::cached(1.7, 65535).get(), a.get());
  EXPECT_EQ(a->exact(1.0f), 255);
}

}  // namespace
