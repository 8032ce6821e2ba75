// Helpers shared by the multislit subcommands.
#pragma once

#include "cli.h"
#include "output_file.h"

#include "multislit/extractor.h"
#include "multislit/image_file.h"  // readMonoImage
#include "multislit/reference.h"
#include "multislit/slit_profile.h"

#include <opencv2/core/mat.hpp>

#include <initializer_list>
#include <string>
#include <vector>

namespace multislit::apps {

void writeImage(const std::string& path, const cv::Mat& image);

/// The files and folders given by `options` (every value of a repeatable one), each named by its
/// option, for refuseOverwritingInputs() and refuseOutputFolder(); options not given are left out.
std::vector<NamedInput> inputsOf(const cli::ArgParser& args,
                                 std::initializer_list<const char*> options);

/// The simulator's peak memory by the size of its camera, measured (1296x964: 181 MB, 2592x1928:
/// 368 MB), for the --sensor help of the commands that render.
inline constexpr const char* kRenderMemory =
    "; rendering takes about 120 MB and 50 bytes a pixel of its camera: 180 MB at 1296x964, "
    "3.4 GB at 8192x8192, 13.5 GB at 16384x16384";
/// "gaussian", "centroid" or "windowed"; throws cli::UsageError otherwise.
Estimator parseEstimator(const std::string& name);
/// The command line's name of an estimator, as parseEstimator() reads it.
std::string estimatorName(Estimator estimator);
/// Declares --estimator and --along-row, how a command measures a slit's centre in frames.
void addExtractorOptions(cli::ArgParser& args);
/// The extractor config of those options.
ExtractorConfig extractorConfigFromArgs(const cli::ArgParser& args);

/// Declares --intrinsics: the camera's calibration file (OpenCV or ROS camera_info YAML).
void addIntrinsicsOption(cli::ArgParser& args);
/// The --sensor file (default: the paper's sensor) with --intrinsics, when given, applied to its
/// camera (withIntrinsicsFile).
SensorConfig sensorFromArgs(const cli::ArgParser& args);
/// Throws unless --intrinsics, when given, is the lens `reference` was made with (what: names it).
void checkIntrinsicsOf(const Reference& reference, const cli::ArgParser& args,
                       const std::string& what);

/// Declares --calibration, --reference, --sensor, --intrinsics and --full-scale, the ways a
/// command gets its reference.
void addReferenceOptions(cli::ArgParser& args);
/// Declares --full-scale: `whose` white, with `note` on where the value goes.
void addFullScaleOption(cli::ArgParser& args, const std::string& whose, const std::string& note);
/// --full-scale's value [DN], checked to lie in [0, 65535].
double fullScaleFromArgs(const cli::ArgParser& args);
/// The calibration file when given (checked against --intrinsics), else the slits of the
/// reference image with the sensor model's scale and lens (the reference pose is the mount of
/// --sensor, the lens --intrinsics').
Reference referenceFromArgs(const cli::ArgParser& args);

/// A string as a JSON string literal, quotes included.
std::string jsonString(const std::string& s);

}  // namespace multislit::apps
