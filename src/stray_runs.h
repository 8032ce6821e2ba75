// Stray runs along a slit. Where a stripe is lost (dark grout, a dark object, a deep shadow), the
// row's assigned region still holds a brightest blob of noise, and its "centre" lies anywhere in
// the region: tens of pixels of dk off the floor, on one side or the other. The columns measured
// across the stripe are shared by neighbouring rows, so such centres come in runs of two or three
// rows that agree with each other and jump away from the points on either side. A surface does
// not: it changes dk by at most 3.5 px from one row to the next (the simulator's truth on the
// ball, the box and the tennis ball), so a short run that jumps by more than that from both its
// neighbours is no surface.
#pragma once

#include <cstddef>
#include <vector>

namespace multislit::detail {

/// One point of a slit, in order along it.
struct SlitSample {
  int row = 0;      ///< image row [px]
  double dk = 0.0;  ///< its dk [px]; NaN: not measured
};

/// Of `samples` (one slit, rows ascending), sets to NaN the dk of every run of at most
/// `longest` measured points that is a stray: a run is points on rows at most 2 apart each within
/// `step` px of dk of the one before; it is a stray when a measured point lies within 2 rows
/// before or after it (the run's neighbour, which jumps by more than `step` from it, or it would
/// belong to the run). A run with no measured point within 2 rows on either side is kept: nothing
/// says it is not a surface. The rule has no side: a run of the floor as short as that between
/// two jumps goes too (a slit's floor runs hundreds of rows). `longest` 0: nothing is dropped.
/// Returns the points dropped.
std::size_t dropStrayRuns(std::vector<SlitSample>& samples, int longest, double step);

}  // namespace multislit::detail
