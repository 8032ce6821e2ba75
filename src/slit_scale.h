// Points off the floor at longer scales along a slit: an object lifts a run of
// neighbouring rows of one slit, noise is correlated only over a speckle grain, so the median
// residual of a window of rows sees a shift that no single point shows above the frame's noise.
// Private to the library: FloorDetector's step 6.
#pragma once

#include "multislit/point_types.h"

#include <pcl/point_cloud.h>
#include <pcl/types.h>

#include <Eigen/Core>

#include <vector>

namespace multislit::detail {

struct SlitScaleOff {
  pcl::Indices points;           ///< off the floor at some scale, in the order of `candidates`
  std::vector<float> residuals;  ///< their residuals dk - (A u + B v + C), parallel [px]
  std::vector<double> sigmas;    ///< per window length (w, 2 w + 1, ...): measured noise, or NaN
};

/// Among `candidates` (cloud indices of the floor points of an organized RDMap: cloud row = slit,
/// column = position along it), the points whose window of w rows (w = min_window, 2 w + 1, ...
/// up to `max_window`, centred on the point, over the candidates only, at least half of it
/// candidates) has more than half of its candidates (its median) beyond `sigmas` times that
/// window length's noise and beyond `min_shift`, on the side of the point's own residual. The
/// noise of each window length is measured on the frame: 1.4826 x the median |window median| over
/// the candidates, so the correlation along a slit is measured, not assumed. Nothing when the
/// cloud is not organized.
SlitScaleOff offFloorAtScales(const pcl::PointCloud<PointRDM>& cloud,
                              const pcl::Indices& candidates, const Eigen::Vector3d& plane,
                              int min_window, int max_window, double sigmas, double min_shift);

}  // namespace multislit::detail
