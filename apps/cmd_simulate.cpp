// multislit simulate: a reference image and a sequence of a named scenario, with ground truth.
#include "cli.h"
#include "commands.h"
#include "common.h"
#include "config_options.h"
#include "output_file.h"
#include "photometry_input.h"

#include "multislit/odometry.h"
#include "multislit/sim/photometry.h"
#include "multislit/sim/scenarios.h"
#include "multislit/sim/simulator.h"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>

namespace multislit::apps {
namespace {

// The names separated by commas, a new line before a line grows past 78 characters.
std::string joined(const std::vector<std::string>& names, std::size_t first_line = 0) {
  std::string s;
  std::size_t line = first_line;
  for (const std::string& n : names) {
    const std::string sep = s.empty() ? "" : line + n.size() + 2 > 78 ? ",\n" : ", ";
    line = sep == ",\n" ? n.size() : line + sep.size() + n.size();
    s += sep + n;
  }
  return s;
}

std::vector<std::string> photometryChoices() {
  std::vector<std::string> names = photometryPresetNames();
  names.push_back("random (drawn from --seed)");
  return names;
}

void addSimulateOptions(cli::ArgParser& args) {
  args.option("scenario", "reference", "named scenario (scene, pose and motion)");
  args.option("scene", "", "scene YAML replacing the scenario's objects and floor");
  args.option(
      "sensor", "",
      std::string("sensor YAML (default: the paper's sensor, data/sensor.yaml)") + kRenderMemory);
  args.option("frames", "10", "number of sequence frames");
  args.option("fps", "30", "frame rate for the time stamps [Hz]");
  args.option("seed", "",
              "noise seed (and random photometry; default 1, or the photometry.yaml's); the "
              "same seed gives the same bytes");
  args.option("photometry", "",
              "preset, random or YAML: light, speckle, stripes, floor, objects, lens");
  args.option("bit-depth", "", "8 or 16 bits per pixel (default 8, or the photometry's)");
  args.option("distortion", "",
              "k1,k2,p1,p2[,k3[,k4,k5,k6]]: render through a lens with OpenCV's distortion "
              "coefficients (replacing the sensor file's; written to sensor.yaml)");
  args.option("tilt", "", "override the pose's theta [deg]");
  args.option("roll", "", "override the pose's phi [deg]");
  args.option("height", "", "override the pose's h [m]");
  args.option("step", "", "override the robot's advance per frame [m]");
  args.option("wall-depth", "", "scenario wall: the wall's distance along the optical axis [m]");
  args.option("out", "out/simulate", "output folder");
  args.flag("no-noise", "render without speckle, shot and read noise");
  args.flag("no-reference", "skip the reference image");
}

// --distortion's coefficients, checked as the sensor file's would be.
LensDistortion distortionFromArgs(const cli::ArgParser& args, SensorConfig sensor) {
  const std::string text = args.str("distortion");
  std::vector<double> numbers;
  std::size_t begin = 0;
  while (begin <= text.size()) {
    const std::size_t end = std::min(text.find(',', begin), text.size());
    const std::string item = text.substr(begin, end - begin);
    char* stop = nullptr;
    numbers.push_back(std::strtod(item.c_str(), &stop));
    if (item.empty() || *stop != '\0')
      throw cli::UsageError("--distortion takes numbers separated by commas, not '" + text + "'");
    begin = end + 1;
  }
  try {
    sensor.camera.distortion = LensDistortion::fromOpenCV(numbers);
    sensor.validate();
  } catch (const std::invalid_argument& e) {
    throw cli::UsageError(std::string("--distortion ") + e.what());
  }
  return sensor.camera.distortion;
}

// --scenario or --wall-depth, with --scene and the pose's overrides.
Scenario scenarioFromArgs(const cli::ArgParser& args) {
  Scenario scenario = args.has("wall-depth") ? makeWallScenario(args.number("wall-depth", 0.05, 10))
                                             : makeScenario(args.str("scenario"));
  if (args.has("scene")) scenario.scene = Scene::load(args.str("scene"));
  if (args.has("tilt")) scenario.mount.tilt = args.number("tilt");
  if (args.has("roll")) scenario.mount.roll = args.number("roll");
  if (args.has("height")) scenario.mount.height = args.number("height");
  if (args.has("step")) scenario.step = args.number("step", -1, 1);  // a walk's step: within 1 m
  SensorConfig pose;  // the mount's ranges are SensorConfig::validate()'s
  pose.mount = scenario.mount;
  validateOptions(pose, args);
  return scenario;
}

// The photometry as rendered: floor and object surfaces into `scene`, the rest (with --seed,
// --bit-depth and --no-noise) into its render config. Without --photometry the scene (and a
// --scene file) keeps its own surfaces.
Photometry photometryFromArgs(const cli::ArgParser& args, uint64_t seed, Scene& scene) {
  Photometry photometry;
  photometry.floor = scene.floor;
  if (args.has("photometry")) {
    photometry = choosePhotometry(args.str("photometry"), seed);
    applyPhotometry(photometry, scene);
  }
  RenderConfig& render = photometry.render;
  if (args.has("seed") || !args.has("photometry")) render.seed = seed;
  if (args.has("bit-depth")) render.bit_depth = static_cast<int>(args.integer("bit-depth", 8, 16));
  render.noise = render.noise && !args.has("no-noise");
  return photometry;
}

/// The ground truth of a frame, whole or absent.
void writeGroundTruth(const std::filesystem::path& path, const std::vector<SlitCrossing>& truth,
                      const Scene& scene) {
  writeWhole(path, [&](const std::string& p) { writeGroundTruthCsv(p, truth, scene); });
}

// The sequence: frame_NNNNNN.png and .csv (ground truth) per frame, frames.csv (index and
// poses) and odometry.csv in `out`. Returns the number of slit crossings in all frames.
/// The sequence's frames, ground truth, frames.csv and odometry.csv; Ctrl-C ends it after a whole
/// frame, with both index files listing exactly the frames written. Returns the crossings.
std::size_t writeSequence(const Simulator& sim, const Scenario& scenario, long frames, double fps,
                          const std::filesystem::path& out) {
  OutputFile index_file(out / "frames.csv");
  std::ofstream& index = index_file.stream();
  index << "frame,file,stamp_us,robot_x,camera_x,camera_y,camera_z,tilt,roll,height\n";
  const auto stamp0 = std::chrono::duration_cast<std::chrono::microseconds>(
                          std::chrono::system_clock::now().time_since_epoch())
                          .count();
  cli::Progress progress(static_cast<std::size_t>(frames), "simulate");
  std::size_t crossings = 0;
  std::vector<OdometrySample> odometry;  // the robot at each frame's stamp (multislit map)
  for (long k = 0; k < frames && !StopSignal::requested(); ++k) {
    const auto frame = static_cast<uint64_t>(k);
    const Eigen::Isometry3d world_from_camera =
        scenario.worldFromRobot(frame) * sim.geometry().robotFromCamera(scenario.mount);
    const RenderedFrame f = sim.render(scenario.scene, world_from_camera, frame);
    char name[32];
    std::snprintf(name, sizeof name, "frame_%06ld", k);
    writeImage((out / (std::string(name) + ".png")).string(), f.image);
    writeGroundTruth(out / (std::string(name) + ".csv"), f.truth, scenario.scene);
    crossings += f.truth.size();
    const Eigen::Vector3d c = world_from_camera.translation();
    const auto stamp = static_cast<std::uint64_t>(stamp0 + static_cast<long long>(k * 1e6 / fps));
    odometry.push_back({stamp, scenario.worldFromRobot(frame)});
    index << k << ',' << name << ".png," << stamp << ','
          << scenario.worldFromRobot(frame).translation().x() << ',' << c.x() << ',' << c.y() << ','
          << c.z() << ',' << scenario.mount.tilt << ',' << scenario.mount.roll << ','
          << scenario.mount.height << '\n';
    progress.update(static_cast<std::size_t>(k + 1));
  }
  progress.finish();
  index_file.commit();
  if (!odometry.empty()) writeOdometry(out / "odometry.csv", odometry);
  return crossings;
}

// What was written, and how fast.
void printSummary(const Scenario& scenario, const Photometry& photometry,
                  const std::filesystem::path& out, long images, long frames, std::size_t crossings,
                  double seconds) {
  std::cout << "scenario " << scenario.name << ": " << scenario.description << "\n"
            << "photometry " << photometry.name << " (" << (out / "photometry.yaml").string()
            << ")\n"
            << "wrote " << images << " images to " << out.string() << " ("
            << (images > 0 ? 1000.0 * seconds / static_cast<double>(images) : 0.0)
            << " ms per image)";
  if (frames > 0)
    std::cout << ", " << crossings / static_cast<std::size_t>(frames)
              << " slit crossings per frame";
  std::cout << "\n  reference: " << (out / "reference.png").string() << " (+ .csv ground truth)\n"
            << "  sequence:  " << (out / "frame_*.png").string() << ", index in "
            << (out / "frames.csv").string() << ", poses in " << (out / "odometry.csv").string()
            << "\n";
}

}  // namespace

int runSimulate(int argc, char** argv) {
  cli::ArgParser args("simulate",
                      "Renders the reference image (the bare floor at the reference pose) and a\n"
                      "sequence of a scenario, each image with its ground truth (CSV: for every\n"
                      "slit and row, the exact slit centre, 3D point, object and height).\n"
                      "Scenarios: " +
                          joined(scenarioNames()) +
                          "\nPhotometries (--photometry): " + joined(photometryChoices(), 29) +
                          "\nor the photometry.yaml of an earlier run");
  addSimulateOptions(args);
  if (!args.parse(argc, argv)) return 0;
  const StopSignal stop;  // Ctrl-C: the sequence ends after a whole frame

  Scenario scenario = scenarioFromArgs(args);
  SensorConfig sensor =
      args.has("sensor") ? SensorConfig::load(args.str("sensor")) : SensorConfig{};
  if (args.has("distortion")) sensor.camera.distortion = distortionFromArgs(args, sensor);
  const auto seed =
      args.has("seed")
          ? static_cast<uint64_t>(args.integer("seed", 0, std::numeric_limits<long>::max()))
          : 1u;
  const Photometry photometry = photometryFromArgs(args, seed, scenario.scene);
  // The photometry's lens, unless --distortion names one.
  if (photometry.distortion.any() && !args.has("distortion"))
    sensor.camera.distortion = photometry.distortion;
  const long frames = args.integer("frames", 0, 10000000);
  const double fps = args.number("fps", 0.01, 100000);
  SensorConfig used = sensor;
  used.mount = scenario.mount;
  used.validate();  // the sensor.yaml written below is one SensorConfig::load() takes

  const std::filesystem::path out = args.str("out");
  const std::vector<NamedInput> inputs = inputsWithPhotometry(args, {"sensor", "scene"});
  refuseOutputFolder(out, "--out",
                     {"sensor.yaml", "scene.yaml", "photometry.yaml", "reference.png",
                      "reference.csv", "frames.csv", "odometry.csv"},
                     inputs);
  std::filesystem::create_directories(out);
  const Simulator sim(sensor, photometry.render);
  writeWhole(
      out / "sensor.yaml", [&used](const std::string& p) { used.save(p); },
      [](const std::string& p) { SensorConfig::load(p); });
  writeWhole(
      out / "scene.yaml", [&scenario](const std::string& p) { scenario.scene.save(p); },
      [](const std::string& p) { Scene::load(p); });
  writeWhole(
      out / "photometry.yaml",
      [&photometry](const std::string& p) { savePhotometry(photometry, p); },
      [](const std::string& p) { loadPhotometry(p); });

  const auto t0 = std::chrono::steady_clock::now();
  if (!args.has("no-reference")) {
    // The reference: the bare floor, seen from the reference pose (Sec. II-C, Fig. 8).
    const Scene floor_only{scenario.scene.floor, {}};
    const RenderedFrame ref = sim.renderReference(floor_only, scenario.reference_mount);
    writeImage((out / "reference.png").string(), ref.image);
    writeGroundTruth(out / "reference.csv", ref.truth, floor_only);
  }
  const std::size_t crossings = writeSequence(sim, scenario, frames, fps, out);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  printSummary(scenario, photometry, out, frames + (args.has("no-reference") ? 0 : 1), frames,
               crossings, seconds);
  if (StopSignal::requested()) std::cout << "interrupted (Ctrl-C): the frames above are whole\n";
  return StopSignal::requested() ? kInterruptedExit : 0;
}

}  // namespace multislit::apps
