// The noise of the rendered image: laser speckle and the camera's shot and read noise.
#include "sim/image_noise.h"

#include "sim/parallel_rows.h"

#include <boost/math/special_functions/gamma.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace multislit {
namespace {

// Counter-based random numbers: each image row has its own stream, so the bytes do not depend
// on how rows are shared between threads.
class RowRandom {
 public:
  RowRandom(uint64_t seed, uint64_t frame, uint64_t row, uint64_t stream)
      : state_(mix(mix(mix(seed) ^ frame) ^ (row << 8 | stream))) {}

  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = 1.0 - uniform(), u2 = uniform();  // u1 in (0, 1]
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * M_PI * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * M_PI * u2);
  }

 private:
  static uint64_t mix(uint64_t z) {
    z += 0x9E3779B97F4A7C15ULL;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  uint64_t next() { return mix(state_ += 0x9E3779B97F4A7C15ULL); }

  uint64_t state_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

enum Stream : uint64_t { kSpeckle = 1, kSensorNoise = 2 };

// The gamma speckle's quantile table: standard normal values z in [-reach, reach], `step` per unit.
constexpr double kQuantileReach = 8.0, kQuantileStep = 128.0;

}  // namespace

// Gamma(shape k, mean 1) quantile at the normal quantile of each z of the table.
std::vector<float> gammaQuantiles(double contrast) {
  const double k = 1.0 / (contrast * contrast);
  const int n = static_cast<int>(2 * kQuantileReach * kQuantileStep) + 1;
  std::vector<float> table(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double z = i / kQuantileStep - kQuantileReach;
    // The lower tail from P, the upper tail from Q: both accurate far out.
    const double x = z < 0 ? boost::math::gamma_p_inv(k, 0.5 * std::erfc(-z / std::sqrt(2.0)))
                           : boost::math::gamma_q_inv(k, 0.5 * std::erfc(z / std::sqrt(2.0)));
    table[static_cast<std::size_t>(i)] = static_cast<float>(x / k);
  }
  return table;
}

// Multiplies `laser` by the speckle of `render` (mean 1, std speckle_contrast per pixel): a
// white Gaussian field blurred by the grain, then either 1 + contrast x field clamped at 0
// (Gaussian) or the field's normal quantile mapped to the gamma distribution's (Gamma).
void applySpeckle(cv::Mat& laser, const RenderConfig& render, uint64_t frame,
                  const std::vector<float>& gamma_quantiles) {
  cv::Mat speckle(laser.rows, laser.cols, CV_32F);
  parallelRows(laser.rows, [&](const cv::Range& rows) {
    for (int r = rows.start; r < rows.end; ++r) {
      RowRandom rng(render.seed, frame, static_cast<uint64_t>(r), kSpeckle);
      float* s = speckle.ptr<float>(r);
      for (int c = 0; c < laser.cols; ++c) s[c] = static_cast<float>(rng.normal());
    }
  });
  const double g = render.speckle_grain;
  cv::GaussianBlur(speckle, speckle, cv::Size(), g, g, cv::BORDER_REFLECT);
  if (render.speckle_model == SpeckleModel::Gaussian) {
    speckle = 1.0 + render.speckle_contrast * 2.0 * std::sqrt(M_PI) * g * speckle;
    cv::max(speckle, 0.0, speckle);
  } else {
    // The blurred field's std is the sum of the squared 1-D kernel weights (OpenCV's kernel).
    const cv::Mat k = cv::getGaussianKernel(cv::saturate_cast<int>(g * 8 + 1) | 1, g, CV_64F);
    const double scale = 1.0 / k.dot(k), last = static_cast<double>(gamma_quantiles.size() - 1);
    parallelRows(laser.rows, [&](const cv::Range& rows) {
      for (int r = rows.start; r < rows.end; ++r) {
        float* s = speckle.ptr<float>(r);
        for (int c = 0; c < laser.cols; ++c) {
          const double x = std::clamp((s[c] * scale + kQuantileReach) * kQuantileStep, 0.0, last);
          const auto i = std::min(static_cast<std::size_t>(x), gamma_quantiles.size() - 2);
          const double f = x - static_cast<double>(i);
          s[c] = static_cast<float>((1 - f) * gamma_quantiles[i] + f * gamma_quantiles[i + 1]);
        }
      }
    });
  }
  laser = laser.mul(speckle);
}

// The camera's image of `irradiance` [FS]: lens blur, then shot and read noise, saturation and
// quantization to render.bit_depth.
cv::Mat exposeSensor(cv::Mat irradiance, const RenderConfig& render, uint64_t frame) {
  if (render.blur_sigma > 0)
    cv::GaussianBlur(irradiance, irradiance, cv::Size(), render.blur_sigma, render.blur_sigma,
                     cv::BORDER_REFLECT);
  const double full = render.bit_depth == 8 ? 255.0 : 65535.0;
  cv::Mat image(irradiance.rows, irradiance.cols, render.bit_depth == 8 ? CV_8U : CV_16U);
  parallelRows(irradiance.rows, [&](const cv::Range& rows) {
    for (int r = rows.start; r < rows.end; ++r) {
      RowRandom rng(render.seed, frame, static_cast<uint64_t>(r), kSensorNoise);
      const float* e = irradiance.ptr<float>(r);
      for (int c = 0; c < irradiance.cols; ++c) {
        double value = e[c];
        if (render.noise) {
          const double noise = std::sqrt(std::max(value, 0.0) / render.full_well +
                                         render.read_noise * render.read_noise);
          value += noise * rng.normal();
        }
        value = std::clamp(value, 0.0, 1.0);
        if (render.gamma != 1.0) value = std::pow(value, 1.0 / render.gamma);
        const double dn = std::round(value * full);
        if (render.bit_depth == 8)
          image.ptr<uint8_t>(r)[c] = static_cast<uint8_t>(dn);
        else
          image.ptr<uint16_t>(r)[c] = static_cast<uint16_t>(dn);
      }
    }
  });
  return image;
}

}  // namespace multislit
