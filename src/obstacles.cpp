#include "multislit/obstacles.h"
#include "multislit/plane_model.h"

#include "config_check.h"
#include "obstacle_surface.h"
#include "slit_run.h"

#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

namespace multislit {

namespace {

/// Disjoint sets over 0 .. n-1 (union by size, path halving).
class DisjointSets {
 public:
  /// n singletons, in the arrays of earlier calls.
  void reset(std::size_t n) {
    parent_.resize(n);
    std::iota(parent_.begin(), parent_.end(), std::size_t{0});
    size_.assign(n, 1);
  }
  std::size_t find(std::size_t i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  }
  void join(std::size_t a, std::size_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (size_[a] < size_[b]) std::swap(a, b);
    parent_[b] = a;
    size_[a] += size_[b];
  }

 private:
  std::vector<std::size_t> parent_, size_;
};

/// The buffers of the grid grouping, kept from frame to frame (one per thread): the stage runs on
/// every frame, and allocating them took as long as the grouping itself.
struct GridWorkspace {
  pcl::Indices sorted;                                        ///< the obstacle points, ascending
  std::vector<char> in_run;                                   ///< per point: run >= min_run
  std::vector<std::size_t> slit_start;                        ///< per slit: its first point
  std::vector<std::pair<std::size_t, std::size_t>> links;     ///< neighbours not both in runs
  std::vector<std::size_t> next_start, next_to, seed, queue;  ///< growFromRuns
  std::vector<std::size_t> group_of;                          ///< per set root: its group
  DisjointSets sets;
};

GridWorkspace& gridWorkspace() {
  thread_local GridWorkspace w;
  return w;
}

}  // namespace

void ObstacleClustererConfig::validate() const {
  constexpr detail::FieldCheck require("ObstacleClustererConfig");
  require(max_gap >= 0, "max_gap", "must be >= 0 points");
  require(slit_link_radius > 0, "slit_link_radius", "must be > 0 px");
  require(tolerance > 0 && tolerance < 1, "tolerance", "must be in (0, 1) m");
  require(min_points >= 1, "min_points", "must be >= 1");
  require(min_run >= 1, "min_run", "must be >= 1");
  require(max_hops >= 0, "max_hops", "must be >= 0");
  require(std::isfinite(max_step) && max_step > 0, "max_step", "must be > 0 px");
}

std::size_t Obstacle::surfacePointsAbove(double least) const {
  return static_cast<std::size_t>(std::count_if(surface_heights.begin(), surface_heights.end(),
                                                [least](float h) { return h >= least; }));
}

std::size_t Obstacle::surfacePointsBelow(double most) const {
  return surface_heights.size() - surfacePointsAbove(most);
}

std::size_t ObstacleResult::pointCount() const {
  std::size_t n = 0;
  for (const Obstacle& o : obstacles) n += o.pointCount();
  return n;
}

ObstacleClusterer::ObstacleClusterer(const ObstacleClustererConfig& config, const FootConfig& feet)
    : config_(config), feet_(feet) {
  config_.validate();
  feet_.validate();
}

namespace {

/// Calls run(start, end) for each run [start, end) of the points `sorted` (cloud indices in
/// ascending order): the points of one slit (one cloud row) on neighbouring rows, a gap of one row
/// allowed; with `plane` (A, B, C) given, only points on one side of it (the sign of
/// dk - (A u + B v + C)) make a run.
template <typename Run>
void forEachRun(const pcl::PointCloud<PointRDM>& cloud, const pcl::Indices& sorted,
                const Eigen::Vector3d* plane, Run&& run) {
  const auto width = static_cast<pcl::index_t>(cloud.width);
  const auto above = [&](pcl::index_t i) {
    return planeResidual(cloud[static_cast<std::size_t>(i)], *plane) > 0;
  };
  std::size_t start = 0;
  for (std::size_t i = 1; i <= sorted.size(); ++i) {
    const bool continues = i < sorted.size() && sorted[i] / width == sorted[i - 1] / width &&
                           sorted[i] - sorted[i - 1] <= detail::kRunReach &&
                           (!plane || above(sorted[i]) == above(sorted[i - 1]));
    if (continues) continue;
    run(start, i);
    start = i;
  }
}

/// The longest run (forEachRun) among the points of `group`.
int longestRun(const pcl::PointCloud<PointRDM>& cloud, const pcl::Indices& group,
               const Eigen::Vector3d* plane) {
  thread_local pcl::Indices copy;  // only for a group not in ascending order
  std::size_t longest = 0;
  forEachRun(cloud, detail::inAscendingOrder(group, copy), plane,
             [&](std::size_t start, std::size_t end) { longest = std::max(longest, end - start); });
  return static_cast<int>(longest);
}

/// Each point of ws.links (pairs of neighbours) that lies in no run (ws.in_run false) joins the
/// group of the nearest point in a run at most `max_hops` links away, reached first, and that group
/// only: points in no run neither chain groups together nor reach further. Those no run reaches
/// are grouped with their neighbours as before.
void growFromRuns(GridWorkspace& ws, int max_hops) {
  const std::vector<char>& in_run = ws.in_run;
  const std::size_t n = in_run.size();
  // The neighbours of each point, in the order of the links: those of j are
  // next_to[next_start[j] .. next_start[j + 1]).
  std::vector<std::size_t>& start = ws.next_start;
  start.assign(n + 1, 0);
  for (const auto& [a, b] : ws.links) ++start[a + 1], ++start[b + 1];
  for (std::size_t j = 0; j < n; ++j) start[j + 1] += start[j];
  ws.next_to.resize(start[n]);
  ws.queue.assign(start.begin(), start.end() - 1);  // where the next neighbour of each goes
  for (const auto& [a, b] : ws.links) ws.next_to[ws.queue[a]++] = b, ws.next_to[ws.queue[b]++] = a;
  // Breadth first from the points in runs, one hop at a time: queue[begin, end) is the frontier.
  std::vector<std::size_t>& seed = ws.seed;
  seed.assign(n, n);
  ws.queue.clear();
  for (std::size_t j = 0; j < n; ++j)
    if (in_run[j]) seed[j] = j, ws.queue.push_back(j);
  std::size_t begin = 0, end = ws.queue.size();
  for (int hop = 1; hop <= max_hops && begin < end; ++hop) {
    for (std::size_t f = begin; f < end; ++f) {
      const std::size_t a = ws.queue[f];
      for (std::size_t k = start[a]; k < start[a + 1]; ++k) {
        const std::size_t b = ws.next_to[k];
        if (seed[b] == n) seed[b] = seed[a], ws.queue.push_back(b);
      }
    }
    begin = end;
    end = ws.queue.size();
  }
  for (std::size_t j = 0; j < n; ++j)
    if (!in_run[j] && seed[j] < n) ws.sets.join(j, seed[j]);
  // What no run reaches stays together as before, a group of noise that the run rule rejects.
  for (const auto& [a, b] : ws.links)
    if (seed[a] == n && seed[b] == n) ws.sets.join(a, b);
}

}  // namespace

ObstacleResult ObstacleClusterer::cluster(const pcl::PointCloud<PointRDM>::ConstPtr& cloud,
                                          const FloorResult& floor,
                                          const Eigen::Isometry3d& robot_from_camera) const {
  ObstacleResult result;
  if (!cloud || !floor.found) return result;
  // The floor in metric space, from which heights are measured.
  result.floor = fitMetricFloor(*cloud, floor.inliers);
  // Group the points off the floor.
  const Eigen::Vector3d* plane = config_.run_one_side ? &floor.plane : nullptr;
  std::vector<pcl::Indices> groups = config_.method == ClusterMethod::Grid
                                         ? gridGroups(*cloud, floor.obstacles, plane)
                                         : euclideanGroups(*cloud, floor.obstacles);
  // Reject groups too small to be real, then size and place the others.
  for (pcl::Indices& group : groups) {
    if (group.size() < static_cast<std::size_t>(config_.min_points) ||
        longestRun(*cloud, group, plane) < config_.min_run) {
      ++result.rejected_groups;
      result.rejected.insert(result.rejected.end(), group.begin(), group.end());
      continue;
    }
    result.obstacles.push_back(
        describe(*cloud, floor, result.floor, std::move(group), robot_from_camera));
  }
  const auto distance = [](const Obstacle& o) {  // unplaced (NaN) last
    return std::isnan(o.distance) ? std::numeric_limits<double>::infinity() : o.distance;
  };
  std::stable_sort(result.obstacles.begin(), result.obstacles.end(),
                   [&](const Obstacle& a, const Obstacle& b) { return distance(a) < distance(b); });
  return result;
}

std::vector<pcl::Indices> ObstacleClusterer::gridGroups(const pcl::PointCloud<PointRDM>& cloud,
                                                        const pcl::Indices& points,
                                                        const Eigen::Vector3d* plane) const {
  GridWorkspace& ws = gridWorkspace();
  pcl::Indices& sorted = ws.sorted;
  sorted.assign(points.begin(), points.end());
  std::sort(sorted.begin(), sorted.end());
  const std::size_t n = sorted.size();
  // Cloud row = slit, column = position along the slit (one image row each): the points of slit s
  // are sorted[slit_start[s] .. slit_start[s + 1]).
  const std::size_t width = cloud.width, slits = cloud.height;
  ws.slit_start.assign(slits + 1, 0);
  for (const auto i : sorted) ++ws.slit_start[static_cast<std::size_t>(i) / width + 1];
  for (std::size_t s = 0; s < slits; ++s) ws.slit_start[s + 1] += ws.slit_start[s];
  ws.in_run.resize(n);
  forEachRun(cloud, sorted, plane, [&](std::size_t start, std::size_t end) {
    const bool long_enough = end - start >= static_cast<std::size_t>(config_.min_run);
    std::fill(ws.in_run.begin() + static_cast<std::ptrdiff_t>(start),
              ws.in_run.begin() + static_cast<std::ptrdiff_t>(end), long_enough);
  });
  // Points in runs are joined directly; the links of the others are kept for growFromRuns.
  ws.sets.reset(n);
  ws.links.clear();
  const auto link = [&](std::size_t a, std::size_t b) {
    if (ws.in_run[a] && ws.in_run[b])
      ws.sets.join(a, b);
    else
      ws.links.emplace_back(a, b);
  };
  const double r2 = config_.slit_link_radius * config_.slit_link_radius;
  for (std::size_t s = 0; s < slits; ++s) {
    const std::size_t first = ws.slit_start[s], last = ws.slit_start[s + 1];
    // Along the slit: at most max_gap cells between neighbours.
    for (std::size_t a = first + 1; a < last; ++a)
      if (sorted[a] - sorted[a - 1] <= config_.max_gap + 1) link(a - 1, a);
    if (s + 1 >= slits) continue;
    // Across to the next slit: reference positions close in the image.
    for (std::size_t a = first; a < last; ++a) {
      const PointRDM& p = cloud[static_cast<std::size_t>(sorted[a])];
      for (std::size_t b = last; b < ws.slit_start[s + 2]; ++b) {
        const PointRDM& q = cloud[static_cast<std::size_t>(sorted[b])];
        const double du = p.u - q.u, dv = p.v - q.v;
        if (du * du + dv * dv <= r2) link(a, b);
      }
    }
  }
  growFromRuns(ws, config_.max_hops);
  // One group per set, in the order of their first points; each in ascending order.
  std::vector<pcl::Indices> groups;
  constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  ws.group_of.assign(n, kNone);
  for (std::size_t j = 0; j < n; ++j) {
    std::size_t& g = ws.group_of[ws.sets.find(j)];
    if (g == kNone) {
      g = groups.size();
      groups.emplace_back();
    }
    groups[g].push_back(sorted[j]);
  }
  return groups;
}

std::vector<pcl::Indices> ObstacleClusterer::euclideanGroups(const pcl::PointCloud<PointRDM>& cloud,
                                                             const pcl::Indices& points) const {
  // pcl::PointXYZ has PCL's precompiled instantiations (no PointRDM template code to build).
  auto xyz = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  pcl::Indices source;
  for (const auto i : points) {
    const PointRDM& p = cloud[static_cast<std::size_t>(i)];
    if (!hasXYZ(p)) continue;
    xyz->push_back(pcl::PointXYZ(p.x, p.y, p.z));
    source.push_back(i);
  }
  if (xyz->empty()) return {};
  auto tree = pcl::make_shared<pcl::search::KdTree<pcl::PointXYZ>>();
  pcl::EuclideanClusterExtraction<pcl::PointXYZ> extraction;
  extraction.setClusterTolerance(config_.tolerance);
  extraction.setMinClusterSize(1);  // the rejection rule is ours, applied by cluster()
  extraction.setMaxClusterSize(std::numeric_limits<pcl::uindex_t>::max());
  extraction.setSearchMethod(tree);
  extraction.setInputCloud(xyz);
  std::vector<pcl::PointIndices> found;
  extraction.extract(found);
  std::vector<pcl::Indices> groups;
  for (const pcl::PointIndices& c : found) {
    groups.emplace_back();
    for (const auto j : c.indices) groups.back().push_back(source[static_cast<std::size_t>(j)]);
  }
  return groups;
}

Obstacle ObstacleClusterer::describe(const pcl::PointCloud<PointRDM>& cloud,
                                     const FloorResult& floor, const MetricFloor& metric,
                                     pcl::Indices indices,
                                     const Eigen::Isometry3d& robot_from_camera) const {
  Obstacle o;
  const double inf = std::numeric_limits<double>::infinity();
  o.min.setConstant(inf);
  o.max.setConstant(-inf);
  o.distance = inf;
  thread_local std::vector<double> heights;  // kept from frame to frame
  thread_local std::vector<int> slits;
  heights.clear();
  slits.clear();
  const auto height = [&](const Eigen::Vector3d& camera) {
    return metric.valid ? metric.height(camera) : (robot_from_camera * camera).z();
  };
  for (const auto i : indices) {
    const PointRDM& p = cloud[static_cast<std::size_t>(i)];
    slits.push_back(p.slit);
    const double residual = planeResidual(p, floor.plane);
    o.max_residual = std::max(o.max_residual, std::abs(residual));
    if (!hasXYZ(p)) continue;
    const Eigen::Vector3d camera(p.x, p.y, p.z);
    const Eigen::Vector3d robot = robot_from_camera * camera;
    o.centroid += robot;
    o.min = o.min.cwiseMin(robot);
    o.max = o.max.cwiseMax(robot);
    heights.push_back(height(camera));
    const double dx = std::max(0.0, std::abs(robot.x()) - feet_.toe());
    const double dy = std::max(0.0, std::abs(robot.y()) - feet_.halfWidth());
    o.distance = std::min(o.distance, std::hypot(dx, dy));
  }
  std::sort(slits.begin(), slits.end());
  o.slits = static_cast<int>(std::unique(slits.begin(), slits.end()) - slits.begin());
  if (!heights.empty()) {
    o.centroid /= static_cast<double>(heights.size());
    o.length = o.max.x() - o.min.x();
    o.width = o.max.y() - o.min.y();
    const auto top = heights.begin() + static_cast<std::ptrdiff_t>(0.9 * (heights.size() - 1));
    std::nth_element(heights.begin(), top, heights.end());
    o.height = *top;
  } else {  // no metric position (a reference without scale): sizes unknown
    const double nan = std::numeric_limits<double>::quiet_NaN();
    o.centroid.setConstant(nan);
    o.min = o.max = o.centroid;
    o.length = o.width = o.height = o.distance = nan;
  }
  o.surface = detail::surfacePoints(cloud, indices, floor.plane, config_.max_step, config_.min_run);
  for (const auto i : o.surface) {
    const PointRDM& p = cloud[static_cast<std::size_t>(i)];
    if (hasXYZ(p)) o.surface_heights.push_back(static_cast<float>(height({p.x, p.y, p.z})));
  }
  o.indices = std::move(indices);
  return o;
}

}  // namespace multislit
