// The private parts of the slit-profile measure (private to the core library), shared by
// src/slit_profile.cpp (the scalar measure, its estimators and measurePeaks()),
// src/slit_profile_four.cpp (four profiles at a time in double lanes of AVX2) and
// src/slit_profile_eight.cpp (eight profiles at a time in float lanes of AVX2 and FMA).
#pragma once

#include "multislit/slit_profile.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__x86_64__) && defined(__GNUC__)
#define MULTISLIT_X86 1  // SSE2 is part of x86-64; AVX2 is chosen at run time
#include <immintrin.h>
#endif

namespace multislit::profile {

// The background under a profile: a line through the means of three pixels on each flank.
struct Background {
  double at_left = 0, x_left = 0, slope = 0;
  double operator()(double x) const { return at_left + slope * (x - x_left); }
};

/// ln(v) for a finite v >= 2^-1000 to within one ulp, inlined and branch-free (no table, so
/// the vector code needs no gathers): v = 2^k z with z in [sqrt(1/2), sqrt(2)), f = z - 1,
/// s = f / (2 + f), ln z = 2 atanh(s) = f - s (f - R(s)) by fdlibm's minimax R, whose error is
/// below 2^-58 (FreeBSD msun e_log.c). The vector code has the same operations, so both give the
/// same bits.
struct FastLog {
  static constexpr std::uint64_t kOff = 0x3fe6a09e667f3bcd;  // sqrt(1/2)
  static constexpr double kLn2Hi = 6.93147180369123816490e-01, kLn2Lo = 1.90821492927058770002e-10;
  static constexpr double kLg1 = 6.666666666666735130e-01, kLg2 = 3.999999999940941908e-01,
                          kLg3 = 2.857142874366239149e-01, kLg4 = 2.222219843214978396e-01,
                          kLg5 = 1.818357216161805012e-01, kLg6 = 1.531383769920937332e-01,
                          kLg7 = 1.479819860511658591e-01;

  static double log(double v) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    const std::uint64_t shifted = bits - kOff;
    const auto k = static_cast<double>(static_cast<std::int64_t>(shifted) >> 52);
    const std::uint64_t z_bits = bits - (shifted & (std::uint64_t{0xfff} << 52));
    double z;
    std::memcpy(&z, &z_bits, sizeof z);
    // ln(2^k (1 + f)), f in [sqrt(1/2) - 1, sqrt(2) - 1)
    const double f = z - 1.0, s = f / (2.0 + f), s2 = s * s, s4 = s2 * s2;
    const double r =
        s4 * (kLg2 + s4 * (kLg4 + s4 * kLg6)) + s2 * (kLg1 + s4 * (kLg3 + s4 * (kLg5 + s4 * kLg7)));
    const double half_f2 = 0.5 * f * f;
    return k * kLn2Hi - ((half_f2 - (s * (half_f2 + r) + k * kLn2Lo)) - f);
  }
};

template <typename T>
double centroid(const T* row, int lo, int hi, const Background& bg, double floor) {
  double sum = 0, moment = 0;
  for (int x = lo; x <= hi; ++x) {
    const double v = row[x] - bg(x);
    if (v <= floor) continue;
    sum += v;
    moment += v * x;
  }
  return moment / sum;
}

/// Added to the half-contrast and fit thresholds in every path: background-free values are
/// rationals of small denominators (thirds, fifths, 2 hw + 4), so a pixel can lie exactly on a
/// threshold, where float and double rounding would decide it differently. Off by this, a tie is
/// out in both, and no pixel lies within float rounding of the threshold [DN].
constexpr double kTieBreak = 1.0 / 1024;

/// Caruana's normal equations [s0 s1 s2; s1 s2 s3; s2 s3 s4] (a b c) = (r0 r1 r2) by Cramer's
/// rule: b = nb / det, c = nc / det (the row's gaussianCentre() and the columns' fit across a
/// stripe; solveByCramer() below is the same in four lanes).
struct CramerScalar {
  double det, nb, nc;
};

inline CramerScalar solveByCramer(double s0, double s1, double s2, double s3, double s4, double r0,
                                  double r1, double r2) {
  const double m00 = s0, m01 = s1, m02 = s2, m11 = s2, m12 = s3, m22 = s4;
  return {
      m00 * (m11 * m22 - m12 * m12) - m01 * (m01 * m22 - m12 * m02) + m02 * (m01 * m12 - m11 * m02),
      m00 * (r1 * m22 - m12 * r2) - r0 * (m01 * m22 - m12 * m02) + m02 * (m01 * r2 - r1 * m02),
      m00 * (m11 * r2 - r1 * m12) - m01 * (m01 * r2 - r1 * m02) + r0 * (m01 * m12 - m11 * m02)};
}

/// Index of the first largest of the n > 0 values at p (std::max_element), without intrinsics.
template <typename T>
int firstMaxPlain(const T* p, int n) {
  T best = p[0];
  for (int i = 1; i < n; ++i) best = std::max(best, p[i]);  // vectorizes: no branch
  int i = 0;
  while (p[i] != best) ++i;
  return i;
}

/// Index of the first largest of the n > 0 values at p (std::max_element).
template <typename T>
int firstMax(const T* p, int n) {
  return firstMaxPlain(p, n);
}

#if defined(MULTISLIT_X86)
/// The 32 bytes at p: 32 8-bit or 16 16-bit pixels.
inline __attribute__((target("avx2"), always_inline)) __m256i loadBytes(const std::uint8_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}
inline __attribute__((target("avx2"), always_inline)) __m256i loadBytes(const std::uint16_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}

// 8-bit rows (the usual camera format): 32 pixels per instruction with AVX2, else 16
// (slit_profile.cpp).
template <>
int firstMax<std::uint8_t>(const std::uint8_t* p, int n);
// 16-bit rows: 16 pixels per instruction with AVX2 (slit_profile.cpp).
template <>
int firstMax<std::uint16_t>(const std::uint16_t* p, int n);

/// Caruana's normal equations [s0 s1 s2; s1 s2 s3; s2 s3 s4] (a b c) = (r0 r1 r2) in four lanes,
/// by Cramer's rule as gaussianCentre(): b = nb / det, c = nc / det.
struct Cramer {
  __m256d det, nb, nc;
};

inline __attribute__((target("avx2"), always_inline)) Cramer solveByCramer(__m256d s0, __m256d s1,
                                                                           __m256d s2, __m256d s3,
                                                                           __m256d s4, __m256d r0,
                                                                           __m256d r1, __m256d r2) {
  const __m256d m00 = s0, m01 = s1, m02 = s2, m11 = s2, m12 = s3, m22 = s4;
  return {
      m00 * (m11 * m22 - m12 * m12) - m01 * (m01 * m22 - m12 * m02) + m02 * (m01 * m12 - m11 * m02),
      m00 * (r1 * m22 - m12 * r2) - r0 * (m01 * m22 - m12 * m02) + m02 * (m01 * r2 - r1 * m02),
      m00 * (m11 * r2 - r1 * m12) - m01 * (m01 * r2 - r1 * m02) + r0 * (m01 * m12 - m11 * m02)};
}

/// Step 1 of measureFour() and measureEight(): each region's maximum, as measurePeak(). The
/// profiles the lanes cannot take (saturated, or `fits(x)` false: pixels the lanes read lie
/// outside the row) are measured one by one here; the others are returned in rows, tops and
/// slots (their region's index). Returns the number of lanes filled. Inlined into its one caller
/// in each kernel's file, as when all were in one file.
template <typename T, typename Fits>
inline __attribute__((always_inline)) int fillLanes(const PeakRegion<T>* regions, int count,
                                                    int columns, const ProfileParams& p, Fits fits,
                                                    Peak* peaks, bool* found, const T** rows,
                                                    int* tops, int* slots) {
  int lanes = 0;
  for (int i = 0; i < count; ++i) {
    const PeakRegion<T>& region = regions[i];
    const T* row = region.row;
    const int first = std::max(region.first, 0), last = std::min(region.last, columns - 1);
    found[i] = false;
    if (first > last) continue;
    const int x = first + firstMax(row + first, last - first + 1);
    if (x == first && first > 0 && row[first - 1] > row[x]) continue;
    if (x == last && last < columns - 1 && row[last + 1] > row[x]) continue;
    if (row[x] >= p.saturation || !fits(x)) {
      found[i] = measurePeakAt(row, columns, x, p, &peaks[i]);
      continue;
    }
    rows[lanes] = row;
    tops[lanes] = x;
    slots[lanes++] = i;
  }
  for (int l = lanes; l < 8 && l > 0; ++l) rows[l] = rows[0], tops[l] = tops[0];  // spare: a copy
  return lanes;
}

/// Step 2 of measureFour() and measureEight(): a lane's tests and centre as measurePeakAt(), from
/// its background line, contrast, width and fitted centre (NaN where the fit does not hold).
template <typename T>
bool finishLane(const T* row, int top, const ProfileParams& p, const Background& bg,
                double contrast, int width, double centre, Peak* peak) {
  if (contrast < p.min_contrast || width < p.min_width || width > p.max_width) return false;
  if (std::isnan(centre)) {  // as measurePeakAt(): the centroid when the fit does not hold
    centre =
        centroid(row, top - p.half_window, top + p.half_window, bg, p.fit_threshold * contrast);
  }
  peak->centre = centre;
  peak->contrast = contrast;
  peak->width = width;
  peak->saturated = false;
  return true;
}

/// Widest half window eightProfiles() takes: two 32-byte loads hold an 8-bit profile's 2 hw + 1
/// pixels and its two 3-pixel flanks (one load up to hw = 12, the paper's sensor), four a 16-bit
/// one (two up to hw = 12).
constexpr int kEightMaxHalfWindow = 28;

/// Four profiles at a time, one per lane of AVX2 doubles, bit for bit as measurePeak()
/// (slit_profile_four.cpp; instantiated for 8- and 16-bit rows).
template <typename T>
void measureFour(const PeakRegion<T>* regions, int count, int columns, const ProfileParams& p,
                 Peak* peaks, bool* found);

/// Eight profiles at a time in float lanes of AVX2 and FMA (slit_profile_eight.cpp; instantiated
/// for 8- and 16-bit rows).
template <typename T>
void measureEight(const PeakRegion<T>* regions, int count, int columns, const ProfileParams& p,
                  Peak* peaks, bool* found);
#endif

}  // namespace multislit::profile
