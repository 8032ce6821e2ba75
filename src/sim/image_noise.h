// The noise of the rendered image (private to the simulator): laser speckle, then the camera's
// lens blur, shot and read noise and quantization. Each pixel draws its own random numbers, so
// the bytes do not depend on how rows are shared between threads.
#pragma once

#include "multislit/sim/simulator.h"

#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <vector>

namespace multislit {

/// The gamma speckle's intensity (mean 1) at each standard normal quantile of its table, for
/// RenderConfig::speckle_contrast `contrast`.
std::vector<float> gammaQuantiles(double contrast);

/// Multiplies `laser` by the speckle of `render` (mean 1, std speckle_contrast per pixel) of frame
/// `frame`, where `lit` (CV_8U) is set; `laser` must be 0 elsewhere. `gamma_quantiles` from
/// gammaQuantiles() for SpeckleModel::Gamma. `field` and `blurred` are buffers (made by create()).
void applySpeckle(cv::Mat& laser, const cv::Mat& lit, const RenderConfig& render, uint64_t frame,
                  const std::vector<float>& gamma_quantiles, cv::Mat& field, cv::Mat& blurred);

/// The camera's image of `sharp`, the irradiance (CV_32F) [FS]: lens blur, then shot and read
/// noise, saturation and quantization to render.bit_depth (CV_8U or CV_16U). `blurred` is a
/// buffer (made by create()), not `sharp`.
cv::Mat exposeSensor(const cv::Mat& sharp, const RenderConfig& render, uint64_t frame,
                     cv::Mat& blurred);

}  // namespace multislit
