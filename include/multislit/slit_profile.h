// The slit's centre on one image row (paper Sec. II-C: "centroids of a slit are calculated along
// the horizontal direction"), with background removal and validity tests.
#pragma once

#include <cstddef>
#include <cstdint>

namespace multislit {

/// How the sub-pixel centre of a slit profile is estimated.
enum class Estimator {
  Centroid,  ///< the paper's centre of mass of the background-subtracted profile
  Gaussian,  ///< weighted least-squares parabola through the log of the profile (Caruana)
  Windowed,  ///< centroid under a Gaussian window of the profile's width, re-centred (matched)
};

/// Parameters of one row profile, in the image's own digital numbers (DN).
struct ProfileParams {
  Estimator estimator = Estimator::Gaussian;
  int half_window = 10;        ///< pixels on each side of the peak used for the centre [px]
  double min_contrast = 15.0;  ///< peak above the background [DN]
  double min_width = 1.5;      ///< narrowest profile (pixels above half maximum) [px]
  double max_width = 20.0;     ///< widest profile (reflections, blooming) [px]
  double saturation = 255.0;   ///< a pixel at or above this is saturated [DN]
  int max_saturated = 12;      ///< longest saturated run still measured [px]
  double fit_threshold = 0.2;  ///< pixels below this share of the contrast are ignored [-]
  double window_sigma = 3.5;   ///< Gaussian window of the Windowed estimator [px]
};

/// A measured slit profile.
struct Peak {
  double centre = 0.0;    ///< sub-pixel column [px]
  double contrast = 0.0;  ///< peak minus background [DN]
  double width = 0.0;     ///< pixels above half of the contrast [px]
  bool saturated = false;
};

/// Finds the brightest profile whose peak lies in columns [first, last] of `row` (a row of
/// `columns` pixels) and measures it. False when no valid profile is there.
template <typename T>
bool measurePeak(const T* row, int columns, int first, int last, const ProfileParams& params,
                 Peak* peak);

/// Measures the profile whose maximum is at column `top` (no search).
template <typename T>
bool measurePeakAt(const T* row, int columns, int top, const ProfileParams& params, Peak* peak);

/// One region of measurePeaks(): columns [first, last] of an image row.
template <typename T>
struct PeakRegion {
  const T* row = nullptr;
  int first = 0, last = 0;
};

/// measurePeak() of `count` regions of rows `columns` wide: found[i] and peaks[i] are what
/// measurePeak(regions[i].row, columns, regions[i].first, regions[i].last, ...) returns and
/// measures. Faster: with the Gaussian estimator, CPUs with AVX2 and FMA measure eight profiles
/// (8- or 16-bit) at a time in float (the same profiles found, centres within float rounding:
/// 8e-6 px at 8 bits, 1.6e-5 px at 16, on rendered frames); otherwise (profiles wider than 57 px,
/// no FMA) AVX2 measures four at a time in double, bit for bit.
template <typename T>
void measurePeaks(const PeakRegion<T>* regions, std::size_t count, int columns,
                  const ProfileParams& params, Peak* peaks, bool* found);

extern template bool measurePeak<uint8_t>(const uint8_t*, int, int, int, const ProfileParams&,
                                          Peak*);
extern template bool measurePeak<uint16_t>(const uint16_t*, int, int, int, const ProfileParams&,
                                           Peak*);
extern template bool measurePeakAt<uint8_t>(const uint8_t*, int, int, const ProfileParams&, Peak*);
extern template bool measurePeakAt<uint16_t>(const uint16_t*, int, int, const ProfileParams&,
                                             Peak*);
extern template void measurePeaks<uint8_t>(const PeakRegion<uint8_t>*, std::size_t, int,
                                           const ProfileParams&, Peak*, bool*);
extern template void measurePeaks<uint16_t>(const PeakRegion<uint16_t>*, std::size_t, int,
                                            const ProfileParams&, Peak*, bool*);

}  // namespace multislit
