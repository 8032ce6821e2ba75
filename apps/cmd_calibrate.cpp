// multislit calibrate: reference image (+ planes at known depths) to a calibration file.
#include "cli.h"
#include "commands.h"
#include "common.h"
#include "config_options.h"
#include "output_file.h"

#include "multislit/reference.h"
#include "multislit/slit_bend.h"

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

namespace multislit::apps {
namespace {

// --region-width, --estimator, --min-contrast and --slits.
ReferenceConfig referenceConfigFromArgs(const cli::ArgParser& args) {
  ReferenceConfig rc;
  rc.region_width = intOption(args, "region-width");
  rc.estimator = parseEstimator(args.str("estimator"));
  rc.min_contrast = args.number("min-contrast");
  rc.expected_slits = intOption(args, "slits");
  rc.full_scale = fullScaleFromArgs(args);
  validateOptions(rc, args, {{"expected_slits", "slits"}});
  return rc;
}

// The images of a plane at known depths, in the order given.
struct PlaneImages {
  std::vector<cv::Mat> images;
  std::vector<double> depths;  ///< [m]
};

// Each --plane DEPTH:IMAGE; a malformed one is a usage error.
PlaneImages readPlanes(const std::vector<std::string>& planes) {
  PlaneImages out;
  for (const std::string& p : planes) {
    const std::size_t colon = p.find(':');
    if (colon == std::string::npos)
      throw cli::UsageError("--plane takes DEPTH:IMAGE, not '" + p + "'");
    char* end = nullptr;
    const std::string depth = p.substr(0, colon);
    out.depths.push_back(std::strtod(depth.c_str(), &end));
    if (depth.empty() || *end != '\0' || !(out.depths.back() > 0))
      throw cli::UsageError("--plane depth must be a positive number of metres, not '" + depth +
                            "'");
    out.images.push_back(readMonoImage(p.substr(colon + 1)));
  }
  return out;
}

// The reference's slits, regions and scale, with the fit's rms over `planes` plane images.
void printCalibration(const Reference& ref, const std::string& ref_path, std::size_t planes,
                      double fit_rms) {
  std::printf("reference %s: %zu slits, %zu points (%.0f per slit)\n", ref_path.c_str(),
              ref.slits.size(), ref.pointCount(),
              static_cast<double>(ref.pointCount()) / static_cast<double>(ref.slits.size()));
  std::printf("  assigned region %d px (widest without overlap %d px), slit profile %.1f px wide\n",
              ref.region_width, ref.max_region_width, ref.profile_width);
  std::printf(
      "  slit smoothing rms %.3f px; %d slit pieces joined across gaps, %d tracks dropped "
      "as not slits (speckle, texture)\n",
      ref.smoothing_rms, ref.joined_pieces, ref.dropped_tracks);
  std::printf("  metric scale (%s): f * baseline = %.4f px m", ref.scale.source.c_str(),
              ref.scale.disparity_constant);
  if (planes > 0) std::printf(", fit rms %.3f px over %zu planes", fit_rms, planes);
}

// Every file calibrate reads: the reference images, the plane images and the sensor file.
std::vector<NamedInput> calibrateInputs(const cli::ArgParser& args) {
  std::vector<NamedInput> inputs = inputsOf(args, {"reference", "sensor", "intrinsics"});
  for (const std::string& plane : args.list("plane"))
    inputs.push_back({"--plane", plane.substr(plane.find(':') + 1)});
  return inputs;
}

// A warning on stderr when the reference's slits bend more than the projector model lets them:
// the camera's lens distortion is likely missing (or the sensor file describes another sensor).
void warnOfSlitBend(const Reference& ref, const SensorConfig& sensor) {
  const double bend = slitBend(ref, sensor, sensor.mount);
  if (bend <= kMaxSlitBend) return;
  std::fprintf(stderr,
               "warning: the reference's slits bend up to %.1f px away from the shape the "
               "projector model gives them (at most %.1f px): is the lens distortion missing? "
               "Give the camera's calibration with --intrinsics (OpenCV or ROS camera_info "
               "YAML), or check the sensor file's projector and mount\n",
               bend, kMaxSlitBend);
}

// Whole or absent: written beside `path`, read back (a full disk cuts it), then renamed.
void writeCalibration(const Reference& ref, const std::string& path) {
  writeWhole(
      path, [&ref](const std::string& tmp) { ref.save(tmp); },
      [](const std::string& tmp) { Reference::load(tmp); });
}

// The options of `multislit calibrate`.
void addCalibrateOptions(cli::ArgParser& args) {
  args.repeatable("reference",
                  "reference image of a plane (required; repeat to average several); memory: "
                  "about 130 MB and 3 bytes a pixel of one image (125 MB at 1296x964, 340 MB at "
                  "8192x8192, 0.96 GB at 16384x16384), averaging 11 bytes a pixel more (1.06 GB "
                  "for two of 8192x8192)");
  args.option("sensor", "",
              "sensor YAML: camera intrinsics and the reference pose (default: the paper's)");
  addIntrinsicsOption(args);
  args.repeatable("plane", "DEPTH:IMAGE, a wall at DEPTH metres");
  const ReferenceConfig defaults;
  args.option("region-width", defaultText(defaults.region_width),
              "assigned region width [px]; 0: the widest without overlap");
  args.option("estimator", estimatorName(defaults.estimator),
              "sub-pixel estimator: gaussian, centroid or windowed");
  args.option("min-contrast", defaultText(defaults.min_contrast),
              "slit peak above its background [share of full scale]");
  args.option("slits", defaultText(defaults.expected_slits), "number of slits the projector casts");
  addFullScaleOption(args, "the camera's white", "kept in the calibration");
  args.option("camera-id", "",
              "serial number (or DeviceID) of the camera; another is refused when the calibration "
              "is used with a camera");
  args.option("out", "calibration.yaml", "calibration file to write");
}

}  // namespace

int runCalibrate(int argc, char** argv) {
  cli::ArgParser args(
      "calibrate",
      "Finds the slits in a reference image of a plane (Sec. II-C), assigns each reference\n"
      "point its region (Fig. 7) and stores the metric scale. Without --plane the scale comes\n"
      "from the sensor model and the reference pose (--sensor, its mount section); with two or\n"
      "more --plane DEPTH:IMAGE (a wall facing the level sensor, DEPTH metres along the optical\n"
      "axis) it is measured. With --intrinsics the camera's lens distortion is taken off the\n"
      "slits' points (stored in the calibration); without it, calibrate warns when the slits\n"
      "bend more than the projector model allows. Several --reference images of the same\n"
      "plane from the same pose are averaged first: speckle and noise weaken, slits broken in\n"
      "one frame join. Ctrl-C ends it with nothing written (rc 130).\n"
      "\n"
      "example (a real sensor: 5 frames of the floor, the robot standing still):\n"
      "  multislit calibrate --reference f1.png --reference f2.png --reference f3.png \\\n"
      "    --reference f4.png --reference f5.png --sensor my_sensor.yaml --out calibration.yaml");
  addCalibrateOptions(args);
  if (!args.parse(argc, argv)) return 0;
  const std::vector<std::string> ref_paths = args.list("reference");
  if (ref_paths.empty()) throw cli::UsageError("--reference is required");

  refuseOverwritingInputs(args.str("out"), calibrateInputs(args));
  const StopSignal stop;  // Ctrl-C: nothing is written, as for a calibration that failed
  const SensorConfig sensor = sensorFromArgs(args);
  const ReferenceConfig rc = referenceConfigFromArgs(args);
  std::vector<cv::Mat> ref_images;
  for (const std::string& path : ref_paths) {
    if (StopSignal::requested()) return interruptedNothingWritten("calibrate");
    ref_images.push_back(readMonoImage(path));
  }
  const std::string ref_path =
      ref_paths.front() +
      (ref_paths.size() > 1 ? " (+" + std::to_string(ref_paths.size() - 1) + " averaged)" : "");
  Reference ref;
  try {
    ref = Reference::fromImages(ref_images, rc);
  } catch (const std::exception& e) {
    throw std::runtime_error(ref_path + ": " + e.what());
  }
  ref.camera_id = args.str("camera-id");
  ref.setNominalScale(sensor, sensor.mount);
  warnOfSlitBend(ref, sensor);

  const std::vector<std::string> planes = args.list("plane");
  double fit_rms = 0;
  if (!planes.empty()) {
    const PlaneImages plane_images = readPlanes(planes);
    fit_rms = ref.calibrateWithPlanes(plane_images.images, plane_images.depths, sensor.camera, rc);
  }
  if (StopSignal::requested()) return interruptedNothingWritten("calibrate");
  writeCalibration(ref, args.str("out"));

  printCalibration(ref, ref_path, planes.size(), fit_rms);
  std::printf("\nwrote %s\n", args.str("out").c_str());
  return 0;
}

}  // namespace multislit::apps
