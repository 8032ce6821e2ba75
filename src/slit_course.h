// A slit followed down an image: its centres row by row (Track), and how pieces of one slit,
// broken by speckle, a dark grout line or an occluder, are joined along one course. Internal to
// the slit finding (slit_tracks.cpp).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace multislit {

/// The value at position size / 2 of `values` in order (the upper median); `values` not empty.
inline double upperMedian(std::vector<double> values) {
  const auto mid = values.begin() + static_cast<long>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

/// A slit's centre on one image row, and its profile's width there.
struct Centre {
  int row;
  double u, width;
};

/// A slit being followed down the image, row by row.
struct Track {
  std::vector<Centre> points;
  int firstRow() const { return points.front().row; }
  int lastRow() const { return points.back().row; }
  double predict(int row) const {  // linear extrapolation over the last few rows
    const Centre& b = points.back();
    if (points.size() < 2) return b.u;
    const Centre& a = points[points.size() - std::min<std::size_t>(points.size(), 8)];
    if (a.row == b.row) return b.u;
    return b.u + (b.u - a.u) / (b.row - a.row) * (row - b.row);
  }
};

/// Joins the tracks that are pieces of one slit, over gaps up to `max_join_gap` rows, when one
/// course with the pattern's curvature fits both within `tolerance` [px] or their own scatter.
/// Drops pieces too short to have a course. Returns how many were joined.
int joinTracks(std::vector<Track>& tracks, int max_join_gap, double tolerance);

}  // namespace multislit
