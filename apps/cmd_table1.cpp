// multislit table1: the paper's Table I and Fig. 12 reproduced on the simulator.
#include "cli.h"
#include "commands.h"
#include "common.h"
#include "output_file.h"
#include "plot.h"

#include "multislit/extractor.h"
#include "multislit/plane_model.h"
#include "multislit/sim/rdmap_synth.h"
#include "multislit/sim/scenarios.h"
#include "multislit/sim/simulator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numeric>

namespace multislit::apps {

namespace {

// The residual std of eq. (2) fitted to all points of each RDMap, over `frames` frames of
// `floor` seen from `mount` (condition `cond` of Table I: its own noise).
struct FloorNoise {
  double mean = 0;    ///< mean of the frames' residual std [px]
  double spread = 0;  ///< std of the frames' residual std [px]
  double points = 0;  ///< mean points per frame
};

FloorNoise measureFloorNoise(const Simulator& sim, const Extractor& extractor, const Scene& floor,
                             const MountConfig& mount, int cond, long frames,
                             cli::Progress& progress) {
  const Eigen::Isometry3d pose = sim.geometry().robotFromCamera(mount);
  std::vector<double> stds;
  double points = 0;
  for (long k = 0; k < frames && !StopSignal::requested(); ++k) {
    const RenderedFrame f = sim.render(floor, pose, static_cast<uint64_t>(cond * 100000 + k));
    pcl::PointCloud<PointRDM> cloud;
    extractor.extract(f.image, cloud);
    pcl::Indices all(cloud.size());
    std::iota(all.begin(), all.end(), 0);
    const RDMapPlaneFit fit = fitRDMapPlane(cloud, all);  // eq. (2) on all points
    stds.push_back(fit.residual_std);
    points += static_cast<double>(fit.points);
    progress.update(static_cast<std::size_t>(cond * frames + k + 1));
  }
  const double n = static_cast<double>(stds.size());
  const double mean = std::accumulate(stds.begin(), stds.end(), 0.0) / n;
  double var = 0;
  for (double s : stds) var += (s - mean) * (s - mean);
  return {mean, std::sqrt(var / n), points / n};
}

// The table (`rows`, one per condition) on stdout and Fig. 12 (fig12.png in `out`): the mean
// residual std per condition with its spread; then `csv` (table1.csv) is committed: both files
// or neither.
void reportTable1(const std::filesystem::path& out, OutputFile& csv, long frames,
                  const std::vector<std::string>& rows, const std::vector<std::string>& labels,
                  const std::vector<double>& means, const std::vector<double>& spreads) {
  std::printf("%-10s %6s %6s %6s %8s %13s\n", "condition", "theta", "phi", "h", "points",
              "residual std");
  for (const std::string& row : rows) std::fputs(row.c_str(), stdout);
  drawBarChart(
      (out / "fig12.png").string(),
      "Fig. 12: floor residual std per Table I pose (" + std::to_string(frames) + " frames each)",
      "std [px]", labels, means, spreads);
  csv.commit();
  const auto [lo, hi] = std::minmax_element(means.begin(), means.end());
  std::printf("max / min over the conditions: %.2f (the paper: almost constant)\nwrote %s and %s\n",
              *hi / *lo, (out / "table1.csv").string().c_str(),
              (out / "fig12.png").string().c_str());
}

}  // namespace

int runTable1(int argc, char** argv) {
  cli::ArgParser args(
      "table1",
      "Reproduces Table I and Fig. 12: for the reference pose and the six conditions, simulates\n"
      "frames of the bare floor, fits a plane to all points of each RDMap with eq. (2) and\n"
      "averages the standard deviation of the residuals. The paper's claim: the std is almost\n"
      "the same for every pose. Writes table1.csv and fig12.png.");
  args.option("frames", "100", "frames per condition (the paper averaged 100)");
  args.option("seed", "1", "noise seed");
  args.option("sensor", "",
              std::string("sensor YAML (default: the paper's sensor)") + kRenderMemory);
  args.option("out", "out/table1", "output folder");
  if (!args.parse(argc, argv)) return 0;
  const StopSignal stop;  // Ctrl-C: nothing is written (a table of fewer poses is no Table I)
  const std::filesystem::path out = args.str("out");
  refuseOutputFolder(out, "--out", {"table1.csv", "fig12.png"}, inputsOf(args, {"sensor"}));
  const long frames = args.integer("frames", 1, 1000000);
  const SensorConfig sensor =
      args.has("sensor") ? SensorConfig::load(args.str("sensor")) : SensorConfig{};
  RenderConfig rc;
  rc.seed = static_cast<uint64_t>(args.integer("seed", 0, std::numeric_limits<long>::max()));
  const Simulator sim(sensor, rc);

  // The reference: the bare floor at the reference pose (Sec. II-C).
  const Scenario ref_scene = makeScenario("reference");
  const Extractor extractor(renderFloorReference(sensor, ref_scene.reference_mount, rc));

  std::filesystem::create_directories(out);
  OutputFile csv_file(out / "table1.csv");  // whole or absent
  std::ofstream& csv = csv_file.stream();
  csv << "condition,theta_deg,phi_deg,h_mm,frames,mean_points,mean_residual_std_px,std_of_std_px\n";
  std::vector<std::string> labels;
  std::vector<double> means, spreads;
  cli::Progress progress(static_cast<std::size_t>(7 * frames), "table1");
  std::vector<std::string> rows;
  for (int cond = 0; cond <= 6 && !StopSignal::requested(); ++cond) {
    const MountConfig mount = tableIPose(cond);
    const FloorNoise noise =
        measureFloorNoise(sim, extractor, ref_scene.scene, mount, cond, frames, progress);
    const double mean = noise.mean, spread = noise.spread, points = noise.points;
    const std::string name = cond == 0 ? "reference" : std::to_string(cond);
    labels.push_back(cond == 0 ? "ref" : name);
    means.push_back(mean);
    spreads.push_back(spread);
    csv << name << ',' << mount.tilt << ',' << mount.roll << ',' << mount.height * 1000 << ','
        << frames << ',' << points << ',' << mean << ',' << spread << '\n';
    char row[128];
    std::snprintf(row, sizeof row, "%-10s %6.0f %6.0f %6.0f %8.0f %10.3f px\n", name.c_str(),
                  mount.tilt, mount.roll, mount.height * 1000, points, mean);
    rows.push_back(row);
  }
  progress.finish();
  if (StopSignal::requested()) return interruptedNothingWritten("table1");
  reportTable1(out, csv_file, frames, rows, labels, means, spreads);
  return 0;
}

}  // namespace multislit::apps
