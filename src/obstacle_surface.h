// The points of an obstacle group that lie on a surface. Where a stripe is lost on dark grout,
// the assigned region's brightest pixel is speckle: such points pass the floor threshold, join
// groups through their neighbours and reach any height, but neighbouring rows of one slit jump
// by tens of pixels of dk, so they seldom make a run of one surface.
#pragma once

#include "multislit/point_types.h"

#include <pcl/point_cloud.h>
#include <pcl/types.h>

#include <Eigen/Core>

#include <algorithm>

namespace multislit::detail {

/// `indices` in ascending order: `indices` itself where it already is (groups usually are), else
/// a sorted copy made in `copy`.
inline const pcl::Indices& inAscendingOrder(const pcl::Indices& indices, pcl::Indices& copy) {
  if (std::is_sorted(indices.begin(), indices.end())) return indices;
  copy.assign(indices.begin(), indices.end());
  std::sort(copy.begin(), copy.end());
  return copy;
}

/// The points of `group` on a surface: runs of at least `min_run` points of one slit on
/// neighbouring rows (a gap of one row allowed), all on one side of the floor `plane` (A, B, C:
/// dk = A u + B v + C), each within `max_step` px of dk of the one before it in the run; points
/// off the run in between are passed over. In ascending order.
pcl::Indices surfacePoints(const pcl::PointCloud<PointRDM>& cloud, const pcl::Indices& group,
                           const Eigen::Vector3d& plane, double max_step, int min_run);

}  // namespace multislit::detail
