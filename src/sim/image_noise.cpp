// The noise of the rendered image: laser speckle and the camera's shot and read noise.
#include "image_noise.h"

#include "avx2_clones.h"
#include "gamma_levels.h"
#include "normal_rows.h"
#include "parallel_rows.h"

#include <boost/math/special_functions/gamma.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <memory>

namespace multislit {
namespace {

enum Stream : uint64_t { kSpeckle = 1, kSensorNoise = 2 };

// The gamma speckle's quantile table: standard normal values z in [-reach, reach], `step` per unit.
constexpr double kQuantileReach = 8.0, kQuantileStep = 128.0;

// value[c] = the irradiance e[c] [FS] with shot and read noise (z[c] standard normal; none when
// z is null), clipped to [0, 1]: no branches, the compiler vectorizes it.
MULTISLIT_AVX2_CLONES void addSensorNoise(const float* __restrict e, const float* __restrict z,
                                          float* __restrict value, int n, float per_electron,
                                          float read_variance) {
  if (!z) {
    for (int c = 0; c < n; ++c) value[c] = std::min(std::max(e[c], 0.0f), 1.0f);
    return;
  }
  for (int c = 0; c < n; ++c) {
    const float v = e[c] + std::sqrt(std::max(e[c], 0.0f) * per_electron + read_variance) * z[c];
    value[c] = std::min(std::max(v, 0.0f), 1.0f);
  }
}

// out[c] = value[c] x full rounded (value in [0, 1]): a loop the compiler vectorizes.
template <typename T>
void quantize(const float* __restrict value, float full, T* __restrict out, int n) {
  for (int c = 0; c < n; ++c) out[c] = static_cast<T>(static_cast<int>(value[c] * full + 0.5f));
}

// cv::GaussianBlur of `image` (kernel `ksize`, sigma `sigma`, BORDER_REFLECT) into `out` (made by
// create(), not `image`) in bands of rows on OpenCV's threads (its filters run on one). Each band
// is filtered as a region of the whole image, which takes the rows beyond the band from the image
// (the reflection only at its edges): the same values as one call.
void blurInBands(const cv::Mat& image, cv::Size ksize, double sigma, cv::Mat& out) {
  out.create(image.size(), image.type());
  const int bands = std::max(1, std::min(image.rows / 64, 2 * cv::getNumThreads()));
  parallelRows(bands, [&](const cv::Range& range) {
    for (int b = range.start; b < range.end; ++b) {
      const cv::Range rows(image.rows * b / bands, image.rows * (b + 1) / bands);
      cv::Mat band = out.rowRange(rows);
      cv::GaussianBlur(image.rowRange(rows), band, ksize, sigma, sigma, cv::BORDER_REFLECT);
    }
  });
}

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
// (Gaussian) or the field's normal quantile mapped to the gamma distribution's (Gamma), where
// `lit` (CV_8U) is set: `laser` must be 0 elsewhere.
void applySpeckle(cv::Mat& laser, const cv::Mat& lit, const RenderConfig& render, uint64_t frame,
                  const std::vector<float>& gamma_quantiles, cv::Mat& field, cv::Mat& blurred) {
  const double g = render.speckle_grain;
  const int ksize = cv::saturate_cast<int>(g * 8 + 1) | 1;  // OpenCV's kernel for CV_32F
  field.create(laser.rows, laser.cols, CV_32F);
  parallelRows(laser.rows, [&](const cv::Range& rows) {
    for (int r = rows.start; r < rows.end; ++r)
      normalRow(rowStream(render.seed, frame, static_cast<uint64_t>(r), kSpeckle),
                field.ptr<float>(r), laser.cols);
  });
  blurInBands(field, cv::Size(ksize, ksize), g, blurred);
  const cv::Mat& speckle = blurred;
  // Gaussian: 1 + contrast x the field of unit std; Gamma: the field's normal quantile mapped to
  // the gamma distribution's. The blurred field's std is the sum of the squared 1-D kernel
  // weights (OpenCV's kernel); a continuous kernel gives 1 / (2 sqrt(pi) g).
  const bool gaussian = render.speckle_model == SpeckleModel::Gaussian;
  const cv::Mat k = cv::getGaussianKernel(ksize, g, CV_64F);
  const double scale =
                   gaussian ? render.speckle_contrast * 2.0 * std::sqrt(M_PI) * g : 1.0 / k.dot(k),
               last = static_cast<double>(gamma_quantiles.size()) - 1;
  parallelRows(laser.rows, [&](const cv::Range& rows) {
    for (int r = rows.start; r < rows.end; ++r) {
      const uchar* l = lit.ptr<uchar>(r);
      const float* s = speckle.ptr<float>(r);
      float* out = laser.ptr<float>(r);
      for (int c = 0; c < laser.cols; ++c) {
        if (!l[c]) continue;
        double factor;
        if (gaussian) {
          factor = std::max(0.0, 1.0 + scale * s[c]);
        } else {
          const double x = std::clamp((s[c] * scale + kQuantileReach) * kQuantileStep, 0.0, last);
          const auto i = std::min(static_cast<std::size_t>(x), gamma_quantiles.size() - 2);
          const double f = x - static_cast<double>(i);
          factor = (1 - f) * gamma_quantiles[i] + f * gamma_quantiles[i + 1];
        }
        out[c] = static_cast<float>(out[c] * factor);
      }
    }
  });
}

// The camera's image of `sharp` (the irradiance [FS]): lens blur, then shot and read noise,
// saturation and quantization to render.bit_depth.
cv::Mat exposeSensor(const cv::Mat& sharp, const RenderConfig& render, uint64_t frame,
                     cv::Mat& blurred) {
  if (render.blur_sigma > 0) blurInBands(sharp, cv::Size(), render.blur_sigma, blurred);
  const cv::Mat& irradiance = render.blur_sigma > 0 ? blurred : sharp;
  const float full = render.bit_depth == 8 ? 255.0f : 65535.0f;
  cv::Mat image(irradiance.rows, irradiance.cols, render.bit_depth == 8 ? CV_8U : CV_16U);
  const auto per_electron = static_cast<float>(1.0 / render.full_well),
             read_variance = static_cast<float>(render.read_noise * render.read_noise);
  // The gamma (before quantizing) by the least value of each level, not a std::pow per pixel.
  const std::shared_ptr<const GammaLevels> levels =
      render.gamma != 1.0 ? GammaLevels::cached(render.gamma, full) : nullptr;
  parallelRows(irradiance.rows, [&](const cv::Range& rows) {
    std::vector<float> value(static_cast<std::size_t>(irradiance.cols)), z(value.size());
    for (int r = rows.start; r < rows.end; ++r) {
      if (render.noise)
        normalRow(rowStream(render.seed, frame, static_cast<uint64_t>(r), kSensorNoise), z.data(),
                  irradiance.cols);
      addSensorNoise(irradiance.ptr<float>(r), render.noise ? z.data() : nullptr, value.data(),
                     irradiance.cols, per_electron, read_variance);
      // Rounded to the nearest DN: value is in [0, 1].
      const auto quantizeRow = [&](auto* out) {
        if (levels)
          levels->quantize(value.data(), out, irradiance.cols);
        else
          quantize(value.data(), full, out, irradiance.cols);
      };
      if (render.bit_depth == 8)
        quantizeRow(image.ptr<uint8_t>(r));
      else
        quantizeRow(image.ptr<uint16_t>(r));
    }
  });
  return image;
}

}  // namespace multislit
