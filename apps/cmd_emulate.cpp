// multislit emulate: a GigE Vision camera on 127.0.0.1 serving the simulator's images of a walk.
#include "cli.h"
#include "commands.h"
#include "output_file.h"

#include "multislit/sim/camera_emulator.h"
#include "multislit/sim/scenarios.h"
#include "multislit/sim/simulator.h"
#include "multislit/sim/walk.h"

#include <chrono>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <thread>
#include <vector>

namespace multislit::apps {
namespace {

// --serial, --fps and --loss; a value out of range is a usage error.
EmulatorConfig emulatorConfigFromArgs(const cli::ArgParser& args) {
  EmulatorConfig config;
  config.serial = args.str("serial");
  config.fps = args.number("fps");
  config.lost_packet_ratio = args.number("loss");
  try {
    config.validate();
  } catch (const std::invalid_argument& e) {
    throw cli::UsageError(e.what());
  }
  return config;
}

// The first `frames` frames of the scenario's walk, rendered once (rendering is far slower than
// serving).
std::vector<cv::Mat> renderWalk(const Simulator& sim, const Scenario& scenario, long frames) {
  std::vector<cv::Mat> images;
  cli::Progress progress(static_cast<std::size_t>(frames), "render");
  for (long k = 0; k < frames; ++k) {
    const auto frame = static_cast<uint64_t>(k);
    const Eigen::Isometry3d world_from_camera =
        scenario.worldFromRobot(frame) * sim.geometry().robotFromCamera(scenario.mount);
    images.push_back(sim.render(scenario.scene, world_from_camera, frame).image);
    progress.update(static_cast<std::size_t>(k + 1));
  }
  progress.finish();
  return images;
}

// Serves until interrupted or, when `seconds` > 0, for `seconds` from `start`; reports the frames
// served every 5 s, and for live images those sent late (the last image again) and made.
void serve(const CameraEmulator& camera, std::chrono::steady_clock::time_point start,
           double seconds, bool live) {
  auto report = start;
  std::uint64_t reported = 0;
  for (;;) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    const auto now = std::chrono::steady_clock::now();
    if (StopSignal::requested() ||
        (seconds > 0 && now - start >= std::chrono::duration<double>(seconds)))
      break;
    if (live && !camera.lastError().empty())
      throw std::runtime_error("the live walk stopped: " + camera.lastError());
    if (now - report >= std::chrono::seconds(5)) {
      const std::uint64_t served = camera.framesServed();
      std::cout << "served " << served << " frames ("
                << static_cast<double>(served - reported) /
                       std::chrono::duration<double>(now - report).count()
                << " fps)";
      if (live)
        std::cout << ", " << camera.imagesMade() << " rendered, " << camera.framesLate()
                  << " sent late (the last image again)";
      std::cout << "\n" << std::flush;
      report = now;
      reported = served;
    }
  }
}

// The demo's walk (multislit walk: floor, ball, cable, the robot walking as its decisions say)
// rendered as the camera asks for it: each call the next frame's image.
CameraEmulator::ImageMaker liveWalk(const SensorConfig& sensor, const RenderConfig& render) {
  WalkConfig config;
  config.pipeline.sensor = sensor;
  config.render_config = render;
  auto walk = std::make_shared<WalkSimulation>(config);
  return [walk] { return walk->step().image; };
}

// The camera: the demo's walk rendered live (--walk), or a scenario's frames rendered first.
// `what` receives what it serves.
std::unique_ptr<CameraEmulator> makeCamera(const cli::ArgParser& args, const SensorConfig& sensor,
                                           const RenderConfig& render, const EmulatorConfig& config,
                                           long frames, std::string* what) {
  if (args.has("walk")) {
    *what = "the demo's walk, rendered live,";
    const cv::Size size(sensor.camera.width, sensor.camera.height);
    return std::make_unique<CameraEmulator>(liveWalk(sensor, render), size,
                                            render.bit_depth == 8 ? CV_8UC1 : CV_16UC1, config);
  }
  const Scenario scenario = makeScenario(args.str("scenario"));
  *what = std::to_string(frames) + " frames of scenario " + scenario.name + " in turn";
  return std::make_unique<CameraEmulator>(renderWalk(Simulator(sensor, render), scenario, frames),
                                          config);
}

}  // namespace

int runEmulate(int argc, char** argv) {
  cli::ArgParser args(
      "emulate",
      "Serves the simulator's images of a walk as a GigE Vision camera on 127.0.0.1 (Aravis's\n"
      "fake camera, GVCP port 3956) until interrupted (Ctrl-C) or for --seconds: a scenario's\n"
      "frames rendered first and served in turn, or with --walk the demo's walk rendered as\n"
      "the camera sends it. Open the camera by its address, e.g.\n"
      "multislit_grabber_example --camera 127.0.0.1 --calibration FILE. A client's\n"
      "AcquisitionFrameRate replaces --fps.");
  args.option("scenario", "ball", "named scenario whose walk is filmed");
  args.option("frames", "16", "walk frames rendered beforehand and served in turn");
  args.option("fps", "30", "frame rate until a client sets its own [Hz]");
  args.option("seconds", "0", "serve this long [s]; 0: until interrupted");
  args.option("serial", "MULTISLIT", "device serial number");
  args.option("loss", "0", "fraction of stream packets not sent, to test lossy links");
  args.option("bit-depth", "8", "8 (Mono8) or 16 (Mono16)");
  args.option("seed", "1", "noise seed");
  args.option("sensor", "", "sensor YAML (default: the paper's sensor)");
  args.flag("no-noise", "render without speckle, shot and read noise");
  args.flag("walk",
            "serve the demo's walk (multislit walk) rendered live as the camera sends, instead "
            "of a scenario's frames rendered first; a frame not rendered in time carries the "
            "last image again and is counted");
  if (!args.parse(argc, argv)) return 0;

  const long frames = args.integer("frames", 1, 100000);
  const double seconds = args.number("seconds", 0, 1e9);
  const EmulatorConfig config = emulatorConfigFromArgs(args);
  const bool live = args.has("walk");

  RenderConfig render;
  render.seed = static_cast<uint64_t>(args.integer("seed"));
  render.bit_depth = static_cast<int>(args.integer("bit-depth"));
  render.noise = !args.has("no-noise");
  const SensorConfig sensor =
      args.has("sensor") ? SensorConfig::load(args.str("sensor")) : SensorConfig{};
  std::string what;
  const std::unique_ptr<CameraEmulator> camera =
      makeCamera(args, sensor, render, config, frames, &what);
  const StopSignal stop;  // Ctrl-C and SIGTERM end the serving
  std::cout << "GigE Vision camera " << CameraEmulator::kAddress << " (serial " << config.serial
            << "): " << sensor.camera.width << "x" << sensor.camera.height << " Mono"
            << render.bit_depth << ", " << what << " at " << config.fps << " Hz; ";
  if (seconds > 0)
    std::cout << "for " << seconds << " s\n" << std::flush;
  else
    std::cout << "Ctrl-C stops\n" << std::flush;

  const auto start = std::chrono::steady_clock::now();
  serve(*camera, start, seconds, live);
  std::cout << "served " << camera->framesServed() << " frames in "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()
            << " s";
  if (live)
    std::cout << "; " << camera->imagesMade() << " rendered, " << camera->framesLate()
              << " sent late (the last image again)";
  std::cout << "\n";
  return StopSignal::requested() ? kInterruptedExit : 0;
}

}  // namespace multislit::apps
