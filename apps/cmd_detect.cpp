// multislit detect: floor and obstacles in each frame's RDMap, one JSON object per line.
#include "cli.h"
#include "commands.h"
#include "common.h"

#include "multislit/extractor.h"
#include "multislit/floor_detector.h"

#include <chrono>
#include <cstdio>
#include <fstream>

namespace multislit::apps {
namespace {

// One line of the JSONL output. Keys "frame", "points", "found", "plane", "inliers",
// "residual_std" and "obstacle_points" ([u, v, dk] in px) are read by other tools: keep them.
void writeJsonLine(std::ostream& out, const std::string& frame,
                   const pcl::PointCloud<PointRDM>& cloud, const FloorResult& r, double ms) {
  char buf[256];
  out << "{\"frame\": " << jsonString(frame) << ", \"points\": " << r.valid_points
      << ", \"found\": " << (r.found ? "true" : "false");
  std::snprintf(buf, sizeof buf, ", \"plane\": [%.9g, %.9g, %.9g]", r.plane.x(), r.plane.y(),
                r.plane.z());
  out << (r.found ? buf : ", \"plane\": null") << ", \"inliers\": " << r.inliers.size();
  if (r.found) {
    std::snprintf(buf, sizeof buf, ", \"residual_std\": %.6f", r.residual_std);
    out << buf;
  } else {
    out << ", \"residual_std\": null";
  }
  out << ", \"obstacle_count\": " << r.obstacles.size() << ", \"stamp_us\": " << cloud.header.stamp;
  std::snprintf(buf, sizeof buf, ", \"time_ms\": %.3f", ms);
  out << buf << ", \"obstacle_points\": [";
  for (std::size_t i = 0; i < r.obstacles.size(); ++i) {
    const PointRDM& p = cloud[static_cast<std::size_t>(r.obstacles[i])];
    std::snprintf(buf, sizeof buf, "%s[%.3f, %.0f, %.4f]", i ? ", " : "", p.u, p.v, p.dk);
    out << buf;
  }
  out << "]}\n";
}

}  // namespace

int runDetect(int argc, char** argv) {
  cli::ArgParser args(
      "detect",
      "Finds the floor in each frame's RDMap with RANSAC (eq. 1-3) and the points off it\n"
      "(Sec. III-B). Writes one JSON object per frame and line: frame, points, found, plane\n"
      "[A, B, C] of dk = A u + B v + C, inliers, residual_std [px], obstacle_count, stamp_us,\n"
      "time_ms and obstacle_points [[u, v, dk], ...] (reference position and disparity, px).");
  addReferenceOptions(args);
  args.option("estimator", "gaussian", "sub-pixel estimator: gaussian, centroid or windowed");
  args.option("sigma", "0.3", "sensor noise sigma [px]; the threshold is 3 sigma");
  args.option("threshold-sigmas", "3", "floor / obstacle threshold in sigmas");
  args.option("iterations", "0", "RANSAC iterations; 0: from eq. (3) (35)");
  args.option("out", "", "JSONL file to write (required)");
  args.positionals("FRAME...", "8- or 16-bit images", 1);
  if (!args.parse(argc, argv)) return 0;
  if (!args.has("out")) throw cli::UsageError("--out is required");

  ExtractorConfig ec;
  ec.estimator = parseEstimator(args.str("estimator"));
  const Extractor extractor(referenceFromArgs(args), ec);
  FloorDetectorConfig fc;
  fc.sigma = args.number("sigma");
  fc.threshold_sigmas = args.number("threshold-sigmas");
  fc.max_iterations = static_cast<int>(args.integer("iterations"));
  const FloorDetector detector(fc);

  std::ofstream out(args.str("out"));
  if (!out) throw std::runtime_error("cannot write '" + args.str("out") + "'");
  const std::vector<std::string>& frames = args.rest();
  cli::Progress progress(frames.size(), "detect");
  std::size_t found = 0, obstacles = 0, points = 0;
  double total_ms = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const cv::Mat image = readMonoImage(frames[i]);
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
    total_ms += ms;
    writeJsonLine(out, frames[i], *cloud, r, ms);
    found += r.found;
    obstacles += r.obstacles.size();
    points += r.valid_points;
    progress.update(i + 1);
  }
  progress.finish();
  if (!out) throw std::runtime_error("could not write '" + args.str("out") + "' completely");
  const double n = static_cast<double>(frames.size());
  std::printf(
      "%zu frames: floor found in %zu, %.0f points and %.1f obstacle points per frame, "
      "%.2f ms per frame (image to floor) -> %s\n",
      frames.size(), found, static_cast<double>(points) / n, static_cast<double>(obstacles) / n,
      total_ms / n, args.str("out").c_str());
  return 0;
}

}  // namespace multislit::apps
