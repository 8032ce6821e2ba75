#include "map_input.h"

#include "cli.h"

#include "multislit/intrinsics_file.h"

#include <filesystem>
#include <utility>

namespace multislit::apps {
MapInput openMapInput(const MapInputOptions& o, const SimulatedInputOpener& simulated) {
  const std::string& p = o.prefix;
  const int given = !o.camera.empty() + !o.sequence.empty() + !o.simulate.empty();
  if (given != 1)
    throw cli::UsageError("give one of " + p + "camera, " + p + "sequence and " + p + "simulate");
  MapInput in;
  const std::filesystem::path sequence = o.sequence;
  if (!o.sensor.empty())
    in.sensor = SensorConfig::load(o.sensor);
  else if (!o.sequence.empty() && std::filesystem::exists(sequence / "sensor.yaml"))
    in.sensor = SensorConfig::load((sequence / "sensor.yaml").string());
  if (!o.intrinsics.empty()) in.sensor.camera = withIntrinsicsFile(in.sensor.camera, o.intrinsics);
  if (!o.calibration.empty()) {
    in.reference = Reference::load(o.calibration);
    if (!o.intrinsics.empty())
      in.reference.checkLens(in.sensor.camera, "calibration '" + o.calibration + "'");
  }
  if (!o.simulate.empty()) {
    if (!simulated)
      throw cli::UsageError(p + "simulate: this program was built without the simulator");
    return simulated(o, std::move(in));
  }
  if (o.calibration.empty())
    throw cli::UsageError(p + "calibration FILE is needed (the reference of multislit calibrate)");
  if (!o.camera.empty()) {
    AravisConfig config = o.camera_settings;
    config.camera = o.camera;
    config.frame_rate = o.fps;
    config.roi_width = in.reference.image_width;
    config.roi_height = in.reference.image_height;
    config.camera_id = in.reference.camera_id;  // the camera the calibration was taken with
    in.source = std::make_unique<AravisSource>(config);
  } else {
    ImageSequenceConfig config;
    config.folder = sequence.string();
    if (o.paced) config.fps = o.fps;
    in.source = std::make_unique<ImageSequenceSource>(config);
  }
  in.description = in.source->name();
  return in;
}

std::vector<NamedInput> inputFiles(const MapInputOptions& o) {
  return {{o.prefix + "sequence", o.sequence},
          {o.prefix + "calibration", o.calibration},
          {o.prefix + "sensor", o.sensor},
          {o.prefix + "intrinsics", o.intrinsics}};
}

MapPoses::MapPoses(const MapPoseOptions& options, const std::string& sequence, const MapInput& in,
                   const PipelineConfig& pipeline)
    : gait_(GaitConfig{}, pipeline.foot, pipeline.sensor.mount) {
  std::string choice = options.choice;
  const std::filesystem::path recorded = std::filesystem::path(sequence) / "odometry.csv";
  if (choice.empty())
    choice = !sequence.empty() && std::filesystem::exists(recorded) ? recorded.string()
             : in.scenario_motion                                   ? "scenario"
                                                                    : "still";
  if (choice == "scenario" && !in.scenario_motion)
    throw cli::UsageError(options.prefix + "poses scenario needs " + options.prefix + "simulate");
  mode_ = choice == "still" || choice == "gait" || choice == "scenario" ? choice : "file";
  if (mode_ == "file") {
    if (!(options.max_gap >= 1e-6 && options.max_gap <= 3600))
      throw cli::UsageError(options.prefix + options.max_gap_name + " must be in [1e-06, 3600]");
    odometry_.emplace(Odometry::load(choice, static_cast<std::uint64_t>(options.max_gap * 1e6)));
  }
  scenario_motion_ = in.scenario_motion;
  description_ = mode_ == "file" ? "odometry " + choice : mode_;
}

std::optional<PipelineInput> MapPoses::at(const Frame& frame, PoseMiss& miss) const {
  PipelineInput in;
  miss = PoseMiss::None;
  if (mode_ == "file") {
    const auto pose = odometry_->at(frame.stamp_us, &miss);
    if (!pose) return std::nullopt;
    in.world_from_robot = *pose;
  } else if (mode_ == "scenario") {
    in.world_from_robot = scenario_motion_(frame.seq);
  } else if (mode_ == "gait") {
    in.world_from_robot = gait_.worldFromRobot();
    in.next_foot = gait_.nextFoot();
  }
  return in;
}

void MapPoses::follow(const WalkerResult& decision) {
  if (mode_ == "gait") gait_.advance(decision.command, decision.turn_direction);
}

}  // namespace multislit::apps
