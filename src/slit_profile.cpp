// The scalar measure of a slit profile (measurePeakAt(), measurePeak() and the estimators) and
// measurePeaks(), which hands the profiles to the four- and eight-lane kernels
// (slit_profile_four.cpp, slit_profile_eight.cpp) on CPUs that have them.
#include "multislit/slit_profile.h"

#include "slit_profile_simd.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace multislit {

using profile::Background;
using profile::centroid;
using profile::FastLog;
using profile::firstMax;
using profile::kTieBreak;
#if defined(MULTISLIT_X86)
using profile::kEightMaxHalfWindow;
using profile::measureEight;
using profile::measureFour;
#endif

namespace {

#if defined(MULTISLIT_X86)
bool hasAvx2() {
  static const bool yes = __builtin_cpu_supports("avx2");
  return yes;
}

/// CPUs with AVX2 and FMA: measureEight() runs there.
bool hasAvx2Fma() {
  static const bool yes = hasAvx2() && __builtin_cpu_supports("fma");
  return yes;
}
#endif

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

// Caruana's Gaussian fit: ln(v) = a + b x + c x^2, weighted by v^2; centre -b / 2c, kept when it
// lies among the pixels fitted, [first, last] (fuzz/fuzz_image: a fit up to the window's width
// beyond them put a profile cut by the image's edge 3 px outside the image).
bool gaussianCentre(const ProfilePass& pass, int top, int first, int last, double* centre) {
  if (pass.used < 3) return false;
  const double* s = pass.s;
  const double* r = pass.r;
  const profile::CramerScalar k =
      profile::solveByCramer(s[0], s[1], s[2], s[3], s[4], r[0], r[1], r[2]);
  if (std::abs(k.det) < 1e-12) return false;
  const double b = k.nb / k.det, c = k.nc / k.det;
  if (!(c < 0)) return false;
  const double offset = -b / (2 * c);
  if (!(offset >= first - top && offset <= last - top)) return false;
  *centre = top + offset;
  return true;
}

}  // namespace

#if defined(MULTISLIT_X86)
namespace profile {
namespace {

/// The largest of the 16 bytes of h.
inline std::uint8_t maxByte(__m128i h) {
  h = _mm_max_epu8(h, _mm_srli_si128(h, 8));
  h = _mm_max_epu8(h, _mm_srli_si128(h, 4));
  h = _mm_max_epu8(h, _mm_srli_si128(h, 2));
  h = _mm_max_epu8(h, _mm_srli_si128(h, 1));
  return static_cast<std::uint8_t>(_mm_cvtsi128_si32(h) & 0xff);
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

/// firstMax() of n >= 16 16-bit pixels with AVX2, 16 per instruction; the last load overlaps the
/// one before it.
__attribute__((target("avx2"))) int firstMaxAvx2(const std::uint16_t* p, int n) {
  __m256i m = loadBytes(p + n - 16);
  for (int i = 0; i + 16 < n; i += 16) m = _mm256_max_epu16(m, loadBytes(p + i));
  __m128i h = _mm_max_epu16(_mm256_castsi256_si128(m), _mm256_extracti128_si256(m, 1));
  h = _mm_max_epu16(h, _mm_srli_si128(h, 8));
  h = _mm_max_epu16(h, _mm_srli_si128(h, 4));
  h = _mm_max_epu16(h, _mm_srli_si128(h, 2));
  const __m256i best = _mm256_set1_epi16(static_cast<short>(_mm_extract_epi16(h, 0)));
  for (int i = 0;; i += 16) {
    const int at = std::min(i, n - 16);
    const auto hits =
        static_cast<unsigned>(_mm256_movemask_epi8(_mm256_cmpeq_epi16(loadBytes(p + at), best)));
    if (hits != 0) return at + __builtin_ctz(hits) / 2;
  }
}

}  // namespace

// 16-bit rows: 16 pixels per instruction with AVX2, else the generic loop.
template <>
int firstMax<std::uint16_t>(const std::uint16_t* p, int n) {
  if (n >= 16 && hasAvx2()) return firstMaxAvx2(p, n);
  return firstMaxPlain(p, n);
}

// 8-bit rows (the usual camera format): 32 pixels per instruction with AVX2, else 16. The loads
// stay inside [p, p + n): the last block overlaps the one before it.
template <>
int firstMax<std::uint8_t>(const std::uint8_t* p, int n) {
  if (n >= 32 && hasAvx2()) return firstMaxAvx2(p, n);
  if (n < 16) return firstMaxPlain(p, n);
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
}  // namespace profile
#endif

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
  } else if (!fit || !gaussianCentre(pass, top, first, last, &centre)) {
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

template <typename T>
void measurePeaks(const PeakRegion<T>* regions, std::size_t count, int columns,
                  const ProfileParams& params, Peak* peaks, bool* found) {
#if defined(MULTISLIT_X86)
  if (params.estimator == Estimator::Gaussian && hasAvx2()) {
    std::size_t lanes = 4;
    auto measure = measureFour<T>;
    if (hasAvx2Fma() && params.half_window <= kEightMaxHalfWindow)
      lanes = 8, measure = measureEight<T>;
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
