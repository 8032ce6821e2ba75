#include "slit_tracks.h"

#include "full_scale.h"
#include "slit_course.h"
#include "slit_fit.h"
#include "slit_pattern.h"
#include "slit_selection.h"
#include "stripe_across.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace multislit {
namespace {

constexpr double kFwhmPerSigma = 2.3548;

/// Rows of an image as float, each smoothed by a Gaussian of `sigma` [px] along the row only: a
/// slit's profile lies along the row, and a symmetric kernel keeps its centre where it is. One
/// row at a time, so that no float copy of the whole image is held (1 GB at 16384 x 16384 px).
class RowSmoother {
 public:
  explicit RowSmoother(double sigma)
      : along_(
            cv::getGaussianKernel(2 * static_cast<int>(std::ceil(3 * sigma)) + 1, sigma, CV_32F)),
        across_(cv::Mat::ones(1, 1, CV_32F)) {}
  /// Row `r` of `image`, smoothed; valid until the next call.
  const cv::Mat& operator()(const cv::Mat& image, int r) {
    image.row(r).convertTo(row_, CV_32F);
    cv::sepFilter2D(row_, row_, CV_32F, along_, across_, cv::Point(-1, -1), 0,
                    cv::BORDER_REPLICATE);
    return row_;
  }

 private:
  cv::Mat along_, across_, row_;
};

/// Full width at half maximum of the profile whose top is p[x] over a background `low`, by
/// linear interpolation of both flanks; 0 when a flank does not fall within `reach` pixels.
double halfMaximumWidth(const float* p, int x, float low, int reach) {
  const float half = 0.5f * (p[x] + low);
  int l = x, r = x;
  while (l > x - reach && p[l] > half) --l;
  while (r < x + reach && p[r] > half) ++r;
  if (p[l] > half || p[r] > half) return 0;
  const double left = l + (half - p[l]) / static_cast<double>(p[l + 1] - p[l]);
  const double right = r - (half - p[r]) / static_cast<double>(p[r - 1] - p[r]);
  return right - left;
}

// 1. Every row: maxima that stand out, measured to sub-pixel precision on the smoothed rows.
std::vector<std::vector<Centre>> rowCentres(const cv::Mat& smooth, const ProfileParams& p) {
  std::vector<std::vector<Centre>> rows(static_cast<std::size_t>(smooth.rows));
  const int w = p.half_window, n = smooth.cols;
  for (int r = 0; r < smooth.rows; ++r) {
    const auto* row = smooth.ptr<std::uint16_t>(r);
    int last_kept = -1000;
    double last_value = 0;
    for (int x = 1; x + 1 < n; ++x) {
      if (!(row[x] > row[x - 1] && row[x] >= row[x + 1])) continue;
      const double base = std::min(row[std::max(0, x - w - 2)], row[std::min(n - 1, x + w + 2)]);
      if (row[x] - base < p.min_contrast) continue;
      Peak peak;
      if (!measurePeakAt(row, n, x, p, &peak)) continue;
      // A slit falls to under half its contrast on both sides within the window; the edge of a
      // bright tile or a lamp's glare stays up on one.
      const double half = row[x] - 0.5 * peak.contrast;
      if (!(row[std::max(0, x - w)] < half && row[std::min(n - 1, x + w)] < half)) continue;
      auto& out = rows[static_cast<std::size_t>(r)];
      if (x - last_kept <= 2 * w && !out.empty()) {  // two maxima of one profile: keep the higher
        if (row[x] <= last_value) continue;
        out.pop_back();
      }
      out.push_back({r, peak.centre, peak.width});
      last_kept = x;
      last_value = row[x];
    }
  }
  return rows;
}

// 2. Link centres of consecutive rows into tracks; a track ends after `max_gap` empty rows.
std::vector<Track> linkTracks(const std::vector<std::vector<Centre>>& rows, int max_gap,
                              double tolerance) {
  const double first_step = std::max(15.0, 2 * tolerance);  // [px]
  std::vector<Track> open, done;
  for (const auto& centres : rows) {
    if (centres.empty()) continue;
    const int row = centres.front().row;
    std::vector<bool> used(centres.size(), false);
    for (Track& t : open) {
      const double tol = t.points.size() < 2 ? first_step : tolerance;
      int best = -1;
      double best_d = tol;
      for (std::size_t k = 0; k < centres.size(); ++k) {
        const double d = std::abs(centres[k].u - t.predict(row));
        if (!used[k] && d < best_d) best = static_cast<int>(k), best_d = d;
      }
      if (best >= 0) {
        t.points.push_back(centres[static_cast<std::size_t>(best)]);
        used[static_cast<std::size_t>(best)] = true;
      }
    }
    for (std::size_t k = 0; k < centres.size(); ++k)
      if (!used[k]) open.push_back(Track{{centres[k]}});
    for (auto it = open.begin(); it != open.end();) {
      if (row - it->lastRow() > max_gap) {
        done.push_back(std::move(*it));
        it = open.erase(it);
      } else {
        ++it;
      }
    }
  }
  done.insert(done.end(), open.begin(), open.end());
  return done;
}

/// A track's centres measured across the stripe (stripe_across.h), as the extractor measures a
/// frame's, along the track's own course over kReach centres each side.
void measureAcross(const cv::Mat& image, double width, Track* t) {
  constexpr std::size_t kReach = 4;
  const std::vector<Centre> along_rows = t->points;
  const std::size_t n = along_rows.size();
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t lo = i >= kReach ? i - kReach : 0, hi = std::min(n - 1, i + kReach);
    if (along_rows[i].width <= 0 || along_rows[hi].row == along_rows[lo].row) continue;
    const double slope =
        (along_rows[hi].u - along_rows[lo].u) / (along_rows[hi].row - along_rows[lo].row);
    AcrossStripe p;
    p.min_contrast = 0;
    p.max_move = std::max(1.0, 0.25 * width);
    p.half_rows = acrossHalfRows(1.25 * width, slope);
    acrossStripeCentre(image, along_rows[i].row, along_rows[i].u, slope, p, &t->points[i].u);
  }
}

/// Each centre measured again in the raw image, where smoothing neither widens a profile cut by
/// the slit's end nor moves its centre: its width, and its centre where the raw profile gives one
/// (width 0 where it does not).
template <typename T>
void measureRaw(const cv::Mat& image, double width, Estimator estimator,
                std::vector<Track>* tracks) {
  ProfileParams p;
  p.estimator = estimator;
  p.half_window = std::max(3, static_cast<int>(std::lround(1.25 * width)));
  p.min_contrast = 0;
  p.min_width = 0;
  p.max_width = image.cols;
  p.saturation = image.depth() == CV_8U ? 255.0 : 65535.0;
  p.max_saturated = image.cols;
  const int reach = std::max(1, static_cast<int>(std::lround(0.25 * width)));
  for (Track& t : *tracks)
    for (Centre& c : t.points) {
      const T* row = image.ptr<T>(c.row);
      const int x0 = std::clamp(static_cast<int>(std::lround(c.u)), 0, image.cols - 1);
      int top = x0;
      for (int x = std::max(0, x0 - reach); x <= std::min(image.cols - 1, x0 + reach); ++x)
        if (row[x] > row[top]) top = x;
      Peak peak;
      const bool ok =
          measurePeakAt(row, image.cols, top, p, &peak) && std::abs(peak.centre - c.u) <= reach;
      c.width = ok ? peak.width : 0.0;
      if (ok) c.u = peak.centre;
    }
  for (Track& t : *tracks) measureAcross(image, width, &t);
}

/// For each centre of each slit, whether it takes part in its slit's final fit: each slit's own
/// robust fit first, then the pattern the slits make together (a stretch that grout pulled
/// sideways is off it). A slit with fewer than min_rows centres on the pattern keeps its own fit.
std::vector<std::vector<bool>> judgeSlits(const std::vector<Track>& slits,
                                          const ReferenceConfig& config) {
  std::vector<std::vector<bool>> on(slits.size());
  for (std::size_t k = 0; k < slits.size(); ++k) on[k].assign(slits[k].points.size(), true);
  if (config.smoothing_degree == 0) return on;  // raw centres: nothing is fitted
  for (std::size_t k = 0; k < slits.size(); ++k) {
    const std::vector<bool> all = on[k];
    fitSlit(slits[k], all, config.smoothing_degree, &on[k]);
  }
  on = onPattern(slits, on);
  for (auto& slit : on)
    if (std::count(slit.begin(), slit.end(), true) < config.min_rows)
      slit.assign(slit.size(), true);
  return on;
}

}  // namespace

double stripeWidth(const cv::Mat& image, double min_contrast) {
  constexpr double kSmooth = 1.5;  // [px] against speckle
  constexpr int kReach = 24;       // [px] a stripe's surroundings, under the slits' spacing
  constexpr int kRowStep = 4;
  RowSmoother smooth(kSmooth);
  std::vector<double> widths;
  for (int r = 0; r < image.rows; r += kRowStep) {
    const float* p = smooth(image, r).ptr<float>();
    for (int x = kReach; x + kReach < image.cols; ++x) {
      if (!(p[x] > p[x - 1] && p[x] >= p[x + 1])) continue;
      float low = p[x];
      bool top = true;
      for (int d = -kReach; d <= kReach && top; ++d) {
        top = d < 0 ? p[x + d] < p[x] : p[x + d] <= p[x];
        low = std::min(low, p[x + d]);
      }
      if (!top || p[x] - low < min_contrast) continue;
      const double width = halfMaximumWidth(p, x, low, kReach);
      if (width > 0) widths.push_back(width);
    }
  }
  if (widths.empty()) return 0;
  const double measured = upperMedian(std::move(widths)), smear = kFwhmPerSigma * kSmooth;
  return std::sqrt(std::max(measured * measured - smear * smear, 1.0));
}

double imageNoise(const cv::Mat& image) {
  constexpr int kRowStep = 8;
  cv::Mat row;
  std::vector<double> d;
  d.reserve(static_cast<std::size_t>((image.rows + kRowStep - 1) / kRowStep) *
            static_cast<std::size_t>(std::max(image.cols - 2, 0)));
  for (int r = 0; r < image.rows; r += kRowStep) {
    image.row(r).convertTo(row, CV_64F);
    const auto* p = row.ptr<double>();
    for (int x = 1; x + 1 < image.cols; ++x)
      d.push_back(std::abs(p[x] - 0.5 * (p[x - 1] + p[x + 1])));
  }
  if (d.empty()) return 0;
  return 1.4826 * upperMedian(std::move(d)) /
         std::sqrt(1.5);  // the second difference has 1.5 variances
}

namespace {

/// Noise of a pixel that the contrast limit stands above: first kNoiseSigmas[0], then, where that
/// finds fewer slits than the projector casts (a dim laser on a dark floor), kNoiseSigmas[1]. The
/// profiles are smoothed along the row over 0.4 stripe widths, which leaves a few times less noise
/// than a pixel has, so the second is still well above the smoothed profile's noise.
constexpr double kNoiseSigmas[2] = {8.0, 4.0};

DetectedSlits detectSlitsInRange(const cv::Mat& image, const ReferenceConfig& config,
                                 const std::string& what, double noise_sigmas) {
  // The image in 16-bit DN (an 8-bit image times 257), so that smoothing keeps its fractions.
  const double to16 = image.depth() == CV_8U ? 257.0 : 1.0;
  // The contrast limit: the configured one, or lower where the image is clean enough that
  // noise_sigmas of its noise are less (a dim laser on a dark floor), never below kLowest.
  constexpr double kLowest = 0.015;
  const double min_contrast =
      std::min(config.min_contrast,
               std::max(kLowest, noise_sigmas * imageNoise(image) * to16 / 65535.0)) *
      65535.0;
  const double width = stripeWidth(image, min_contrast / to16);
  DetectedSlits out;
  out.profile_width = width;
  // Smoothed over 0.4 of the stripe's width, speckle no longer splits a profile in two.
  const double sigma = std::max(1.0, 0.4 * width);
  const double smoothed_width = std::hypot(width, kFwhmPerSigma * sigma);
  cv::Mat smooth16(image.size(), CV_16U);
  RowSmoother smooth(sigma);
  for (int r = 0; r < image.rows; ++r) {
    cv::Mat row = smooth16.row(r);  // a header: convertTo writes into smooth16
    smooth(image, r).convertTo(row, CV_16U, to16);
  }
  ProfileParams params;
  params.estimator = config.estimator;
  params.min_contrast = min_contrast;
  params.saturation = 65535.0;
  params.half_window = std::max(3, static_cast<int>(std::lround(1.25 * smoothed_width)));
  params.min_width = 1.0;
  params.max_width = 2.0 * smoothed_width;  // wider is a brighter tile or a lamp, not a slit
  params.max_saturated = image.cols;        // a saturated plateau is still a slit in a reference
  // A centre may move from row to row by its noise, which grows with the stripe's width.
  const double tolerance = std::max(4.0, 0.3 * smoothed_width);
  std::vector<Track> tracks =
      width > 0 ? linkTracks(rowCentres(smooth16, params), config.max_gap, tolerance)
                : std::vector<Track>{};
  out.joined = joinTracks(tracks, image.rows / 2, 0.5 * tolerance);
  std::vector<Track> slits = selectSlits(std::move(tracks), config, what, &out.dropped);
  if (image.depth() == CV_8U)
    measureRaw<std::uint8_t>(image, width, config.estimator, &slits);
  else
    measureRaw<std::uint16_t>(image, width, config.estimator, &slits);
  double ss = 0;
  std::size_t m = 0;
  const std::vector<std::vector<bool>> on_pattern = judgeSlits(slits, config);
  for (std::size_t k = 0; k < slits.size(); ++k) {
    ReferenceSlit slit;
    if (toSlit(slits[k], on_pattern[k], config, &slit, &ss, &m))
      out.slits.push_back(std::move(slit));
  }
  if (out.slits.size() != slits.size())
    throw std::runtime_error(what + ": " + std::to_string(slits.size() - out.slits.size()) +
                             " slits run clean over fewer than " + std::to_string(config.min_rows) +
                             " rows");
  out.smoothing_rms = m ? std::sqrt(ss / static_cast<double>(m)) : 0.0;
  return out;
}

}  // namespace

DetectedSlits detectSlits(const cv::Mat& input, const ReferenceConfig& config,
                          const std::string& what) {
  const cv::Mat image = toFullRange(input, config.full_scale);
  try {
    try {
      return detectSlitsInRange(image, config, what, kNoiseSigmas[0]);
    } catch (const std::runtime_error& first) {
      try {  // dim slits: a lower limit; if that fails as well, the first attempt's error
        return detectSlitsInRange(image, config, what, kNoiseSigmas[1]);
      } catch (const std::runtime_error&) {
        throw first;
      }
    }
  } catch (const std::runtime_error& e) {
    const std::string hint = fullScaleHint(input, config);
    if (hint.empty()) throw;
    throw std::runtime_error(e.what() + hint);
  }
}

}  // namespace multislit
