// The multi-slit sensor in a PCL program, used like any pcl::Grabber. The same program reads a
// GigE Vision camera, recorded images, or the simulator:
//
//   multislit_grabber_example --simulate ball --seconds 10
//   multislit emulate &   multislit_grabber_example --camera 127.0.0.1 --calibration calib.yaml
//   multislit_grabber_example --sequence out/simulate --calibration calib.yaml --save clouds
#include "camera_options.h"
#include "cli.h"
#include "output_file.h"

#include <multislit/grabber.h>
#include <multislit/pipeline.h>
#include <multislit/sim/simulated_source.h>
#include <multislit/sources.h>

#include <pcl/io/pcd_io.h>

#include <atomic>
#include <chrono>
#include <climits>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

namespace {

using multislit::cli::ArgParser;
using multislit::cli::UsageError;

struct Options {
  std::string camera, sequence, scenario, calibration, save_dir;
  double fps = 0.0, seconds = 10.0;
  long frames = 0, packet_size = 0;
  multislit::AravisConfig camera_settings;  // exposure, gain, pixel format, PTP offset
};

void declareOptions(ArgParser& args) {
  args.program("multislit_grabber_example");
  args.option("camera", "", "GigE Vision camera address (e.g. 127.0.0.1 of multislit emulate)");
  args.option("sequence", "", "recorded PNG images (frames.csv of multislit simulate is used)");
  args.option("simulate", "", "the simulator filming a scenario (ball, cable, fig8, ...)");
  args.option("calibration", "",
              "reference of multislit calibrate (built for --simulate); its camera_id is checked");
  args.option("fps", "0", "camera / replay / simulator rate [Hz]; 0: camera 30, else max");
  args.option("packet-size", "0", "GigE Vision packet size [B]; 0: the camera's");
  multislit::apps::addCameraOptions(args);
  args.option("seconds", "10", "run this long [s]");
  args.option("frames", "0", "stop after this many clouds; 0: no limit");
  args.option("save", "", "folder to write every cloud to as binary PCD");
}

// The options, checked; nullopt when --help was asked for (printed). Throws UsageError.
std::optional<Options> parseOptions(ArgParser& args, int argc, char** argv) {
  if (!args.parse(argc - 1, argv + 1)) return std::nullopt;
  Options o;
  o.camera = args.str("camera");
  o.sequence = args.str("sequence");
  o.scenario = args.str("simulate");
  o.calibration = args.str("calibration");
  o.save_dir = args.str("save");
  o.fps = args.number("fps", 0, 1000);
  o.packet_size = args.integer("packet-size", 0, 65535);
  o.seconds = args.number("seconds", 0.001, 1e7);
  o.frames = args.integer("frames", 0, INT_MAX);
  if (!o.camera.empty() + !o.sequence.empty() + !o.scenario.empty() != 1)
    throw UsageError("give one of --camera, --sequence and --simulate");
  if (o.camera.empty()) multislit::apps::refuseCameraOptionsWithoutCamera(args);
  o.camera_settings = multislit::apps::cameraSettingsFromArgs(args);
  if (o.scenario.empty() && o.calibration.empty())
    throw UsageError("--calibration FILE is needed with --camera and --sequence");
  return o;
}

// A frame source, the reference that goes with it and the sensor's mount for the pipeline.
struct Input {
  std::shared_ptr<multislit::FrameSource> source;
  multislit::Reference reference;
  multislit::PipelineConfig pipeline_config;  // the paper's sensor on its nominal mount
};

Input openInput(const Options& o) {
  Input in;
  if (!o.calibration.empty()) in.reference = multislit::Reference::load(o.calibration);
  if (!o.camera.empty()) {
    multislit::AravisConfig config = o.camera_settings;
    config.camera = o.camera;
    config.frame_rate = o.fps > 0 ? o.fps : 30.0;
    config.roi_width = in.reference.image_width;
    config.roi_height = in.reference.image_height;
    config.packet_size = static_cast<int>(o.packet_size);
    config.camera_id = in.reference.camera_id;  // the camera the calibration was taken with
    in.source = std::make_shared<multislit::AravisSource>(config);
  } else if (!o.sequence.empty()) {
    multislit::ImageSequenceConfig config;
    config.folder = o.sequence;
    config.fps = o.fps;
    in.source = std::make_shared<multislit::ImageSequenceSource>(config);
  } else {
    multislit::SimulatorSourceConfig config;
    config.scenario = o.scenario;
    config.fps = o.fps;
    auto simulator = std::make_shared<multislit::SimulatorSource>(config);
    if (o.calibration.empty()) in.reference = simulator->makeReference();
    in.pipeline_config.sensor.mount = simulator->scenario().mount;
    in.source = simulator;
  }
  return in;
}

// What the callbacks saw, read by the main thread.
struct LastCloud {
  std::atomic<int> clouds{0};
  std::atomic<std::size_t> points{0}, groups{0};
  std::atomic<multislit::Command> decision{multislit::Command::Stop};
  std::mutex mutex;
  std::string save_error;  // the first cloud that could not be written (guarded by mutex)
  std::atomic<bool> failed{false};
};

// One cloud as binary PCD in `folder`, written whole or not at all (a full disk throws).
void saveCloud(const pcl::PointCloud<multislit::PointRDM>& cloud, const std::string& folder) {
  char name[64];
  std::snprintf(name, sizeof name, "cloud_%010u.pcd", cloud.header.seq);
  multislit::apps::OutputFile out(std::filesystem::path(folder) / name);
  bool written = false;
  try {
    written = pcl::io::savePCDFileBinary(out.temporaryPath().string(), cloud) == 0;
  } catch (const pcl::PCLException&) {  // PCL said why on stderr
  }
  if (!written)
    throw std::runtime_error("could not write " + out.path().string() + " (disk full?)");
  out.commit();
}

// Prints each change of the source's state, and each new error (from the processing thread).
void printStatus(const multislit::SourceStatus& s, multislit::SourceStatus& said) {
  if (s.connected != said.connected) {
    if (s.connected)
      std::printf("status: %s is back (reconnect %llu)\n", s.source.c_str(),
                  static_cast<unsigned long long>(s.reconnects));
    else
      std::printf("status: %s lost (loss %llu), reopening it\n", s.source.c_str(),
                  static_cast<unsigned long long>(s.losses));
    std::fflush(stdout);
  }
  if (s.error != said.error && !s.error.empty())
    std::fprintf(stderr, "grabber error: %s\n", s.error.c_str());
  said = s;
}

// Waits while the grabber runs, until o.seconds from `begin`, o.frames clouds, a failed save or
// Ctrl-C, with a line of news every second.
void waitForClouds(const multislit::MultiSlitGrabber& grabber, const Options& o,
                   const LastCloud& last, std::size_t reference_points,
                   std::chrono::steady_clock::time_point begin) {
  auto report = begin;
  while (grabber.isRunning() && !last.failed && !multislit::apps::StopSignal::requested() &&
         std::chrono::steady_clock::now() - begin < std::chrono::duration<double>(o.seconds) &&
         (o.frames == 0 || last.clouds < o.frames)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (std::chrono::steady_clock::now() - report >= std::chrono::seconds(1)) {
      report = std::chrono::steady_clock::now();
      std::printf(
          "%d clouds, %.1f fps, %zu of %zu points in the last cloud, %zu obstacle "
          "group(s), decision: %s\n",
          last.clouds.load(), grabber.getFramesPerSecond(), last.points.load(), reference_points,
          last.groups.load(), multislit::commandName(last.decision));
      std::fflush(stdout);
    }
  }
}

void printStats(const multislit::GrabberStats& s, int clouds, double stop_ms) {
  std::printf(
      "%d clouds; received %llu, processed %llu, dropped %llu (busy), bad buffers %llu "
      "(incomplete %llu), reconnects %llu, read errors %llu, extraction errors %llu, source "
      "errors %llu\nlatency from arrival to callback: median %.2f ms, 99th %.2f ms; stop() took "
      "%.1f ms\n",
      clouds, static_cast<unsigned long long>(s.frames_received),
      static_cast<unsigned long long>(s.frames_processed),
      static_cast<unsigned long long>(s.frames_dropped),
      static_cast<unsigned long long>(s.source.bad_buffers),
      static_cast<unsigned long long>(s.source.incomplete),
      static_cast<unsigned long long>(s.source.reconnects),
      static_cast<unsigned long long>(s.source.read_errors),
      static_cast<unsigned long long>(s.extraction_errors),
      static_cast<unsigned long long>(s.source_errors), s.latency_median_ms, s.latency_p99_ms,
      stop_ms);
  if (clouds > 0 && !s.last_error.empty()) std::printf("last error: %s\n", s.last_error.c_str());
}

// The whole run; returns the exit code.
int run(const Options& o) {
  // 1. A frame source and the reference that goes with it.
  const Input in = openInput(o);

  // 2. The grabber and a callback, as with any pcl::Grabber. The callback runs the whole chain
  //    (floor, obstacle groups, map, footsteps, decision) on each cloud, the robot standing
  //    still at the origin; a robot would give its odometry as input.world_from_robot.
  multislit::MultiSlitGrabber grabber(in.source, in.reference);
  multislit::Pipeline pipeline(in.pipeline_config);
  LastCloud last;
  std::function<void(const pcl::PointCloud<multislit::PointRDM>::ConstPtr&)> on_cloud =
      [&](const pcl::PointCloud<multislit::PointRDM>::ConstPtr& cloud) {
        multislit::PipelineInput input;
        input.cloud = cloud;
        const multislit::PipelineResult r = pipeline.process(input);
        last.points = r.floor.valid_points;
        last.groups = r.obstacles.obstacles.size();
        last.decision = r.walker.command;
        if (!o.save_dir.empty() && !last.failed) {
          try {
            saveCloud(*cloud, o.save_dir);
          } catch (const std::exception& e) {  // a full disk: the run ends, and fails
            std::lock_guard<std::mutex> lock(last.mutex);
            last.save_error = e.what();
            last.failed = true;
            return;
          }
        }
        ++last.clouds;
      };
  multislit::SourceStatus said;
  std::function<void(const multislit::SourceStatus&)> on_status =
      [&said](const multislit::SourceStatus& s) { printStatus(s, said); };
  grabber.registerCallback(on_cloud);
  grabber.registerCallback(on_status);
  if (!o.save_dir.empty()) std::filesystem::create_directories(o.save_dir);

  // 3. Run for a while, then stop.
  const multislit::apps::StopSignal ctrl_c;
  const auto begin = std::chrono::steady_clock::now();
  grabber.start();
  std::printf("%s: %s\n", grabber.getName().c_str(), in.source->name().c_str());
  waitForClouds(grabber, o, last, in.reference.pointCount(), begin);
  const auto stopping = std::chrono::steady_clock::now();
  grabber.stop();
  const double stop_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - stopping)
          .count();
  const multislit::GrabberStats stats = grabber.getStats();
  printStats(stats, last.clouds.load(), stop_ms);
  if (last.failed) throw std::runtime_error(last.save_error);
  if (last.clouds == 0 && !stats.last_error.empty())
    throw std::runtime_error("not one cloud: " + stats.last_error);
  return multislit::apps::StopSignal::requested() ? multislit::apps::kInterruptedExit : 0;
}

}  // namespace

int main(int argc, char** argv) {
  ArgParser args("grabber_example",
                 "The multi-slit sensor as a pcl::Grabber: clouds from a GigE Vision camera, a\n"
                 "recorded PNG sequence or the simulator, each through the whole Pipeline.");
  declareOptions(args);
  std::optional<Options> options;
  try {
    options = parseOptions(args, argc, argv);
  } catch (const UsageError& e) {
    std::cerr << "multislit_grabber_example: " << e.what() << "\n\n" << args.help();
    return 2;
  }
  if (!options) return 0;  // --help
  try {
    return run(*options);
  } catch (const pcl::PCLException& e) {  // its own words, without PCL's function, file and line
    const std::string what = e.what();
    const std::size_t at = what.find(" : ");
    std::fprintf(stderr, "error: %s\n", at == std::string::npos ? e.what() : &what[at + 3]);
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
