#include "multislit/occupancy_map.h"
#include "multislit/plane_model.h"

#include "config_check.h"
#include "key_order_update.h"
#include "map_evidence.h"
#include "ray_keys.h"

#include <octomap/octomap_utils.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace multislit {

using detail::FrameEvidence;

namespace {

bool isProbability(double p) { return p > 0 && p < 1; }

/// A move of the slits at world x, y [m] as a move at map column x, y [cells].
SweepStep columnStep(const SweepStep& world, const octomap::OcTree& tree) {
  const double origin = tree.keyToCoord(octomap::key_type{0});  // world x or y of column 0 [m]
  const double cell = tree.getResolution();
  SweepStep column = world;
  column.offset = world.offset + (world.per_x + world.per_y) * origin;
  column.per_x = world.per_x * cell;
  column.per_y = world.per_y * cell;
  return column;
}

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
  sweep.validate();
}

OccupancyMap::OccupancyMap(const OccupancyMapConfig& config) : config_(config) {
  config_.validate();
  tree_ = makeTree();
  evidence_ = std::make_unique<detail::FrameEvidence>();
  slit_sweep_ = std::make_unique<detail::SlitSweep>();
  sweep_ = std::make_unique<SweepEvidence>(config_.sweep);
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
  stats.sweep = sweep_->sweep();
  if (config_.sweep.record_passes) stats.passes = sweep_->takePasses();
  if (++frames_ % static_cast<std::size_t>(config_.crop_interval) == 0) {
    crop(world_from_camera.translation().head<2>());
    stats.cropped = true;
  }
  return stats;
}

void OccupancyMap::collect(const pcl::PointCloud<PointRDM>& cloud, const FloorResult& floor,
                           const ObstacleResult& obstacles,
                           const Eigen::Isometry3d& world_from_camera,
                           const Eigen::Vector3d& light_origin_camera, FrameEvidence& e) {
  const MapFrame map{cloud, obstacles.floor, world_from_camera, *tree_, config_.resolution};
  e.clearMarks();
  e.sweep_points.clear();
  e.sweep_keys.clear();
  const auto evidence = [&](const Eigen::Vector3d& m, bool above, bool strong, bool tall) {
    const octomap::OcTreeKey key = map.keyOf(m);
    e.sweep_points.push_back(
        SweepPoint{key[0], key[1], static_cast<float>(m.z()), above, strong, tall});
    e.sweep_keys.push_back(key);
  };
  // Evidence: the obstacles' points, the points of groups rejected as noise (weak).
  const SweepEvidenceConfig& sweep = config_.sweep;
  for (const Obstacle& o : obstacles.obstacles)
    for (const auto i : o.indices) {
      const auto idx = static_cast<std::size_t>(i);
      if (!hasXYZ(cloud[idx])) continue;
      const Eigen::Vector3d m = map.pointAt(idx);
      const bool above = planeResidual(cloud[idx], floor.plane) > 0;
      // Tall only on its surface: speckle where a stripe was lost reaches any height.
      const bool tall = above && m.z() >= sweep.tall_height &&
                        std::binary_search(o.surface.begin(), o.surface.end(), i);
      if (m.z() <= config_.max_height) evidence(m, above, true, tall);
    }
  for (const auto i : obstacles.rejected) {
    const auto idx = static_cast<std::size_t>(i);
    if (!hasXYZ(cloud[idx])) continue;
    const Eigen::Vector3d m = map.pointAt(idx);
    if (m.z() <= config_.max_height)
      evidence(m, planeResidual(cloud[idx], floor.plane) > 0, false, false);
  }
  e.measureSlits(cloud, floor, config_);
  e.flagWeakFloorPoints(cloud, floor, config_);
  // Floor points: weak evidence, or floor marks and the free cells of the light ray that reached
  // them; and how far the slits moved across the floor since the last frame.
  const Eigen::Vector3d light = map.toMap(light_origin_camera);
  const detail::RayKeys rays(*tree_);
  octomap::OcTreeKey last_ray;  // floor voxel of the last ray: the points of a slit come in order
  int last_slit = -1;
  slit_sweep_->begin(cloud.size());
  for (const auto i : floor.inliers) {
    const auto idx = static_cast<std::size_t>(i);
    const PointRDM& p = cloud[idx];
    if (!hasXYZ(p)) continue;
    Eigen::Vector3d m = map.pointAt(idx);
    m.z() = 0.0;  // on the floor: its height is noise
    slit_sweep_->add(idx, p.slit, m.head<2>());
    if (e.weak_point[idx] != 0) {
      evidence(m, e.weak_point[idx] > 0, false, false);
      continue;
    }
    const octomap::OcTreeKey key = map.keyOf(m);
    e.mark(key, FrameEvidence::kFloor);
    if (key == last_ray && p.slit == last_slit) continue;
    addFreeRay(m, light, key, rays, e);  // one ray per slit and floor voxel
    last_ray = key;
    last_slit = p.slit;
  }
  sweep_->beginFrame(columnStep(slit_sweep_->finish(config_.sweep.dead_zone), *tree_));
  markEvidence(e);
}

void OccupancyMap::markEvidence(FrameEvidence& e) {
  // The evidence judged over the sweep: only what is consistent as the slits sweep it is a hit.
  sweep_->addEvidence(e.sweep_points);
  for (std::size_t j = 0; j < e.sweep_points.size(); ++j) {
    const SweepPoint& p = e.sweep_points[j];
    const SweepVerdict v = sweep_->verdictAt(p.x, p.y);
    if (v == SweepVerdict::Above && p.above)
      e.mark(e.sweep_keys[j], p.strong ? FrameEvidence::kHit : FrameEvidence::kWeak);
    else if (v == SweepVerdict::Below && !p.above && p.strong)
      e.mark(e.sweep_keys[j], FrameEvidence::kHit);  // a hole: its floor-layer voxel
    else
      e.mark(e.sweep_keys[j], FrameEvidence::kPending);  // unknown
  }
}

void OccupancyMap::addFreeRay(const Eigen::Vector3d& floor_point, const Eigen::Vector3d& light,
                              const octomap::OcTreeKey& floor_key, const detail::RayKeys& rays,
                              FrameEvidence& e) const {
  const Eigen::Vector3d to_light = light - floor_point;
  if (to_light.z() <= config_.free_height) return;
  // The light came down to the floor point: the cells it crossed below free_height are free.
  const double res = config_.resolution;
  const Eigen::Vector3d top = floor_point + to_light * (config_.free_height / to_light.z());
  const Eigen::Vector3d low = floor_point + to_light * (0.5 * res / to_light.z());
  rays.walk(toOcto(top), toOcto(low), [&](const octomap::OcTreeKey& key) {
    if (key[2] != floor_key[2]) e.mark(key, FrameEvidence::kRay);  // floor voxels: own points
  });
}

MapUpdateStats OccupancyMap::apply(FrameEvidence& e) {
  MapUpdateStats stats;
  stats.inserted = true;
  e.sortMarks();
  detail::KeyOrderUpdate leaves(*tree_);  // the voxels come in the order of their codes
  for (std::size_t i = 0; i < e.marks.size();) {
    // The marks of one voxel: a hit wins, then enough weak points; a miss only without weak
    // points (an object split between voxels lifts a few points in each).
    constexpr int kBits = FrameEvidence::kKindBits;
    constexpr std::uint64_t kKind = (1u << kBits) - 1;
    const std::uint64_t voxel = e.marks[i] >> kBits;  // its VoxelCode
    int weak = 0;
    bool hit = false, pending = false;
    for (; i < e.marks.size() && e.marks[i] >> kBits == voxel; ++i) {
      const std::uint64_t kind = e.marks[i] & kKind;
      weak += kind == FrameEvidence::kWeak;
      hit = hit || kind == FrameEvidence::kHit;
      pending = pending || kind == FrameEvidence::kPending;
    }
    if (hit) {
      leaves.update(voxel, log_hit_);
      ++stats.hit_voxels;
    } else if (weak >= config_.min_weak_points) {
      leaves.update(voxel, log_weak_);
      ++stats.weak_voxels;
    } else if (weak == 0 && !pending) {
      leaves.update(voxel, log_miss_);
      ++stats.free_voxels;
    } else {  // evidence not consistent over the sweep, or too few weak points: unknown
      ++stats.pending_voxels;
    }
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
  const octomap::OcTreeKey centre = tree_->coordToKey(
      octomap::point3d(static_cast<float>(robot_xy.x()), static_cast<float>(robot_xy.y()), 0.0f));
  sweep_->crop(centre[0], centre[1],
               static_cast<std::int32_t>(std::ceil(config_.window_half_size / config_.resolution)));
}

void OccupancyMap::save(const std::string& path) const {
  std::ofstream out(path, std::ios::binary);
  if (!out || !tree_->writeBinaryConst(out) || !out.flush())
    throw std::runtime_error("occupancy map: cannot write '" + path + "'");
}

}  // namespace multislit
