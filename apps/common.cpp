#include "common.h"

#include "cli.h"
#include "output_file.h"

#include "multislit/intrinsics_file.h"

#include <opencv2/imgcodecs.hpp>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <utility>
#include <vector>

namespace multislit::apps {

void writeImage(const std::string& path, const cv::Mat& image) {
  std::vector<std::uint8_t> bytes;
  const std::string extension = std::filesystem::path(path).extension().string();
  if (!cv::imencode(extension, image, bytes))
    throw std::runtime_error("cannot write image '" + path + "'");
  OutputFile file(path);  // whole or absent
  file.stream().write(reinterpret_cast<const char*>(bytes.data()),
                      static_cast<std::streamsize>(bytes.size()));
  file.commit();
}

std::vector<NamedInput> inputsOf(const cli::ArgParser& args,
                                 std::initializer_list<const char*> options) {
  std::vector<NamedInput> inputs;
  for (const char* option : options) {
    std::vector<std::string> values = args.list(option);
    if (values.empty() && args.has(option)) values.push_back(args.str(option));
    for (std::string& value : values) inputs.push_back({std::string("--") + option, value});
  }
  return inputs;
}

void addIntrinsicsOption(cli::ArgParser& args) {
  args.option("intrinsics", "",
              "the camera's own calibration: OpenCV calibrateCamera YAML (camera_matrix, "
              "distortion_coefficients) or ROS camera_info YAML; its focal length, principal "
              "point and lens distortion replace the sensor file's");
}

SensorConfig sensorFromArgs(const cli::ArgParser& args) {
  SensorConfig sensor =
      args.has("sensor") ? SensorConfig::load(args.str("sensor")) : SensorConfig{};
  if (args.has("intrinsics"))
    sensor.camera = withIntrinsicsFile(sensor.camera, args.str("intrinsics"));
  return sensor;
}

void checkIntrinsicsOf(const Reference& reference, const cli::ArgParser& args,
                       const std::string& what) {
  if (!args.has("intrinsics")) return;
  const std::string& path = args.str("intrinsics");
  reference.checkLens(intrinsicsForImage(reference.image_width, reference.image_height, path),
                      what);
}

void addReferenceOptions(cli::ArgParser& args) {
  args.option("calibration", "", "calibration file from multislit calibrate");
  args.option("reference", "", "reference image of the floor (instead of --calibration)");
  args.option("sensor", "", "sensor YAML; its mount is the reference pose (default: the paper's)");
  addIntrinsicsOption(args);
  addFullScaleOption(args, "the --reference image's white", "a calibration keeps its own");
}

void addFullScaleOption(cli::ArgParser& args, const std::string& whose, const std::string& note) {
  args.option("full-scale", "0",
              whose + " [DN], 4095 for 12-bit data in 16-bit images; 0: the image type's (255 or " +
                  "65535; " + note + ")");
}

double fullScaleFromArgs(const cli::ArgParser& args) { return args.number("full-scale", 0, 65535); }

Reference referenceFromArgs(const cli::ArgParser& args) {
  const double full_scale = fullScaleFromArgs(args);
  if (args.has("calibration")) {
    if (full_scale > 0)
      throw cli::UsageError("--full-scale goes with --reference; a calibration keeps its own");
    Reference ref = Reference::load(args.str("calibration"));
    checkIntrinsicsOf(ref, args, "calibration '" + args.str("calibration") + "'");
    return ref;
  }
  if (!args.has("reference")) throw cli::UsageError("give --calibration FILE or --reference IMAGE");
  const SensorConfig sensor = sensorFromArgs(args);
  const std::string path = args.str("reference");
  Reference ref;
  try {
    ReferenceConfig config;
    config.full_scale = full_scale;
    config.expected_slits = sensor.projector.slit_count;
    ref = Reference::fromImage(readMonoImage(path), config);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  ref.setNominalScale(sensor, sensor.mount);
  return ref;
}

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

namespace {
constexpr std::pair<Estimator, const char*> kEstimatorNames[] = {{Estimator::Gaussian, "gaussian"},
                                                                 {Estimator::Centroid, "centroid"},
                                                                 {Estimator::Windowed, "windowed"}};
}  // namespace

Estimator parseEstimator(const std::string& name) {
  for (const auto& [estimator, text] : kEstimatorNames)
    if (name == text) return estimator;
  throw cli::UsageError("--estimator must be gaussian, centroid or windowed, not '" + name + "'");
}

std::string estimatorName(Estimator estimator) {
  for (const auto& [e, text] : kEstimatorNames)
    if (e == estimator) return text;
  throw std::logic_error("an estimator without a name");
}

void addExtractorOptions(cli::ArgParser& args) {
  args.option("estimator", estimatorName(ExtractorConfig{}.estimator),
              "sub-pixel estimator of the row's profile: gaussian, centroid or windowed (it sets "
              "the centre only with --along-row)");
  args.flag("along-row",
            "measure the centre along the image row, as the paper does, not across the stripe: "
            "about ten times faster, and pulled by tile edges and grain");
  const ExtractorConfig defaults;
  char stray[256];
  std::snprintf(stray, sizeof stray,
                "drop runs of up to V points of a slit whose dk jumps by more than %g px from the "
                "points on both sides: where a stripe is lost on dark grout or a dark object, its "
                "region's noise; 0: keep them",
                defaults.stray_step);
  args.option("stray-run", std::to_string(defaults.stray_run), stray);
}

ExtractorConfig extractorConfigFromArgs(const cli::ArgParser& args) {
  ExtractorConfig ec;
  ec.estimator = parseEstimator(args.str("estimator"));
  ec.across_stripe = !args.has("along-row");
  ec.stray_run = static_cast<int>(args.integer("stray-run", 0, 1000));
  return ec;
}

}  // namespace multislit::apps
