// multislit detect: floor and obstacles in each frame's RDMap, one JSON object per line.
#include "cli.h"
#include "commands.h"
#include "common.h"
#include "config_options.h"
#include "output_file.h"

#include "multislit/extractor.h"
#include "multislit/floor_detector.h"
#include "multislit/obstacles.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <string>

namespace multislit::apps {
namespace {

/// A number, or null when it is not finite (JSON has no NaN or infinity).
std::string jsonNumber(double value, const char* format) {
  if (!std::isfinite(value)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof buf, format, value);
  return buf;
}

/// The points written as obstacle_points: those of the groups kept by the noise rule, or with
/// `raw` every point off the plane. Sorted, as FloorResult::obstacles.
pcl::Indices listedPoints(const FloorResult& floor, const ObstacleResult& groups, bool raw) {
  if (raw) return floor.obstacles;
  pcl::Indices points;
  for (const Obstacle& o : groups.obstacles)
    points.insert(points.end(), o.indices.begin(), o.indices.end());
  std::sort(points.begin(), points.end());
  return points;
}

// "groups": [{"points", "u", "v" (centroid), "u_min", "u_max", "v_min", "v_max"}, ...] in px,
// the groups of obstacle points kept by the noise rule.
void writeGroups(std::ostream& out, const pcl::PointCloud<PointRDM>& cloud,
                 const ObstacleResult& groups) {
  char buf[256];
  out << ", \"groups\": [";
  for (std::size_t g = 0; g < groups.obstacles.size(); ++g) {
    const pcl::Indices& indices = groups.obstacles[g].indices;
    double su = 0, sv = 0;
    float u0 = cloud[static_cast<std::size_t>(indices[0])].u, u1 = u0;
    float v0 = cloud[static_cast<std::size_t>(indices[0])].v, v1 = v0;
    for (const auto i : indices) {
      const PointRDM& p = cloud[static_cast<std::size_t>(i)];
      su += p.u;
      sv += p.v;
      u0 = std::min(u0, p.u), u1 = std::max(u1, p.u);
      v0 = std::min(v0, p.v), v1 = std::max(v1, p.v);
    }
    const double n = static_cast<double>(indices.size());
    std::snprintf(buf, sizeof buf,
                  "%s{\"points\": %zu, \"u\": %.3f, \"v\": %.3f, \"u_min\": %.3f, \"u_max\": %.3f, "
                  "\"v_min\": %.0f, \"v_max\": %.0f}",
                  g ? ", " : "", indices.size(), su / n, sv / n, u0, u1, v0, v1);
    out << buf;
  }
  out << "]";
}

// One line of the JSONL output. Keys "frame", "points", "found", "plane", "inliers",
// "residual_std" and "obstacle_points" ([u, v, dk] in px) are read by other tools: keep them.
void writeJsonLine(std::ostream& out, const std::string& frame,
                   const pcl::PointCloud<PointRDM>& cloud, const FloorResult& r,
                   const ObstacleResult& groups, bool raw, double ms) {
  char buf[256];
  out << "{\"frame\": " << jsonString(frame) << ", \"points\": " << r.valid_points
      << ", \"found\": " << (r.found ? "true" : "false");
  std::snprintf(buf, sizeof buf, ", \"plane\": [%.9g, %.9g, %.9g]", r.plane.x(), r.plane.y(),
                r.plane.z());
  out << (r.found ? buf : ", \"plane\": null") << ", \"inliers\": " << r.inliers.size()
      << ", \"residual_std\": " << (r.found ? jsonNumber(r.residual_std, "%.6f") : "null")
      << ", \"sigma_px\": " << jsonNumber(r.sigma, "%.6f")
      << ", \"sigma_estimate_px\": " << jsonNumber(r.sigma_estimate, "%.6f")
      << ", \"threshold_px\": " << jsonNumber(r.threshold, "%.6f");
  const pcl::Indices listed = listedPoints(r, groups, raw);
  out << ", \"off_plane_count\": " << r.obstacles.size()
      << ", \"obstacle_count\": " << listed.size()
      << ", \"rejected_groups\": " << groups.rejected_groups
      << ", \"stamp_us\": " << cloud.header.stamp;
  std::snprintf(buf, sizeof buf, ", \"time_ms\": %.3f", ms);
  out << buf;
  writeGroups(out, cloud, groups);
  out << ", \"obstacle_points\": [";
  for (std::size_t i = 0; i < listed.size(); ++i) {
    const PointRDM& p = cloud[static_cast<std::size_t>(listed[i])];
    // v: a whole row, or an ideal row through a distorting lens (%g prints a whole one bare).
    std::snprintf(buf, sizeof buf, "%s[%.3f, %.6g, %.4f]", i ? ", " : "", p.u, p.v, p.dk);
    out << buf;
  }
  out << "]}\n";
}

// --iterations sets FloorDetectorConfig::max_iterations; the other options are named after their
// fields.
const std::map<std::string, std::string> kRenamed = {{"max_iterations", "iterations"}};

FloorDetectorConfig detectorConfig(const cli::ArgParser& args) {
  FloorDetectorConfig fc;
  fc.sigma = args.number("sigma");
  fc.estimate_sigma = !args.has("fixed-sigma");
  fc.min_sigma = args.number("min-sigma");
  fc.max_sigma = args.number("max-sigma");
  fc.threshold_sigmas = args.number("threshold-sigmas");
  fc.max_iterations = intOption(args, "iterations");
  validateOptions(fc, args, kRenamed);
  return fc;
}

// --help: what detect measures and the fields of its JSON lines.
std::string summary() {
  return "Finds the floor in each frame's RDMap with RANSAC (eq. 1-3) and the points off it\n"
         "(Sec. III-B). The threshold is --threshold-sigmas x sigma, sigma measured in each\n"
         "frame's own floor residuals (1.4826 x their median |residual|, clamped to [--min-sigma,\n"
         "--max-sigma]); off-plane points are grouped along slits and across adjacent slits, and\n"
         "groups of fewer than " +
         std::to_string(ObstacleClustererConfig{}.min_points) +
         " points are noise. Writes one JSON object per frame and line: frame,\n"
         "points, found, plane [A, B, C] of dk = A u + B v + C, inliers, residual_std [px],\n"
         "sigma_px (the sigma used), sigma_estimate_px (before clamping), threshold_px,\n"
         "off_plane_count (every point off the plane), obstacle_count (points listed in\n"
         "obstacle_points), rejected_groups, stamp_us, time_ms (image to floor), groups [{points,\n"
         "u, v (centroid), u_min, u_max, v_min, v_max}, ...] (px) and obstacle_points [[u, v, "
         "dk],\n"
         "...] (reference position and disparity, px): the points of the groups, or with --raw\n"
         "every point off the plane. null: not found or not measured.";
}

void addDetectOptions(cli::ArgParser& args) {
  const FloorDetectorConfig defaults;
  addReferenceOptions(args);
  addExtractorOptions(args);
  args.option("sigma", defaultText(defaults.sigma),
              "sensor noise sigma [px]: RANSAC's threshold is --threshold-sigmas x sigma");
  args.flag("fixed-sigma", "use --sigma for every frame instead of measuring each frame's");
  args.option("min-sigma", defaultText(defaults.min_sigma),
              "lower bound of the measured sigma [px]");
  args.option("max-sigma", defaultText(defaults.max_sigma),
              "upper bound of the measured sigma [px]");
  args.option("threshold-sigmas", defaultText(defaults.threshold_sigmas),
              "floor / obstacle threshold in sigmas");
  args.option("iterations", defaultText(defaults.max_iterations),
              "RANSAC iterations; 0: from eq. (3) (" + std::to_string(defaults.iterations()) + ")");
  args.flag("raw", "obstacle_points: every point off the plane, also groups below " +
                       std::to_string(ObstacleClustererConfig{}.min_points) + " points");
  args.option("out", "", "JSONL file to write (required)");
  args.positionals("FRAME...", "8- or 16-bit images", 1);
}

}  // namespace

int runDetect(int argc, char** argv) {
  cli::ArgParser args("detect", summary());
  addDetectOptions(args);
  if (!args.parse(argc, argv)) return 0;
  if (!args.has("out")) throw cli::UsageError("--out is required");

  const ExtractorConfig ec = extractorConfigFromArgs(args);
  const Extractor extractor(referenceFromArgs(args), ec);
  const FloorDetector detector(detectorConfig(args));
  const ObstacleClusterer clusterer;  // the default grouping (grid) and noise rule
  const bool raw = args.has("raw");

  const std::vector<std::string>& frames = args.rest();
  std::vector<NamedInput> inputs =
      inputsOf(args, {"calibration", "reference", "sensor", "intrinsics"});
  for (const std::string& frame : frames) inputs.push_back({"", frame});
  refuseOverwritingInputs(args.str("out"), inputs);
  OutputFile file(args.str("out"));  // whole or absent: a bad frame leaves no partial JSONL
  std::ofstream& out = file.stream();
  const StopSignal stop;
  cli::Progress progress(frames.size(), "detect");
  std::size_t found = 0, obstacles = 0, off_plane = 0, points = 0, done = 0;
  double total_ms = 0;
  for (std::size_t i = 0; i < frames.size() && !StopSignal::requested(); ++i, ++done) {
    const Reference& ref = extractor.reference();
    const cv::Mat image = readMonoImage(frames[i], cv::Size(ref.image_width, ref.image_height));
    const auto t0 = std::chrono::steady_clock::now();
    pcl::PointCloud<PointRDM>::Ptr cloud;
    try {
      cloud = extractor.extract(image, 0, static_cast<std::uint32_t>(i));
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(frames[i] + ": " + e.what());
    }
    const FloorResult r = detector.detect(cloud);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const ObstacleResult groups = clusterer.cluster(cloud, r, Eigen::Isometry3d::Identity());
    total_ms += ms;
    writeJsonLine(out, frames[i], *cloud, r, groups, raw, ms);
    found += r.found;
    obstacles += raw ? r.obstacles.size() : groups.pointCount();
    off_plane += r.obstacles.size();
    points += r.valid_points;
    progress.update(i + 1);
  }
  progress.finish();
  file.commit();  // flushed and checked: a full disk is an error, not an empty file
  const double n = static_cast<double>(std::max<std::size_t>(done, 1));
  std::printf(
      "%zu frames%s: floor found in %zu, %.0f points, %.1f off the plane and %.1f obstacle points "
      "per frame, %.2f ms per frame (image to floor) -> %s\n",
      done, StopSignal::requested() ? " (interrupted)" : "", found, static_cast<double>(points) / n,
      static_cast<double>(off_plane) / n, static_cast<double>(obstacles) / n, total_ms / n,
      args.str("out").c_str());
  return StopSignal::requested() ? kInterruptedExit : 0;
}

}  // namespace multislit::apps
