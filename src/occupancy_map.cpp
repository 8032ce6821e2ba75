#include "multislit/occupancy_map.h"
#include "multislit/plane_model.h"

#include "config_check.h"

#include <octomap/octomap_utils.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <stdexcept>
#include <string>
#include <unordered_set>
#include <utility>

namespace multislit {

namespace {

bool isProbability(double p) { return p > 0 && p < 1; }

octomap::point3d toOcto(const Eigen::Vector3d& p) {
  return octomap::point3d(static_cast<float>(p.x()), static_cast<float>(p.y()),
                          static_cast<float>(p.z()));
}

// One cloud in the map frame: world x, y; height above the floor measured in this frame.
struct MapFrame {
  const pcl::PointCloud<PointRDM>& cloud;
  const MetricFloor& metric;
  const Eigen::Isometry3d& world_from_camera;
  const octomap::OcTree& tree;
  double resolution;  ///< [m]

  Eigen::Vector3d toMap(const Eigen::Vector3d& camera) const {
    const Eigen::Vector3d w = world_from_camera * camera;
    return Eigen::Vector3d(w.x(), w.y(), metric.height(camera));
  }
  Eigen::Vector3d pointAt(std::size_t i) const {
    const PointRDM& p = cloud[i];
    return toMap(Eigen::Vector3d(p.x, p.y, p.z));
  }
  octomap::OcTreeKey keyOf(Eigen::Vector3d m) const {  // below the floor: the floor layer
    m.z() = std::max(m.z(), 0.5 * resolution);
    return tree.coordToKey(toOcto(m));
  }
};

}  // namespace

void OccupancyMapConfig::validate() const {
  constexpr detail::FieldCheck require("OccupancyMapConfig");
  require(resolution >= 0.001 && resolution <= 0.5, "resolution", "must be in [0.001, 0.5] m");
  require(isProbability(prob_hit) && prob_hit > 0.5, "prob_hit", "must be in (0.5, 1)");
  require(isProbability(prob_weak_hit) && prob_weak_hit > 0.5, "prob_weak_hit",
          "must be in (0.5, 1)");
  require(isProbability(prob_miss) && prob_miss < 0.5, "prob_miss", "must be in (0, 0.5)");
  require(isProbability(occupancy_threshold), "occupancy_threshold", "must be in (0, 1)");
  require(isProbability(clamp_min) && clamp_min < occupancy_threshold, "clamp_min",
          "must be in (0, occupancy_threshold)");
  require(isProbability(clamp_max) && clamp_max > occupancy_threshold, "clamp_max",
          "must be in (occupancy_threshold, 1)");
  require(weak_sigmas > 0, "weak_sigmas", "must be > 0");
  require(min_sigma > 0, "min_sigma", "must be > 0 px");
  require(min_weak_points >= 1, "min_weak_points", "must be >= 1");
  require(weak_end_margin >= 0, "weak_end_margin", "must be >= 0");
  require(min_weak_run >= 1, "min_weak_run", "must be >= 1");
  require(free_height >= resolution, "free_height", "must be >= resolution");
  require(max_height > resolution, "max_height", "must be > resolution");
  require(window_half_size > 0, "window_half_size", "must be > 0 m");
  require(crop_interval >= 1, "crop_interval", "must be >= 1 frame");
}

/// One frame's evidence: a mark per point (its voxel and kind) and per cell of a light ray, as
/// (packed key << 2 | kind) so that sorting gathers the marks of each voxel.
struct OccupancyMap::FrameEvidence {
  enum Kind : std::uint64_t { kRay = 0, kFloor = 1, kWeak = 2, kHit = 3 };
  std::vector<std::uint64_t> marks;
  octomap::KeyRay ray;  ///< (allocates room for 100 000 keys: made once)
  /// One slit (RDMap row) in this frame: its floor points' noise and where its measured run ends.
  struct Slit {
    double sum_sq = 0.0;      ///< squared residuals of its floor points [px^2]
    std::size_t count = 0;    ///< its floor points
    std::uint32_t first = 0;  ///< first column with a floor point
    std::uint32_t last = 0;   ///< last column with a floor point
    double weak = 0.0;        ///< residual from which a point is weak [px]
  };
  std::vector<Slit> slits;
  std::vector<double> residual;          ///< per cloud point (floor inliers only) [px]
  std::vector<std::uint8_t> weak_point;  ///< per cloud point: weak, in a run long enough
  /// Voxels whose leaf is at the lower clamping bound: a miss cannot change them (octomap's
  /// updateNode() would search the tree to find that out), so it is skipped. Kept across frames;
  /// emptied when the tree is rebuilt by crop().
  std::unordered_set<std::uint64_t> saturated_free;

  void mark(const octomap::OcTreeKey& key, Kind kind) {
    const std::uint64_t m =
        (std::uint64_t{key[0]} | std::uint64_t{key[1]} << 16 | std::uint64_t{key[2]} << 32) << 2 |
        kind;
    // The points of a slit come in order, several per voxel: a repeat of the last mark adds
    // nothing (except for weak points, which are counted), and leaves less to sort.
    if (kind != kWeak && !marks.empty() && marks.back() == m) return;
    marks.push_back(m);
  }
  static octomap::OcTreeKey keyOf(std::uint64_t mark) {
    return octomap::OcTreeKey(static_cast<octomap::key_type>(mark >> 2),
                              static_cast<octomap::key_type>(mark >> 18),
                              static_cast<octomap::key_type>(mark >> 34));
  }

  /// Each slit's own noise (the outer slits, dimmer and farther, are noisier than the frame's
  /// mean), and where each slit's measured points end (a profile cut by the slit's end is biased):
  /// `slits` and, per floor inlier, `residual`.
  void measureSlits(const pcl::PointCloud<PointRDM>& cloud, const FloorResult& floor,
                    const OccupancyMapConfig& config);
  /// `weak_point`: the floor inliers high above the plane for their slit and away from its ends,
  /// in runs of min_weak_run consecutive points along the slit: an object lifts every row that
  /// crosses it, while noise lifts one row or a pair. After measureSlits().
  void flagWeakFloorPoints(const pcl::PointCloud<PointRDM>& cloud, const FloorResult& floor,
                           const OccupancyMapConfig& config);
};

void OccupancyMap::FrameEvidence::measureSlits(const pcl::PointCloud<PointRDM>& cloud,
                                               const FloorResult& floor,
                                               const OccupancyMapConfig& config) {
  const std::size_t rows = cloud.height, width = cloud.width;
  slits.assign(rows, Slit{0.0, 0, static_cast<std::uint32_t>(width), 0, 0.0});
  residual.resize(cloud.size());
  for (const auto i : floor.inliers) {
    const auto idx = static_cast<std::size_t>(i);
    Slit& slit = slits[idx / width];
    const auto col = static_cast<std::uint32_t>(idx % width);
    const double r = planeResidual(cloud[idx], floor.plane);
    residual[idx] = r;
    slit.sum_sq += r * r;
    ++slit.count;
    slit.first = std::min(slit.first, col);
    slit.last = std::max(slit.last, col);
  }
  for (Slit& slit : slits) {
    const double sigma = slit.count > 1 ? std::sqrt(slit.sum_sq / static_cast<double>(slit.count))
                                        : floor.residual_std;
    slit.weak = config.weak_sigmas * std::max(sigma, config.min_sigma);
  }
}

void OccupancyMap::FrameEvidence::flagWeakFloorPoints(const pcl::PointCloud<PointRDM>& cloud,
                                                      const FloorResult& floor,
                                                      const OccupancyMapConfig& config) {
  const std::size_t rows = cloud.height, width = cloud.width;
  const auto end = static_cast<std::uint32_t>(config.weak_end_margin);
  weak_point.assign(cloud.size(), 0);
  for (const auto i : floor.inliers) {
    const auto idx = static_cast<std::size_t>(i);
    const Slit& slit = slits[idx / width];
    const auto col = static_cast<std::uint32_t>(idx % width);
    weak_point[idx] =
        residual[idx] >= slit.weak && col >= slit.first + end && col + end <= slit.last;
  }
  const auto run = static_cast<std::size_t>(config.min_weak_run);
  for (std::size_t row = 0; row < rows; ++row) {
    std::uint8_t* flags = weak_point.data() + row * width;
    for (std::size_t col = 0; col < width;) {
      if (!flags[col]) {
        ++col;
        continue;
      }
      std::size_t stop = col;
      while (stop < width && flags[stop]) ++stop;
      if (stop - col < run) std::fill(flags + col, flags + stop, std::uint8_t{0});
      col = stop;
    }
  }
}

OccupancyMap::OccupancyMap(const OccupancyMapConfig& config) : config_(config) {
  config_.validate();
  tree_ = makeTree();
  evidence_ = std::make_unique<FrameEvidence>();
  log_hit_ = octomap::logodds(config_.prob_hit);
  log_weak_ = octomap::logodds(config_.prob_weak_hit);
  log_miss_ = octomap::logodds(config_.prob_miss);
}

OccupancyMap::OccupancyMap(OccupancyMap&&) noexcept = default;
OccupancyMap& OccupancyMap::operator=(OccupancyMap&&) noexcept = default;
OccupancyMap::~OccupancyMap() = default;

std::unique_ptr<octomap::OcTree> OccupancyMap::makeTree() const {
  auto tree = std::make_unique<octomap::OcTree>(config_.resolution);
  tree->setOccupancyThres(config_.occupancy_threshold);
  tree->setClampingThresMin(config_.clamp_min);
  tree->setClampingThresMax(config_.clamp_max);
  tree->setProbHit(config_.prob_hit);
  tree->setProbMiss(config_.prob_miss);
  return tree;
}

MapUpdateStats OccupancyMap::insertFrame(const pcl::PointCloud<PointRDM>& cloud,
                                         const FloorResult& floor, const ObstacleResult& obstacles,
                                         const Eigen::Isometry3d& world_from_camera,
                                         const Eigen::Vector3d& light_origin_camera) {
  MapUpdateStats stats;
  if (!floor.found || !obstacles.floor.valid) return stats;  // nothing to learn: no guess
  collect(cloud, floor, obstacles, world_from_camera, light_origin_camera, *evidence_);
  stats = apply(*evidence_);
  if (++frames_ % static_cast<std::size_t>(config_.crop_interval) == 0) {
    crop(world_from_camera.translation().head<2>());
    stats.cropped = true;
  }
  return stats;
}

void OccupancyMap::collect(const pcl::PointCloud<PointRDM>& cloud, const FloorResult& floor,
                           const ObstacleResult& obstacles,
                           const Eigen::Isometry3d& world_from_camera,
                           const Eigen::Vector3d& light_origin_camera, FrameEvidence& e) const {
  const MapFrame map{cloud, obstacles.floor, world_from_camera, *tree_, config_.resolution};
  e.marks.clear();
  // Hits: the obstacles' points.
  for (const Obstacle& o : obstacles.obstacles)
    for (const auto i : o.indices) {
      if (!hasXYZ(cloud[static_cast<std::size_t>(i)])) continue;
      const Eigen::Vector3d m = map.pointAt(static_cast<std::size_t>(i));
      if (m.z() <= config_.max_height) e.mark(map.keyOf(m), FrameEvidence::kHit);
    }
  // Weak points: groups rejected as noise, and floor points high above the plane.
  for (const auto i : obstacles.rejected) {
    const PointRDM& p = cloud[static_cast<std::size_t>(i)];
    if (!hasXYZ(p) || planeResidual(p, floor.plane) <= 0) continue;
    const Eigen::Vector3d m = map.pointAt(static_cast<std::size_t>(i));
    if (m.z() <= config_.max_height) e.mark(map.keyOf(m), FrameEvidence::kWeak);
  }
  e.measureSlits(cloud, floor, config_);
  e.flagWeakFloorPoints(cloud, floor, config_);
  // Floor points: floor (or weak) marks, and the free cells of the light ray that reached them.
  const Eigen::Vector3d light = map.toMap(light_origin_camera);
  octomap::OcTreeKey last_ray;  // floor voxel of the last ray: the points of a slit come in order
  int last_slit = -1;
  for (const auto i : floor.inliers) {
    const PointRDM& p = cloud[static_cast<std::size_t>(i)];
    if (!hasXYZ(p)) continue;
    Eigen::Vector3d m = map.pointAt(static_cast<std::size_t>(i));
    m.z() = 0.0;  // on the floor: its height is noise
    const octomap::OcTreeKey key = map.keyOf(m);
    const bool is_weak = e.weak_point[static_cast<std::size_t>(i)] != 0;
    e.mark(key, is_weak ? FrameEvidence::kWeak : FrameEvidence::kFloor);
    if (is_weak || (key == last_ray && p.slit == last_slit)) continue;
    addFreeRay(m, light, key, e);  // one ray per slit and floor voxel
    last_ray = key;
    last_slit = p.slit;
  }
}

void OccupancyMap::addFreeRay(const Eigen::Vector3d& floor_point, const Eigen::Vector3d& light,
                              const octomap::OcTreeKey& floor_key, FrameEvidence& e) const {
  const Eigen::Vector3d to_light = light - floor_point;
  if (to_light.z() <= config_.free_height) return;
  // The light came down to the floor point: the cells it crossed below free_height are free.
  const double res = config_.resolution;
  const Eigen::Vector3d top = floor_point + to_light * (config_.free_height / to_light.z());
  const Eigen::Vector3d low = floor_point + to_light * (0.5 * res / to_light.z());
  if (!tree_->computeRayKeys(toOcto(top), toOcto(low), e.ray)) return;
  for (const octomap::OcTreeKey& key : e.ray)
    if (key[2] != floor_key[2]) e.mark(key, FrameEvidence::kRay);  // floor voxels: own points
}

MapUpdateStats OccupancyMap::apply(FrameEvidence& e) {
  MapUpdateStats stats;
  stats.inserted = true;
  std::sort(e.marks.begin(), e.marks.end());
  for (std::size_t i = 0; i < e.marks.size();) {
    // The marks of one voxel: a hit wins, then enough weak points; a miss only without weak
    // points (an object split between voxels lifts a few points in each).
    const std::uint64_t voxel = e.marks[i] >> 2;
    int weak = 0;
    bool hit = false;
    for (; i < e.marks.size() && e.marks[i] >> 2 == voxel; ++i) {
      weak += (e.marks[i] & 3) == FrameEvidence::kWeak;
      hit = hit || (e.marks[i] & 3) == FrameEvidence::kHit;
    }
    const octomap::OcTreeKey key = FrameEvidence::keyOf(voxel << 2);
    if (hit) {
      e.saturated_free.erase(voxel);
      tree_->updateNode(key, log_hit_, true);
      ++stats.hit_voxels;
    } else if (weak >= config_.min_weak_points) {
      e.saturated_free.erase(voxel);
      tree_->updateNode(key, log_weak_, true);
      ++stats.weak_voxels;
    } else if (weak == 0) {
      ++stats.free_voxels;
      if (e.saturated_free.count(voxel)) continue;  // as octomap: no change at the bound
      const octomap::OcTreeNode* node = tree_->updateNode(key, log_miss_, true);
      if (node && node->getLogOdds() <= tree_->getClampingThresMinLog())
        e.saturated_free.insert(voxel);
    }  // too few weak points: no evidence either way this frame
  }
  return stats;
}

std::vector<MapCell> OccupancyMap::occupiedInBox(const Eigen::Vector3d& min,
                                                 const Eigen::Vector3d& max) const {
  std::vector<MapCell> cells;
  for (auto it = tree_->begin_leafs_bbx(toOcto(min), toOcto(max)), end = tree_->end_leafs_bbx();
       it != end; ++it) {
    if (!tree_->isNodeOccupied(*it)) continue;
    const octomap::point3d c = it.getCoordinate();
    const double half = 0.5 * it.getSize();
    if (c.x() + half < min.x() || c.x() - half > max.x() || c.y() + half < min.y() ||
        c.y() - half > max.y() || c.z() + half < min.z() || c.z() - half > max.z())
      continue;
    cells.push_back(
        MapCell{Eigen::Vector3d(c.x(), c.y(), c.z()), it.getSize(), it->getOccupancy()});
  }
  return cells;
}

std::vector<MapCell> OccupancyMap::occupiedUnder(const Footprint& footprint, double min_height,
                                                 double max_height) const {
  Eigen::Vector2d lo = footprint.centre, hi = footprint.centre;
  for (const Eigen::Vector2d& c : footprint.corners()) {
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  std::vector<MapCell> cells = occupiedInBox(Eigen::Vector3d(lo.x(), lo.y(), min_height),
                                             Eigen::Vector3d(hi.x(), hi.y(), max_height));
  // Keep the cells whose square overlaps the rectangle (separating axes of the rectangle).
  const double c = std::cos(footprint.yaw), s = std::sin(footprint.yaw);
  const auto overlaps = [&](const MapCell& cell) {
    const Eigen::Vector2d d = cell.centre.head<2>() - footprint.centre;
    const double reach = 0.5 * cell.size * (std::abs(c) + std::abs(s));
    return std::abs(d.x() * c + d.y() * s) <= 0.5 * footprint.length + reach &&
           std::abs(-d.x() * s + d.y() * c) <= 0.5 * footprint.width + reach;
  };
  cells.erase(std::remove_if(cells.begin(), cells.end(),
                             [&](const MapCell& cell) { return !overlaps(cell); }),
              cells.end());
  return cells;
}

std::size_t OccupancyMap::occupiedCount() const {
  std::size_t n = 0;
  for (auto it = tree_->begin_leafs(), end = tree_->end_leafs(); it != end; ++it)
    n += tree_->isNodeOccupied(*it);
  return n;
}

void OccupancyMap::crop(const Eigen::Vector2d& robot_xy) {
  // octomap 1.9's deleteNode() aborts when a deletion empties an inner node (the node is deleted
  // with its empty child array), so the voxels inside the window are copied into a new tree.
  std::unique_ptr<octomap::OcTree> kept = makeTree();
  const unsigned depth_max = tree_->getTreeDepth();
  for (auto it = tree_->begin_leafs(), end = tree_->end_leafs(); it != end; ++it) {
    const octomap::point3d c = it.getCoordinate();
    const double half = 0.5 * it.getSize();
    if (std::abs(c.x() - robot_xy.x()) - half > config_.window_half_size ||
        std::abs(c.y() - robot_xy.y()) - half > config_.window_half_size ||
        c.z() - half > config_.max_height)
      continue;
    // A pruned leaf covers n^3 voxels of the finest level.
    const octomap::OcTreeKey base = it.getIndexKey();
    const unsigned n = 1u << (depth_max - it.getDepth());
    for (unsigned i = 0; i < n * n * n; ++i) {
      const octomap::OcTreeKey key(static_cast<octomap::key_type>(base[0] + i % n),
                                   static_cast<octomap::key_type>(base[1] + i / n % n),
                                   static_cast<octomap::key_type>(base[2] + i / (n * n)));
      kept->setNodeValue(key, it->getLogOdds(), true);
    }
  }
  kept->updateInnerOccupancy();
  kept->prune();
  tree_ = std::move(kept);
  evidence_->saturated_free.clear();
}

void OccupancyMap::save(const std::string& path) const {
  std::ofstream out(path, std::ios::binary);
  if (!out || !tree_->writeBinaryConst(out) || !out.flush())
    throw std::runtime_error("occupancy map: cannot write '" + path + "'");
}

}  // namespace multislit
