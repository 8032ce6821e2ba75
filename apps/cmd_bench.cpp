// multislit bench: the time of every stage of the pipeline on one core, against the stock PCL
// path on the same frames, with the agreement of the two paths' detections.
#include "bench_input.h"
#include "bench_plain.h"
#include "bench_render.h"
#include "bench_run.h"
#include "bench_soak.h"
#include "bench_stock.h"
#include "cli.h"
#include "commands.h"
#include "common.h"
#include "output_file.h"

#include "multislit/extractor.h"
#include "multislit/floor_detector.h"
#include "multislit/pipeline.h"

#include <opencv2/core/utility.hpp>

#include <sched.h>
#include <sys/resource.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace multislit::apps {
namespace {

// ---- time and memory ----------------------------------------------------------------------------

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

// ---- the two paths ------------------------------------------------------------------------------

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
  for (int pass = -1; pass < passes && !StopSignal::requested(); ++pass) {  // -1: warm-up
    Pipeline pipeline(config);  // each pass maps the same walk from scratch
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
  PlainRun plain;  ///< the paper's extraction and the pixels read once, on the same frames
  MetricThreshold threshold;
  Agreement agreement;
};

/// One line of the table: a stage, or stages run one after the other, in both paths.
struct Row {
  std::string stage;
  StageTimes ours, stock;
};

/// The stages, then their sums. Extraction is ours in both paths (PCL has no slit extractor);
/// below it, its anchors: the paper's plain method and the regions' pixels read once.
std::vector<Row> rowsOf(const ScaleResult& r) {
  const PathRun &a = r.ours, &b = r.stock;
  return {{"extraction (both)", a.extract, a.extract},
          {"plain extraction", r.plain.plain, StageTimes()},
          {"pixels read once", r.plain.read, StageTimes()},
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
      "  extraction: %.1fx the paper's plain method (maximum and centroid on the row), %.1fx "
      "reading every assigned pixel once (medians)\n",
      r.ours.extract.quantile(0.5) / r.plain.plain.quantile(0.5),
      r.ours.extract.quantile(0.5) / r.plain.read.quantile(0.5));
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
  if (StopSignal::requested()) return r;
  r.plain = runPlain(in, passes);
  if (StopSignal::requested()) return r;
  r.points = r.ours.valid_points;
  r.threshold = metricThreshold(in.reference, FloorDetectorConfig{}.threshold());
  r.stock = runStockPath(in, std::max(1, passes / 4), r.threshold.median);
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

// The options of `multislit bench`.
void addBenchOptions(cli::ArgParser& args) {
  addReferenceOptions(args);
  args.option("sequence", "", "folder of PNG frames (with a reference option); default: simulate");
  args.option("scenario", "cable", "simulated walking scenario");
  args.option("frames", "40", "simulated frames, rendered once");
  args.option("step", "0.008", "simulated advance per frame [m]; the cable crosses the view");
  args.option("scale", "1", "points per frame, times the paper's sensor: 1, 2, 4 or a list");
  args.option("passes", "",
              "timed passes over the frames: 20 (the stock path: a quarter), 1 with --render");
  args.option("tolerance", "0.1", "share of differing obstacle points two agreeing frames allow");
  args.option("cpu", "-1", "CPU to pin to; -1: the one the command starts on");
  args.option("out", "", "CSV file of the table");
  args.option("soak", "0",
              "instead of timing: run the whole chain over this many frames (the rendered ones "
              "in turn) sampling resident memory; rc 1 when it grows over 5 % after warm-up");
  args.option("soak-png", "", "figure of the soak's memory curve (PNG)");
  args.flag("render",
            "instead: time the simulator's rendering of --frames frames of the walk on every "
            "core, the renderer before (exhaustive) next to today's (culled)");
}

}  // namespace

int runBench(int argc, char** argv) {
  cli::ArgParser args(
      "bench",
      "Times every stage on one core (CPU time, median and 99th percentile per frame), frames\n"
      "per second and peak memory, and the stock PCL path on the same frames: SACSegmentation\n"
      "(SACMODEL_PLANE) on x, y, z, EuclideanClusterExtraction on a KdTree and\n"
      "OcTree::insertPointCloud; prints the speed-up and how often both detect the same.");
  addBenchOptions(args);
  if (!args.parse(argc, argv)) return 0;
  const StopSignal stop;  // Ctrl-C: the soak's report so far; else nothing (no table of a part)
  const std::vector<NamedInput> files =
      inputsOf(args, {"sequence", "calibration", "reference", "sensor", "intrinsics"});
  for (const char* output : {"out", "soak-png"})
    refuseOverwritingInputs(args.str(output), files, std::string("--") + output);
  const std::vector<int> scales = parseScales(args.str("scale"));
  const int passes = args.has("passes")   ? static_cast<int>(args.integer("passes", 1, 100000))
                     : args.has("render") ? 1
                                          : 20;
  const long frames = args.integer("frames", 1, 100000);
  const double step = args.number("step", -1, 1), tolerance = args.number("tolerance", 0, 1);
  const long soak_frames = args.integer("soak", 0, 1000000000000L);
  if (args.has("sequence") && scales != std::vector<int>{1})
    throw cli::UsageError("--scale needs simulated frames (no --sequence)");
  const auto cpu_asked = static_cast<int>(args.integer("cpu", -1, CPU_SETSIZE - 1));
  if (args.has("render")) return benchRender(frames, passes, args.str("out"));

  std::vector<BenchInput> inputs;
  for (const int scale : scales)
    inputs.push_back(args.has("sequence")
                         ? readBenchInput(args)
                         : renderBenchInput(args.str("scenario"), frames, step, scale));
  if (StopSignal::requested()) return interruptedNothingWritten("bench");
  if (soak_frames > 0) {
    const SoakResult r = soak(inputs.front(), static_cast<std::size_t>(soak_frames), 200);
    const int rc = reportSoak(r, 0.1, 0.05, args.str("soak-png"));
    return StopSignal::requested() ? kInterruptedExit : rc;
  }
  const double rss_before = peakRssMb();
  const int cpu = pinToOneCore(cpu_asked);
  std::vector<ScaleResult> results;
  for (const BenchInput& in : inputs) {
    results.push_back(measure(in, passes, tolerance));
    if (StopSignal::requested()) return interruptedNothingWritten("bench");
  }

  std::printf("multislit bench: %s, pinned to CPU %d, %d passes (stock: %d)\n",
              inputs.front().label.c_str(), cpu, passes, std::max(1, passes / 4));
  std::unique_ptr<OutputFile> csv;  // whole or absent
  if (args.has("out")) csv = std::make_unique<OutputFile>(args.str("out"));
  printTable(results, csv ? &csv->stream() : nullptr);
  if (csv) csv->commit();
  for (const ScaleResult& r : results) printSummary(r);
  std::printf("peak memory %.0f MB (%.0f MB before the timed passes: images and simulator)\n",
              peakRssMb(), rss_before);
  return 0;
}

}  // namespace multislit::apps
