// multislit map: the whole chain on frames of a camera, a recording or the simulator, with the
// robot's poses from odometry, a robot standing still or the built-in gait model. Every frame:
// image -> RDMap -> floor -> obstacle groups -> OctoMap -> footsteps -> walk / turn / stop.
#include "camera_options.h"
#include "cli.h"
#include "commands.h"
#include "config_options.h"
#include "map_input.h"
#include "map_input_sim.h"
#include "map_outputs.h"
#include "output_file.h"

#include "multislit/extractor.h"
#include "multislit/pipeline.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

namespace multislit::apps {
namespace {

void declareMapOptions(cli::ArgParser& args) {
  args.option("camera", "", "GigE Vision camera address (127.0.0.1 for multislit emulate)");
  args.option("sequence", "", "folder of recorded PNG frames (frames.csv gives their stamps)");
  args.option("simulate", "", "the simulator filming a scenario (ball, cable, floor, ...)");
  args.option("calibration", "",
              "calibration YAML from multislit calibrate (needed but for "
              "--simulate)");
  args.option("sensor", "",
              "sensor YAML: the camera's mount on the robot (default: the "
              "sequence's sensor.yaml, else the paper's sensor)");
  args.option("intrinsics", "",
              "the camera's OpenCV calibrateCamera or ROS camera_info YAML (focal length, "
              "principal point, lens distortion), replacing the sensor file's; --calibration "
              "must have been made with it");
  args.option("poses", "",
              "FILE (odometry CSV: stamp_us,x,y,z,roll,pitch,yaw), still (a robot standing at "
              "the origin) or gait (the built-in gait model walks as the decisions say); default: "
              "the sequence's odometry.csv, the scenario's motion, else still");
  args.option("max-gap", defaultText(MapPoseOptions{}.max_gap),
              "odometry samples farther apart are not interpolated [s]");
  args.option("frames", "0", "stop after this many frames (0: all, or until Ctrl-C)");
  args.option("fps", defaultText(MapInputOptions{}.fps), "camera frame rate [Hz]");
  addCameraOptions(args);
  args.option("out", "out/map", "output folder (not an input's: --sequence's is refused)");
  args.flag("strict",
            "a frame file of a recording that cannot be read is an error (default: "
            "named, counted in summary.txt and skipped)");
}

MapInputOptions inputOptions(const cli::ArgParser& args) {
  MapInputOptions o;
  o.camera = args.str("camera");
  o.sequence = args.str("sequence");
  o.simulate = args.str("simulate");
  o.calibration = args.str("calibration");
  o.sensor = args.str("sensor");
  o.intrinsics = args.str("intrinsics");
  o.fps = args.number("fps", 0.1, 1000);
  o.frames = static_cast<std::uint64_t>(args.integer("frames", 0, 1000000000));
  if (o.camera.empty()) refuseCameraOptionsWithoutCamera(args);
  o.camera_settings = cameraSettingsFromArgs(args);
  return o;
}

MapPoseOptions poseOptions(const cli::ArgParser& args) {
  MapPoseOptions o;
  o.choice = args.str("poses");
  o.max_gap = args.number("max-gap");
  return o;
}

/// A status line on a terminal, at most twice a second.
void status(std::size_t frames, double seconds, const PipelineResult& r, std::size_t occupied) {
  static auto last = std::chrono::steady_clock::time_point{};
  const auto now = std::chrono::steady_clock::now();
  if (!isatty(STDERR_FILENO) || now - last < std::chrono::milliseconds(500)) return;
  last = now;
  std::fprintf(stderr, "\rmap: %zu frames, %.1f fps, %s, %zu obstacle points, %zu occupied   ",
               frames, static_cast<double>(frames) / std::max(seconds, 1e-9),
               commandName(r.walker.command), r.obstacles.pointCount(), occupied);
}

void reportMiss(const Frame& frame, PoseMiss miss, std::size_t& misses) {
  if (misses++ == 0)
    std::cerr << "frame " << frame.seq << " (stamp_us " << frame.stamp_us << ") is "
              << poseMissName(miss) << ": skipped; frames without a pose are counted in "
              << "summary.txt\n";
}

/// What the run over the frames measured.
struct FrameCounts {
  std::size_t processed = 0;              ///< frames through the whole chain
  std::size_t misses = 0;                 ///< frames without a pose, skipped
  std::size_t bad_frames = 0;             ///< frames the extractor refused
  std::uint64_t unreadable = 0;           ///< frame files missing, unreadable or not images
  StampSource clock = StampSource::Host;  ///< the stamps' clock, of the last frame measured
};

/// Every frame of `source` through the chain, until the source ends, Ctrl-C or `max_frames`
/// (0: no limit); `t0` the run's start, for the status line. Starts the source. A frame file that
/// cannot be read is named and counted (an error with `strict`).
FrameCounts processFrames(FrameSource& source, const Extractor& extractor, MapPoses& poses,
                          Pipeline& pipeline, MapRecorder& recorder, long max_frames, bool strict,
                          std::chrono::steady_clock::time_point t0) {
  FrameCounts n;
  source.start();
  while (!StopSignal::requested() &&
         (max_frames == 0 || static_cast<long>(n.processed) < max_frames)) {
    const std::optional<Frame> frame = source.next(std::chrono::milliseconds(200));
    if (!frame) {
      if (source.stats().read_errors > n.unreadable) {
        n.unreadable = source.stats().read_errors;
        if (strict) throw std::runtime_error(source.lastError() + " (--strict)");
        std::cerr << "skipped: " << source.lastError() << "\n";
        recorder.unreadable(source.lastError());
      }
      if (source.finished()) break;
      continue;
    }
    PoseMiss miss;
    std::optional<PipelineInput> input = poses.at(*frame, miss);
    if (!input) {
      reportMiss(*frame, miss, n.misses);
      recorder.skip();
      continue;
    }
    const double extract_start = threadCpuSeconds();
    try {
      input->cloud =
          extractor.extract(frame->image, frame->stamp_us, static_cast<std::uint32_t>(frame->seq));
    } catch (const std::exception& e) {  // a frame of another size or kind: said, counted
      if (n.bad_frames++ == 0) std::cerr << "frame " << frame->seq << ": " << e.what() << "\n";
      continue;
    }
    const double extract_seconds = threadCpuSeconds() - extract_start;
    n.clock = frame->stamp_source;
    const PipelineResult r = pipeline.process(*input);
    poses.follow(r.walker);
    recorder.record(frame->seq, frame->stamp_us, extract_seconds, *input->cloud, r, pipeline.map());
    ++n.processed;
    status(n.processed,
           std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), r,
           pipeline.map().occupiedCount());
  }
  return n;
}

}  // namespace

int runMap(int argc, char** argv) {
  cli::ArgParser args(
      "map",
      "The whole chain on a camera, a recording or the simulator, with the robot's odometry:\n"
      "image -> RDMap -> floor (RANSAC) -> obstacle groups -> OctoMap -> footsteps ->\n"
      "walk / turn / stop. Ctrl-C ends the run at a frame boundary with every file complete.\n"
      "decisions.csv and obstacles.csv grow a row at a time as decisions.csv.part and\n"
      "obstacles.csv.part (tail -f follows them) and take their names when the run ends.\n"
      "On a robot, with the sensor calibrated and the odometry logged by the robot:\n"
      "  multislit map --camera 192.168.1.20 --calibration calib.yaml --sensor sensor.yaml \\\n"
      "      --poses odometry.csv --out run1\n"
      "A recording (multislit simulate or walk --record writes one):\n"
      "  multislit map --sequence rec --calibration rec/calibration.yaml --out out/map");
  declareMapOptions(args);
  if (!args.parse(argc, argv)) return 0;
  const StopSignal stop;  // Ctrl-C and SIGTERM end the run at a frame boundary
  const long max_frames = args.integer("frames", 0, 1000000000);
  const MapInputOptions options = inputOptions(args);
  MapInput in = openMapInput(options, openSimulatedInput);
  PipelineConfig config;
  config.sensor = in.sensor;
  Pipeline pipeline(config);
  MapPoses poses(poseOptions(args), args.str("sequence"), in, config);
  const Extractor extractor(in.reference);
  std::vector<NamedInput> inputs = inputFiles(options);
  if (poses.mode() == "file") inputs.push_back({"--poses", args.str("poses")});
  MapRecorder recorder(args.str("out"), "--out", inputs);

  const auto t0 = std::chrono::steady_clock::now();
  const FrameCounts counts = processFrames(*in.source, extractor, poses, pipeline, recorder,
                                           max_frames, args.has("strict"), t0);
  in.source->stop();
  if (isatty(STDERR_FILENO)) std::fprintf(stderr, "\n");
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::string stamps = args.has("camera")
                                 ? timeBaseText(counts.clock, args.number("ptp-utc-offset"))
                                 : std::string("recorded");
  const std::string heading =
      "multislit map: " + in.description + " (stamps: " + stamps + "), poses from " +
      poses.description() +
      (counts.bad_frames ? ", " + std::to_string(counts.bad_frames) + " bad frames" : "");
  std::cout << recorder.finish(pipeline, heading, seconds, StopSignal::requested());
  if (counts.processed == 0 && counts.bad_frames > 0)
    throw std::runtime_error("no frame could be measured with this calibration");
  return StopSignal::requested() ? kInterruptedExit : 0;
}

}  // namespace multislit::apps
