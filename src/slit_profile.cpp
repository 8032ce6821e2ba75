#include "multislit/slit_profile.h"

#include <algorithm>
#include <cmath>

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

// Caruana's Gaussian fit: ln(v) = a + b x + c x^2, weighted by v^2; centre -b / 2c.
template <typename T>
bool gaussianCentre(const T* row, int lo, int hi, int top, const Background& bg, double floor,
                    double* centre) {
  double s[5] = {0, 0, 0, 0, 0}, r[3] = {0, 0, 0};
  int used = 0;
  for (int x = lo; x <= hi; ++x) {
    const double v = row[x] - bg(x);
    if (v <= floor) continue;
    const double w = v * v, l = std::log(v), d = x - top;
    double p = w;
    for (int k = 0; k < 5; ++k, p *= d) s[k] += p;
    r[0] += w * l;
    r[1] += w * l * d;
    r[2] += w * l * d * d;
    ++used;
  }
  if (used < 3) return false;
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
  if (!(std::abs(offset) <= hi - lo)) return false;
  *centre = top + offset;
  return true;
}

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
  int width = 0;
  for (int x = first; x <= last; ++x) width += (row[x] - bg(x)) > 0.5 * contrast;
  if (width < p.min_width || width > p.max_width) return false;

  const double floor = p.fit_threshold * contrast;
  double centre = 0;
  if (p.estimator == Estimator::Windowed) {
    centre = windowedCentroid(row, first, last, centroid(row, first, last, bg, floor), bg,
                              p.window_sigma);
  } else if (saturated || p.estimator == Estimator::Centroid ||
             !gaussianCentre(row, first, last, top, bg, floor, &centre)) {
    centre = centroid(row, first, last, bg, floor);
  }
  peak->centre = centre;
  peak->contrast = contrast;
  peak->width = width;
  peak->saturated = saturated;
  return true;
}

template <typename T>
bool measurePeak(const T* row, int columns, int first, int last, const ProfileParams& p,
                 Peak* peak) {
  first = std::max(first, 0);
  last = std::min(last, columns - 1);
  if (first > last) return false;
  const T* top = std::max_element(row + first, row + last + 1);
  const int x = static_cast<int>(top - row);
  // A maximum on the region's border that keeps rising outside belongs to a profile outside.
  if (x == first && first > 0 && row[first - 1] > *top) return false;
  if (x == last && last < columns - 1 && row[last + 1] > *top) return false;
  return measurePeakAt(row, columns, x, p, peak);
}

template bool measurePeak<uint8_t>(const uint8_t*, int, int, int, const ProfileParams&, Peak*);
template bool measurePeak<uint16_t>(const uint16_t*, int, int, int, const ProfileParams&, Peak*);
template bool measurePeakAt<uint8_t>(const uint8_t*, int, int, const ProfileParams&, Peak*);
template bool measurePeakAt<uint16_t>(const uint16_t*, int, int, const ProfileParams&, Peak*);

}  // namespace multislit
