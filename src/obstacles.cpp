#include "multislit/obstacles.h"
#include "multislit/plane_model.h"

#include "config_check.h"
#include "obstacle_surface.h"

#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string>

namespace multislit {

namespace {

/// Disjoint sets over 0 .. n-1 (union by size, path halving).
class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n), size_(n, 1) {
    std::iota(parent_.begin(), parent_.end(), std::size_t{0});
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

/// The sums over the points with x, y, z among points[indices[0 .. n)] of x, y, z, of their squares
/// (xx, yy, zz) and of their cross products (xy, yz, zx), taken about (x0, y0, z0) so that they
/// stay small.
struct XYZSums {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), squares = Eigen::Vector3d::Zero(),
                  cross = Eigen::Vector3d::Zero();
  std::size_t points = 0;
};

/// One pass in float with four lanes (x, y, z, 0) per point, added to double every kFlush points,
/// which keeps the sums accurate to ~1e-7. Two sets of lanes take the points in turn, so that each
/// add need not wait for the one before.
XYZSums sumXYZ(const PointRDM* points, const pcl::index_t* indices, std::size_t n, float x0,
               float y0, float z0) {
  typedef float F4 __attribute__((vector_size(16)));
  typedef std::int32_t I4 __attribute__((vector_size(16)));
  constexpr std::size_t kFlush = 64;
  const I4 xyz = {-1, -1, -1, 0};
  const F4 origin = {x0, y0, z0, 0.0f};
  struct Lanes {
    F4 sum = {}, squares = {}, cross = {};
    std::size_t points = 0;
  };
  // p minus the origin, as (x, y, z, 0); (0, 0, 0, 0) when p has no x, y, z, which adds nothing.
  const auto add = [&](Lanes& lanes, const PointRDM& p) {
    const bool ok = hasXYZ(p);
    F4 q;  // (x, y, z, data[3])
    std::memcpy(&q, p.data, sizeof q);
    const F4 d = (F4)((I4)(q - origin) & (ok ? xyz : I4{}));
    lanes.sum += d;
    lanes.squares += d * d;
    lanes.cross += d * __builtin_shufflevector(d, d, 1, 2, 0, 3);  // (xy, yz, zx, 0)
    lanes.points += ok;
  };
  XYZSums out;
  for (std::size_t k = 0; k < n;) {
    Lanes even, odd;
    for (const std::size_t stop = std::min(n, k + kFlush); k < stop; k += 2) {
      add(even, points[indices[k]]);
      if (k + 1 < stop) add(odd, points[indices[k + 1]]);
    }
    for (int axis = 0; axis < 3; ++axis) {
      out.sum[axis] += static_cast<double>(even.sum[axis]) + odd.sum[axis];
      out.squares[axis] += static_cast<double>(even.squares[axis]) + odd.squares[axis];
      out.cross[axis] += static_cast<double>(even.cross[axis]) + odd.cross[axis];
    }
    out.points += even.points + odd.points;
  }
  return out;
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

std::size_t ObstacleResult::pointCount() const {
  std::size_t n = 0;
  for (const Obstacle& o : obstacles) n += o.pointCount();
  return n;
}

MetricFloor fitMetricFloor(const pcl::PointCloud<PointRDM>& cloud, const pcl::Indices& inliers) {
  MetricFloor floor;
  const std::size_t n = inliers.size();
  std::size_t first = 0;
  while (first < n && !hasXYZ(cloud[static_cast<std::size_t>(inliers[first])])) ++first;
  if (first == n) return floor;
  // The sums about the first floor point with x, y, z: it lies among the others.
  const PointRDM& o = cloud[static_cast<std::size_t>(inliers[first])];
  const XYZSums sums =
      sumXYZ(cloud.points.data(), inliers.data() + first, n - first, o.x, o.y, o.z);
  floor.points = sums.points;
  if (floor.points < 3) return floor;
  const Eigen::Vector3d origin(o.x, o.y, o.z);
  const double count = static_cast<double>(floor.points);
  const Eigen::Vector3d mean = sums.sum / count;  // about the origin
  Eigen::Matrix3d covariance;
  covariance << sums.squares[0], sums.cross[0], sums.cross[2], sums.cross[0], sums.squares[1],
      sums.cross[1], sums.cross[2], sums.cross[1], sums.squares[2];
  covariance = covariance / count - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  // The plane's normal is the axis of least spread; the two others must spread (not a line).
  if (eigen.eigenvalues()(1) <= 1e-12) return floor;
  floor.normal = eigen.eigenvectors().col(0).normalized();
  floor.offset = -floor.normal.dot(mean + origin);
  if (floor.offset < 0) {  // the camera (the origin) is above the floor
    floor.normal = -floor.normal;
    floor.offset = -floor.offset;
  }
  floor.valid = true;
  return floor;
}

ObstacleClusterer::ObstacleClusterer(const ObstacleClustererConfig& config, const FootConfig& feet)
    : config_(config), feet_(feet) {
  config_.validate();
  feet_.validate();
}

namespace {

/// For each of the points `sorted` (cloud indices in ascending order), the length of its run: the
/// points of one slit (one cloud row) on neighbouring rows, a gap of one row allowed; with `plane`
/// (A, B, C) given, only points on one side of it (the sign of dk - (A u + B v + C)) make a run.
std::vector<int> runLengths(const pcl::PointCloud<PointRDM>& cloud, const pcl::Indices& sorted,
                            const Eigen::Vector3d* plane) {
  const auto width = static_cast<pcl::index_t>(cloud.width);
  const auto above = [&](pcl::index_t i) {
    return planeResidual(cloud[static_cast<std::size_t>(i)], *plane) > 0;
  };
  std::vector<int> length(sorted.size());
  std::size_t start = 0;
  for (std::size_t i = 1; i <= sorted.size(); ++i) {
    const bool continues = i < sorted.size() && sorted[i] / width == sorted[i - 1] / width &&
                           sorted[i] - sorted[i - 1] <= 2 &&
                           (!plane || above(sorted[i]) == above(sorted[i - 1]));
    if (continues) continue;
    std::fill(length.begin() + static_cast<std::ptrdiff_t>(start),
              length.begin() + static_cast<std::ptrdiff_t>(i), static_cast<int>(i - start));
    start = i;
  }
  return length;
}

/// The longest run (runLengths) among the points of `group`.
int longestRun(const pcl::PointCloud<PointRDM>& cloud, pcl::Indices group,
               const Eigen::Vector3d* plane) {
  std::sort(group.begin(), group.end());
  const std::vector<int> length = runLengths(cloud, group, plane);
  return length.empty() ? 0 : *std::max_element(length.begin(), length.end());
}

/// Each point of `links` (pairs of neighbours) that lies in no run (in_run false) joins the group
/// of the nearest point in a run at most `max_hops` links away, reached first, and that group
/// only: points in no run neither chain groups together nor reach further. Those no run reaches
/// are grouped with their neighbours as before.
void growFromRuns(const std::vector<char>& in_run,
                  const std::vector<std::pair<std::size_t, std::size_t>>& links, int max_hops,
                  DisjointSets& sets) {
  const std::size_t n = in_run.size();
  std::vector<std::vector<std::size_t>> next_to(n);
  for (const auto& [a, b] : links) next_to[a].push_back(b), next_to[b].push_back(a);
  std::vector<std::size_t> seed(n, n), frontier;
  for (std::size_t j = 0; j < n; ++j)
    if (in_run[j]) seed[j] = j, frontier.push_back(j);
  for (int hop = 1; hop <= max_hops && !frontier.empty(); ++hop) {
    std::vector<std::size_t> reached;
    for (const std::size_t a : frontier)
      for (const std::size_t b : next_to[a])
        if (seed[b] == n) seed[b] = seed[a], reached.push_back(b);
    frontier.swap(reached);
  }
  for (std::size_t j = 0; j < n; ++j)
    if (!in_run[j] && seed[j] < n) sets.join(j, seed[j]);
  // What no run reaches stays together as before, a group of noise that the run rule rejects.
  for (const auto& [a, b] : links)
    if (seed[a] == n && seed[b] == n) sets.join(a, b);
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
  const std::vector<pcl::Indices> groups = config_.method == ClusterMethod::Grid
                                               ? gridGroups(*cloud, floor.obstacles, plane)
                                               : euclideanGroups(*cloud, floor.obstacles);
  // Reject groups too small to be real, then size and place the others.
  for (const pcl::Indices& group : groups) {
    if (group.size() < static_cast<std::size_t>(config_.min_points) ||
        longestRun(*cloud, group, plane) < config_.min_run) {
      ++result.rejected_groups;
      result.rejected.insert(result.rejected.end(), group.begin(), group.end());
      continue;
    }
    result.obstacles.push_back(describe(*cloud, floor, result.floor, group, robot_from_camera));
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
  // Cloud row = slit, column = position along the slit (one image row each).
  const std::size_t width = cloud.width;
  std::vector<std::vector<std::size_t>> by_slit(cloud.height);
  pcl::Indices sorted = points;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t j = 0; j < sorted.size(); ++j)
    by_slit[static_cast<std::size_t>(sorted[j]) / width].push_back(j);
  const std::vector<int> run = runLengths(cloud, sorted, plane);
  std::vector<char> in_run(sorted.size());
  for (std::size_t j = 0; j < sorted.size(); ++j) in_run[j] = run[j] >= config_.min_run;
  // Points in runs are joined directly; the links of the others are kept for growFromRuns.
  DisjointSets sets(sorted.size());
  std::vector<std::pair<std::size_t, std::size_t>> links;
  const auto link = [&](std::size_t a, std::size_t b) {
    if (in_run[a] && in_run[b])
      sets.join(a, b);
    else
      links.emplace_back(a, b);
  };
  const double r2 = config_.slit_link_radius * config_.slit_link_radius;
  for (std::size_t s = 0; s < by_slit.size(); ++s) {
    const std::vector<std::size_t>& here = by_slit[s];
    // Along the slit: at most max_gap cells between neighbours.
    for (std::size_t a = 1; a < here.size(); ++a)
      if (sorted[here[a]] - sorted[here[a - 1]] <= config_.max_gap + 1) link(here[a - 1], here[a]);
    if (s + 1 >= by_slit.size()) continue;
    // Across to the next slit: reference positions close in the image.
    for (const std::size_t a : here) {
      const PointRDM& p = cloud[static_cast<std::size_t>(sorted[a])];
      for (const std::size_t b : by_slit[s + 1]) {
        const PointRDM& q = cloud[static_cast<std::size_t>(sorted[b])];
        const double du = p.u - q.u, dv = p.v - q.v;
        if (du * du + dv * dv <= r2) link(a, b);
      }
    }
  }
  growFromRuns(in_run, links, config_.max_hops, sets);
  std::vector<pcl::Indices> groups;
  std::vector<std::size_t> group_of(sorted.size(), std::numeric_limits<std::size_t>::max());
  for (std::size_t j = 0; j < sorted.size(); ++j) {
    std::size_t& g = group_of[sets.find(j)];
    if (g == std::numeric_limits<std::size_t>::max()) {
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
  std::vector<double> heights;
  std::set<int> slits;
  const auto height = [&](const Eigen::Vector3d& camera) {
    return metric.valid ? metric.height(camera) : (robot_from_camera * camera).z();
  };
  for (const auto i : indices) {
    const PointRDM& p = cloud[static_cast<std::size_t>(i)];
    slits.insert(p.slit);
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
  o.slits = static_cast<int>(slits.size());
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
