// Eight slit profiles (8- or 16-bit) at a time, in float lanes of AVX2 and FMA (chosen at run
// time): measureEight() for measurePeaks().
#include "slit_profile_simd.h"

#include <cstdint>
#include <limits>

#if defined(MULTISLIT_X86)
namespace multislit::profile {
namespace {

// Eight profiles at a time, in float lanes of AVX2 and FMA: about five times faster than four in
// double, as each vector holds twice the profiles and the logarithm needs no division. Results
// differ from measurePeakAt() by float rounding only (the tests bound it, for 8 and 16 bits).

/// Pixels in a 32-byte block of a row.
template <typename T>
constexpr int kBlockPixels = 32 / static_cast<int>(sizeof(T));

/// The 32-byte blocks that hold the 2 hw + 7 pixels of a profile and its flanks.
template <typename T>
constexpr int blocksOf(int hw) {
  return (2 * hw + 7 + kBlockPixels<T> - 1) / kBlockPixels<T>;
}

/// Pixels of the window of the widest half window: 2 kEightMaxHalfWindow + 1.
constexpr int kEightWindow = 2 * kEightMaxHalfWindow + 1;

/// ln(v) of eight normal floats v > 0, within 4e-7 for v below 256 and 1e-6 below 65536: v = 2^e m
/// with m in [sqrt(1/2), sqrt(2)), ln v = e ln 2 + ln(1 + f), f = m - 1, and ln(1 + f) = f + f^2
/// q(f) with q the degree-6 Chebyshev interpolant of (ln(1 + f) - f) / f^2 on that interval (its
/// error: 1.2e-7). e comes from the bits of v less those of sqrt(1/2), whose borrow picks the
/// interval, and q is summed in pairs of terms (Estrin), a chain of four operations instead of
/// Horner's six.
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

/// The 16 pixels at each of p[0..7], transposed: column c of the eight rows (p[0][c] .. p[7][c])
/// lands at out[columnAt16(c)] as eight 16-bit pixels (256 bytes). Three rounds of interleaving
/// within the 128-bit halves, the high half doing columns 8..15 as the low half does 0..7.
inline __attribute__((target("avx2"), always_inline)) void transposeEight(
    const std::uint16_t* const p[8], std::uint8_t* out) {
  __m256i r[8], a[8], b[8];
  for (int l = 0; l < 8; ++l) r[l] = loadBytes(p[l]);
  for (int k = 0; k < 4; ++k) {  // a[2k]: columns 0..3 of rows 2k, 2k + 1; a[2k + 1]: 4..7
    a[2 * k] = _mm256_unpacklo_epi16(r[2 * k], r[2 * k + 1]);
    a[2 * k + 1] = _mm256_unpackhi_epi16(r[2 * k], r[2 * k + 1]);
  }
  for (int k = 0; k < 2; ++k) {  // b[4k + j]: columns 2j, 2j + 1 of rows 4k .. 4k + 3
    b[4 * k] = _mm256_unpacklo_epi32(a[4 * k], a[4 * k + 2]);
    b[4 * k + 1] = _mm256_unpackhi_epi32(a[4 * k], a[4 * k + 2]);
    b[4 * k + 2] = _mm256_unpacklo_epi32(a[4 * k + 1], a[4 * k + 3]);
    b[4 * k + 3] = _mm256_unpackhi_epi32(a[4 * k + 1], a[4 * k + 3]);
  }
  for (int j = 0; j < 4; ++j) {  // columns 2j and 2j + 1 of all rows
    _mm256_store_si256(reinterpret_cast<__m256i*>(out + 64 * j),
                       _mm256_unpacklo_epi64(b[j], b[4 + j]));
    _mm256_store_si256(reinterpret_cast<__m256i*>(out + 64 * j + 32),
                       _mm256_unpackhi_epi64(b[j], b[4 + j]));
  }
}

/// Where the 16-bit transposeEight() puts column c: its block of 16 columns c / 16 (one call
/// each), the store c % 8, its half (c % 16) / 8.
constexpr int columnAt16(int c) { return 256 * (c / 16) + 32 * (c % 8) + 16 * ((c % 16) / 8); }

/// Column c of the 16-bit transposeEight()'s output as eight floats.
inline __attribute__((target("avx2"), always_inline)) __m256 columnOf16(const std::uint8_t* columns,
                                                                        int c) {
  const __m128i pixels = _mm_load_si128(reinterpret_cast<const __m128i*>(columns + columnAt16(c)));
  return _mm256_cvtepi32_ps(_mm256_cvtepu16_epi32(pixels));
}

/// Column c of the transposed pixels of T as eight floats.
template <typename T>
inline __attribute__((target("avx2"), always_inline)) __m256 columnOfT(const std::uint8_t* columns,
                                                                       int c) {
  if constexpr (sizeof(T) == 1)
    return columnOf(columns, c);
  else
    return columnOf16(columns, c);
}

/// The profiles of eight lanes around their maxima `tops` (not saturated; pixels top - hw - 3 to
/// top - hw - 4 + kBlockPixels blocksOf(hw) inside the row): background, contrast and width as
/// measurePeakAt(), and the centre of Caruana's fit as gaussianCentre() (NaN where the fit does not
/// hold).
struct EightProfiles {
  alignas(32) float contrast[8], at_left[8], slope[8];
  alignas(32) std::int32_t width[8];
  alignas(32) double centre[8];
};

/// eightProfiles() step 1: the blocksOf(hw) blocks of 32 bytes of each lane from top - hw - 3 on,
/// transposed by transposeEight() into columns (256 bytes a block).
template <typename T>
inline __attribute__((target("avx2"), always_inline)) void transposeLanes(const T* const rows[8],
                                                                          const int tops[8], int hw,
                                                                          std::uint8_t* columns) {
  const T* starts[8];
  for (int l = 0; l < 8; ++l) starts[l] = rows[l] + tops[l] - hw - 3;
  for (int block = 0; block < blocksOf<T>(hw); ++block) {
    transposeEight(starts, columns + 256 * block);
    for (const T*& start : starts) start += kBlockPixels<T>;
  }
}

/// The flanks' background line of eight lanes, bg(d) = at_top + slope d, their contrast, and the
/// thresholds of the width (half) and of the fit (floor).
struct EightLine {
  __m256 at_left, slope, at_top, contrast, half, floor;
};

/// eightProfiles() step 2: EightLine from the transposed columns.
template <typename T>
inline __attribute__((target("avx2,fma"), always_inline)) EightLine eightLine(
    const std::uint8_t* columns, int hw, const ProfileParams& p) {
  // Column c is pixel top + c - hw - 3: the left flank is c = 0..2, the window c = 3..2 hw + 3
  // (d = x - top from -hw to hw), the right flank c = 2 hw + 4..2 hw + 6.
  const __m256 at_left =
      (columnOfT<T>(columns, 0) + columnOfT<T>(columns, 1) + columnOfT<T>(columns, 2)) / 3.0f;
  const __m256 right = (columnOfT<T>(columns, 2 * hw + 4) + columnOfT<T>(columns, 2 * hw + 5) +
                        columnOfT<T>(columns, 2 * hw + 6)) /
                       3.0f;
  const __m256 slope = (right - at_left) / static_cast<float>(2 * hw + 4);
  const __m256 at_top = _mm256_fmadd_ps(slope, _mm256_set1_ps(static_cast<float>(hw + 2)), at_left);
  const __m256 contrast = columnOfT<T>(columns, hw + 3) - at_top;
  const __m256 tie = _mm256_set1_ps(static_cast<float>(kTieBreak));
  const __m256 half = 0.5f * contrast + tie,
               floor = static_cast<float>(p.fit_threshold) * contrast + tie;
  return {at_left, slope, at_top, contrast, half, floor};
}

/// The lanes' widths and pixels in the fit (used), and bit j of some_in: some lane has pixel j
/// in the fit (2 hw + 1 <= 57 bits).
struct EightWidths {
  __m256i width, used;
  std::uint64_t some_in;
};

/// eightProfiles() step 3: the background-free values of the window's pixels j = d + hw into
/// values[j], and EightWidths.
template <typename T>
inline __attribute__((target("avx2,fma"), always_inline)) EightWidths eightValues(
    const std::uint8_t* columns, int hw, const EightLine& line, float (*values)[8]) {
  const __m256 at_top = line.at_top, slope = line.slope, half = line.half, floor = line.floor;
  __m256i width = _mm256_setzero_si256(), used = width;
  std::uint64_t some_in = 0;
  __m256 bg = _mm256_fnmadd_ps(slope, _mm256_set1_ps(static_cast<float>(hw)), at_top);  // at -hw
  for (int j = 0; j <= 2 * hw; ++j, bg += slope) {
    const __m256 v = columnOfT<T>(columns, j + 3) - bg;
    width = _mm256_sub_epi32(width, _mm256_castps_si256(_mm256_cmp_ps(v, half, _CMP_GT_OQ)));
    const __m256 in = _mm256_cmp_ps(v, floor, _CMP_GT_OQ);
    used = _mm256_sub_epi32(used, _mm256_castps_si256(in));
    _mm256_store_ps(values[j], v);
    some_in |= std::uint64_t{_mm256_movemask_ps(in) != 0} << j;
  }
  return {width, used, some_in};
}

/// The sums of Caruana's fit in eight lanes.
struct EightSums {
  __m256 s0, s1, s2, s3, s4, r0, r1, r2;
};

/// eightProfiles() step 4: EightSums from the values of eightValues() (overwritten).
inline __attribute__((target("avx2,fma"), always_inline)) EightSums eightSums(float (*values)[8],
                                                                              int hw,
                                                                              std::uint64_t some_in,
                                                                              __m256 floor) {
  __m256 s0 = _mm256_setzero_ps(), s1 = s0, s2 = s0, s3 = s0, s4 = s0, r0 = s0, r1 = s0, r2 = s0;
  // The weights and logarithms out to the farthest pixel in the fit on either side, then the sums
  // over pixels d and -d together: their even moments take w(d) + w(-d), the odd ones
  // w(d) - w(-d). The pixels out of the fit add zeros.
  const int reach =  // |d| of the farthest pixel in the fit; -1 where no lane has one
      some_in == 0 ? -1
                   : std::max(hw - __builtin_ctzll(some_in), 63 - __builtin_clzll(some_in) - hw);
  alignas(32) float weights[kEightWindow][8];
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
  return {s0, s1, s2, s3, s4, r0, r1, r2};
}

/// eightProfiles() step 5: Caruana's fit in double, as gaussianCentre(), four lanes at a time:
/// centre[l] (NaN where the fit does not hold). The determinant of the normal equations cancels
/// in the centre -b / 2c, so c < 0 is: nc and det of unlike signs.
inline __attribute__((target("avx2,fma"), always_inline)) void eightCentres(const EightSums& sums,
                                                                            __m256i used,
                                                                            const int tops[8],
                                                                            int hw, double* out) {
  alignas(32) float sums_of[8][8];  // s0..s4, r0..r2 of the eight lanes
  const __m256 all[8] = {sums.s0, sums.s1, sums.s2, sums.s3, sums.s4, sums.r0, sums.r1, sums.r2};
  for (int k = 0; k < 8; ++k) _mm256_store_ps(sums_of[k], all[k]);
  alignas(32) std::int32_t used_lanes[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(used_lanes), used);
  const __m256d magnitude = _mm256_set1_pd(-0.0);  // the sign bit: |x| is x without it
  for (int h = 0; h < 2; ++h) {
    __m256d wide[8];
    for (int k = 0; k < 8; ++k) wide[k] = _mm256_cvtps_pd(_mm_load_ps(sums_of[k] + 4 * h));
    const auto [det, nb, nc] =
        solveByCramer(wide[0], wide[1], wide[2], wide[3], wide[4], wide[5], wide[6], wide[7]);
    const __m256d offset = -nb / (2.0 * nc);
    __m256d fitted = _mm256_cmp_pd(fourInts(used_lanes + 4 * h), _mm256_set1_pd(3.0), _CMP_GE_OQ);
    fitted = _mm256_and_pd(
        fitted, _mm256_cmp_pd(_mm256_andnot_pd(magnitude, det), _mm256_set1_pd(1e-12), _CMP_GE_OQ));
    fitted = _mm256_and_pd(fitted, _mm256_xor_pd(nc, det));  // sign bit: unlike signs
    fitted = _mm256_and_pd(fitted, _mm256_cmp_pd(nc, _mm256_setzero_pd(), _CMP_NEQ_OQ));
    fitted = _mm256_and_pd(
        fitted, _mm256_cmp_pd(_mm256_andnot_pd(magnitude, offset), _mm256_set1_pd(hw), _CMP_LE_OQ));
    const __m256d centre = fourInts(tops + 4 * h) + offset;
    _mm256_store_pd(
        out + 4 * h,
        _mm256_blendv_pd(_mm256_set1_pd(std::numeric_limits<double>::quiet_NaN()), centre, fitted));
  }
}

template <typename T>
__attribute__((target("avx2,fma"))) EightProfiles eightProfiles(const T* const rows[8],
                                                                const int tops[8],
                                                                const ProfileParams& p) {
  const int hw = p.half_window;
  alignas(32) std::uint8_t columns[256 * blocksOf<T>(kEightMaxHalfWindow)];
  transposeLanes(rows, tops, hw, columns);
  const EightLine line = eightLine<T>(columns, hw, p);
  // Three passes over the window, none with a branch or a chain from one pixel to the next but
  // the sums, so that the core overlaps the pixels: the background-free values and the lanes'
  // widths; over the pixels where some lane is in the fit, the weights and the logarithms; the
  // sums of the fit.
  alignas(32) float values[kEightWindow][8];
  const EightWidths widths = eightValues<T>(columns, hw, line, values);
  const EightSums sums = eightSums(values, hw, widths.some_in, line.floor);
  EightProfiles out;
  _mm256_store_ps(out.contrast, line.contrast);
  _mm256_store_ps(out.at_left, line.at_left);
  _mm256_store_ps(out.slope, line.slope);
  _mm256_store_si256(reinterpret_cast<__m256i*>(out.width), widths.width);
  eightCentres(sums, widths.used, tops, hw, out.centre);
  return out;
}

}  // namespace

template <typename T>
void measureEight(const PeakRegion<T>* regions, int count, int columns, const ProfileParams& p,
                  Peak* peaks, bool* found) {
  const T* rows[8];
  int tops[8], slots[8];
  const int hw = p.half_window;
  const int lanes = fillLanes(
      regions, count, columns, p,
      [&](int x) {
        return x - hw - 3 >= 0 && x - hw - 4 + kBlockPixels<T> * blocksOf<T>(hw) <= columns - 1;
      },
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

template void measureEight<std::uint8_t>(const PeakRegion<std::uint8_t>*, int, int,
                                         const ProfileParams&, Peak*, bool*);
template void measureEight<std::uint16_t>(const PeakRegion<std::uint16_t>*, int, int,
                                          const ProfileParams&, Peak*, bool*);

}  // namespace multislit::profile
#endif
