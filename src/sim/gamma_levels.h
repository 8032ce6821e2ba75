// The camera's gamma and quantization in the simulator (private to it): the output level of each
// exposed value v in [0, 1], (int)((float)std::pow(v, 1 / gamma) x full + 0.5f), bit for bit,
// without a std::pow per pixel. The level rises with v, so the least v of every level, found once
// per gamma and bit depth, decides it: a float estimate of the level, then moved up or down to the
// level whose least v is the largest at most v.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

namespace multislit {

class GammaLevels {
 public:
  /// The levels of a camera with `gamma` (> 0) whose full scale is `full` (255 or 65535).
  GammaLevels(double gamma, float full);

  /// The table for `gamma` and `full`, made once and kept (the last few, for every thread).
  static std::shared_ptr<const GammaLevels> cached(double gamma, float full);

  /// The level of v by std::pow: what the table reproduces.
  int exact(float v) const;

  /// out[c] = exact(value[c]) for c < n, each value in [0, 1] (T: std::uint8_t or std::uint16_t).
  template <typename T>
  void quantize(const float* value, T* out, int n) const;

 private:
  /// The least value of `level` or above (1 <= level <= top_), by bisection on the floats' bits.
  float leastOf(int level) const;

  double exponent_;           ///< 1 / gamma, as the camera model computes it
  float full_;                ///< [DN]
  int top_;                   ///< the level of 1
  std::vector<float> least_;  ///< least_[k]: the least v of level k or above; least_[top_ + 1]: inf
};

}  // namespace multislit
