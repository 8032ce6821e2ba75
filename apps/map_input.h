// What `multislit map` and the ROS node (apps/ros) share: the frames' source with its reference
// and sensor, and the robot's pose for each frame (an odometry file, standing still, the gait
// model or the scenario's motion). Option names in messages carry the caller's prefix ("--" on
// the command line, "~" for ROS private parameters). The core library only: the simulated input
// is map_input_sim.h's, handed to openMapInput() by the programs that link the simulator.
#pragma once

#include "output_file.h"

#include "multislit/gait.h"
#include "multislit/odometry.h"
#include "multislit/pipeline.h"
#include "multislit/reference.h"
#include "multislit/sensor.h"
#include "multislit/sources.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace multislit::apps {

/// Where the frames come from: exactly one of camera, sequence and simulate.
struct MapInputOptions {
  std::string camera;       ///< GigE Vision camera address
  std::string sequence;     ///< folder of recorded PNG frames
  std::string simulate;     ///< scenario the simulator films
  std::string calibration;  ///< calibration YAML (needed but for simulate)
  std::string sensor;       ///< sensor YAML (default: the sequence's sensor.yaml, else the paper's)
  /// The camera's OpenCV or ROS calibration YAML, applied to the sensor's camera; a calibration
  /// must have been made with it (Reference::checkLens). "": the sensor file's camera.
  std::string intrinsics;
  double fps = 30.0;         ///< camera frame rate; with `paced`, the replay rate [Hz]
  std::uint64_t frames = 0;  ///< frames the simulator renders; 0: endless [-]
  /// Recorded and simulated frames come at `fps`, as from a camera; false: as fast as taken.
  bool paced = false;
  std::string prefix = "--";  ///< how messages name the options
  /// What the camera is set to (exposure, gain, pixel format, PTP offset); its address, rate,
  /// region and identity come from the fields above and the calibration.
  AravisConfig camera_settings;
};

/// The frames' source, the reference that goes with them, and the sensor on the robot.
struct MapInput {
  std::unique_ptr<FrameSource> source;
  Reference reference;
  SensorConfig sensor;
  /// simulate: the scenario's world-from-robot at each frame (seq); empty otherwise.
  std::function<Eigen::Isometry3d(std::uint64_t)> scenario_motion;
  std::string description;
};

/// Opens the simulated input of options.simulate into `in` (which holds the sensor and, when
/// given, the calibration): map_input_sim.h's openSimulatedInput.
using SimulatedInputOpener = std::function<MapInput(const MapInputOptions&, MapInput in)>;

/// The files and the folder the options name (sequence, calibration, sensor, intrinsics), each
/// named by its option with the caller's prefix: what an output folder must not overwrite.
std::vector<NamedInput> inputFiles(const MapInputOptions& options);

/// Opens the source (not started). Throws cli::UsageError for a wrong choice of options (the
/// simulator without `simulated`), and what the files' loaders throw.
MapInput openMapInput(const MapInputOptions& options, const SimulatedInputOpener& simulated = {});

/// The choice of poses: a file (odometry CSV), "still", "gait" or "scenario".
struct MapPoseOptions {
  /// "": the sequence's odometry.csv, else the scenario's motion, else still.
  std::string choice;
  double max_gap = 0.5;  ///< odometry samples farther apart are not interpolated [s]
  std::string prefix = "--";
  std::string max_gap_name = "max-gap";  ///< how messages name max_gap (after the prefix)
};

/// The robot's pose for each frame: odometry, standing still, the scenario's motion or the gait.
class MapPoses {
 public:
  /// `sequence`: the recording's folder ("" for none). Throws cli::UsageError.
  MapPoses(const MapPoseOptions& options, const std::string& sequence, const MapInput& in,
           const PipelineConfig& pipeline);

  /// The input of the frame, or nullopt (the reason in `miss`) when it has no pose.
  std::optional<PipelineInput> at(const Frame& frame, PoseMiss& miss) const;
  /// The gait model takes the decision (the other poses do not depend on it).
  void follow(const WalkerResult& decision);
  /// "file", "still", "gait" or "scenario".
  const std::string& mode() const { return mode_; }
  const std::string& description() const { return description_; }

 private:
  std::string mode_, description_;
  std::optional<Odometry> odometry_;
  std::function<Eigen::Isometry3d(std::uint64_t)> scenario_motion_;
  Gait gait_;
};

}  // namespace multislit::apps
