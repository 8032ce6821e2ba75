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
#include <limits>

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
  static constexpr long kNone = std::numeric_limits<long>::min();  ///< x of an empty slot
  long x;                                                          ///< image column [px]
  long first_row;   ///< first row of the window centred on its expected crossing [px]
  int half_rows;    ///< rows each side of the expected crossing [px]
  bool usable;      ///< inside the image, its contrast at least the limit, some signal
  double weight;    ///< its signal above the fit limit (0 unless usable)
  double moment_x;  ///< weight times its column
  double moment_y;  ///< weight times the row where the stripe crosses it
};

/// The columns measured for the points of one slit, reused by its next points: neighbouring
/// points of a slit (rows k and k + 1) measure columns about |du/dv| apart, so seven columns a
/// point share four or five with the next. Measured eight at a time, ahead along the slit; a
/// column is reused when its profile was placed where this point places it (the same rows), so
/// every point's centre is what it would measure from its own columns.
/// clear() before each slit and each image.
class AcrossColumns {
 public:
  AcrossColumns() { clear(); }
  void clear() {
    for (AcrossColumn& m : slots_) m.x = AcrossColumn::kNone;
  }
  /// `columns` columns from x0 on, measured for the stripe through (`c`, `row`) of direction
  /// `slope` with `p`'s window and limits: the cached ones where placed alike, the others now.
  template <typename T>
  void gather(const cv::Mat& image, int row, double c, double slope, const AcrossStripe& p, long x0,
              int columns, const AcrossColumn** out);

 private:
  static constexpr std::size_t kSlots = 32;  ///< a power of two over a point's columns and a batch
  AcrossColumn slots_[kSlots];
};

/// The column where the stripe through (`centre`, `row`) of direction `slope` (du/dv) crosses
/// `row`, measured from the columns' profiles of `image` (CV_8U or CV_16U). False, leaving
/// `*out` alone, when too few columns show the stripe inside the image. With `shared`, the columns
/// come from and go to it (the extractor's points of one slit, in order along it).
bool acrossStripeCentre(const cv::Mat& image, int row, double centre, double slope,
                        const AcrossStripe& params, double* out, AcrossColumns* shared = nullptr);

}  // namespace multislit
