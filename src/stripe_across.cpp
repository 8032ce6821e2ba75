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

/// The natural logarithm for x > 0 (float, to about 1e-7 relative), written so that a loop over
/// lanes vectorizes: x = m 2^e with m in [sqrt(1/2), sqrt(2)), ln m = 2 atanh((m - 1) / (m + 1)).
inline float lanesLog(float x) {
  std::uint32_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  const std::uint32_t mantissa = (bits & 0x007fffffu) | 0x3f800000u;  // m in [1, 2)
  float m;
  std::memcpy(&m, &mantissa, sizeof m);
  float e = static_cast<float>(static_cast<int>((bits >> 23) & 0xffu) - 127);
  const bool high = m > 1.41421356f;
  m = high ? 0.5f * m : m;
  e = high ? e + 1.0f : e;
  const float s = (m - 1.0f) / (m + 1.0f), s2 = s * s;
  const float series = 1.0f + s2 * (1.0f / 3 + s2 * (1.0f / 5 + s2 * (1.0f / 7 + s2 * (1.0f / 9))));
  return e * 0.693147181f + 2.0f * s * series;
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
    bool above = false;
    for (int j = 0; j < kLanes; ++j) above = above || c.v[i][j] > limit[j];
    begin = above ? std::min(begin, i) : begin;
    end = above ? i + 1 : end;
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

template <typename T>
bool across(const cv::Mat& image, int row, double start, double slope, const AcrossStripe& p,
            double* out) {
  const int h = p.half_rows, count = 2 * h + 1;
  if (count > kMaxRows || 2 * p.half_columns + 1 > kLanes) return false;
  Columns cols;
  long first_row[kLanes] = {};
  double c = start;
  for (int pass = 0; pass < 2; ++pass) {
    const long x0 = std::lround(c) - p.half_columns;
    for (int j = 0; j < kLanes; ++j) {  // each column from where the stripe should cross it
      const long x = x0 + j;
      const long lo = std::lround(row + (static_cast<double>(x) - c) / slope) - h;
      const bool inside = j <= 2 * p.half_columns && x >= 0 && x < image.cols && lo >= 0 &&
                          lo + count <= image.rows;
      cols.used[j] = inside ? 1.0f : 0.0f;
      first_row[j] = lo;
      if (!inside) {
        for (int i = 0; i < count; ++i) cols.v[i][j] = 0;
        continue;
      }
      const T* pixel = image.ptr<T>(static_cast<int>(lo)) + x;
      const std::size_t step = image.step1();
      for (int i = 0; i < count; ++i) cols.v[i][j] = static_cast<float>(pixel[i * step]);
    }
    sumColumns(cols, count, static_cast<float>(p.fit_threshold));
    alignas(32) double offsets[kLanes];
    columnOffsets(cols, offsets);
    double weight = 0, sum = 0;
    int columns = 0;
    for (int j = 0; j < kLanes; ++j) {
      if (!(cols.top[j] >= p.min_contrast) || !(cols.sum[j] > 0)) continue;
      const double y = static_cast<double>(first_row[j]) + h + offsets[j];
      sum += cols.sum[j] * (static_cast<double>(x0 + j) + slope * (row - y));
      weight += cols.sum[j];
      ++columns;
    }
    if (columns <= p.half_columns) return false;  // more than half the columns must see it
    const double moved = sum / weight - c;
    c += moved;
    if (!(std::abs(c - start) <= p.max_move)) return false;
    if (std::abs(moved) < 1.0) break;  // the columns' crossings hardly change: done
  }
  *out = c;
  return true;
}

}  // namespace

bool acrossStripeCentre(const cv::Mat& image, int row, double centre, double slope,
                        const AcrossStripe& params, double* out) {
  if (!(std::abs(slope) >= kAcrossMinSlope) || params.half_rows < 2) return false;
  return image.depth() == CV_8U ? across<std::uint8_t>(image, row, centre, slope, params, out)
                                : across<std::uint16_t>(image, row, centre, slope, params, out);
}

}  // namespace multislit
