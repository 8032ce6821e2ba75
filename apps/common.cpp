#include "common.h"

#include "cli.h"

#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace multislit::apps {

cv::Mat readMonoImage(const std::string& path) {
  if (!std::filesystem::is_regular_file(path))
    throw std::runtime_error("image '" + path + "' does not exist");
  cv::Mat image;
  try {
    image = cv::imread(path, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw std::runtime_error("image '" + path + "' cannot be decoded: " + e.err);
  }
  if (image.empty()) throw std::runtime_error("image '" + path + "' is corrupt or not an image");
  if (image.channels() != 1 || (image.depth() != CV_8U && image.depth() != CV_16U))
    throw std::runtime_error("image '" + path + "' must be 8- or 16-bit grey (one channel), not " +
                             std::to_string(image.channels()) + " channel(s) of depth " +
                             std::to_string(image.depth()));
  return image;
}

void writeImage(const std::string& path, const cv::Mat& image) {
  if (!cv::imwrite(path, image)) throw std::runtime_error("cannot write image '" + path + "'");
}

void addReferenceOptions(cli::ArgParser& args) {
  args.option("calibration", "", "calibration file from multislit calibrate");
  args.option("reference", "", "reference image of the floor (instead of --calibration)");
  args.option("sensor", "", "sensor YAML; its mount is the reference pose (default: the paper's)");
}

Reference referenceFromArgs(const cli::ArgParser& args) {
  if (args.has("calibration")) return Reference::load(args.str("calibration"));
  if (!args.has("reference")) throw cli::UsageError("give --calibration FILE or --reference IMAGE");
  const SensorConfig sensor =
      args.has("sensor") ? SensorConfig::load(args.str("sensor")) : SensorConfig{};
  const std::string path = args.str("reference");
  Reference ref;
  try {
    ref = Reference::fromImage(readMonoImage(path));
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

Estimator parseEstimator(const std::string& name) {
  if (name == "gaussian") return Estimator::Gaussian;
  if (name == "centroid") return Estimator::Centroid;
  if (name == "windowed") return Estimator::Windowed;
  throw cli::UsageError("--estimator must be gaussian, centroid or windowed, not '" + name + "'");
}

}  // namespace multislit::apps
