#include "normal_rows.h"

#include "avx2_clones.h"

#include <boost/math/special_functions/erf.hpp>

#include <array>
#include <cmath>

namespace multislit {
namespace {

// Inverse normal distribution at probability p < 1/2.
double quantile(double p) { return -M_SQRT2 * boost::math::erfc_inv(2 * p); }

// The lower half of the inverse normal distribution at 32-bit probabilities g / 2^32, g < 2^31:
// [0, 4096] the tail g < 2^20 at g = j 2^8 (node 0 at 2^-33, the smallest probability drawn),
// [4096 + i] the body at g = i 2^20, i in [1, 2048].
struct QuantileTable {
  static constexpr int kTail = 4096, kBody = 2048;
  std::array<float, kTail + kBody + 1> node{};

  QuantileTable() {
    node[0] = static_cast<float>(quantile(0x1p-33));
    for (int j = 1; j <= kTail; ++j) node[j] = static_cast<float>(quantile(j * 0x1p-24));
    for (int i = 1; i < kBody; ++i) node[kTail + i] = static_cast<float>(quantile(i * 0x1p-12));
    node[kTail + kBody] = 0.0f;  // the median
  }
};

const QuantileTable& quantileTable() {
  static const QuantileTable table;
  return table;
}

// A bijective 32-bit hash with low bias (C. Wellons' lowbias32).
inline std::uint32_t hash32(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

// normalRow without branches between columns: the compiler vectorizes it.
MULTISLIT_AVX2_CLONES void normalRowKernel(std::uint32_t stream, float* __restrict out, int n,
                                           const float* __restrict node) {
  for (int c = 0; c < n; ++c) {
    const std::uint32_t h = hash32(stream + static_cast<std::uint32_t>(c) * 0x9E3779B9U);
    const std::uint32_t upper = h >> 31;  // the upper half: the mirror image of ~h
    const auto g = static_cast<std::int32_t>(h ^ (0U - upper));           // in [0, 2^31)
    const std::int32_t tail = -static_cast<std::int32_t>(g < (1 << 20));  // all ones in the tail
    const std::int32_t k = ((g >> 8) & tail) | ((QuantileTable::kTail + (g >> 20)) & ~tail);
    const float frac = static_cast<float>((g & 0xFF & tail) | (g & 0xFFFFF & ~tail)) *
                       (0x1p-20f + (0x1p-8f - 0x1p-20f) * static_cast<float>(-tail));
    const float z = node[k] + frac * (node[k + 1] - node[k]);
    out[c] = z * (1.0f - 2.0f * static_cast<float>(upper));
  }
}

inline std::uint64_t mix(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

}  // namespace

std::uint32_t rowStream(std::uint64_t seed, std::uint64_t frame, std::uint64_t row,
                        std::uint64_t source) {
  return static_cast<std::uint32_t>(mix(mix(mix(seed) ^ frame) ^ (row << 8 | source)) >> 32);
}

void normalRow(std::uint32_t stream, float* out, int n) {
  normalRowKernel(stream, out, n, quantileTable().node.data());
}

}  // namespace multislit
