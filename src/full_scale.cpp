// An image's full scale: 12-bit data in 16-bit images stretched to 16 bits, and the hint when an
// image looks like 12-bit data read as 16-bit.
#include "full_scale.h"

#include <opencv2/core.hpp>

#include <stdexcept>

namespace multislit {

/// The image stretched so that `full_scale` [DN] becomes its type's white (12-bit data in a 16-bit
/// image times 16): the contrast limits are shares of full scale. 0 keeps the image.
cv::Mat toFullRange(const cv::Mat& image, double full_scale) {
  const double white = image.depth() == CV_8U ? 255.0 : 65535.0;
  if (!(full_scale > 0) || full_scale == white) return image;
  if (full_scale > white)
    throw std::invalid_argument("full_scale " + std::to_string(full_scale) + " DN is above the " +
                                std::to_string(static_cast<int>(white)) + " of the image's type");
  cv::Mat out;
  image.convertTo(out, image.depth(), white / full_scale);
  return out;
}

/// A hint for an image that shows no slit: 16-bit images whose values stay under 4096 hold
/// 12-bit data (or 10-bit), whose stripes are under any share of 65535.
std::string fullScaleHint(const cv::Mat& image, const ReferenceConfig& config) {
  if (image.depth() != CV_16U || config.full_scale > 0) return "";
  double top = 0;
  cv::minMaxLoc(image, nullptr, &top);
  if (top >= 4096) return "";
  return "; the image's values reach only " + std::to_string(static_cast<int>(top)) +
         " of 65535: for 12-bit data give the full scale (calibrate --full-scale 4095)";
}

}  // namespace multislit
