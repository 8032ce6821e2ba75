// The stock PCL path of `multislit bench`: SACSegmentation (SACMODEL_PLANE) on x, y, z,
// EuclideanClusterExtraction on a KdTree and OcTree::insertPointCloud.
#include "bench_stock.h"

#include "multislit/extractor.h"
#include "multislit/floor_detector.h"
#include "multislit/obstacles.h"
#include "multislit/occupancy_map.h"

#include <octomap/OcTree.h>
#include <pcl/ModelCoefficients.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <algorithm>
#include <vector>

namespace multislit::apps {
namespace {

/// The stock PCL objects of one frame, made once and reused like ours.
struct StockPath {
  explicit StockPath(double threshold) {
    segmentation.setModelType(pcl::SACMODEL_PLANE);
    segmentation.setMethodType(pcl::SAC_RANSAC);
    segmentation.setDistanceThreshold(threshold);
    segmentation.setMaxIterations(FloorDetectorConfig{}.iterations());
    segmentation.setProbability(FloorDetectorConfig{}.probability);
    segmentation.setOptimizeCoefficients(true);  // PCL's default, like our eq. (2) refit
    clustering.setClusterTolerance(0.02);        // [m]: the points of a slit are 1-3 mm apart
    clustering.setMinClusterSize(ObstacleClustererConfig{}.min_points);
    clustering.setSearchMethod(pcl::make_shared<pcl::search::KdTree<pcl::PointXYZ>>());
  }
  pcl::SACSegmentation<pcl::PointXYZ> segmentation;
  pcl::EuclideanClusterExtraction<pcl::PointXYZ> clustering;
  pcl::PointCloud<pcl::PointXYZ>::Ptr xyz = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  pcl::PointCloud<pcl::PointXYZ>::Ptr off = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  std::vector<int> source, off_source;  ///< cloud index of each point of xyz and off
};

/// The floor of the metric cloud: SACSegmentation (SACMODEL_PLANE) on x, y, z of the valid
/// points, then every point off the plane is an obstacle. Same fail-safe rule as ours.
bool stockFloor(const pcl::PointCloud<PointRDM>& cloud, StockPath& s) {
  s.xyz->clear();
  s.source.clear();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const PointRDM& p = cloud[i];
    if (!hasXYZ(p)) continue;
    s.xyz->push_back(pcl::PointXYZ(p.x, p.y, p.z));
    s.source.push_back(static_cast<int>(i));
  }
  pcl::PointIndices inliers;
  pcl::ModelCoefficients plane;
  s.off->clear();
  s.off_source.clear();
  const FloorDetectorConfig config;
  if (s.xyz->size() < static_cast<std::size_t>(config.min_points)) return false;
  s.segmentation.setInputCloud(s.xyz);
  s.segmentation.segment(inliers, plane);
  std::size_t next = 0;  // the inliers come sorted
  for (std::size_t j = 0; j < s.xyz->size(); ++j) {
    if (next < inliers.indices.size() && inliers.indices[next] == static_cast<int>(j)) {
      ++next;
      continue;
    }
    s.off->push_back((*s.xyz)[j]);
    s.off_source.push_back(s.source[j]);
  }
  return static_cast<double>(inliers.indices.size()) >=
         std::max(3.0, config.min_inlier_ratio * static_cast<double>(s.xyz->size()));
}

/// Every valid point of the metric cloud into the map, world frame, with its ray from the camera:
/// OcTree::insertPointCloud, OctoMap's way to map a range sensor's cloud.
void stockMap(const StockPath& s, const Eigen::Isometry3d& world_from_camera,
              octomap::OcTree& tree) {
  octomap::Pointcloud scan;
  scan.reserve(s.xyz->size());
  for (const pcl::PointXYZ& p : *s.xyz) {
    const Eigen::Vector3d w = world_from_camera * Eigen::Vector3d(p.x, p.y, p.z);
    scan.push_back(static_cast<float>(w.x()), static_cast<float>(w.y()), static_cast<float>(w.z()));
  }
  const Eigen::Vector3d origin = world_from_camera.translation();
  tree.insertPointCloud(
      scan, octomap::point3d(static_cast<float>(origin.x()), static_cast<float>(origin.y()),
                             static_cast<float>(origin.z())));
}

}  // namespace

PathRun runStockPath(const BenchInput& in, int passes, double threshold) {
  const std::size_t n = in.images.size();
  PathRun run{StageTimes(n), StageTimes(n), StageTimes(n), StageTimes(n), StageTimes(0), {}, 0};
  run.detections.resize(n);
  const Extractor extractor(in.reference);
  StockPath stock(threshold);
  std::vector<pcl::PointCloud<PointRDM>> clouds(n);  // extraction is ours: timed there
  for (std::size_t k = 0; k < n; ++k) extractor.extract(in.images[k], clouds[k]);
  for (int pass = -1; pass < passes; ++pass) {
    octomap::OcTree tree(OccupancyMapConfig{}.resolution);
    for (std::size_t k = 0; k < n; ++k) {
      const double t0 = threadSeconds();
      const bool found = stockFloor(clouds[k], stock);
      const double t1 = threadSeconds();
      std::vector<pcl::PointIndices> groups;
      if (found && !stock.off->empty()) {
        stock.clustering.setInputCloud(stock.off);
        stock.clustering.extract(groups);
      }
      const double t2 = threadSeconds();
      if (found) stockMap(stock, in.world_from_camera[k], tree);
      const double t3 = threadSeconds();
      if (pass < 0) continue;
      run.floor.add(k, t1 - t0);
      run.clusters.add(k, t2 - t1);
      run.map.add(k, t3 - t2);
      if (pass > 0) continue;
      Detection& d = run.detections[k];
      d.found = found;
      if (found) d.obstacle_points = stock.off_source;
      d.clusters = groups.size();
    }
  }
  return run;
}

}  // namespace multislit::apps
