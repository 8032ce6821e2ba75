// multislit rdmap: images to relative disparity maps as PCD files.
#include "cli.h"
#include "commands.h"
#include "common.h"
#include "output_file.h"

#include "multislit/extractor.h"

#include <pcl/common/transforms.h>
#include <pcl/io/pcd_io.h>

#include <cstdio>
#include <filesystem>

namespace multislit::apps {

namespace {

// Where each cloud goes: IMAGE.pcd, --out, or --out/IMAGE.pcd. None may replace an input (an
// image, the calibration, the sensor file), nor two be the same file.
std::vector<std::filesystem::path> outputTargets(const cli::ArgParser& args, bool to_folder) {
  const std::vector<std::string>& images = args.rest();
  const std::filesystem::path out = args.str("out");
  std::vector<std::filesystem::path> targets;
  for (const std::string& image : images) {
    std::filesystem::path target = image;
    target.replace_extension(".pcd");
    if (to_folder && !out.empty())
      target = out / target.filename();
    else if (!out.empty())
      target = out;
    targets.push_back(target);
  }
  refuseSameOutputTwice(targets, images);
  std::vector<NamedInput> inputs = inputsOf(args, {"calibration", "sensor", "intrinsics"});
  for (const std::string& image : images) inputs.push_back({"", image});
  for (const auto& target : targets) refuseOverwritingInputs(target, inputs);
  return targets;
}

}  // namespace

int runRdmap(int argc, char** argv) {
  cli::ArgParser args(
      "rdmap",
      "Measures the relative disparity map (Sec. III-A) of each image and writes it as an\n"
      "organized PCD cloud (fields x y z u v dk slit: one row per slit, NaN where nothing was\n"
      "measured) that pcl_viewer and pcl::io::loadPCDFile read.");
  args.option("calibration", "", "calibration file from multislit calibrate (required)");
  addExtractorOptions(args);
  args.option("sensor", "", "sensor YAML whose mount places the sensor on the robot");
  addIntrinsicsOption(args);
  args.flag("robot-frame",
            "x, y, z in the robot frame (x forward, y left, z up) instead of the camera's");
  args.option("out", "", "PCD file (one image) or folder (several images); default: IMAGE.pcd");
  args.positionals("IMAGE...", "8- or 16-bit images taken with the calibrated sensor", 1);
  if (!args.parse(argc, argv)) return 0;
  if (!args.has("calibration")) throw cli::UsageError("--calibration is required");

  ExtractorConfig ec = extractorConfigFromArgs(args);
  const bool robot = args.has("robot-frame");
  if (robot) ec.frame_id = "multislit_robot";
  Reference reference = Reference::load(args.str("calibration"));
  checkIntrinsicsOf(reference, args, "calibration '" + args.str("calibration") + "'");
  const Extractor extractor(std::move(reference), ec);
  const SensorConfig sensor = sensorFromArgs(args);
  const Eigen::Affine3f robot_from_camera = SensorGeometry(sensor).robotFromCamera().cast<float>();
  const std::vector<std::string>& images = args.rest();
  const std::filesystem::path out = args.str("out");
  const bool to_folder = images.size() > 1 || (!out.empty() && std::filesystem::is_directory(out));
  const std::vector<std::filesystem::path> targets = outputTargets(args, to_folder);
  if (to_folder && !out.empty()) std::filesystem::create_directories(out);

  const StopSignal stop;
  cli::Progress progress(images.size(), "rdmap");
  for (std::size_t i = 0; i < images.size() && !StopSignal::requested(); ++i) {
    const std::filesystem::path in = images[i];
    const Reference& ref = extractor.reference();
    const cv::Mat image = readMonoImage(in.string(), cv::Size(ref.image_width, ref.image_height));
    pcl::PointCloud<PointRDM> cloud;
    ExtractionStats stats;
    try {
      stats = extractor.extract(image, cloud);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(in.string() + ": " + e.what());
    }
    cloud.header.frame_id = ec.frame_id;
    cloud.header.seq = static_cast<std::uint32_t>(i);
    if (robot) pcl::transformPointCloud(cloud, cloud, robot_from_camera);
    const std::filesystem::path& target = targets[i];
    OutputFile file(target);  // whole or absent
    file.stream().close();
    if (pcl::io::savePCDFileBinary(file.temporaryPath().string(), cloud) != 0)
      throw std::runtime_error("cannot write '" + target.string() + "'");
    file.commit();
    if (images.size() <= 20)
      std::printf("%s: %zu of %zu points -> %s\n", in.string().c_str(), stats.valid,
                  stats.reference_points, target.string().c_str());
    progress.update(i + 1);
  }
  return StopSignal::requested() ? kInterruptedExit : 0;
}

}  // namespace multislit::apps
