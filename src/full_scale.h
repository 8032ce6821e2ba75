// An image's full scale (ReferenceConfig::full_scale), internal to the library: the contrast
// limits of the slit search are shares of full scale, so data of fewer bits is stretched first.
#pragma once

#include "multislit/reference.h"

#include <opencv2/core/mat.hpp>

#include <string>

namespace multislit {

/// The image stretched so that `full_scale` [DN] becomes its type's white (12-bit data in a 16-bit
/// image times 16). 0, or the type's white, keeps the image; above it is std::invalid_argument.
cv::Mat toFullRange(const cv::Mat& image, double full_scale);

/// "; the image's values reach only N of 65535: ... --full-scale 4095" for a 16-bit image whose
/// values stay under 4096 when no full scale is configured; "" otherwise.
std::string fullScaleHint(const cv::Mat& image, const ReferenceConfig& config);

}  // namespace multislit
