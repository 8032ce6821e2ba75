#include "gamma_levels.h"

#include "avx2_clones.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <utility>

namespace multislit {
namespace {

std::uint32_t bitsOf(float v) {
  std::uint32_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

float floatOf(std::uint32_t b) {
  float v;
  std::memcpy(&v, &b, sizeof v);
  return v;
}

/// level[c]: an estimate of the level of value[c] in [0, 1], (float)v^exponent x full + 0.5 to
/// within about 1e-6 of it, in [0, top]: e^(exponent ln v), ln v from v's exponent and a series in
/// s = (m - 1) / (m + 1) of its mantissa m in [sqrt(1/2), sqrt(2)), e^y = 2^k e^r with |r| <= ln 2
/// by a series of degree 7. Branch-free, so that the compiler vectorizes it.
MULTISLIT_AVX2_CLONES void estimateLevels(const float* __restrict value, int n, float exponent,
                                          float full, int top, std::int32_t* __restrict level) {
  for (int c = 0; c < n; ++c) {
    const float v = std::max(value[c], 1e-30f);  // 0 gives 1e-30^exponent: level 0
    const std::uint32_t bits = bitsOf(v);
    const std::int32_t e = (static_cast<std::int32_t>(bits) - 0x3f3504f3) >> 23;
    const float m = floatOf(bits - (static_cast<std::uint32_t>(e) << 23));
    const float f = m - 1.0f, s = f / (2.0f + f), s2 = s * s;
    const float ln_m = 2.0f * s * (1.0f + s2 * (1.0f / 3 + s2 * (0.2f + s2 * (1.0f / 7))));
    const float y = std::max(exponent * (static_cast<float>(e) * 0.693147181f + ln_m), -87.0f);
    const auto k = static_cast<std::int32_t>(y * 1.44269504f - 0.5f);  // y <= 0: ceil, |r| < ln 2
    const float kf = static_cast<float>(k);
    const float r = (y - kf * 0.693145752f) - kf * 1.42860677e-6f;
    const float p =
        1 +
        r * (1 + r * (0.5f + r * (1.0f / 6 +
                                  r * (1.0f / 24 +
                                       r * (1.0f / 120 + r * (1.0f / 720 + r * (1.0f / 5040)))))));
    const float power = floatOf(bitsOf(p) + (static_cast<std::uint32_t>(k) << 23));
    const auto estimate = static_cast<std::int32_t>(power * full + 0.5f);
    level[c] = std::min(std::max(estimate, std::int32_t{0}), top);
  }
}

}  // namespace

GammaLevels::GammaLevels(double gamma, float full)
    : exponent_(1.0 / gamma), full_(full), top_(exact(1.0f)) {
  least_.resize(static_cast<std::size_t>(top_) + 2);
  least_[0] = 0.0f;  // 0^exponent is 0: level 0
  for (int k = 1; k <= top_; ++k) least_[static_cast<std::size_t>(k)] = leastOf(k);
  least_.back() = std::numeric_limits<float>::infinity();
}

int GammaLevels::exact(float v) const {
  return static_cast<int>(static_cast<float>(std::pow(v, exponent_)) * full_ + 0.5f);
}

float GammaLevels::leastOf(int level) const {
  // From the level's edge by the inverse, widened until exact(lo) < level <= exact(hi), then
  // halved: the floats in [0, 1] are ordered as their bits.
  const std::uint32_t one = bitsOf(1.0f);
  const double edge = std::pow((level - 0.5) / full_, 1.0 / exponent_);
  std::uint32_t lo = bitsOf(static_cast<float>(std::min(edge, 1.0))), hi = lo;
  for (std::uint32_t step = 8; lo > 0 && exact(floatOf(lo)) >= level; step *= 4)
    lo = lo > step ? lo - step : 0;
  for (std::uint32_t step = 8; hi < one && exact(floatOf(hi)) < level; step *= 4)
    hi = std::min(one, hi + step);
  while (hi - lo > 1) {
    const std::uint32_t mid = lo + (hi - lo) / 2;
    (exact(floatOf(mid)) < level ? lo : hi) = mid;
  }
  return floatOf(hi);
}

std::shared_ptr<const GammaLevels> GammaLevels::cached(double gamma, float full) {
  using Key = std::pair<double, float>;
  static std::mutex mutex;
  static std::vector<std::pair<Key, std::shared_ptr<const GammaLevels>>> kept;  // newest last
  constexpr std::size_t kKept = 4;  // a 16-bit table is 256 KB
  const std::lock_guard<std::mutex> lock(mutex);
  const Key key(gamma, full);
  for (const auto& [k, levels] : kept)
    if (k == key) return levels;
  auto made = std::make_shared<const GammaLevels>(gamma, full);
  kept.emplace_back(key, made);
  if (kept.size() > kKept) kept.erase(kept.begin());
  return made;
}

template <typename T>
void GammaLevels::quantize(const float* value, T* out, int n) const {
  constexpr int kChunk = 256;
  std::int32_t estimate[kChunk];
  for (int begin = 0; begin < n; begin += kChunk) {
    const int count = std::min(kChunk, n - begin);
    estimateLevels(value + begin, count, static_cast<float>(exponent_), full_, top_, estimate);
    for (int c = 0; c < count; ++c) {
      const float v = value[begin + c];
      auto k = static_cast<std::size_t>(estimate[c]);
      while (v < least_[k]) --k;  // least_[0] is 0
      while (v >= least_[k + 1]) ++k;
      out[begin + c] = static_cast<T>(k);
    }
  }
}

template void GammaLevels::quantize<std::uint8_t>(const float*, std::uint8_t*, int) const;
template void GammaLevels::quantize<std::uint16_t>(const float*, std::uint16_t*, int) const;

}  // namespace multislit
