// A reference slit from its track (paper Sec. II-C): a plane's slit is a smooth curve, so its
// centres are smoothed by a robust polynomial u(v), and the rows where the slit runs clean are
// kept. Internal to the slit finding (slit_tracks.cpp).
#pragma once

#include "multislit/reference.h"

#include "slit_course.h"

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace multislit {

/// Robust polynomial u(v) of degree `degree` along a track. A piece of something else joined to a
/// slit's end (a neighbour's end, a bright grain) must not pull the curve: the first fit is a
/// parabola through the middle half of the rows only (or, where the pattern judged that half
/// mostly off it, its centres elsewhere), and each later fit takes the centres near the one
/// before, its limit from the median residual (robust), not the mean square. Only the centres
/// `on_pattern` (slit_pattern.h) take part. Returns the coefficients over the track's rows scaled
/// to [-1, 1], and in `inlier` the centres the last fit kept.
Eigen::VectorXd fitSlit(const Track& t, const std::vector<bool>& on_pattern, int degree,
                        std::vector<bool>* inlier);

/// A track as a reference slit: raw centres (smoothing_degree 0), or the smoothed curve over the
/// rows where the slit runs clean. Adds the squared residuals of the kept centres to `ss`, their
/// count to `m`. False when fewer than min_rows clean rows are left.
bool toSlit(const Track& t, const std::vector<bool>& on_pattern, const ReferenceConfig& config,
            ReferenceSlit* slit, double* ss, std::size_t* m);

}  // namespace multislit
