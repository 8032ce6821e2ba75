// Finding the slits of a reference image (paper Sec. II-C, Fig. 6): the slit centres on every
// row, followed down the image into tracks, pieces of one slit joined, spurious tracks dropped.
// Internal to the library (reference.cpp and its calibration use it).
#pragma once

#include "multislit/reference.h"

#include <opencv2/core/mat.hpp>

#include <string>
#include <vector>

namespace multislit {

/// The slits found in one image of a plane, ordered across the fan.
struct DetectedSlits {
  std::vector<ReferenceSlit> slits;
  double profile_width = 0;  ///< the stripe's width across a row (FWHM), median [px]
  double smoothing_rms = 0;  ///< rms of the row centres about the smoothed slits [px]
  int joined = 0;            ///< pieces joined to a slit across a gap [-]
  int dropped = 0;           ///< tracks that were not slits (speckle, reflections) [-]
};

/// The stripe's width across a row (FWHM) [px], measured on rows smoothed against speckle and
/// corrected for that smoothing; 0 when no stripe stands `min_contrast` [DN] above its
/// surroundings. Nothing is assumed about the width: it is what the image shows.
double stripeWidth(const cv::Mat& image, double min_contrast);

/// The noise of an image's pixels (std) [DN], from the median of their second differences along
/// rows: the background is smooth, so what is left is noise.
double imageNoise(const cv::Mat& image);

/// Finds `config.expected_slits` slits in an 8- or 16-bit image of a plane. Throws
/// std::runtime_error starting with `what` and saying what was found when the image does not
/// show the pattern.
DetectedSlits detectSlits(const cv::Mat& image, const ReferenceConfig& config,
                          const std::string& what);

}  // namespace multislit
