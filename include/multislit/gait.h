// The HOAP-2's gait, simply: the robot's pose integrates its own commands (walk a step, turn in
// place a step, stand), feet land at the end of each step, and the body sways the sensor.
#pragma once

#include "multislit/footsteps.h"
#include "multislit/sensor.h"
#include "multislit/walker.h"

#include <Eigen/Geometry>

#include <optional>

namespace multislit {

struct GaitConfig {
  double frame_rate = 30.0;  ///< sensor frames per second (the paper: more than 30 Hz) [Hz]
  int step_frames = 24;      ///< frames per step: 0.8 s, 40 mm per step make 50 mm/s [-]
  /// Sway of the sensor: the roll follows the stance foot (one period per two steps), the height
  /// bobs once per step. Standing still, the sensor is at its nominal mount.
  double roll_amplitude = 2.0;      ///< [deg]
  double height_amplitude = 0.005;  ///< [m]

  double speed(const FootConfig& foot) const {  ///< walking speed [m/s]
    return foot.step_length * frame_rate / step_frames;
  }
  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// The robot's odometry: it knows exactly how it moved (the simulation has no slip). A humanoid
/// changes what it does between steps: a command starts a step (a walking step of step_length, or
/// a turn in place of turn_step) and the step is finished before the next command is taken. Stop
/// acts at once: the swing foot is put down where it is, and the next command starts a new step.
class Gait {
 public:
  /// Starts standing at `start` with the feet side by side; the left foot swings first.
  Gait(const GaitConfig& config, const FootConfig& foot, const MountConfig& nominal_mount,
       const Pose2D& start = {});

  const Pose2D& pose() const { return pose_; }  ///< the body now
  Eigen::Isometry3d worldFromRobot() const { return pose_.isometry(); }
  /// The sensor's mount now: the nominal one with this frame's sway.
  MountConfig mount() const;
  Foot nextFoot() const { return swing_; }          ///< the foot that swings (or swings next)
  Command command() const { return command_; }      ///< what the body did in the last frame
  int turnDirection() const { return direction_; }  ///< +1 left, -1 right (Turn only)

  /// One frame: `command` (turn_direction +1: left, -1: right) starts a step when none is under
  /// way; else the step under way goes on. Returns the footstep that landed in this frame.
  std::optional<Footstep> advance(Command command, int turn_direction = 1);

 private:
  Footstep land(double ahead);

  GaitConfig config_;
  FootConfig foot_;
  MountConfig nominal_;
  Pose2D pose_;
  Foot swing_ = Foot::Left;
  int phase_ = 0;                    ///< frames of the step under way done; 0: none under way
  Command command_ = Command::Stop;  ///< of the step under way, or Stop
  int direction_ = 0;                ///< of the step under way
};

}  // namespace multislit
