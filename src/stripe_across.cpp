#include "stripe_across.h"

#include "avx2_clones.h"
#include "lanes.h"
#include "slit_profile_simd.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <limits>

namespace multislit {

namespace {

constexpr int kLanes = 8;     // columns measured together (7 used with half_columns = 3)
constexpr int kMaxRows = 32;  // longest column profile [px]

// The helpers below return eight-lane vectors by value (and take them by reference: a parameter by
// value draws GCC's note on its ABI whatever the warning's setting); each is inlined into the AVX2
// and default clones of its caller, so no call ever has the ABI GCC warns about.
#pragma GCC diagnostic ignored "-Wpsabi"

using lanes::F8;
using lanes::I8;
using lanes::U8;

__attribute__((always_inline)) inline F8 loadLanes(const float* p) {
  F8 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
__attribute__((always_inline)) inline void storeLanes(float* p, const F8& v) {
  std::memcpy(p, &v, sizeof v);
}
/// Row i of the pixels as floats.
__attribute__((always_inline)) inline F8 pixelLanes(const std::uint16_t* p) {
  typedef std::uint16_t P8 __attribute__((vector_size(16)));
  P8 v;
  std::memcpy(&v, p, sizeof v);
  return __builtin_convertvector(v, F8);
}

/// ln(x) of normal floats x > 0 to within 4e-7, without a division: x = 2^e m with m in
/// [sqrt(1/2), sqrt(2)), f = m - 1, ln x = e ln 2 + f + f^2 q(f), q the degree-6 polynomial of the
/// row's eight-lane fit (slit_profile_eight.cpp), summed in pairs of terms.
__attribute__((always_inline)) inline F8 lanesLog(const F8& x) {
  I8 bits;
  std::memcpy(&bits, &x, sizeof bits);
  const I8 e = (bits - 0x3f3504f3) >> 23;  // the borrow picks m's interval
  const I8 m_bits = bits - (I8)((U8)e << 23);
  F8 m;
  std::memcpy(&m, &m_bits, sizeof m);
  const F8 f = m - 1.0f, f2 = f * f, f4 = f2 * f2;
  const F8 q01 = 0.333341136f * f - 0.500000912f, q23 = 0.199290571f * f - 0.249824512f;
  const F8 q456 = -0.101885865f * f2 + (0.15984096f * f - 0.171323873f);
  const F8 q = f4 * q456 + (f2 * q23 + q01);
  return __builtin_convertvector(e, F8) * 0.693147181f + (f2 * q + f);
}

/// The columns' profiles, row i of column j at v[i][j], and the sums of each column's fit.
struct Columns {
  alignas(32) std::uint16_t pixels[kMaxRows][kLanes];  // as read: 8 or 16 bits
  alignas(32) float v[kMaxRows][kLanes];
  alignas(32) float used[kLanes];  // 1: a column inside the image, 0: a lane left empty
  // Per column: the contrast above the background line through the two pixels at each end, and
  // over the pixels above fit_threshold of it: their signal, moment and the weighted sums of
  // Caruana's log-parabola (weights v^2) about the middle row d = i - count / 2.
  alignas(32) float top[kLanes], sum[kLanes], moment[kLanes];
  alignas(32) float s1[kLanes], s2[kLanes], s3[kLanes], s4[kLanes], w0[kLanes];
  alignas(32) float t0[kLanes], t1[kLanes], t2[kLanes];
};

/// Each column's values above its background line (into c.v), its contrast (c.top) and the limit
/// of the fit (+inf-like in an empty lane, which then sums nothing).
__attribute__((always_inline)) inline F8 backgroundAndLimit(Columns& c, int count,
                                                            float fit_threshold) {
  const F8 left = 0.5f * (pixelLanes(c.pixels[0]) + pixelLanes(c.pixels[1]));
  const F8 right = 0.5f * (pixelLanes(c.pixels[count - 1]) + pixelLanes(c.pixels[count - 2]));
  const F8 tilt = (right - left) / static_cast<float>(count - 2);
  F8 top = {};
  for (int i = 0; i < count; ++i) {
    const F8 v = pixelLanes(c.pixels[i]) - (left + tilt * (static_cast<float>(i) - 0.5f));
    storeLanes(c.v[i], v);
    top = top < v ? v : top;
  }
  top *= loadLanes(c.used);
  storeLanes(c.top, top);
  const F8 none = F8{} + 3.4e38f;
  return top > 0 ? fit_threshold * top : none;
}

/// Background, contrast and the fit's sums of every column at once (the lanes in vector
/// registers; AVX2 where the CPU has it).
MULTISLIT_AVX2_CLONES void sumColumns(Columns& c, int count, float fit_threshold) {
  const F8 limit = backgroundAndLimit(c, count, fit_threshold);
  // Rows where no column stands above its limit add nothing (zeros) to any sum: only the rows from
  // the first to the last that does are summed, in the same order, so the sums are the same bits.
  // Bit i of `rows`: row i holds the stripe in some lane (no branch: that is hard to predict).
  U8 lanes_rows = {}, bit = U8{} + 1;
  for (int i = 0; i < count; ++i, bit += bit) lanes_rows |= (U8)(loadLanes(c.v[i]) > limit) & bit;
  std::uint32_t rows = 0;
  for (int j = 0; j < kLanes; ++j) rows |= lanes_rows[j];
  const int begin = rows ? __builtin_ctz(rows) : count, end = rows ? 32 - __builtin_clz(rows) : 0;
  const float half = 0.5f * static_cast<float>(count - 1);
  F8 sum = {}, moment = {}, w0 = {}, s1 = {}, s2 = {}, s3 = {}, s4 = {}, t0 = {}, t1 = {}, t2 = {};
  for (int i = begin; i < end; ++i) {
    const float d = static_cast<float>(i) - half, d2 = d * d;
    const F8 v = loadLanes(c.v[i]);
    const F8 a = (F8)((I8)(v > limit) & (I8)v), w = a * a;  // v where above the limit, else 0
    const F8 wl = w * lanesLog(v < 1e-20f ? F8{} + 1e-20f : v);
    sum += a, moment += a * d;
    w0 += w, s1 += w * d, s2 += w * d2, s3 += w * d2 * d;
    s4 += w * d2 * d2, t0 += wl, t1 += wl * d, t2 += wl * d2;
  }
  storeLanes(c.sum, sum), storeLanes(c.moment, moment), storeLanes(c.w0, w0);
  storeLanes(c.s1, s1), storeLanes(c.s2, s2), storeLanes(c.s3, s3), storeLanes(c.s4, s4);
  storeLanes(c.t0, t0), storeLanes(c.t1, t1), storeLanes(c.t2, t2);
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

/// Fills lane j of `cols` with the profile of column xs[j] from row first_rows[j] on, `h` rows
/// each side of its middle (lanes [0, lanes)); cols.used is 0 where the window leaves the image
/// and in lanes past `lanes`: an empty lane.
template <typename T>
void placeColumns(const cv::Mat& image, const long* xs, const long* first_rows, int h, int lanes,
                  Columns& cols) {
  const int count = 2 * h + 1;
  const std::size_t step = image.step1();
  for (int j = 0; j < kLanes; ++j) {
    const bool inside = j < lanes && xs[j] >= 0 && xs[j] < image.cols && first_rows[j] >= 0 &&
                        first_rows[j] + count <= image.rows;
    cols.used[j] = inside ? 1.0f : 0.0f;
    if (!inside) {
      for (int i = 0; i < count; ++i) cols.pixels[i][j] = 0;
      continue;
    }
    // Integers here; sumColumns() turns whole rows of lanes into floats.
    const T* pixel = image.ptr<T>(static_cast<int>(first_rows[j])) + xs[j];
    for (int i = 0; i < count; ++i) cols.pixels[i][j] = pixel[i * step];
  }
}

/// Measures the `lanes` (<= kLanes) columns xs[j] from first_rows[j] on, `h` rows each side of
/// their middles, into `out`.
template <typename T>
void measureColumns(const cv::Mat& image, const long* xs, const long* first_rows, int h, int lanes,
                    double fit_threshold, double min_contrast, AcrossColumn* out) {
  Columns cols;
  placeColumns<T>(image, xs, first_rows, h, lanes, cols);
  sumColumns(cols, 2 * h + 1, static_cast<float>(fit_threshold));
  alignas(32) double offsets[kLanes];
  columnOffsets(cols, offsets);
  for (int j = 0; j < lanes; ++j) {
    AcrossColumn& m = out[j];
    m.x = xs[j], m.first_row = first_rows[j], m.half_rows = h;
    m.usable = cols.used[j] > 0 && cols.top[j] >= min_contrast && cols.sum[j] > 0;
    m.weight = m.usable ? cols.sum[j] : 0.0;
    m.moment_x = m.weight * static_cast<double>(m.x);
    m.moment_y = m.usable ? m.weight * (static_cast<double>(first_rows[j]) + h + offsets[j]) : 0.0;
  }
}

/// The columns a point measures around `c`: x0 and each one's first row.
void pointColumns(int row, double c, double slope, int half_columns, int half_rows, long* xs,
                  long* first_rows) {
  const long x0 = std::lround(c) - half_columns;
  const double per_column = 1.0 / slope;
  for (int j = 0; j < 2 * half_columns + 1; ++j)
    xs[j] = x0 + j, first_rows[j] = firstRowOf(row, c, per_column, half_rows, x0 + j);
}

/// Whether a point of these parameters is measured across the stripe at all.
bool measuredAcross(double slope, int half_columns, int half_rows) {
  return std::abs(slope) >= kAcrossMinSlope && half_rows >= 2 && 2 * half_rows + 1 <= kMaxRows &&
         2 * half_columns + 1 <= kLanes;
}

/// The centre across the stripe from the row's centre `start`: the signal-weighted mean of the
/// crossings of the columns around it, each carried back to `row` along the stripe, once more
/// around the new centre where it moved a pixel or more. columns(c, pass, measured) gives the
/// columns around c.
template <typename GetColumns>
bool across(int row, double start, double slope, const AcrossStripe& p, GetColumns columns,
            double* out) {
  const int columns_used = 2 * p.half_columns + 1;
  double c = start;
  for (int pass = 0; pass < 2; ++pass) {
    const AcrossColumn* measured[kLanes];
    AcrossColumn own[kLanes];
    columns(c, pass, measured, own);
    // The signal-weighted mean of the columns' crossings, each carried back to `row` along the
    // stripe: x + slope (row - y).
    double weight = 0, moment_x = 0, moment_y = 0;
    int usable = 0;
    for (int j = 0; j < columns_used; ++j) {
      const AcrossColumn& m = *measured[j];
      weight += m.weight, moment_x += m.moment_x, moment_y += m.moment_y;
      usable += m.usable;
    }
    if (usable <= p.half_columns) return false;  // more than half the columns must see it
    const double moved = (moment_x + slope * (row * weight - moment_y)) / weight - c;
    c += moved;
    if (!(std::abs(c - start) <= p.max_move)) return false;
    if (std::abs(moved) < 1.0) break;  // the columns' crossings hardly change: done
  }
  *out = c;
  return true;
}

/// A point's own columns around c, measured now.
template <typename T>
void ownColumns(const cv::Mat& image, int row, double c, double slope, const AcrossStripe& p,
                const AcrossColumn** measured, AcrossColumn* own) {
  long xs[kLanes], first_rows[kLanes];
  pointColumns(row, c, slope, p.half_columns, p.half_rows, xs, first_rows);
  const int n = 2 * p.half_columns + 1;
  measureColumns<T>(image, xs, first_rows, p.half_rows, n, p.fit_threshold, p.min_contrast, own);
  for (int j = 0; j < n; ++j) measured[j] = &own[j];
}

constexpr std::size_t kNotAcross = std::numeric_limits<std::size_t>::max();
constexpr std::uint32_t kNoColumn = std::numeric_limits<std::uint32_t>::max();

}  // namespace

void SlitColumns::clear(const AcrossStripe& limits) {
  params_ = limits;
  columns_.clear(), uses_.clear(), points_.clear();
  std::fill(std::begin(slots_), std::end(slots_), kNoColumn);
}

void SlitColumns::plan(int row, double centre, double slope, int half_rows) {
  Point& point = points_.emplace_back();
  point.row = row, point.half_rows = half_rows, point.start = centre, point.slope = slope;
  point.first_use = kNotAcross;
  const int half_columns = params_.half_columns;
  if (!measuredAcross(slope, half_columns, half_rows)) return;
  point.first_use = uses_.size();
  long xs[kLanes], first_rows[kLanes];
  pointColumns(row, centre, slope, half_columns, half_rows, xs, first_rows);
  for (int j = 0; j < 2 * half_columns + 1; ++j) {
    std::uint32_t& slot = slots_[static_cast<std::size_t>(xs[j]) & (kSlots - 1)];
    const bool same = slot != kNoColumn && columns_[slot].x == xs[j] &&
                      columns_[slot].first_row == first_rows[j] &&
                      columns_[slot].half_rows == half_rows;
    if (!same) {
      slot = static_cast<std::uint32_t>(columns_.size());
      columns_.emplace_back();  // measured by measure()
      AcrossColumn& m = columns_.back();
      m.x = xs[j], m.first_row = first_rows[j], m.half_rows = half_rows;
    }
    uses_.push_back(slot);
  }
}

template <typename T>
void SlitColumns::measure(const cv::Mat& image) {
  // Eight columns of the same window length at a time, in order of first use.
  for (std::size_t begin = 0; begin < columns_.size();) {
    const int h = columns_[begin].half_rows;
    long xs[kLanes], first_rows[kLanes];
    int lanes = 0;
    for (; lanes < kLanes && begin + lanes < columns_.size(); ++lanes) {
      const AcrossColumn& m = columns_[begin + lanes];
      if (m.half_rows != h) break;
      xs[lanes] = m.x, first_rows[lanes] = m.first_row;
    }
    measureColumns<T>(image, xs, first_rows, h, lanes, params_.fit_threshold, params_.min_contrast,
                      &columns_[begin]);
    begin += static_cast<std::size_t>(lanes);
  }
}

template <typename T>
bool SlitColumns::centre(const cv::Mat& image, std::size_t point, double* out) const {
  const Point& pt = points_[point];
  if (pt.first_use == kNotAcross) return false;
  AcrossStripe p = params_;
  p.half_rows = pt.half_rows;
  auto columns = [&](double c, int pass, const AcrossColumn** measured, AcrossColumn* own) {
    if (pass > 0) return ownColumns<T>(image, pt.row, c, pt.slope, p, measured, own);
    for (int j = 0; j < 2 * p.half_columns + 1; ++j)
      measured[j] = &columns_[uses_[pt.first_use + static_cast<std::size_t>(j)]];
  };
  return across(pt.row, pt.start, pt.slope, p, columns, out);
}

template void SlitColumns::measure<std::uint8_t>(const cv::Mat&);
template void SlitColumns::measure<std::uint16_t>(const cv::Mat&);
template bool SlitColumns::centre<std::uint8_t>(const cv::Mat&, std::size_t, double*) const;
template bool SlitColumns::centre<std::uint16_t>(const cv::Mat&, std::size_t, double*) const;

bool acrossStripeCentre(const cv::Mat& image, int row, double centre, double slope,
                        const AcrossStripe& params, double* out) {
  if (!measuredAcross(slope, params.half_columns, params.half_rows)) return false;
  auto columns = [&](double c, int, const AcrossColumn** measured, AcrossColumn* own) {
    if (image.depth() == CV_8U)
      ownColumns<std::uint8_t>(image, row, c, slope, params, measured, own);
    else
      ownColumns<std::uint16_t>(image, row, c, slope, params, measured, own);
  };
  return across(row, centre, slope, params, columns, out);
}

}  // namespace multislit
