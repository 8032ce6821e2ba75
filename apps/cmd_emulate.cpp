// multislit emulate: a GigE Vision camera on 127.0.0.1 serving the simulator's images of a walk.
#include "cli.h"
#include "commands.h"
#include "common.h"
#include "config_options.h"
#include "output_file.h"

#include "multislit/sim/camera_emulator.h"
#include "multislit/sim/scenarios.h"
#include "multislit/sim/simulator.h"
#include "multislit/sim/walk.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace multislit::apps {
namespace {

// --serial, --fps, --loss, --ptp and --clock-offset; a value out of range is a usage error.
EmulatorConfig emulatorConfigFromArgs(const cli::ArgParser& args) {
  EmulatorConfig config;
  config.serial = args.str("serial");
  config.fps = args.number("fps");
  config.lost_packet_ratio = args.number("loss");
  config.ptp = args.has("ptp");
  config.clock_offset_s = args.number("clock-offset");
  validateOptions(config, args,
                  {{"lost_packet_ratio", "loss"}, {"clock_offset_s", "clock-offset"}});
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

// The images the live walk keeps ready (--ahead), at most what 2 GiB hold.
std::size_t aheadLimit(const SensorConfig& sensor, int bit_depth) {
  const double bytes =
      static_cast<double>(sensor.camera.width) * sensor.camera.height * bit_depth / 8;
  return std::max(CameraEmulator::kDefaultAhead,
                  static_cast<std::size_t>(std::floor(2.0 * (1 << 30) / bytes)));
}

constexpr std::size_t kTimed = 5;  // images timed by --ahead auto

// --ahead auto: enough images that the demo's walk (kWalkFrames) comes at `fps` without a late
// one, from the time the first images took to make, half as many again to spare (a client on the
// same machine slows the making: map --camera, by a fifth on 2 cores), at most the
// walk; CameraEmulator::kDefaultAhead when the making keeps up.
std::size_t autoAhead(const CameraEmulator& camera, double fps, std::size_t limit) {
  const auto start = std::chrono::steady_clock::now();
  const std::uint64_t first = camera.imagesMade();
  while (camera.imagesMade() < first + kTimed && camera.lastError().empty() &&
         !StopSignal::requested())
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  const double made_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() /
      static_cast<double>(kTimed);
  const double short_by = std::max(0.0, 1.0 - 1.0 / (fps * made_s));  // per frame sent
  const auto ahead = static_cast<std::size_t>(
      std::min(std::ceil(1.5 * kWalkFrames * short_by), static_cast<double>(kWalkFrames)) +
      CameraEmulator::kDefaultAhead);
  const std::streamsize precision = std::cout.precision();
  std::cout << std::fixed << std::setprecision(1) << "an image takes " << 1e3 * made_s
            << " ms to make, the camera sends one every " << 1e3 / fps << " ms: " << ahead
            << " images ahead for the walk's " << kWalkFrames << " frames";
  std::cout.unsetf(std::ios::floatfield);
  std::cout.precision(precision);  // the fps and seconds printed later keep their digits
  if (ahead > limit) std::cout << " (only " << limit << " fit in 2 GiB)";
  std::cout << "\n" << std::flush;
  return std::min(ahead, limit);
}

// Waits until `ahead` images are ready, a client streams, the making stops or Ctrl-C.
void makeAhead(const CameraEmulator& camera, std::size_t ahead) {
  cli::Progress progress(ahead, "render ahead");
  while (camera.imagesReady() < ahead && camera.framesServed() == 0 && camera.lastError().empty() &&
         !StopSignal::requested()) {
    progress.update(camera.imagesReady());
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  progress.finish();
  std::cout << camera.imagesReady() << " images ready\n" << std::flush;
}

// The camera: the demo's walk rendered live (--walk), or a scenario's frames rendered first.
// `what` receives what it serves.
std::unique_ptr<CameraEmulator> makeCamera(const cli::ArgParser& args, const SensorConfig& sensor,
                                           const RenderConfig& render, const EmulatorConfig& config,
                                           long frames, std::size_t ahead, std::string* what) {
  if (args.has("walk")) {
    *what = "the demo's walk, rendered live,";
    const cv::Size size(sensor.camera.width, sensor.camera.height);
    return std::make_unique<CameraEmulator>(
        liveWalk(sensor, render), size, render.bit_depth == 8 ? CV_8UC1 : CV_16UC1, config, ahead);
  }
  const Scenario scenario = makeScenario(args.str("scenario"));
  *what = std::to_string(frames) + " frames of scenario " + scenario.name + " in turn";
  return std::make_unique<CameraEmulator>(renderWalk(Simulator(sensor, render), scenario, frames),
                                          config);
}

void addOptions(cli::ArgParser& args) {
  args.option("scenario", "ball", "named scenario whose walk is filmed");
  args.option("frames", "16", "walk frames rendered beforehand and served in turn");
  const EmulatorConfig emulator;
  const RenderConfig render;
  args.option("fps", defaultText(emulator.fps), "frame rate until a client sets its own [Hz]");
  args.option("seconds", "0", "serve this long [s]; 0: until interrupted");
  args.option("serial", emulator.serial, "device serial number");
  args.option("loss", defaultText(emulator.lost_packet_ratio),
              "fraction of stream packets not sent, to test lossy links");
  args.option("bit-depth", defaultText(render.bit_depth),
              "the images' bits, 8 or 16; a client may ask Mono8, Mono12 or Mono16 of them");
  args.flag("ptp",
            "announce a clock synchronized by PTP (PtpEnable on, PtpStatus Slave): clients stamp "
            "frames with the camera's clock");
  args.option("clock-offset", defaultText(emulator.clock_offset_s),
              "the camera clock's lead over the host's UTC clock [s]; with --ptp, 37 makes a PTP "
              "clock on TAI");
  args.option("seed", std::to_string(render.seed), "noise seed");
  args.option("sensor", "",
              std::string("sensor YAML (default: the paper's sensor)") + kRenderMemory);
  args.flag("no-noise", "render without speckle, shot and read noise");
  args.flag("walk",
            "serve the demo's walk (multislit walk) rendered live as the camera sends, instead "
            "of a scenario's frames rendered first; a frame not rendered in time carries the "
            "last image again and is counted");
  args.option("ahead", std::to_string(CameraEmulator::kDefaultAhead),
              "with --walk: images made ahead and kept ready, made while no client streams (the "
              "command waits for them); auto: enough that the demo's walk of " +
                  std::to_string(kWalkFrames) +
                  " frames comes at --fps without a late frame, from the time the first images "
                  "take");
}

// --ahead for the live walk: the images to make before serving (auto: measured), made.
void renderAhead(CameraEmulator& camera, bool automatic, std::size_t ahead, double fps,
                 std::size_t limit) {
  if (automatic) {
    ahead = autoAhead(camera, fps, limit);
    camera.setImagesAhead(ahead);
  }
  if (ahead > CameraEmulator::kDefaultAhead) makeAhead(camera, ahead);
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
  addOptions(args);
  if (!args.parse(argc, argv)) return 0;

  const long frames = args.integer("frames", 1, 100000);
  const double seconds = args.number("seconds", 0, 1e9);
  const EmulatorConfig config = emulatorConfigFromArgs(args);
  const bool live = args.has("walk");
  const bool auto_ahead = args.str("ahead") == "auto";
  if (args.given("ahead") && !live)
    throw cli::UsageError("--ahead needs --walk: a scenario's frames are all made before serving");

  RenderConfig render;
  render.seed = static_cast<uint64_t>(args.integer("seed", 0, std::numeric_limits<long>::max()));
  render.bit_depth = static_cast<int>(args.integer("bit-depth", 8, 16));
  render.noise = !args.has("no-noise");
  const SensorConfig sensor =
      args.has("sensor") ? SensorConfig::load(args.str("sensor")) : SensorConfig{};
  const std::size_t limit = aheadLimit(sensor, render.bit_depth);
  // auto: room for the images it times while no client streams
  const std::size_t ahead =
      auto_ahead ? kTimed + 1 : static_cast<std::size_t>(args.integer("ahead", 1, 100000));
  if (ahead > limit)
    throw cli::UsageError("--ahead " + std::to_string(ahead) + ": at most " +
                          std::to_string(limit) + " images of this size fit in 2 GiB");
  std::string what;
  const std::unique_ptr<CameraEmulator> camera =
      makeCamera(args, sensor, render, config, frames, ahead, &what);
  const StopSignal stop;  // Ctrl-C and SIGTERM end the serving
  std::cout << "GigE Vision camera " << CameraEmulator::kAddress << " (serial " << config.serial
            << "): " << sensor.camera.width << "x" << sensor.camera.height << " Mono"
            << render.bit_depth << ", " << what << " at " << config.fps << " Hz"
            << (config.ptp ? ", PTP clock" : "");
  if (config.clock_offset_s != 0) std::cout << " " << config.clock_offset_s << " s ahead of UTC";
  std::cout << "; ";
  if (seconds > 0)
    std::cout << "for " << seconds << " s\n" << std::flush;
  else
    std::cout << "Ctrl-C stops\n" << std::flush;
  if (live) renderAhead(*camera, auto_ahead, ahead, config.fps, limit);

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
