#include "multislit/slit_profile.h"

#include <algorithm>
#include <cmath>
#include <cstring>

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
// 8-bit rows (the usual camera format): 16 pixels per instruction. The loads stay inside
// [p, p + n): the last block overlaps the one before it.
template <>
int firstMax<std::uint8_t>(const std::uint8_t* p, int n) {
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
  m = _mm_max_epu8(m, _mm_srli_si128(m, 8));
  m = _mm_max_epu8(m, _mm_srli_si128(m, 4));
  m = _mm_max_epu8(m, _mm_srli_si128(m, 2));
  m = _mm_max_epu8(m, _mm_srli_si128(m, 1));
  const __m128i best = _mm_set1_epi8(static_cast<char>(_mm_cvtsi128_si32(m) & 0xff));
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
  const double floor = p.fit_threshold * contrast;
  const bool fit = !saturated && p.estimator == Estimator::Gaussian;
  const ProfilePass pass = profilePass(row, first, last, top, bg, 0.5 * contrast, floor, fit);
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

bool hasAvx2() {
  static const bool yes = __builtin_cpu_supports("avx2");
  return yes;
}

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
  const __m256d half = 0.5 * contrast, floor = p.fit_threshold * contrast;
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
  // Caruana's fit in every lane, as gaussianCentre(): the normal equations by Cramer's rule.
  const __m256d m00 = s0, m01 = s1, m02 = s2, m11 = s2, m12 = s3, m22 = s4;
  const __m256d det =
      m00 * (m11 * m22 - m12 * m12) - m01 * (m01 * m22 - m12 * m02) + m02 * (m01 * m12 - m11 * m02);
  const __m256d b =
      (m00 * (r1 * m22 - m12 * r2) - r0 * (m01 * m22 - m12 * m02) + m02 * (m01 * r2 - r1 * m02)) /
      det;
  const __m256d c =
      (m00 * (m11 * r2 - r1 * m12) - m01 * (m01 * r2 - r1 * m02) + r0 * (m01 * m12 - m11 * m02)) /
      det;
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

template <typename T>
void measureFour(const PeakRegion<T>* regions, int count, int columns, const ProfileParams& p,
                 Peak* peaks, bool* found) {
  // 1. Each region's maximum, as measurePeak(); the profiles four lanes cannot take (saturated,
  // or a flank outside the row) are measured one by one.
  const T* rows[4];
  int tops[4], slots[4], lanes = 0;
  for (int i = 0; i < count; ++i) {
    const PeakRegion<T>& region = regions[i];
    const T* row = region.row;
    const int first = std::max(region.first, 0), last = std::min(region.last, columns - 1);
    found[i] = false;
    if (first > last) continue;
    const int x = first + firstMax(row + first, last - first + 1);
    if (x == first && first > 0 && row[first - 1] > row[x]) continue;
    if (x == last && last < columns - 1 && row[last + 1] > row[x]) continue;
    if (row[x] >= p.saturation || x - p.half_window - 3 < 0 ||
        x + p.half_window + 3 > columns - 1) {
      found[i] = measurePeakAt(row, columns, x, p, &peaks[i]);
      continue;
    }
    rows[lanes] = row;
    tops[lanes] = x;
    slots[lanes++] = i;
  }
  if (lanes == 0) return;
  for (int l = lanes; l < 4; ++l) rows[l] = rows[0], tops[l] = tops[0];  // spare lanes: a copy
  // 2. The four profiles at once, then each lane's tests and centre as measurePeakAt().
  const FourProfiles f = fourProfiles(rows, tops, p);
  for (int l = 0; l < lanes; ++l) {
    const auto width = static_cast<int>(f.width[l]);
    if (f.contrast[l] < p.min_contrast || width < p.min_width || width > p.max_width) continue;
    Peak& peak = peaks[slots[l]];
    peak.centre = f.centre[l];
    if (!f.fitted[l]) {  // as measurePeakAt(): the centroid when the fit does not hold
      const int lo = tops[l] - p.half_window, hi = tops[l] + p.half_window;
      Background bg;
      bg.at_left = f.at_left[l];
      bg.x_left = f.x_left[l];
      bg.slope = f.slope[l];
      peak.centre = centroid(rows[l], lo, hi, bg, p.fit_threshold * f.contrast[l]);
    }
    peak.contrast = f.contrast[l];
    peak.width = width;
    peak.saturated = false;
    found[slots[l]] = true;
  }
}
#endif

}  // namespace

template <typename T>
void measurePeaks(const PeakRegion<T>* regions, std::size_t count, int columns,
                  const ProfileParams& params, Peak* peaks, bool* found) {
#if defined(MULTISLIT_X86)
  if (params.estimator == Estimator::Gaussian && hasAvx2()) {
    for (std::size_t i = 0; i < count; i += 4)
      measureFour(regions + i, static_cast<int>(std::min<std::size_t>(4, count - i)), columns,
                  params, peaks + i, found + i);
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
