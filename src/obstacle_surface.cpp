#include "obstacle_surface.h"

#include "slit_run.h"

#include "multislit/plane_model.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace multislit::detail {

pcl::Indices surfacePoints(const pcl::PointCloud<PointRDM>& cloud, const pcl::Indices& group,
                           const Eigen::Vector3d& plane, double max_step, int min_run) {
  // The buffers are kept from frame to frame (one per thread); a copy only when not ascending.
  thread_local pcl::Indices copy;
  thread_local std::vector<std::size_t> run;
  thread_local std::vector<int> length;
  const pcl::Indices& sorted = inAscendingOrder(group, copy);
  const auto width = static_cast<pcl::index_t>(cloud.width);
  const auto at = [&](std::size_t j) -> const PointRDM& {
    return cloud[static_cast<std::size_t>(sorted[j])];
  };
  const auto above = [&](std::size_t j) { return planeResidual(at(j), plane) > 0; };
  // Each point continues the run of the nearest point before it, at most kRunReach cells back on
  // its slit, on its side of the floor and within max_step of its dk.
  const std::size_t n = sorted.size();
  run.resize(n);
  length.assign(n, 0);
  for (std::size_t j = 0; j < n; ++j) {
    run[j] = j;
    for (std::size_t k = j; k-- > 0;) {
      if (sorted[k] / width != sorted[j] / width || sorted[j] - sorted[k] > kRunReach) break;
      if (above(k) == above(j) && std::abs(at(k).dk - at(j).dk) <= max_step) {
        run[j] = run[k];
        break;
      }
    }
    ++length[run[j]];
  }
  pcl::Indices surface;
  for (std::size_t j = 0; j < n; ++j)
    if (length[run[j]] >= min_run) surface.push_back(sorted[j]);
  return surface;
}

}  // namespace multislit::detail
