// The slits of a reference image as one pattern: one projector casts them all, so on a
// plane their courses change smoothly from slit to slit as well as along each slit. A stretch of
// one slit that a dark grout line, a stain or a grain running along it has pulled sideways (by
// pixels, over a hundred rows) is a smooth curve of its own, which that slit's polynomial alone
// follows; its neighbours show where it should lie. Internal to the slit finding
// (slit_tracks.cpp).
#pragma once

#include "slit_course.h"

#include <vector>

namespace multislit {

/// For each centre of each slit (`slits` ordered across the fan), whether it lies on the pattern:
/// within max(0.3 px, 3 sigma) of a least-squares surface u(slit, row), a polynomial of degree 5
/// in each, fitted first to the centres `start` marks (those each slit's own robust fit keeps:
/// the strays at a track's ends are out), then again to those near it (sigma: 1.4826 x the median
/// |residual| of the centres kept). On the exact slits of the default sensor at the Table I poses
/// the surface leaves at most 0.04 px. Every centre is on the pattern (nothing is judged) when
/// there are fewer than 3 slits or too few centres for the surface, or when fewer than 60 % of
/// the centres fit it: a projector whose slits do not make one smooth pattern keeps each slit's
/// own fit.
std::vector<std::vector<bool>> onPattern(const std::vector<Track>& slits,
                                         const std::vector<std::vector<bool>>& start);

}  // namespace multislit
