#include "multislit/slit_profile.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#if defined(__x86_64__) && defined(__GNUC__)
#define MULTISLIT_X86 1  // SSE2 is part of x86-64; AVX2 is chosen at run time
#include <immintrin.h>
#endif

namespace multislit {
namespace {

// The background under a profile: a line through the means of three pixels on each flank.
struct Background {
  double at_left = 0, x_left = 0, slope = 0;
  double operator()(double x) const { return at_left + slope * (x - x_left); }
};

template <typename T>
bool flankBackground(const T* row, int columns, int lo, int hi, Background* bg) {
  constexpr int kFlank = 3;
  double left = 0, right = 0;
  int nl = 0, nr = 0;
  for (int x = lo - kFlank; x < lo; ++x)
    if (x >= 0) left += row[x], ++nl;
  for (int x = hi + 1; x <= hi + kFlank; ++x)
    if (x < columns) right += row[x], ++nr;
  if (nl == 0 && nr == 0) return false;
  const double xl = lo - 0.5 * (kFlank + 1), xr = hi + 0.5 * (kFlank + 1);
  if (nl == 0 || nr == 0) {  // at the image border: a flat background from the other side
    bg->at_left = nl ? left / nl : right / nr;
    bg->x_left = xl;
    bg->slope = 0;
    return true;
  }
  bg->at_left = left / nl;
  bg->x_left = xl;
  bg->slope = (right / nr - bg->at_left) / (xr - xl);
  return true;
}

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

// Centroid under a Gaussian window that follows the centre: unbiased for a symmetric profile,
// and it weights the pixels as a matched filter would.
template <typename T>
double windowedCentroid(const T* row, int lo, int hi, double start, const Background& bg,
                        double sigma) {
  const double k = -0.5 / (sigma * sigma);
  double centre = start;
  for (int pass = 0; pass < 4; ++pass) {
    double sum = 0, moment = 0;
    for (int x = lo; x <= hi; ++x) {
      const double v = std::max(0.0, row[x] - bg(x)) * std::exp(k * (x - centre) * (x - centre));
      sum += v;
      moment += v * x;
    }
    if (!(sum > 0)) break;
    const double next = moment / sum;
    const bool done = std::abs(next - centre) < 1e-3;
    centre = next;
    if (done) break;
  }
  return centre;
}

/// Added to the half-contrast and fit thresholds in every path: background-free values are
/// rationals of small denominators (thirds, fifths, 2 hw + 4), so a pixel can lie exactly on a
/// threshold, where float and double rounding would decide it differently. Off by this, a tie is
/// out in both, and no pixel lies within float rounding of the threshold [DN].
constexpr double kTieBreak = 1.0 / 1024;

/// Pixels above half the contrast (the profile's width), counted in the pass that gathers
/// the sums of Caruana's fit when `fit` is set.
struct ProfilePass {
  int width = 0;
  int used = 0;                   ///< pixels in the fit (above the floor)
  double s[5] = {0, 0, 0, 0, 0};  ///< sum of w d^k, w = v^2, d = x - top
  double r[3] = {0, 0, 0};        ///< sum of w ln(v) d^k
};

// One pass over the profile: its width, and with `fit` the sums of the Gaussian fit
// ln(v) = a + b d + c d^2 weighted by v^2 over the pixels above `floor`.
template <typename T>
ProfilePass profilePass(const T* row, int lo, int hi, int top, const Background& bg, double half,
                        double floor, bool fit) {
  int width = 0, used = 0;
  double s0 = 0, s1 = 0, s2 = 0, s3 = 0, s4 = 0, r0 = 0, r1 = 0, r2 = 0;  // in registers
  for (int x = lo; x <= hi; ++x) {
    const double v = row[x] - bg(x);
    width += v > half;
    if (!fit || !(v > floor)) continue;
    const double w = v * v, wl = w * FastLog::log(v), d = x - top, d2 = d * d;
    s0 += w;
    s1 += w * d;
    s2 += w * d2;
    s3 += w * (d2 * d);
    s4 += w * (d2 * d2);
    r0 += wl;
    r1 += wl * d;
    r2 += wl * d2;
    ++used;
  }
  return {width, used, {s0, s1, s2, s3, s4}, {r0, r1, r2}};
}

// Caruana's Gaussian fit: ln(v) = a + b x + c x^2, weighted by v^2; centre -b / 2c.
bool gaussianCentre(const ProfilePass& pass, int top, int span, double* centre) {
  if (pass.used < 3) return false;
  const double* s = pass.s;
  const double* r = pass.r;
  // Normal equations [s0 s1 s2; s1 s2 s3; s2 s3 s4] (a b c) = r, by Cramer's rule.
  const double m00 = s[0], m01 = s[1], m02 = s[2], m11 = s[2], m12 = s[3], m22 = s[4];
  const double det =
      m00 * (m11 * m22 - m12 * m12) - m01 * (m01 * m22 - m12 * m02) + m02 * (m01 * m12 - m11 * m02);
  if (std::abs(det) < 1e-12) return false;
  const double b = (m00 * (r[1] * m22 - m12 * r[2]) - r[0] * (m01 * m22 - m12 * m02) +
                    m02 * (m01 * r[2] - r[1] * m02)) /
                   det;
  const double c = (m00 * (m11 * r[2] - r[1] * m12) - m01 * (m01 * r[2] - r[1] * m02) +
                    r[0] * (m01 * m12 - m11 * m02)) /
                   det;
  if (!(c < 0)) return false;
  const double offset = -b / (2 * c);
  if (!(std::abs(offset) <= span)) return false;
  *centre = top + offset;
  return true;
}

/// Index of the first largest of the n > 0 values at p (std::max_element).
template <typename T>
int firstMax(const T* p, int n) {
  T best = p[0];
  for (int i = 1; i < n; ++i) best = std::max(best, p[i]);  // vectorizes: no branch
  int i = 0;
  while (p[i] != best) ++i;
  return i;
}

#if defined(MULTISLIT_X86)
bool hasAvx2() {
  static const bool yes = __builtin_cpu_supports("avx2");
  return yes;
}

/// The largest of the 16 bytes of h.
inline std::uint8_t maxByte(__m128i h) {
  h = _mm_max_epu8(h, _mm_srli_si128(h, 8));
  h = _mm_max_epu8(h, _mm_srli_si128(h, 4));
  h = _mm_max_epu8(h, _mm_srli_si128(h, 2));
  h = _mm_max_epu8(h, _mm_srli_si128(h, 1));
  return static_cast<std::uint8_t>(_mm_cvtsi128_si32(h) & 0xff);
}

inline __attribute__((target("avx2"), always_inline)) __m256i loadBytes(const std::uint8_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}

/// firstMax() of n >= 32 bytes with AVX2, 32 per instruction; the last load overlaps the one
/// before it.
__attribute__((target("avx2"))) int firstMaxAvx2(const std::uint8_t* p, int n) {
  __m256i m = loadBytes(p + n - 32);
  for (int i = 0; i + 32 < n; i += 32) m = _mm256_max_epu8(m, loadBytes(p + i));
  const __m256i best = _mm256_set1_epi8(static_cast<char>(
      maxByte(_mm_max_epu8(_mm256_castsi256_si128(m), _mm256_extracti128_si256(m, 1)))));
  for (int i = 0;; i += 32) {
    const int at = std::min(i, n - 32);
    const auto hits =
        static_cast<unsigned>(_mm256_movemask_epi8(_mm256_cmpeq_epi8(loadBytes(p + at), best)));
    if (hits != 0) return at + __builtin_ctz(hits);
  }
}

// 8-bit rows (the usual camera format): 32 pixels per instruction with AVX2, else 16. The loads
// stay inside [p, p + n): the last block overlaps the one before it.
template <>
int firstMax<std::uint8_t>(const std::uint8_t* p, int n) {
  if (n >= 32 && hasAvx2()) return firstMaxAvx2(p, n);
  if (n < 16) {
    std::uint8_t best = p[0];
    for (int i = 1; i < n; ++i) best = std::max(best, p[i]);
    int i = 0;
    while (p[i] != best) ++i;
    return i;
  }
  const auto load = [p](int i) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + i)); };
  __m128i m = load(n - 16);
  for (int i = 0; i + 16 < n; i += 16) m = _mm_max_epu8(m, load(i));
  const __m128i best = _mm_set1_epi8(static_cast<char>(maxByte(m)));
  for (int i = 0;; i += 16) {
    const int at = std::min(i, n - 16);
    const int hits = _mm_movemask_epi8(_mm_cmpeq_epi8(load(at), best));
    if (hits != 0) return at + __builtin_ctz(static_cast<unsigned>(hits));
  }
}
#endif

}  // namespace

template <typename T>
bool measurePeakAt(const T* row, int columns, int top, const ProfileParams& p, Peak* peak) {
  int run_lo = top, run_hi = top;
  const bool saturated = row[top] >= p.saturation;
  if (saturated) {  // the centre of a clipped profile is the middle of its plateau and flanks
    while (run_lo > 0 && row[run_lo - 1] >= p.saturation) --run_lo;
    while (run_hi < columns - 1 && row[run_hi + 1] >= p.saturation) ++run_hi;
    if (run_hi - run_lo + 1 > p.max_saturated) return false;
  }
  const int lo = run_lo - p.half_window, hi = run_hi + p.half_window;
  Background bg;
  if (!flankBackground(row, columns, lo, hi, &bg)) return false;
  const double contrast = row[top] - bg(top);
  if (contrast < p.min_contrast) return false;
  const int first = std::max(lo, 0), last = std::min(hi, columns - 1);
  const double floor = p.fit_threshold * contrast + kTieBreak;
  const bool fit = !saturated && p.estimator == Estimator::Gaussian;
  const ProfilePass pass =
      profilePass(row, first, last, top, bg, 0.5 * contrast + kTieBreak, floor, fit);
  if (pass.width < p.min_width || pass.width > p.max_width) return false;

  double centre = 0;
  if (p.estimator == Estimator::Windowed) {
    centre = windowedCentroid(row, first, last, centroid(row, first, last, bg, floor), bg,
                              p.window_sigma);
  } else if (!fit || !gaussianCentre(pass, top, last - first, &centre)) {
    centre = centroid(row, first, last, bg, floor);
  }
  peak->centre = centre;
  peak->contrast = contrast;
  peak->width = pass.width;
  peak->saturated = saturated;
  return true;
}

template <typename T>
bool measurePeak(const T* row, int columns, int first, int last, const ProfileParams& p,
                 Peak* peak) {
  first = std::max(first, 0);
  last = std::min(last, columns - 1);
  if (first > last) return false;
  const int x = first + firstMax(row + first, last - first + 1);
  // A maximum on the region's border that keeps rising outside belongs to a profile outside.
  if (x == first && first > 0 && row[first - 1] > row[x]) return false;
  if (x == last && last < columns - 1 && row[last + 1] > row[x]) return false;
  return measurePeakAt(row, columns, x, p, peak);
}

namespace {

#if defined(MULTISLIT_X86)
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

/// The profiles of four lanes around their maxima `top` (not saturated, both flanks inside the
/// row): background, contrast and width as profilePass(), the centre as gaussianCentre().
struct FourProfiles {
  alignas(32) double contrast[4], at_left[4], x_left[4], slope[4], centre[4];
  alignas(32) std::int64_t width[4], fitted[4];  ///< fitted: all ones where the fit holds
};

template <typename T>
__attribute__((target("avx2"))) FourProfiles fourProfiles(const T* const rows[4], const int tops[4],
                                                          const ProfileParams& p) {
  const int hw = p.half_window;
  FourProfiles out;
  alignas(32) double left[4], right[4], peak[4], lo[4];
  const T* window[4];
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
  // Caruana's fit in every lane, as gaussianCentre().
  const Cramer fit = solveByCramer(s0, s1, s2, s3, s4, r0, r1, r2);
  const __m256d det = fit.det, b = fit.nb / det, c = fit.nc / det;
  const __m256d offset = -b / (2 * c);
  const __m256d magnitude = _mm256_set1_pd(-0.0);  // |x|: x without its sign bit
  __m256d fitted = _mm256_castsi256_pd(_mm256_cmpgt_epi64(used, _mm256_set1_epi64x(2)));
  fitted = _mm256_and_pd(
      fitted, _mm256_cmp_pd(_mm256_andnot_pd(magnitude, det), _mm256_set1_pd(1e-12), _CMP_NLT_UQ));
  fitted = _mm256_and_pd(fitted, _mm256_cmp_pd(c, _mm256_setzero_pd(), _CMP_LT_OQ));
  fitted = _mm256_and_pd(fitted, _mm256_cmp_pd(_mm256_andnot_pd(magnitude, offset),
                                               _mm256_set1_pd(2.0 * hw), _CMP_LE_OQ));
  _mm256_store_pd(out.contrast, contrast);
  _mm256_store_pd(out.at_left, at_left);
  _mm256_store_pd(out.x_left, x_left);
  _mm256_store_pd(out.slope, slope);
  _mm256_store_pd(out.centre, x_top + offset);
  _mm256_store_si256(reinterpret_cast<__m256i*>(out.width), width);
  _mm256_store_si256(reinterpret_cast<__m256i*>(out.fitted), _mm256_castpd_si256(fitted));
  return out;
}

/// Step 1 of measureFour() and measureEight(): each region's maximum, as measurePeak(). The
/// profiles the lanes cannot take (saturated, or `fits(x)` false: pixels the lanes read lie
/// outside the row) are measured one by one here; the others are returned in rows, tops and
/// slots (their region's index). Returns the number of lanes filled.
template <typename T, typename Fits>
int fillLanes(const PeakRegion<T>* regions, int count, int columns, const ProfileParams& p,
              Fits fits, Peak* peaks, bool* found, const T** rows, int* tops, int* slots) {
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

// Eight 8-bit profiles at a time, in float lanes of AVX2 and FMA: about five times faster than
// four in double, as each vector holds twice the profiles and the logarithm needs no division.
// Results differ from measurePeakAt() by float rounding only (the test bounds it).

bool hasAvx2Fma() {
  static const bool yes = hasAvx2() && __builtin_cpu_supports("fma");
  return yes;
}

/// Widest half window eightProfiles() takes: two 32-byte loads hold a profile's 2 hw + 1 pixels
/// and its two 3-pixel flanks (one load up to hw = 12, the paper's sensor).
constexpr int kEightMaxHalfWindow = 28;

/// The 32-byte blocks that hold the 2 hw + 7 pixels of a profile and its flanks.
constexpr int blocksOf(int hw) { return (2 * hw + 7 + 31) / 32; }

/// ln(v) of eight normal floats v > 0, within 4e-7 for v below 256: v = 2^e m with m in [sqrt(1/2),
/// sqrt(2)), ln v = e ln 2 + ln(1 + f), f = m - 1, and ln(1 + f) = f + f^2 q(f) with q the degree-6
/// Chebyshev interpolant of (ln(1 + f) - f) / f^2 on that interval (its error: 1.2e-7). e comes
/// from the bits of v less those of sqrt(1/2), whose borrow picks the interval, and q is summed
/// in pairs of terms (Estrin), a chain of four operations instead of Horner's six.
inline __attribute__((target("avx2,fma"), always_inline)) __m256 logEight(__m256 v) {
  const __m256i bits = _mm256_castps_si256(v);
  const __m256i e = _mm256_srai_epi32(_mm256_sub_epi32(bits, _mm256_set1_epi32(0x3f3504f3)), 23);
  const __m256 m = _mm256_castsi256_ps(_mm256_sub_epi32(bits, _mm256_slli_epi32(e, 23)));
  const __m256 f = m - 1.0f, f2 = f * f, f4 = f2 * f2;
  constexpr float kQ[7] = {-0.500000912f, 0.333341136f, -0.249824512f, 0.199290571f,
                           -0.171323873f, 0.15984096f,  -0.101885865f};
  __m256 k[7];
  for (int i = 0; i < 7; ++i) k[i] = _mm256_set1_ps(kQ[i]);
  const __m256 q01 = _mm256_fmadd_ps(k[1], f, k[0]), q23 = _mm256_fmadd_ps(k[3], f, k[2]);
  const __m256 q456 = _mm256_fmadd_ps(k[6], f2, _mm256_fmadd_ps(k[5], f, k[4]));
  const __m256 q = _mm256_fmadd_ps(f4, q456, _mm256_fmadd_ps(f2, q23, q01));
  return _mm256_fmadd_ps(_mm256_cvtepi32_ps(e), _mm256_set1_ps(0.693147181f),
                         _mm256_fmadd_ps(f2, q, f));
}

/// The four ints at p as doubles.
inline __attribute__((target("avx2"), always_inline)) __m256d fourInts(const std::int32_t* p) {
  return _mm256_cvtepi32_pd(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)));
}

/// The weight w = v^2 of eight values v and w ln v, both zero where v <= floor (out of the fit;
/// the logarithm of 1 there is exactly 0).
inline __attribute__((target("avx2,fma"), always_inline)) void weighEight(const float* values,
                                                                          __m256 floor, __m256& w,
                                                                          __m256& wl) {
  const __m256 v = _mm256_load_ps(values), in = _mm256_cmp_ps(v, floor, _CMP_GT_OQ);
  w = _mm256_and_ps(v * v, in);
  wl = w * logEight(_mm256_blendv_ps(_mm256_set1_ps(1.0f), v, in));
}

/// The 32 bytes at each of p[0..7], transposed: byte l of column c (pixel p[l][c]) lands at
/// out[columnAt(c) + l] (256 bytes). Three rounds of interleaving, each within the 128-bit
/// halves, so that the high half does columns 16..31 as the low half does 0..15.
inline __attribute__((target("avx2"), always_inline)) void transposeEight(
    const std::uint8_t* const p[8], std::uint8_t* out) {
  __m256i r[8], a[8], b[8];
  for (int l = 0; l < 8; ++l) r[l] = loadBytes(p[l]);
  for (int k = 0; k < 4; ++k) {  // a[2k]: columns 0..7 of rows 2k, 2k + 1; a[2k + 1]: 8..15
    a[2 * k] = _mm256_unpacklo_epi8(r[2 * k], r[2 * k + 1]);
    a[2 * k + 1] = _mm256_unpackhi_epi8(r[2 * k], r[2 * k + 1]);
  }
  for (int k = 0; k < 2; ++k) {  // b[4k + j]: four columns of rows 4k .. 4k + 3
    b[4 * k] = _mm256_unpacklo_epi16(a[4 * k], a[4 * k + 2]);
    b[4 * k + 1] = _mm256_unpackhi_epi16(a[4 * k], a[4 * k + 2]);
    b[4 * k + 2] = _mm256_unpacklo_epi16(a[4 * k + 1], a[4 * k + 3]);
    b[4 * k + 3] = _mm256_unpackhi_epi16(a[4 * k + 1], a[4 * k + 3]);
  }
  for (int j = 0; j < 4; ++j) {  // columns 4j .. 4j + 3 of all rows, two per store
    _mm256_store_si256(reinterpret_cast<__m256i*>(out + 64 * j),
                       _mm256_unpacklo_epi32(b[j], b[4 + j]));
    _mm256_store_si256(reinterpret_cast<__m256i*>(out + 64 * j + 32),
                       _mm256_unpackhi_epi32(b[j], b[4 + j]));
  }
}

/// Where transposeEight() puts column c: its block of 32 columns c / 32 (one call each), the
/// store (c % 16) / 2, its half (c % 32) / 16, its 8 bytes c % 2.
constexpr int columnAt(int c) {
  return 256 * (c / 32) + 32 * ((c % 16) / 2) + 16 * ((c % 32) / 16) + 8 * (c % 2);
}

/// Column c of transposeEight()'s output as eight floats.
inline __attribute__((target("avx2"), always_inline)) __m256 columnOf(const std::uint8_t* columns,
                                                                      int c) {
  const __m128i bytes = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(columns + columnAt(c)));
  return _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(bytes));
}

/// The profiles of eight lanes around their maxima `tops` (not saturated; pixels top - hw - 3 to
/// top - hw - 4 + 32 blocksOf(hw) inside the row): background, contrast and width as
/// measurePeakAt(), and the centre of Caruana's fit as gaussianCentre() (NaN where the fit does not
/// hold).
struct EightProfiles {
  alignas(32) float contrast[8], at_left[8], slope[8];
  alignas(32) std::int32_t width[8];
  alignas(32) double centre[8];
};

__attribute__((target("avx2,fma"))) EightProfiles eightProfiles(const std::uint8_t* const rows[8],
                                                                const int tops[8],
                                                                const ProfileParams& p) {
  const int hw = p.half_window;
  const std::uint8_t* starts[8];
  for (int l = 0; l < 8; ++l) starts[l] = rows[l] + tops[l] - hw - 3;
  alignas(32) std::uint8_t columns[256 * blocksOf(kEightMaxHalfWindow)];
  for (int block = 0; block < blocksOf(hw); ++block) {
    transposeEight(starts, columns + 256 * block);
    for (const std::uint8_t*& start : starts) start += 32;
  }
  // Column c is pixel top + c - hw - 3: the left flank is c = 0..2, the window c = 3..2 hw + 3
  // (d = x - top from -hw to hw), the right flank c = 2 hw + 4..2 hw + 6.
  // The flanks' background line, bg(d) = at_top + slope d, and the contrast.
  const __m256 at_left =
      (columnOf(columns, 0) + columnOf(columns, 1) + columnOf(columns, 2)) / 3.0f;
  const __m256 right = (columnOf(columns, 2 * hw + 4) + columnOf(columns, 2 * hw + 5) +
                        columnOf(columns, 2 * hw + 6)) /
                       3.0f;
  const __m256 slope = (right - at_left) / static_cast<float>(2 * hw + 4);
  const __m256 at_top = _mm256_fmadd_ps(slope, _mm256_set1_ps(static_cast<float>(hw + 2)), at_left);
  const __m256 contrast = columnOf(columns, hw + 3) - at_top;
  const __m256 tie = _mm256_set1_ps(static_cast<float>(kTieBreak));
  const __m256 half = 0.5f * contrast + tie,
               floor = static_cast<float>(p.fit_threshold) * contrast + tie;
  __m256i width = _mm256_setzero_si256(), used = width;
  __m256 s0 = _mm256_setzero_ps(), s1 = s0, s2 = s0, s3 = s0, s4 = s0, r0 = s0, r1 = s0, r2 = s0;
  // Three passes over the window, none with a branch or a chain from one pixel to the next but
  // the sums, so that the core overlaps the pixels: the background-free values and the lanes'
  // widths; over the pixels where some lane is in the fit, the weights and the logarithms; the
  // sums of the fit.
  constexpr int kWindow = 2 * kEightMaxHalfWindow + 1;
  alignas(32) float values[kWindow][8];
  std::uint64_t some_in = 0;  // bit j: some lane has pixel j in the fit (2 hw + 1 <= 57 bits)
  __m256 bg = _mm256_fnmadd_ps(slope, _mm256_set1_ps(static_cast<float>(hw)), at_top);  // at -hw
  for (int j = 0; j <= 2 * hw; ++j, bg += slope) {
    const __m256 v = columnOf(columns, j + 3) - bg;
    width = _mm256_sub_epi32(width, _mm256_castps_si256(_mm256_cmp_ps(v, half, _CMP_GT_OQ)));
    const __m256 in = _mm256_cmp_ps(v, floor, _CMP_GT_OQ);
    used = _mm256_sub_epi32(used, _mm256_castps_si256(in));
    _mm256_store_ps(values[j], v);
    some_in |= std::uint64_t{_mm256_movemask_ps(in) != 0} << j;
  }
  // The weights and logarithms out to the farthest pixel in the fit on either side, then the sums
  // over pixels d and -d together: their even moments take w(d) + w(-d), the odd ones
  // w(d) - w(-d). The pixels out of the fit add zeros.
  const int reach =  // |d| of the farthest pixel in the fit; -1 where no lane has one
      some_in == 0 ? -1
                   : std::max(hw - __builtin_ctzll(some_in), 63 - __builtin_clzll(some_in) - hw);
  alignas(32) float weights[kWindow][8];
  for (int j = hw - reach; j <= hw + reach; ++j) {
    __m256 w, wl;
    weighEight(values[j], floor, w, wl);
    _mm256_store_ps(weights[j], w);
    _mm256_store_ps(values[j], wl);
  }
  if (reach >= 0) s0 = _mm256_load_ps(weights[hw]), r0 = _mm256_load_ps(values[hw]);
  for (int d = 1; d <= reach; ++d) {
    const __m256 w_minus = _mm256_load_ps(weights[hw - d]),
                 w_plus = _mm256_load_ps(weights[hw + d]);
    const __m256 wl_minus = _mm256_load_ps(values[hw - d]),
                 wl_plus = _mm256_load_ps(values[hw + d]);
    const __m256 even = w_plus + w_minus, odd = w_plus - w_minus;
    const __m256 even_l = wl_plus + wl_minus, odd_l = wl_plus - wl_minus;
    const auto dd = static_cast<float>(d);
    const __m256 d1 = _mm256_set1_ps(dd), d2 = _mm256_set1_ps(dd * dd);
    s0 += even;
    s1 = _mm256_fmadd_ps(odd, d1, s1);
    s2 = _mm256_fmadd_ps(even, d2, s2);
    s3 = _mm256_fmadd_ps(odd, _mm256_set1_ps(dd * dd * dd), s3);
    s4 = _mm256_fmadd_ps(even, _mm256_set1_ps(dd * dd * dd * dd), s4);
    r0 += even_l;
    r1 = _mm256_fmadd_ps(odd_l, d1, r1);
    r2 = _mm256_fmadd_ps(even_l, d2, r2);
  }
  EightProfiles out;
  _mm256_store_ps(out.contrast, contrast);
  _mm256_store_ps(out.at_left, at_left);
  _mm256_store_ps(out.slope, slope);
  _mm256_store_si256(reinterpret_cast<__m256i*>(out.width), width);
  // Caruana's fit in double, as gaussianCentre(), four lanes at a time; the determinant of the
  // normal equations cancels in the centre -b / 2c, so c < 0 is: nc and det of unlike signs.
  alignas(32) float sums[8][8];  // s0..s4, r0..r2 of the eight lanes
  const __m256 all[8] = {s0, s1, s2, s3, s4, r0, r1, r2};
  for (int k = 0; k < 8; ++k) _mm256_store_ps(sums[k], all[k]);
  alignas(32) std::int32_t used_lanes[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(used_lanes), used);
  const __m256d magnitude = _mm256_set1_pd(-0.0);  // the sign bit: |x| is x without it
  for (int h = 0; h < 2; ++h) {
    __m256d wide[8];
    for (int k = 0; k < 8; ++k) wide[k] = _mm256_cvtps_pd(_mm_load_ps(sums[k] + 4 * h));
    const auto [det, nb, nc] =
        solveByCramer(wide[0], wide[1], wide[2], wide[3], wide[4], wide[5], wide[6], wide[7]);
    const __m256d offset = -nb / (2.0 * nc);
    __m256d fitted = _mm256_cmp_pd(fourInts(used_lanes + 4 * h), _mm256_set1_pd(3.0), _CMP_GE_OQ);
    fitted = _mm256_and_pd(
        fitted, _mm256_cmp_pd(_mm256_andnot_pd(magnitude, det), _mm256_set1_pd(1e-12), _CMP_GE_OQ));
    fitted = _mm256_and_pd(fitted, _mm256_xor_pd(nc, det));  // sign bit: unlike signs
    fitted = _mm256_and_pd(fitted, _mm256_cmp_pd(nc, _mm256_setzero_pd(), _CMP_NEQ_OQ));
    fitted = _mm256_and_pd(fitted, _mm256_cmp_pd(_mm256_andnot_pd(magnitude, offset),
                                                 _mm256_set1_pd(2.0 * hw), _CMP_LE_OQ));
    const __m256d centre = fourInts(tops + 4 * h) + offset;
    _mm256_store_pd(
        out.centre + 4 * h,
        _mm256_blendv_pd(_mm256_set1_pd(std::numeric_limits<double>::quiet_NaN()), centre, fitted));
  }
  return out;
}

void measureEight(const PeakRegion<std::uint8_t>* regions, int count, int columns,
                  const ProfileParams& p, Peak* peaks, bool* found) {
  const std::uint8_t* rows[8];
  int tops[8], slots[8];
  const int hw = p.half_window;
  const int lanes = fillLanes(
      regions, count, columns, p,
      [&](int x) { return x - hw - 3 >= 0 && x - hw - 4 + 32 * blocksOf(hw) <= columns - 1; },
      peaks, found, rows, tops, slots);
  if (lanes == 0) return;
  const EightProfiles f = eightProfiles(rows, tops, p);
  for (int l = 0; l < lanes; ++l) {
    Background bg;
    bg.at_left = f.at_left[l];
    bg.x_left = tops[l] - hw - 2;
    bg.slope = f.slope[l];
    found[slots[l]] = finishLane(rows[l], tops[l], p, bg, f.contrast[l], f.width[l], f.centre[l],
                                 &peaks[slots[l]]);
  }
}
#endif

}  // namespace

template <typename T>
void measurePeaks(const PeakRegion<T>* regions, std::size_t count, int columns,
                  const ProfileParams& params, Peak* peaks, bool* found) {
#if defined(MULTISLIT_X86)
  if (params.estimator == Estimator::Gaussian && hasAvx2()) {
    std::size_t lanes = 4;
    auto measure = measureFour<T>;
    if constexpr (std::is_same_v<T, std::uint8_t>) {
      if (hasAvx2Fma() && params.half_window <= kEightMaxHalfWindow)
        lanes = 8, measure = measureEight;
    }
    for (std::size_t i = 0; i < count; i += lanes)
      measure(regions + i, static_cast<int>(std::min(lanes, count - i)), columns, params, peaks + i,
              found + i);
    return;
  }
#endif
  for (std::size_t i = 0; i < count; ++i)
    found[i] =
        measurePeak(regions[i].row, columns, regions[i].first, regions[i].last, params, &peaks[i]);
}

template bool measurePeak<uint8_t>(const uint8_t*, int, int, int, const ProfileParams&, Peak*);
template bool measurePeak<uint16_t>(const uint16_t*, int, int, int, const ProfileParams&, Peak*);
template bool measurePeakAt<uint8_t>(const uint8_t*, int, int, const ProfileParams&, Peak*);
template bool measurePeakAt<uint16_t>(const uint16_t*, int, int, const ProfileParams&, Peak*);
template void measurePeaks<uint8_t>(const PeakRegion<uint8_t>*, std::size_t, int,
                                    const ProfileParams&, Peak*, bool*);
template void measurePeaks<uint16_t>(const PeakRegion<uint16_t>*, std::size_t, int,
                                     const ProfileParams&, Peak*, bool*);

}  // namespace multislit
