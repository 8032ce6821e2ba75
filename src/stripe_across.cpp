#include "stripe_across.h"

#include "avx2_clones.h"
#include "slit_profile_simd.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace multislit {

namespace {

constexpr int kLanes = 8;     // columns measured together (7 used with half_columns = 3)
constexpr int kMaxRows = 32;  // longest column profile [px]

/// ln(x) of a normal float x > 0 to within 4e-7, without a division, written so that a loop over
/// lanes vectorizes: x = 2^e m with m in [sqrt(1/2), sqrt(2)), f = m - 1, ln x = e ln 2 + f +
/// f^2 q(f), q the degree-6 polynomial of the row's eight-lane fit (slit_profile_eight.cpp),
/// summed in pairs of terms.
inline float lanesLog(float x) {
  std::int32_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  const std::int32_t e = (bits - 0x3f3504f3) >> 23;  // the borrow picks m's interval
  const std::int32_t m_bits = bits - static_cast<std::int32_t>(static_cast<std::uint32_t>(e) << 23);
  float m;
  std::memcpy(&m, &m_bits, sizeof m);
  const float f = m - 1.0f, f2 = f * f, f4 = f2 * f2;
  const float q01 = 0.333341136f * f - 0.500000912f, q23 = 0.199290571f * f - 0.249824512f;
  const float q456 = -0.101885865f * f2 + (0.15984096f * f - 0.171323873f);
  const float q = f4 * q456 + (f2 * q23 + q01);
  return static_cast<float>(e) * 0.693147181f + (f2 * q + f);
}

/// The columns' profiles, row i of column j at v[i][j], and the sums of each column's fit.
struct Columns {
  alignas(32) float v[kMaxRows][kLanes];
  alignas(32) float used[kLanes];  // 1: a column inside the image, 0: a lane left empty
  // Per column: the contrast above the background line through the two pixels at each end, and
  // over the pixels above fit_threshold of it: their signal, moment and the weighted sums of
  // Caruana's log-parabola (weights v^2) about the middle row d = i - count / 2.
  alignas(32) float top[kLanes], sum[kLanes], moment[kLanes];
  alignas(32) float s1[kLanes], s2[kLanes], s3[kLanes], s4[kLanes], w0[kLanes];
  alignas(32) float t0[kLanes], t1[kLanes], t2[kLanes];
};

/// Background, contrast and the fit's sums of every column at once (the loops over lanes run in
/// vector registers; AVX2 where the CPU has it).
MULTISLIT_AVX2_CLONES void sumColumns(Columns& c, int count, float fit_threshold) {
  const float half = 0.5f * static_cast<float>(count - 1);
  alignas(32) float left[kLanes], tilt[kLanes], top[kLanes];
  for (int j = 0; j < kLanes; ++j) {
    left[j] = 0.5f * (c.v[0][j] + c.v[1][j]);
    const float right = 0.5f * (c.v[count - 1][j] + c.v[count - 2][j]);
    tilt[j] = (right - left[j]) / static_cast<float>(count - 2);
    top[j] = 0;
  }
  for (int i = 0; i < count; ++i)
    for (int j = 0; j < kLanes; ++j) {
      c.v[i][j] -= left[j] + tilt[j] * (static_cast<float>(i) - 0.5f);
      top[j] = std::max(top[j], c.v[i][j]);
    }
  alignas(32) float limit[kLanes];
  for (int j = 0; j < kLanes; ++j) {
    c.top[j] = top[j] * c.used[j];
    limit[j] = c.top[j] > 0 ? fit_threshold * c.top[j] : 3.4e38f;  // an empty lane sums nothing
    c.sum[j] = c.moment[j] = c.w0[j] = c.s1[j] = c.s2[j] = c.s3[j] = c.s4[j] = c.t0[j] = c.t1[j] =
        c.t2[j] = 0;
  }
  // Rows where no column stands above its limit add nothing (zeros) to any sum: only the rows from
  // the first to the last that does are summed, in the same order, so the sums are the same bits.
  int begin = count, end = 0;
  for (int i = 0; i < count; ++i) {
    int above = 0;  // without a branch: whether a row holds the stripe is hard to predict
    for (int j = 0; j < kLanes; ++j) above |= c.v[i][j] > limit[j] ? 1 : 0;
    begin = std::min(begin, above ? i : count);
    end = std::max(end, above * (i + 1));
  }
  for (int i = begin; i < end; ++i) {
    const float d = static_cast<float>(i) - half, d2 = d * d;
    for (int j = 0; j < kLanes; ++j) {
      const float v = c.v[i][j];
      const float a = v > limit[j] ? v : 0.0f, w = a * a;
      const float wl = w * lanesLog(std::max(v, 1e-20f));
      c.sum[j] += a, c.moment[j] += a * d;
      c.w0[j] += w, c.s1[j] += w * d, c.s2[j] += w * d2, c.s3[j] += w * d2 * d;
      c.s4[j] += w * d2 * d2, c.t0[j] += wl, c.t1[j] += wl * d, c.t2[j] += wl * d2;
    }
  }
}

/// Every column's centre [rows from the middle row]: the log-parabola's vertex (the normal
/// equations by Cramer's rule, in double), or the centroid where it has no maximum near it. All
/// lanes at once (in vector registers where the CPU has AVX2); a lane whose column saw nothing
/// holds a meaningless number, which the caller skips.
MULTISLIT_AVX2_CLONES void columnOffsets(const Columns& c, double* out) {
  for (int j = 0; j < kLanes; ++j) {
    const double centroid = static_cast<double>(c.moment[j]) / c.sum[j];
    const profile::CramerScalar k = profile::solveByCramer(c.w0[j], c.s1[j], c.s2[j], c.s3[j],
                                                           c.s4[j], c.t0[j], c.t1[j], c.t2[j]);
    const double vertex = -k.nb / (2 * k.nc);
    const bool peaked = std::abs(k.det) > 0 && k.nc / k.det < 0;
    out[j] = peaked && std::abs(vertex - centroid) < 2.0 ? vertex : centroid;
  }
}

/// The first row of column x's profile: `h` rows above where the stripe through (`c`, `row`), at
/// 1 / `per_column` columns a row, should cross it.
inline long firstRowOf(int row, double c, double per_column, int h, long x) {
  return std::lround(row + (static_cast<double>(x) - c) * per_column) - h;
}

/// Fills lane j of `cols` with column x0 + j (lanes [0, lanes)), its profile starting where the
/// stripe through (`c`, `row`) of direction `slope` should cross it, `h` rows above; records each
/// lane's first row (cols.used is 0 where the column's window leaves the image: an empty lane).
template <typename T>
void placeColumns(const cv::Mat& image, int row, double c, double slope, int h, long x0, int lanes,
                  Columns& cols, long* first_row) {
  const int count = 2 * h + 1;
  const double per_column = 1.0 / slope;
  for (int j = 0; j < kLanes; ++j) first_row[j] = firstRowOf(row, c, per_column, h, x0 + j);
  const std::size_t step = image.step1();
  for (int j = 0; j < kLanes; ++j) {
    const long x = x0 + j, lo = first_row[j];
    const bool inside =
        j < lanes && x >= 0 && x < image.cols && lo >= 0 && lo + count <= image.rows;
    cols.used[j] = inside ? 1.0f : 0.0f;
    if (!inside) {
      for (int i = 0; i < count; ++i) cols.v[i][j] = 0;
      continue;
    }
    const T* pixel = image.ptr<T>(static_cast<int>(lo)) + x;
    for (int i = 0; i < count; ++i) cols.v[i][j] = static_cast<float>(pixel[i * step]);
  }
}

/// Measures columns x0 .. x0 + lanes - 1 (placed as placeColumns() does) into `out`.
template <typename T>
void measureColumns(const cv::Mat& image, int row, double c, double slope, const AcrossStripe& p,
                    long x0, int lanes, AcrossColumn* out) {
  const int h = p.half_rows;
  Columns cols;
  long first_row[kLanes];
  placeColumns<T>(image, row, c, slope, h, x0, lanes, cols, first_row);
  sumColumns(cols, 2 * h + 1, static_cast<float>(p.fit_threshold));
  alignas(32) double offsets[kLanes];
  columnOffsets(cols, offsets);
  for (int j = 0; j < lanes; ++j) {
    AcrossColumn& m = out[j];
    m.x = x0 + j, m.first_row = first_row[j], m.half_rows = h;
    m.usable = cols.used[j] > 0 && cols.top[j] >= p.min_contrast && cols.sum[j] > 0;
    m.weight = m.usable ? cols.sum[j] : 0.0;
    m.moment_x = m.weight * static_cast<double>(m.x);
    m.moment_y = m.usable ? m.weight * (static_cast<double>(first_row[j]) + h + offsets[j]) : 0.0;
  }
}

template <typename T>
bool across(const cv::Mat& image, int row, double start, double slope, const AcrossStripe& p,
            AcrossColumns* shared, double* out) {
  const int count = 2 * p.half_rows + 1, columns_used = 2 * p.half_columns + 1;
  if (count > kMaxRows || columns_used > kLanes) return false;
  AcrossColumn own[kLanes];
  double c = start;
  for (int pass = 0; pass < 2; ++pass) {
    const long x0 = std::lround(c) - p.half_columns;
    const AcrossColumn* measured[kLanes];
    if (shared == nullptr) {  // this point's own columns
      measureColumns<T>(image, row, c, slope, p, x0, columns_used, own);
      for (int j = 0; j < columns_used; ++j) measured[j] = &own[j];
    } else {
      shared->gather<T>(image, row, c, slope, p, x0, columns_used, measured);
    }
    // The signal-weighted mean of the columns' crossings, each carried back to `row` along the
    // stripe: x + slope (row - y).
    double weight = 0, moment_x = 0, moment_y = 0;
    int columns = 0;
    for (int j = 0; j < columns_used; ++j) {
      const AcrossColumn& m = *measured[j];
      weight += m.weight, moment_x += m.moment_x, moment_y += m.moment_y;
      columns += m.usable;
    }
    if (columns <= p.half_columns) return false;  // more than half the columns must see it
    const double moved = (moment_x + slope * (row * weight - moment_y)) / weight - c;
    c += moved;
    if (!(std::abs(c - start) <= p.max_move)) return false;
    if (std::abs(moved) < 1.0) break;  // the columns' crossings hardly change: done
  }
  *out = c;
  return true;
}

}  // namespace

template <typename T>
void AcrossColumns::gather(const cv::Mat& image, int row, double c, double slope,
                           const AcrossStripe& p, long x0, int columns, const AcrossColumn** out) {
  const int h = p.half_rows;
  // A column is reused only when it was measured with the window this point would place: then
  // its crossing is what this point would measure. Windows a row off would be reused more often,
  // but they tie neighbouring points' errors together (docs/speed.md).
  const double per_column = 1.0 / slope;
  auto cached = [&](long x) -> const AcrossColumn* {
    const AcrossColumn& m = slots_[static_cast<std::size_t>(x) & (kSlots - 1)];
    const bool same =
        m.x == x && m.half_rows == h && m.first_row == firstRowOf(row, c, per_column, h, x);
    return same ? &m : nullptr;
  };
  long first_missing = 0, last_missing = -1;
  bool missing = false;
  for (int j = 0; j < columns; ++j) {
    if (cached(x0 + j)) continue;
    if (!missing) first_missing = x0 + j;
    last_missing = x0 + j, missing = true;
  }
  if (missing) {
    // The slit's next points lie towards larger columns where it descends to the right
    // (du/dv > 0): measure eight columns from the first missing one on that side.
    const long batch = slope > 0 ? first_missing : last_missing - (kLanes - 1);
    AcrossColumn fresh[kLanes];
    measureColumns<T>(image, row, c, slope, p, batch, kLanes, fresh);
    for (int j = 0; j < kLanes; ++j)
      slots_[static_cast<std::size_t>(batch + j) & (kSlots - 1)] = fresh[j];
  }
  for (int j = 0; j < columns; ++j)
    out[j] = &slots_[static_cast<std::size_t>(x0 + j) & (kSlots - 1)];
}

template void AcrossColumns::gather<std::uint8_t>(const cv::Mat&, int, double, double,
                                                  const AcrossStripe&, long, int,
                                                  const AcrossColumn**);
template void AcrossColumns::gather<std::uint16_t>(const cv::Mat&, int, double, double,
                                                   const AcrossStripe&, long, int,
                                                   const AcrossColumn**);

bool acrossStripeCentre(const cv::Mat& image, int row, double centre, double slope,
                        const AcrossStripe& params, double* out, AcrossColumns* shared) {
  if (!(std::abs(slope) >= kAcrossMinSlope) || params.half_rows < 2) return false;
  return image.depth() == CV_8U
             ? across<std::uint8_t>(image, row, centre, slope, params, shared, out)
             : across<std::uint16_t>(image, row, centre, slope, params, shared, out);
}

}  // namespace multislit
