// The slit's centre on one image row measured across the stripe, not along the row.
//
// The camera is rotated by 70 deg (paper Fig. 3), so a slit crosses an image row at about 20 deg:
// the row runs nearly along the stripe and sees it over about three times its width. Any change
// of the surface's brightness along the stripe within that length (a tile's edge, dark grout, a
// wood grain, a speckle grain) pulls the row's centroid along the stripe, which on the row is a
// shift of several pixels: on tiles with dark grout the row centre jumps by up to 15 px over a
// few rows where the floor is flat. Each image column crosses the stripe at 20 deg from its
// normal instead, so a column's profile sees the stripe's cross-section, not its length. The
// centre here is the signal-weighted mean, over a few columns around the row centre, of where each
// column's profile is centred (a Gaussian fit, as on the row), carried back to the row along the
// stripe's direction (the reference's slope du/dv); the columns span about one row each side along
// the stripe, and their sub-pixel phases differ, so the pixel grid's bias averages out (the
// test Extractor.AcrossTheStripeBeatsTheRowOnPlainAndTiledFloors measures both). Internal to the
// extractor and the reference.
#pragma once

#include <opencv2/core/mat.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace multislit {

struct AcrossStripe {
  int half_columns = 3;        ///< columns each side of the row centre [px]
  int half_rows = 7;           ///< rows each side of a column's expected crossing [px]
  double fit_threshold = 0.2;  ///< pixels below this share of a column's contrast are ignored
  double min_contrast = 15.0;  ///< a column's peak above its background to count [DN]
  double max_move = 10.0;      ///< farthest the centre may move from the row's centre [px]
};

/// Slopes at least this steep (|du/dv| >= 1: the stripe nearer a row than a column) are measured
/// across; a steeper column than row is measured on the row.
constexpr double kAcrossMinSlope = 1.0;

/// AcrossStripe::half_rows for a row profile of `row_half_window` [px] and a stripe of `slope`:
/// the row's window seen along a column, and one row more.
inline int acrossHalfRows(double row_half_window, double slope) {
  return 1 + static_cast<int>(std::ceil(row_half_window / std::max(1.0, std::abs(slope))));
}

/// One column's crossing of the stripe, as measured for some point of a slit.
struct AcrossColumn {
  long x;           ///< image column [px]
  long first_row;   ///< first row of the window centred on its expected crossing [px]
  int half_rows;    ///< rows each side of the expected crossing [px]
  bool usable;      ///< inside the image, its contrast at least the limit, some signal
  double weight;    ///< its signal above the fit limit (0 unless usable)
  double moment_x;  ///< weight times its column
  double moment_y;  ///< weight times the row where the stripe crosses it
};

/// The columns measured across the stripe for the points of one slit, each distinct one once.
/// Neighbouring points of a slit (rows k and k + 1) use columns about |du/dv| apart, so of a
/// point's seven columns four or five are the previous point's. A column's crossing depends only
/// on where its profile lies (its column, first row and length): a column is shared when its
/// profile lies where the other point places it too, so every point's centre is what it would
/// measure from its own columns. Per slit: clear(), plan() each point in order along it,
/// measure() once (eight columns at a time, none twice), then centre() each planned point.
class SlitColumns {
 public:
  /// Starts a slit whose points are measured with `limits` (all but half_rows, each point's own).
  void clear(const AcrossStripe& limits);
  /// Plans the point on `row` whose centre on the row is `centre`, of a stripe of direction
  /// `slope` (du/dv), its columns `half_rows` each side of their expected crossings.
  void plan(int row, double centre, double slope, int half_rows);
  /// Measures every planned column in `image` (CV_8U when T is std::uint8_t, else CV_16U).
  template <typename T>
  void measure(const cv::Mat& image);
  /// As acrossStripeCentre() for the `point`-th planned point, from the measured columns.
  template <typename T>
  bool centre(const cv::Mat& image, std::size_t point, double* out) const;

 private:
  struct Point {
    int row, half_rows;
    double start, slope;
    std::size_t first_use;  ///< its columns: uses_[first_use ..]; npos: not measured across
  };
  static constexpr std::size_t kSlots = 32;  ///< recent columns, by column modulo kSlots
  std::vector<AcrossColumn> columns_;        ///< distinct columns, in order of first use
  std::vector<std::uint32_t> uses_;          ///< each point's columns, as indices into columns_
  std::vector<Point> points_;
  std::uint32_t slots_[kSlots];
  AcrossStripe params_;  ///< the slit's limits (half_rows: each point's own)
};

/// The column where the stripe through (`centre`, `row`) of direction `slope` (du/dv) crosses
/// `row`, measured from the columns' profiles of `image` (CV_8U or CV_16U). False, leaving
/// `*out` alone, when too few columns show the stripe inside the image.
bool acrossStripeCentre(const cv::Mat& image, int row, double centre, double slope,
                        const AcrossStripe& params, double* out);

}  // namespace multislit
