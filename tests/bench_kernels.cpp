// The hot kernels of the pipeline (issue 7), on simulated frames of the paper's sensor: the slit
// search and sub-pixel measure on a real image row, the extraction of a whole frame, and the
// floor fit and the obstacle groups of a real RDMap, and the map update of a stretch of the walk.
// Run with `cmake --build <build> --target bench`; not a test.
#include "multislit/extractor.h"
#include "multislit/floor_detector.h"
#include "multislit/obstacles.h"
#include "multislit/occupancy_map.h"
#include "multislit/plane_model.h"
#include "multislit/sim/scenarios.h"
#include "multislit/sim/simulator.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <vector>

using namespace multislit;

namespace {

/// A reference and a frame of the cable scenario with the cable in view, rendered once.
struct Data {
  Reference reference;
  cv::Mat image;                             ///< 8-bit, 1296 x 964
  pcl::PointCloud<PointRDM>::Ptr cloud;      ///< its RDMap
  int row = 0;                               ///< the image row crossed by the most slits
  std::vector<std::pair<int, int>> regions;  ///< [first, last] of each point on that row [px]
};

const Data& data() {
  static const Data d = [] {
    Data out;
    const Simulator sim{SensorConfig{}};
    const Scenario ref = makeScenario("reference");
    out.reference = Reference::fromImage(
        sim.render(ref.scene, sim.geometry().robotFromCamera(ref.reference_mount), 1000).image);
    out.reference.setNominalScale(sim.geometry().config(), ref.reference_mount);
    Scenario cable = makeScenario("cable");
    cable.step = 0.008;
    const std::uint64_t frame = 20;  // the cable lies across the middle slits
    out.image =
        sim.render(cable.scene,
                   cable.worldFromRobot(frame) * sim.geometry().robotFromCamera(cable.mount), frame)
            .image;
    out.cloud = Extractor(out.reference).extract(out.image, 0, 0);
    // The row with the most reference points, and their assigned regions (Fig. 7).
    std::vector<std::vector<std::pair<int, int>>> by_row(static_cast<std::size_t>(out.image.rows));
    const double half = 0.5 * out.reference.region_width;
    for (const ReferenceSlit& slit : out.reference.slits)
      for (std::size_t k = 0; k < slit.u.size(); ++k)
        if (std::isfinite(slit.u[k]))
          by_row[static_cast<std::size_t>(slit.first_row) + k].emplace_back(
              static_cast<int>(std::ceil(slit.u[k] - half)),
              static_cast<int>(std::floor(slit.u[k] + half)));
    for (std::size_t r = 0; r < by_row.size(); ++r)
      if (by_row[r].size() > out.regions.size()) {
        out.regions = by_row[r];
        out.row = static_cast<int>(r);
      }
    return out;
  }();
  return d;
}

ProfileParams paramsOf(const Reference& ref) {  // as Extractor::extract sets them for 8 bits
  return Extractor(ref).profileParams(CV_8U);
}

// Search each assigned region of one row for its slit and measure it (the per-point kernel).
void BM_MeasurePeakRow(benchmark::State& state, Estimator estimator) {
  const Data& d = data();
  ProfileParams p = paramsOf(d.reference);
  p.estimator = estimator;
  const auto* row = d.image.ptr<std::uint8_t>(d.row);
  for (auto _ : state) {
    for (const auto& [first, last] : d.regions) {
      Peak peak;
      benchmark::DoNotOptimize(measurePeak(row, d.image.cols, first, last, p, &peak));
      benchmark::DoNotOptimize(peak);
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(d.regions.size()));
}
BENCHMARK_CAPTURE(BM_MeasurePeakRow, gaussian, Estimator::Gaussian);
BENCHMARK_CAPTURE(BM_MeasurePeakRow, centroid, Estimator::Centroid);
BENCHMARK_CAPTURE(BM_MeasurePeakRow, windowed, Estimator::Windowed);

// The same regions through measurePeaks(), four profiles at a time where the CPU has AVX2.
void BM_MeasurePeaksRow(benchmark::State& state) {
  const Data& d = data();
  const ProfileParams p = paramsOf(d.reference);
  std::vector<PeakRegion<std::uint8_t>> regions;
  for (const auto& [first, last] : d.regions)
    regions.push_back({d.image.ptr<std::uint8_t>(d.row), first, last});
  std::vector<Peak> peaks(regions.size());
  std::unique_ptr<bool[]> found(new bool[regions.size()]);
  for (auto _ : state) {
    measurePeaks(regions.data(), regions.size(), d.image.cols, p, peaks.data(), found.get());
    benchmark::DoNotOptimize(peaks.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(regions.size()));
}
BENCHMARK(BM_MeasurePeaksRow);

// The sub-pixel measure alone, at the maxima the search found.
void BM_MeasurePeakAtRow(benchmark::State& state) {
  const Data& d = data();
  const ProfileParams p = paramsOf(d.reference);
  const auto* row = d.image.ptr<std::uint8_t>(d.row);
  std::vector<int> tops;
  for (const auto& [first, last] : d.regions) {
    int top = first;
    for (int x = first; x <= last; ++x)
      if (row[x] > row[top]) top = x;
    tops.push_back(top);
  }
  for (auto _ : state) {
    for (const int top : tops) {
      Peak peak;
      benchmark::DoNotOptimize(measurePeakAt(row, d.image.cols, top, p, &peak));
      benchmark::DoNotOptimize(peak);
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(tops.size()));
}
BENCHMARK(BM_MeasurePeakAtRow);

// Image to RDMap: one full 1296 x 964 frame (about 4500 points).
void BM_ExtractFrame(benchmark::State& state) {
  const Data& d = data();
  const Extractor extractor(d.reference);
  pcl::PointCloud<PointRDM> cloud;
  std::size_t points = 0;
  for (auto _ : state) {
    points = extractor.extract(d.image, cloud).reference_points;
    benchmark::DoNotOptimize(cloud.points.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(points));
}
BENCHMARK(BM_ExtractFrame)->Unit(benchmark::kMicrosecond);

// RANSAC (eq. 3), the eq. (2) refit and the classification of every point of a real RDMap.
void BM_FloorDetect(benchmark::State& state) {
  const Data& d = data();
  const FloorDetector detector;
  for (auto _ : state) benchmark::DoNotOptimize(detector.detect(d.cloud));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(d.cloud->size()));
}
BENCHMARK(BM_FloorDetect)->Unit(benchmark::kMicrosecond);

// eq. (2) alone: the least-squares plane through every point of the RDMap.
void BM_PlaneFit(benchmark::State& state) {
  const Data& d = data();
  pcl::Indices all(d.cloud->size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  for (auto _ : state) benchmark::DoNotOptimize(fitRDMapPlane(*d.cloud, all));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(all.size()));
}
BENCHMARK(BM_PlaneFit)->Unit(benchmark::kMicrosecond);

/// The map update's inputs over frames 10 to 29 of the cable walk (the cable comes into the
/// slits): each frame's RDMap, floor and obstacles found once, and the camera's pose.
struct MapFrames {
  std::vector<pcl::PointCloud<PointRDM>::ConstPtr> clouds;
  std::vector<FloorResult> floors;
  std::vector<ObstacleResult> obstacles;
  std::vector<Eigen::Isometry3d> world_from_camera;
  Eigen::Vector3d light = Eigen::Vector3d::Zero();  ///< the projector centre, camera frame [m]
};

const MapFrames& mapFrames() {
  static const MapFrames f = [] {
    MapFrames out;
    const Simulator sim{SensorConfig{}};
    Scenario cable = makeScenario("cable");
    cable.step = 0.008;  // as multislit bench
    const Eigen::Isometry3d robot_from_camera = sim.geometry().robotFromCamera(cable.mount);
    const Extractor extractor(data().reference);
    const FloorDetector detector;
    const ObstacleClusterer clusterer;
    for (std::uint64_t frame = 10; frame < 30; ++frame) {
      const Eigen::Isometry3d world_from_camera = cable.worldFromRobot(frame) * robot_from_camera;
      const pcl::PointCloud<PointRDM>::ConstPtr cloud =
          extractor.extract(sim.render(cable.scene, world_from_camera, frame).image, 0, 0);
      out.floors.push_back(detector.detect(cloud));
      out.obstacles.push_back(clusterer.cluster(cloud, out.floors.back(), robot_from_camera));
      out.clouds.push_back(cloud);
      out.world_from_camera.push_back(world_from_camera);
    }
    out.light = sim.geometry().projectorCentre();
    return out;
  }();
  return f;
}

// The map update (OccupancyMap::insertFrame: evidence, sweep, free rays, OctoMap leaves) of those
// 20 frames into a new map; items are frames.
void BM_MapUpdate(benchmark::State& state) {
  const MapFrames& f = mapFrames();
  for (auto _ : state) {
    state.PauseTiming();
    auto map = std::make_unique<OccupancyMap>();
    state.ResumeTiming();
    for (std::size_t k = 0; k < f.clouds.size(); ++k)
      benchmark::DoNotOptimize(map->insertFrame(*f.clouds[k], f.floors[k], f.obstacles[k],
                                                f.world_from_camera[k], f.light));
    state.PauseTiming();
    map.reset();
    state.ResumeTiming();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(f.clouds.size()));
}
BENCHMARK(BM_MapUpdate)->Unit(benchmark::kMicrosecond);

// The obstacle points of a real RDMap (its floor found once) grouped, sized and placed.
void BM_ObstacleCluster(benchmark::State& state) {
  const Data& d = data();
  const FloorResult floor = FloorDetector().detect(d.cloud);
  const ObstacleClusterer clusterer;
  const Eigen::Isometry3d robot_from_camera = Eigen::Isometry3d::Identity();
  for (auto _ : state)
    benchmark::DoNotOptimize(clusterer.cluster(d.cloud, floor, robot_from_camera));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(floor.obstacles.size()));
}
BENCHMARK(BM_ObstacleCluster)->Unit(benchmark::kMicrosecond);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  data();  // render before timing anything
  mapFrames();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
