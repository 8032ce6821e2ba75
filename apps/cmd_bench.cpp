// multislit bench: the time of every stage of the pipeline on one core, against the stock PCL
// path on the same frames (issue 7), with the agreement of the two paths' detections.
#include "cli.h"
#include "commands.h"
#include "common.h"

#include "multislit/extractor.h"
#include "multislit/floor_detector.h"
#include "multislit/obstacles.h"
#include "multislit/occupancy_map.h"
#include "multislit/pipeline.h"
#include "multislit/sim/scenarios.h"
#include "multislit/sim/simulator.h"

#include <octomap/OcTree.h>
#include <pcl/ModelCoefficients.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/sac_segmentation.h>
#include <opencv2/core/utility.hpp>

#include <sched.h>
#include <sys/resource.h>
#include <time.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace multislit::apps {
namespace {

// ---- what is measured ---------------------------------------------------------------------------

/// The frames of one run and what the stages need besides the images.
struct BenchInput {
  std::string label;  ///< scenario or folder
  int scale = 1;      ///< points per frame, times the paper's sensor
  Reference reference;
  SensorConfig sensor;  ///< the sensor and its mount on the robot
  std::vector<cv::Mat> images;
  std::vector<Eigen::Isometry3d> world_from_camera;  ///< per frame: odometry and mount
  Eigen::Isometry3d robot_from_camera = Eigen::Isometry3d::Identity();
  Eigen::Vector3d light_origin = Eigen::Vector3d::Zero();  ///< projector centre, camera frame
};

/// The paper's sensor with `scale` times its points: 2x the slits over the same fan (scale 2),
/// and also 2x the pixels over the same field of view (scale 4: twice the rows per slit).
SensorConfig scaledSensor(int scale) {
  SensorConfig s;
  if (scale >= 2) {
    s.projector.slit_count *= 2;
    s.projector.slit_spacing /= 2;
  }
  if (scale >= 4) {
    s.camera.width *= 2;
    s.camera.height *= 2;
    s.camera.pixel_size /= 2;
  }
  s.validate();
  return s;
}

/// Renders the reference and `frames` frames of a scenario once (the simulator is slow: about
/// 0.3 s per frame); every pass of the benchmark reuses them.
BenchInput simulated(const std::string& scenario, long frames, double step, int scale) {
  BenchInput in;
  in.scale = scale;
  const SensorConfig sensor = scaledSensor(scale);
  const Simulator sim(sensor);
  Scenario s = makeScenario(scenario);
  if (step >= 0) s.step = step;
  in.label = s.name;
  ReferenceConfig rc;
  rc.expected_slits = sensor.projector.slit_count;
  const Scene floor = makeScenario("reference").scene;
  in.reference = Reference::fromImage(sim.renderReference(floor, s.reference_mount).image, rc);
  in.reference.setNominalScale(sensor, s.reference_mount);
  in.robot_from_camera = sim.geometry().robotFromCamera(s.mount);
  in.light_origin = sim.geometry().projectorCentre();
  in.sensor = sensor;
  in.sensor.mount = s.mount;
  cli::Progress progress(static_cast<std::size_t>(frames),
                         "render x" + std::to_string(scale) + " " + s.name);
  for (long k = 0; k < frames; ++k) {
    const auto frame = static_cast<std::uint64_t>(k);
    in.world_from_camera.push_back(s.worldFromRobot(frame) * in.robot_from_camera);
    in.images.push_back(sim.render(s.scene, in.world_from_camera.back(), frame).image);
    progress.update(static_cast<std::size_t>(k + 1));
  }
  progress.finish();
  return in;
}

/// robot_x of each frame from the frames.csv `multislit simulate` writes; 0 without it.
std::vector<double> robotPositions(const std::filesystem::path& dir, std::size_t frames) {
  std::vector<double> x(frames, 0.0);
  std::ifstream csv(dir / "frames.csv");
  std::string line;
  std::getline(csv, line);  // header: frame,file,stamp_us,robot_x,...
  for (std::size_t k = 0; k < frames && std::getline(csv, line); ++k) {
    std::stringstream fields(line);
    std::string field;
    for (int column = 0; column < 4 && std::getline(fields, field, ','); ++column)
      if (column == 3) x[k] = std::stod(field);
  }
  return x;
}

/// The PNGs of a folder (reference.png left out), in name order, with the reference of the
/// reference options; the robot stands at the mount of --sensor, advanced along x as frames.csv
/// says when the folder has one.
BenchInput recorded(const cli::ArgParser& args) {
  BenchInput in;
  const std::filesystem::path dir = args.str("sequence");
  in.label = dir.filename().string();
  in.reference = referenceFromArgs(args);
  if (!in.reference.scale.valid())
    throw std::runtime_error("the reference has no metric scale: the stock path needs x, y, z");
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (entry.path().extension() == ".png" && entry.path().filename() != "reference.png")
      files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  if (files.empty()) throw std::runtime_error("no PNG frames in '" + dir.string() + "'");
  const SensorConfig sensor =
      args.has("sensor") ? SensorConfig::load(args.str("sensor")) : SensorConfig{};
  const SensorGeometry geometry(sensor);
  in.robot_from_camera = geometry.robotFromCamera(sensor.mount);
  in.light_origin = geometry.projectorCentre();
  in.sensor = sensor;
  const std::vector<double> x = robotPositions(dir, files.size());
  for (std::size_t k = 0; k < files.size(); ++k) {
    in.images.push_back(readMonoImage(files[k]));
    Eigen::Isometry3d world_from_robot = Eigen::Isometry3d::Identity();
    world_from_robot.translation().x() = x[k];
    in.world_from_camera.push_back(world_from_robot * in.robot_from_camera);
  }
  return in;
}

// ---- time and memory ----------------------------------------------------------------------------

/// CPU time of the calling thread [s]: every stage runs on this thread (PCL's RANSAC and
/// OctoMap run serially here), and CPU time leaves out the time other processes take the core.
double threadSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double peakRssMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

/// Pins the process to one CPU (the one it runs on, or `cpu` >= 0) and OpenCV to one thread.
int pinToOneCore(int cpu) {
  if (cpu < 0) cpu = sched_getcpu();
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  if (sched_setaffinity(0, sizeof set, &set) != 0)
    throw std::runtime_error("cannot pin the process to CPU " + std::to_string(cpu));
  cv::setNumThreads(1);
  return cpu;
}

/// The times of one stage: per frame, one sample per pass [s].
class StageTimes {
 public:
  explicit StageTimes(std::size_t frames = 0) : samples_(frames) {}
  void add(std::size_t frame, double seconds) { samples_[frame].push_back(seconds); }
  bool empty() const { return samples_.empty() || samples_[0].empty(); }

  /// The q-quantile over frames (nearest rank) of each frame's median over the passes: the
  /// spread between frames is the pipeline's, while the median of a frame's passes drops the
  /// cache misses other engineers' builds cause on the shared cores [s].
  double quantile(double q) const {
    std::vector<double> medians = frameMedians();
    if (medians.empty()) return std::nan("");
    std::sort(medians.begin(), medians.end());
    const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(medians.size())));
    return medians[std::min(medians.size() - 1, rank > 0 ? rank - 1 : 0)];
  }
  /// The mean of the frames' medians [s].
  double mean() const {
    const std::vector<double> medians = frameMedians();
    double sum = 0;
    for (const double m : medians) sum += m;
    return medians.empty() ? std::nan("") : sum / static_cast<double>(medians.size());
  }
  /// Stages run one after the other: per frame, the sum of their medians. Empty when one is.
  static StageTimes sumOf(const std::vector<const StageTimes*>& stages) {
    StageTimes out(stages.front()->samples_.size());
    for (const StageTimes* stage : stages)
      if (stage->empty()) return StageTimes();
    for (const StageTimes* stage : stages) {
      const std::vector<double> medians = stage->frameMedians();
      for (std::size_t k = 0; k < medians.size(); ++k) {
        if (out.samples_[k].empty()) out.samples_[k].push_back(0.0);
        out.samples_[k][0] += medians[k];
      }
    }
    return out;
  }

 private:
  std::vector<double> frameMedians() const {
    std::vector<double> out;
    for (std::vector<double> s : samples_) {
      if (s.empty()) continue;
      std::nth_element(s.begin(), s.begin() + static_cast<long>(s.size() / 2), s.end());
      out.push_back(s[s.size() / 2]);
    }
    return out;
  }
  std::vector<std::vector<double>> samples_;
};

// ---- the two paths ------------------------------------------------------------------------------

/// What a path detected in one frame, for the agreement of the two paths.
struct Detection {
  bool found = false;                ///< a floor was found
  std::vector<int> obstacle_points;  ///< cloud indices off the floor (points with x, y, z), sorted
  std::size_t clusters = 0;          ///< obstacle groups of at least 3 points
};

/// Stage times of a path over every pass, and what it detected in the first pass.
struct PathRun {
  StageTimes extract, floor, clusters, map;
  StageTimes walker;  ///< footsteps and decision (ours only)
  std::vector<Detection> detections;
  double valid_points = 0;  ///< per frame, mean
};

/// Our pipeline as a walking robot runs it: extraction, then multislit::Pipeline (floor fit and
/// classification, obstacle clusters, map update, footsteps and decision), each stage timed.
PathRun runOurs(const BenchInput& in, int passes) {
  const std::size_t n = in.images.size();
  PathRun run{StageTimes(n), StageTimes(n), StageTimes(n), StageTimes(n), StageTimes(n), {}, 0};
  run.detections.resize(n);
  const Extractor extractor(in.reference);
  PipelineConfig config;
  config.sensor = in.sensor;
  const Eigen::Isometry3d camera_from_robot = in.robot_from_camera.inverse();
  auto cloud = pcl::make_shared<pcl::PointCloud<PointRDM>>();
  for (int pass = -1; pass < passes; ++pass) {  // pass -1: warm-up, not timed
    Pipeline pipeline(config);                  // each pass maps the same walk from scratch
    for (std::size_t k = 0; k < n; ++k) {
      const double t0 = threadSeconds();
      const ExtractionStats stats = extractor.extract(in.images[k], *cloud);
      const double t1 = threadSeconds();
      const PipelineResult r = pipeline.process(
          {cloud, in.world_from_camera[k] * camera_from_robot, in.robot_from_camera});
      if (pass < 0) continue;
      run.extract.add(k, t1 - t0);
      run.floor.add(k, r.times.floor);
      run.clusters.add(k, r.times.obstacles);
      run.map.add(k, r.times.map);
      run.walker.add(k, r.times.walker);
      if (pass > 0) continue;
      run.valid_points += static_cast<double>(stats.valid) / static_cast<double>(n);
      Detection& d = run.detections[k];
      d.found = r.floor.found;
      for (const int i : r.floor.obstacles)
        if (hasXYZ((*cloud)[static_cast<std::size_t>(i)])) d.obstacle_points.push_back(i);
      std::sort(d.obstacle_points.begin(), d.obstacle_points.end());
      d.clusters = r.obstacles.obstacles.size();
    }
  }
  return run;
}

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
    clustering.setMinClusterSize(3);             // as ObstacleClustererConfig::min_points
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

/// The stock PCL path on the RDMaps of our extractor (PCL has no slit extractor): metric cloud,
/// SACSegmentation, EuclideanClusterExtraction on a KdTree, OcTree::insertPointCloud.
PathRun runStock(const BenchInput& in, int passes, double threshold) {
  const std::size_t n = in.images.size();
  PathRun run{StageTimes(n), StageTimes(n), StageTimes(n), StageTimes(n), StageTimes(0), {}, 0};
  run.detections.resize(n);
  const Extractor extractor(in.reference);
  StockPath stock(threshold);
  std::vector<pcl::PointCloud<PointRDM>> clouds(n);  // extraction is ours: timed there
  for (std::size_t k = 0; k < n; ++k) extractor.extract(in.images[k], clouds[k]);
  for (int pass = -1; pass < passes; ++pass) {
    octomap::OcTree tree(0.01);  // the resolution of OccupancyMapConfig [m]
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

// ---- the threshold of the stock path and the agreement ------------------------------------------

/// The metric counterpart of the RDMap threshold (3 sigma = 0.9 px): for every reference point,
/// the distance from the reference plane of the point seen `px` nearer (u' = u + px); the
/// median over the image, with its 5% and 95% quantiles. A disparity threshold is a distance
/// threshold that grows with the square of the depth, so no single metric threshold equals it.
struct MetricThreshold {
  double median = 0, low = 0, high = 0;  ///< [m]
};

MetricThreshold metricThreshold(const Reference& ref, double px) {
  const MetricScale& s = ref.scale;
  const auto point = [&](double u, double u_inf, int row) {
    const double z = s.disparity_constant / (u - u_inf);
    return Eigen::Vector3d((u - s.cx) * z / s.f, (row - s.cy) * z / s.f, z);
  };
  std::vector<Eigen::Vector3d> on, off;
  for (const ReferenceSlit& slit : ref.slits)
    for (std::size_t k = 0; k < slit.u.size() && k < slit.u_inf.size(); ++k) {
      if (!std::isfinite(slit.u[k]) || !std::isfinite(slit.u_inf[k])) continue;
      const int row = slit.first_row + static_cast<int>(k);
      on.push_back(point(slit.u[k], slit.u_inf[k], row));
      off.push_back(point(slit.u[k] + px, slit.u_inf[k], row));
    }
  if (on.size() < 3) throw std::runtime_error("the reference has too few metric points");
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : on) mean += p;
  mean /= static_cast<double>(on.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : on) cov += (p - mean) * (p - mean).transpose();
  const Eigen::Vector3d normal =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
  std::vector<double> d;
  for (const auto& p : off) d.push_back(std::abs(normal.dot(p - mean)));
  std::sort(d.begin(), d.end());
  const auto at = [&](double q) { return d[static_cast<std::size_t>(q * (d.size() - 1))]; };
  return {at(0.5), at(0.05), at(0.95)};
}

/// Two detections agree when both found the floor (or neither did) and their obstacle point sets
/// differ by at most `tolerance` of their union (at least 3 points may differ: a point whose
/// residual lies near the threshold falls on either side, as the two thresholds differ with
/// the depth).
struct Agreement {
  std::size_t frames = 0, agreeing = 0, floor_agreeing = 0;
  double mean_jaccard = 0;  ///< |A and B| / |A or B| of the obstacle points, frames with some
};

Agreement compare(const std::vector<Detection>& a, const std::vector<Detection>& b,
                  double tolerance) {
  Agreement r;
  std::size_t with_points = 0;
  for (std::size_t k = 0; k < a.size() && k < b.size(); ++k) {
    ++r.frames;
    const bool floor = a[k].found == b[k].found;
    r.floor_agreeing += floor;
    std::vector<int> both, either;
    std::set_intersection(a[k].obstacle_points.begin(), a[k].obstacle_points.end(),
                          b[k].obstacle_points.begin(), b[k].obstacle_points.end(),
                          std::back_inserter(both));
    std::set_union(a[k].obstacle_points.begin(), a[k].obstacle_points.end(),
                   b[k].obstacle_points.begin(), b[k].obstacle_points.end(),
                   std::back_inserter(either));
    const double differ = static_cast<double>(either.size() - both.size());
    if (!either.empty()) {
      r.mean_jaccard += static_cast<double>(both.size()) / static_cast<double>(either.size());
      ++with_points;
    }
    r.agreeing += floor && differ <= std::max(3.0, tolerance * static_cast<double>(either.size()));
  }
  if (with_points > 0)
    r.mean_jaccard /= static_cast<double>(with_points);
  else
    r.mean_jaccard = 1.0;
  return r;
}

// ---- the table ----------------------------------------------------------------------------------

struct ScaleResult {
  int scale = 1;
  std::size_t frames = 0;
  double points = 0;  ///< valid points per frame
  PathRun ours, stock;
  MetricThreshold threshold;
  Agreement agreement;
};

/// One line of the table: a stage, or stages run one after the other, in both paths.
struct Row {
  std::string stage;
  StageTimes ours, stock;
};

/// The stages, then their sums. Extraction is ours in both paths (PCL has no slit extractor).
std::vector<Row> rowsOf(const ScaleResult& r) {
  const PathRun &a = r.ours, &b = r.stock;
  return {{"extraction (both)", a.extract, a.extract},
          {"floor fit + classify", a.floor, b.floor},
          {"clusters", a.clusters, b.clusters},
          {"map update", a.map, b.map},
          {"footsteps + decision", a.walker, b.walker},
          {"image to floor", StageTimes::sumOf({&a.extract, &a.floor}),
           StageTimes::sumOf({&a.extract, &b.floor})},
          {"image to clusters", StageTimes::sumOf({&a.extract, &a.floor, &a.clusters}),
           StageTimes::sumOf({&a.extract, &b.floor, &b.clusters})},
          {"end to end", StageTimes::sumOf({&a.extract, &a.floor, &a.clusters, &a.map}),
           StageTimes::sumOf({&a.extract, &b.floor, &b.clusters, &b.map})}};
}

std::string ms(const StageTimes& t, double q) {
  if (t.empty()) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f", 1e3 * t.quantile(q));
  return buf;
}

void printTable(const std::vector<ScaleResult>& results, std::ostream* csv) {
  std::printf("%-5s %-20s %10s %10s %10s %10s %8s %9s\n", "scale", "stage [ms per frame]",
              "ours_med", "ours_p99", "pcl_med", "pcl_p99", "speedup", "ns/point");
  if (csv)
    *csv << "scale,points_per_frame,stage,ours_median_ms,ours_p99_ms,pcl_median_ms,pcl_p99_ms,"
            "speedup,ours_ns_per_point\n";
  for (const ScaleResult& r : results) {
    for (const Row& row : rowsOf(r)) {
      const bool both = !row.ours.empty() && !row.stock.empty();
      const double speedup = both ? row.stock.quantile(0.5) / row.ours.quantile(0.5) : NAN;
      const double per_point = row.ours.empty() ? NAN : 1e9 * row.ours.quantile(0.5) / r.points;
      std::printf("%-5d %-20s %10s %10s %10s %10s %8.2f %9.1f\n", r.scale, row.stage.c_str(),
                  ms(row.ours, 0.5).c_str(), ms(row.ours, 0.99).c_str(), ms(row.stock, 0.5).c_str(),
                  ms(row.stock, 0.99).c_str(), speedup, per_point);
      if (csv)
        *csv << r.scale << ',' << r.points << ',' << row.stage << ',' << ms(row.ours, 0.5) << ','
             << ms(row.ours, 0.99) << ',' << ms(row.stock, 0.5) << ',' << ms(row.stock, 0.99) << ','
             << speedup << ',' << per_point << '\n';
    }
  }
}

void printSummary(const ScaleResult& r) {
  const std::vector<Row> rows = rowsOf(r);
  const Row& whole = rows.back();
  std::printf(
      "scale %d: %zu frames, %.0f points per frame; %s: %.0f fps ours, %.0f fps stock PCL\n",
      r.scale, r.frames, r.points, whole.stage.c_str(), 1.0 / whole.ours.mean(),
      1.0 / whole.stock.mean());
  std::printf(
      "  stock SAC threshold %.2f mm = 0.9 px at the median reference point (5%%..95%%: "
      "%.2f..%.2f mm)\n",
      1e3 * r.threshold.median, 1e3 * r.threshold.low, 1e3 * r.threshold.high);
  std::printf(
      "  agreement: %zu of %zu frames (%.0f%%): floor %zu of %zu, obstacle points mean "
      "Jaccard %.2f\n",
      r.agreement.agreeing, r.agreement.frames,
      100.0 * static_cast<double>(r.agreement.agreeing) / static_cast<double>(r.agreement.frames),
      r.agreement.floor_agreeing, r.agreement.frames, r.agreement.mean_jaccard);
}

ScaleResult measure(const BenchInput& in, int passes, double tolerance) {
  ScaleResult r;
  r.scale = in.scale;
  r.frames = in.images.size();
  r.ours = runOurs(in, passes);
  r.points = r.ours.valid_points;
  r.threshold = metricThreshold(in.reference, FloorDetectorConfig{}.threshold());
  r.stock = runStock(in, std::max(1, passes / 4), r.threshold.median);
  r.agreement = compare(r.ours.detections, r.stock.detections, tolerance);
  return r;
}

std::vector<int> parseScales(const std::string& text) {
  std::vector<int> scales;
  std::stringstream list(text);
  std::string item;
  while (std::getline(list, item, ',')) {
    if (item != "1" && item != "2" && item != "4")
      throw cli::UsageError("--scale takes 1, 2 or 4 (or a list such as 1,2,4), not '" + item +
                            "'");
    scales.push_back(std::stoi(item));
  }
  if (scales.empty()) throw cli::UsageError("--scale is empty");
  return scales;
}

}  // namespace

int runBench(int argc, char** argv) {
  cli::ArgParser args(
      "bench",
      "Times every stage on one core (CPU time, median and 99th percentile per frame), frames\n"
      "per second and peak memory, and the stock PCL path on the same frames: SACSegmentation\n"
      "(SACMODEL_PLANE) on x, y, z, EuclideanClusterExtraction on a KdTree and\n"
      "OcTree::insertPointCloud; prints the speed-up and how often both detect the same.");
  addReferenceOptions(args);
  args.option("sequence", "", "folder of PNG frames (with a reference option); default: simulate");
  args.option("scenario", "cable", "simulated walking scenario");
  args.option("frames", "40", "simulated frames, rendered once");
  args.option("step", "0.008", "simulated advance per frame [m]; the cable crosses the view");
  args.option("scale", "1", "points per frame, times the paper's sensor: 1, 2, 4 or a list");
  args.option("passes", "20", "timed passes over the frames (the stock path: a quarter)");
  args.option("tolerance", "0.1", "share of differing obstacle points two agreeing frames allow");
  args.option("cpu", "-1", "CPU to pin to; -1: the one the command starts on");
  args.option("out", "", "CSV file of the table");
  if (!args.parse(argc, argv)) return 0;
  const std::vector<int> scales = parseScales(args.str("scale"));
  const int passes = static_cast<int>(args.integer("passes"));
  if (passes < 1) throw cli::UsageError("--passes must be >= 1");
  if (args.has("sequence") && scales != std::vector<int>{1})
    throw cli::UsageError("--scale needs simulated frames (no --sequence)");

  std::vector<BenchInput> inputs;
  for (const int scale : scales)
    inputs.push_back(args.has("sequence") ? recorded(args)
                                          : simulated(args.str("scenario"), args.integer("frames"),
                                                      args.number("step"), scale));
  const double rss_before = peakRssMb();
  const int cpu = pinToOneCore(static_cast<int>(args.integer("cpu")));
  std::vector<ScaleResult> results;
  for (const BenchInput& in : inputs)
    results.push_back(measure(in, passes, args.number("tolerance")));

  std::printf("multislit bench: %s, pinned to CPU %d, %d passes (stock: %d)\n",
              inputs.front().label.c_str(), cpu, passes, std::max(1, passes / 4));
  std::ofstream csv;
  if (args.has("out")) {
    csv.open(args.str("out"));
    if (!csv) throw std::runtime_error("cannot write '" + args.str("out") + "'");
  }
  printTable(results, args.has("out") ? &csv : nullptr);
  for (const ScaleResult& r : results) printSummary(r);
  std::printf("peak memory %.0f MB (%.0f MB before the timed passes: images and simulator)\n",
              peakRssMb(), rss_before);
  return 0;
}

}  // namespace multislit::apps
