// multislit map: the whole chain on frames of a camera, a recording or the simulator, with the
// robot's poses from odometry, a robot standing still or the built-in gait model. Every frame:
// image -> RDMap -> floor -> obstacle groups -> OctoMap -> footsteps -> walk / turn / stop.
#include "cli.h"
#include "commands.h"
#include "map_outputs.h"
#include "output_file.h"

#include "multislit/extractor.h"
#include "multislit/gait.h"
#include "multislit/odometry.h"
#include "multislit/pipeline.h"
#include "multislit/sim/simulated_source.h"
#include "multislit/sources.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

namespace multislit::apps {
namespace {

void declareOptions(cli::ArgParser& args) {
  args.option("camera", "", "GigE Vision camera address (127.0.0.1 for multislit emulate)");
  args.option("sequence", "", "folder of recorded PNG frames (frames.csv gives their stamps)");
  args.option("simulate", "", "the simulator filming a scenario (ball, cable, floor, ...)");
  args.option("calibration", "",
              "calibration YAML from multislit calibrate (needed but for "
              "--simulate)");
  args.option("sensor", "",
              "sensor YAML: the camera's mount on the robot (default: the "
              "sequence's sensor.yaml, else the paper's sensor)");
  args.option("poses", "",
              "FILE (odometry CSV: stamp_us,x,y,z,roll,pitch,yaw), still (a robot standing at "
              "the origin) or gait (the built-in gait model walks as the decisions say); default: "
              "the sequence's odometry.csv, the scenario's motion, else still");
  args.option("max-gap", "0.5", "odometry samples farther apart are not interpolated [s]");
  args.option("frames", "0", "stop after this many frames (0: all, or until Ctrl-C)");
  args.option("fps", "30", "camera frame rate [Hz]");
  args.option("out", "out/map", "output folder");
}

/// Where the frames come from, the reference that goes with them, and the sensor on the robot.
struct Input {
  std::unique_ptr<FrameSource> source;
  Reference reference;
  SensorConfig sensor;
  std::optional<Scenario> scenario;  ///< --simulate
  std::string description;
};

Input openInput(const cli::ArgParser& args) {
  const int given = args.has("camera") + args.has("sequence") + args.has("simulate");
  if (given != 1) throw cli::UsageError("give one of --camera, --sequence and --simulate");
  Input in;
  const std::filesystem::path sequence = args.str("sequence");
  if (args.has("sensor"))
    in.sensor = SensorConfig::load(args.str("sensor"));
  else if (args.has("sequence") && std::filesystem::exists(sequence / "sensor.yaml"))
    in.sensor = SensorConfig::load((sequence / "sensor.yaml").string());
  if (args.has("calibration")) in.reference = Reference::load(args.str("calibration"));
  if (args.has("simulate")) {
    SimulatorSourceConfig config;
    config.scenario = args.str("simulate");
    config.frames = static_cast<std::uint64_t>(args.integer("frames", 0, 1000000000));
    auto simulator = std::make_unique<SimulatorSource>(config);
    if (!args.has("calibration")) in.reference = simulator->makeReference();
    in.scenario = simulator->scenario();
    in.sensor.mount = in.scenario->mount;
    in.description = simulator->name();
    in.source = std::move(simulator);
    return in;
  }
  if (!args.has("calibration"))
    throw cli::UsageError("--calibration FILE is needed (the reference of multislit calibrate)");
  if (args.has("camera")) {
    AravisConfig config;
    config.camera = args.str("camera");
    config.frame_rate = args.number("fps", 0.1, 1000);
    config.roi_width = in.reference.image_width;
    config.roi_height = in.reference.image_height;
    config.camera_id = in.reference.camera_id;  // the camera the calibration was taken with
    in.source = std::make_unique<AravisSource>(config);
  } else {
    ImageSequenceConfig config;
    config.folder = sequence.string();
    in.source = std::make_unique<ImageSequenceSource>(config);
  }
  in.description = in.source->name();
  return in;
}

/// The robot's pose for each frame: odometry, standing still, the scenario's motion or the gait.
class Poses {
 public:
  Poses(const cli::ArgParser& args, const Input& in, const PipelineConfig& pipeline)
      : gait_(GaitConfig{}, pipeline.foot, pipeline.sensor.mount) {
    std::string choice = args.str("poses");
    const std::filesystem::path recorded =
        std::filesystem::path(args.str("sequence")) / "odometry.csv";
    if (choice.empty())
      choice = args.has("sequence") && std::filesystem::exists(recorded) ? recorded.string()
               : in.scenario                                             ? "scenario"
                                                                         : "still";
    if (choice == "scenario" && !in.scenario)
      throw cli::UsageError("--poses scenario needs --simulate");
    mode_ = choice == "still" || choice == "gait" || choice == "scenario" ? choice : "file";
    if (mode_ == "file") {
      const double gap = args.number("max-gap", 1e-6, 3600);
      odometry_.emplace(Odometry::load(choice, static_cast<std::uint64_t>(gap * 1e6)));
    }
    scenario_ = in.scenario;
    description_ = mode_ == "file" ? "odometry " + choice : mode_;
  }

  /// The input of the frame, or nullopt (the reason in `miss`) when it has no pose.
  std::optional<PipelineInput> at(const Frame& frame, PoseMiss& miss) const {
    PipelineInput in;
    miss = PoseMiss::None;
    if (mode_ == "file") {
      const auto pose = odometry_->at(frame.stamp_us, &miss);
      if (!pose) return std::nullopt;
      in.world_from_robot = *pose;
    } else if (mode_ == "scenario") {
      in.world_from_robot = scenario_->worldFromRobot(frame.seq);
    } else if (mode_ == "gait") {
      in.world_from_robot = gait_.worldFromRobot();
      in.next_foot = gait_.nextFoot();
    }
    return in;
  }
  /// The gait model takes the decision (the other poses do not depend on it).
  void follow(const WalkerResult& decision) {
    if (mode_ == "gait") gait_.advance(decision.command, decision.turn_direction);
  }
  const std::string& description() const { return description_; }

 private:
  std::string mode_, description_;
  std::optional<Odometry> odometry_;
  std::optional<Scenario> scenario_;
  Gait gait_;
};

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
  StampSource clock = StampSource::Host;  ///< the stamps' clock, of the last frame measured
};

/// Every frame of `source` through the chain, until the source ends, Ctrl-C or `max_frames`
/// (0: no limit); `t0` the run's start, for the status line. Starts the source.
FrameCounts processFrames(FrameSource& source, const Extractor& extractor, Poses& poses,
                          Pipeline& pipeline, MapRecorder& recorder, long max_frames,
                          std::chrono::steady_clock::time_point t0) {
  FrameCounts n;
  source.start();
  while (!StopSignal::requested() &&
         (max_frames == 0 || static_cast<long>(n.processed) < max_frames)) {
    const std::optional<Frame> frame = source.next(std::chrono::milliseconds(200));
    if (!frame) {
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
      "On a robot, with the sensor calibrated and the odometry logged by the robot:\n"
      "  multislit map --camera 192.168.1.20 --calibration calib.yaml --sensor sensor.yaml \\\n"
      "      --poses odometry.csv --out run1\n"
      "A recording (multislit simulate or walk --record writes one):\n"
      "  multislit map --sequence rec --calibration rec/calibration.yaml --out out/map");
  declareOptions(args);
  if (!args.parse(argc, argv)) return 0;
  const StopSignal stop;  // Ctrl-C and SIGTERM end the run at a frame boundary
  const long max_frames = args.integer("frames", 0, 1000000000);
  Input in = openInput(args);
  PipelineConfig config;
  config.sensor = in.sensor;
  Pipeline pipeline(config);
  Poses poses(args, in, config);
  const Extractor extractor(in.reference);
  MapRecorder recorder(args.str("out"));

  const auto t0 = std::chrono::steady_clock::now();
  const FrameCounts counts =
      processFrames(*in.source, extractor, poses, pipeline, recorder, max_frames, t0);
  in.source->stop();
  if (isatty(STDERR_FILENO)) std::fprintf(stderr, "\n");
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::string stamps = args.has("camera")
                                 ? std::string(stampSourceName(counts.clock)) + " clock"
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
