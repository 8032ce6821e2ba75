// Four slit profiles at a time with AVX2 (x86-64 CPUs since 2013, chosen at run time), one per
// lane of a vector of doubles: measureFour() for measurePeaks().
#include "slit_profile_simd.h"

#include <cstdint>
#include <limits>

#if defined(MULTISLIT_X86)
namespace multislit::profile {
namespace {

// Four profiles at a time with AVX2 (x86-64 CPUs since 2013, chosen at run time), one per lane
// of a vector of doubles. Every lane runs the operations measurePeakAt() runs for one profile,
// in the same order (the pixels out of the fit add zeros), so the results are the same bits.

/// FastLog::log of four values, with the same operations.
inline __attribute__((target("avx2"), always_inline)) __m256d logFour(__m256d v) {
  const __m256i bits = _mm256_castpd_si256(v);
  const __m256i shifted = _mm256_sub_epi64(bits, _mm256_set1_epi64x(FastLog::kOff));
  const __m256i top12 = _mm256_and_si256(shifted, _mm256_set1_epi64x(0xfffLL << 52));
  const __m256d z = _mm256_castsi256_pd(_mm256_sub_epi64(bits, top12));
  // k: the 12 top bits n of `shifted` through the double 2^52 + n, less 4096 when negative.
  const __m256d two52 = _mm256_set1_pd(4503599627370496.0);
  __m256d k = _mm256_castsi256_pd(
                  _mm256_or_si256(_mm256_srli_epi64(shifted, 52), _mm256_castpd_si256(two52))) -
              two52;
  k -= _mm256_and_pd(_mm256_cmp_pd(k, _mm256_set1_pd(2048.0), _CMP_GE_OQ), _mm256_set1_pd(4096.0));
  const __m256d f = z - 1.0, s = f / (2.0 + f), s2 = s * s, s4 = s2 * s2;
  const __m256d r =
      s4 * (FastLog::kLg2 + s4 * (FastLog::kLg4 + s4 * FastLog::kLg6)) +
      s2 * (FastLog::kLg1 + s4 * (FastLog::kLg3 + s4 * (FastLog::kLg5 + s4 * FastLog::kLg7)));
  const __m256d half_f2 = 0.5 * f * f;
  return k * FastLog::kLn2Hi - ((half_f2 - (s * (half_f2 + r) + k * FastLog::kLn2Lo)) - f);
}

/// The profiles of four lanes around their maxima `top` (not saturated, both flanks inside the
/// row): background, contrast and width as profilePass(), the centre as gaussianCentre().
struct FourProfiles {
  alignas(32) double contrast[4], at_left[4], x_left[4], slope[4], centre[4];
  alignas(32) std::int64_t width[4], fitted[4];  ///< fitted: all ones where the fit holds
};

/// The flanks' background line of four lanes and their contrast, as flankBackground() and
/// measurePeakAt(), with the thresholds of the width (half) and of the fit (floor).
struct FourLine {
  __m256d x_lo, x_left, at_left, slope, x_top, contrast, half, floor;
};

/// fourProfiles() step 1: FourLine of the lanes, and window[l]: pixel top - hw of lane l.
template <typename T>
inline __attribute__((target("avx2"), always_inline)) FourLine fourLine(const T* const rows[4],
                                                                        const int tops[4],
                                                                        const ProfileParams& p,
                                                                        const T* window[4]) {
  const int hw = p.half_window;
  alignas(32) double left[4], right[4], peak[4], lo[4];
  for (int l = 0; l < 4; ++l) {
    const T* q = rows[l] + tops[l];
    left[l] = static_cast<double>(q[-hw - 3] + q[-hw - 2] + q[-hw - 1]);
    right[l] = static_cast<double>(q[hw + 1] + q[hw + 2] + q[hw + 3]);
    peak[l] = q[0];
    lo[l] = tops[l] - hw;
    window[l] = q - hw;
  }
  // The flanks' background line and the contrast, as flankBackground() and measurePeakAt().
  const __m256d x_lo = _mm256_load_pd(lo), x_left = x_lo - 2.0;
  const __m256d at_left = _mm256_load_pd(left) / 3.0;
  const __m256d slope =
      (_mm256_load_pd(right) / 3.0 - at_left) / ((x_lo + 2.0 * hw + 2.0) - x_left);
  const __m256d x_top = x_lo + static_cast<double>(hw);
  const __m256d contrast = _mm256_load_pd(peak) - (at_left + slope * (x_top - x_left));
  const __m256d half = 0.5 * contrast + kTieBreak, floor = p.fit_threshold * contrast + kTieBreak;
  return {x_lo, x_left, at_left, slope, x_top, contrast, half, floor};
}

/// One pass over the windows of four lanes, as profilePass(): the widths, the pixels in the fit
/// (used) and the sums of Caruana's fit.
struct FourSums {
  __m256i width, used;
  __m256d s0, s1, s2, s3, s4, r0, r1, r2;
};

/// fourProfiles() step 2: FourSums of the 2 hw + 1 pixels from window[l] on.
template <typename T>
inline __attribute__((target("avx2"), always_inline)) FourSums fourSums(const T* const window[4],
                                                                        int hw,
                                                                        const FourLine& line) {
  const __m256d x_lo = line.x_lo, x_left = line.x_left, at_left = line.at_left, slope = line.slope,
                half = line.half, floor = line.floor;
  const __m256d one = _mm256_set1_pd(1.0);
  __m256i width = _mm256_setzero_si256(), used = width;
  __m256d s0 = _mm256_setzero_pd(), s1 = s0, s2 = s0, s3 = s0, s4 = s0, r0 = s0, r1 = s0, r2 = s0;
  for (int j = 0; j <= 2 * hw; ++j) {
    const __m256d x = x_lo + static_cast<double>(j);
    const __m256d pixels =
        _mm256_cvtepi32_pd(_mm_set_epi32(window[3][j], window[2][j], window[1][j], window[0][j]));
    const __m256d v = pixels - (at_left + slope * (x - x_left));
    width = _mm256_sub_epi64(width, _mm256_castpd_si256(_mm256_cmp_pd(v, half, _CMP_GT_OQ)));
    const __m256d in = _mm256_cmp_pd(v, floor, _CMP_GT_OQ);
    if (_mm256_movemask_pd(in) == 0) continue;
    used = _mm256_sub_epi64(used, _mm256_castpd_si256(in));
    const __m256d w = _mm256_and_pd(v * v, in);  // 0 outside the fit
    const __m256d wl = w * logFour(_mm256_blendv_pd(one, v, in));
    const double d = j - hw, d2 = d * d, d3 = d2 * d, d4 = d2 * d2;
    s0 += w;
    s1 += w * d;
    s2 += w * d2;
    s3 += w * d3;
    s4 += w * d4;
    r0 += wl;
    r1 += wl * d;
    r2 += wl * d2;
  }
  return {width, used, s0, s1, s2, s3, s4, r0, r1, r2};
}

/// fourProfiles() step 3: Caruana's fit in every lane, as gaussianCentre(): all ones where it
/// holds; *offset: the centre less the top.
inline __attribute__((target("avx2"), always_inline)) __m256d fourFit(const FourSums& sums, int hw,
                                                                      __m256d* offset) {
  const Cramer fit =
      solveByCramer(sums.s0, sums.s1, sums.s2, sums.s3, sums.s4, sums.r0, sums.r1, sums.r2);
  const __m256d det = fit.det, b = fit.nb / det, c = fit.nc / det;
  *offset = -b / (2 * c);
  const __m256d magnitude = _mm256_set1_pd(-0.0);  // |x|: x without its sign bit
  __m256d fitted = _mm256_castsi256_pd(_mm256_cmpgt_epi64(sums.used, _mm256_set1_epi64x(2)));
  fitted = _mm256_and_pd(
      fitted, _mm256_cmp_pd(_mm256_andnot_pd(magnitude, det), _mm256_set1_pd(1e-12), _CMP_NLT_UQ));
  fitted = _mm256_and_pd(fitted, _mm256_cmp_pd(c, _mm256_setzero_pd(), _CMP_LT_OQ));
  return _mm256_and_pd(
      fitted, _mm256_cmp_pd(_mm256_andnot_pd(magnitude, *offset), _mm256_set1_pd(hw), _CMP_LE_OQ));
}

template <typename T>
__attribute__((target("avx2"))) FourProfiles fourProfiles(const T* const rows[4], const int tops[4],
                                                          const ProfileParams& p) {
  const int hw = p.half_window;
  FourProfiles out;
  const T* window[4];
  const FourLine line = fourLine(rows, tops, p, window);
  const FourSums sums = fourSums(window, hw, line);
  __m256d offset;
  const __m256d fitted = fourFit(sums, hw, &offset);
  _mm256_store_pd(out.contrast, line.contrast);
  _mm256_store_pd(out.at_left, line.at_left);
  _mm256_store_pd(out.x_left, line.x_left);
  _mm256_store_pd(out.slope, line.slope);
  _mm256_store_pd(out.centre, line.x_top + offset);
  _mm256_store_si256(reinterpret_cast<__m256i*>(out.width), sums.width);
  _mm256_store_si256(reinterpret_cast<__m256i*>(out.fitted), _mm256_castpd_si256(fitted));
  return out;
}

}  // namespace

template <typename T>
void measureFour(const PeakRegion<T>* regions, int count, int columns, const ProfileParams& p,
                 Peak* peaks, bool* found) {
  const T* rows[8];
  int tops[8], slots[8];
  const int hw = p.half_window;
  const int lanes = fillLanes(
      regions, count, columns, p,
      [&](int x) { return x - hw - 3 >= 0 && x + hw + 3 <= columns - 1; }, peaks, found, rows, tops,
      slots);
  if (lanes == 0) return;
  const FourProfiles f = fourProfiles(rows, tops, p);
  for (int l = 0; l < lanes; ++l) {
    Background bg;
    bg.at_left = f.at_left[l];
    bg.x_left = f.x_left[l];
    bg.slope = f.slope[l];
    const double centre = f.fitted[l] ? f.centre[l] : std::numeric_limits<double>::quiet_NaN();
    found[slots[l]] = finishLane(rows[l], tops[l], p, bg, f.contrast[l],
                                 static_cast<int>(f.width[l]), centre, &peaks[slots[l]]);
  }
}

template void measureFour<std::uint8_t>(const PeakRegion<std::uint8_t>*, int, int,
                                        const ProfileParams&, Peak*, bool*);
template void measureFour<std::uint16_t>(const PeakRegion<std::uint16_t>*, int, int,
                                         const ProfileParams&, Peak*, bool*);

}  // namespace multislit::profile
#endif
