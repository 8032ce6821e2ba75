#include "obstacle_surface.h"

#include "multislit/plane_model.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace multislit::detail {

pcl::Indices surfacePoints(const pcl::PointCloud<PointRDM>& cloud, pcl::Indices group,
                           const Eigen::Vector3d& plane, double max_step, int min_run) {
  std::sort(group.begin(), group.end());
  const auto width = static_cast<pcl::index_t>(cloud.width);
  const auto at = [&](std::size_t j) -> const PointRDM& {
    return cloud[static_cast<std::size_t>(group[j])];
  };
  const auto above = [&](std::size_t j) { return planeResidual(at(j), plane) > 0; };
  // Each point continues the run of the nearest point before it, at most 2 cells back on its
  // slit, on its side of the floor and within max_step of its dk.
  const std::size_t n = group.size();
  std::vector<std::size_t> run(n);
  std::vector<int> length(n, 0);
  for (std::size_t j = 0; j < n; ++j) {
    run[j] = j;
    for (std::size_t k = j; k-- > 0;) {
      if (group[k] / width != group[j] / width || group[j] - group[k] > 2) break;
      if (above(k) == above(j) && std::abs(at(k).dk - at(j).dk) <= max_step) {
        run[j] = run[k];
        break;
      }
    }
    ++length[run[j]];
  }
  pcl::Indices surface;
  for (std::size_t j = 0; j < n; ++j)
    if (length[run[j]] >= min_run) surface.push_back(group[j]);
  return surface;
}

}  // namespace multislit::detail
