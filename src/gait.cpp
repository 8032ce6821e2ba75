#include "multislit/gait.h"
#include "multislit/units.h"

#include "config_check.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace multislit {

void GaitConfig::validate() const {
  constexpr detail::FieldCheck require("GaitConfig");
  require(frame_rate > 0, "frame_rate", "must be > 0 Hz");
  require(step_frames >= 2, "step_frames", "must be >= 2");
  require(roll_amplitude >= 0 && roll_amplitude < 20, "roll_amplitude", "must be in [0, 20) deg");
  require(height_amplitude >= 0 && height_amplitude < 0.05, "height_amplitude",
          "must be in [0, 0.05) m");
}

Gait::Gait(const GaitConfig& config, const FootConfig& foot, const MountConfig& nominal_mount,
           const Pose2D& start)
    : config_(config), foot_(foot), nominal_(nominal_mount), pose_(start) {
  config_.validate();
  foot_.validate();
}

MountConfig Gait::mount() const {
  MountConfig m = nominal_;
  if (command_ == Command::Stop) return m;
  const double step = static_cast<double>(phase_) / config_.step_frames;  // 0 .. 1 in a step
  // The body leans over the stance foot: right while the left foot swings.
  const double side = swing_ == Foot::Left ? 1.0 : -1.0;
  m.roll += side * config_.roll_amplitude * std::sin(M_PI * step);
  m.height += config_.height_amplitude * std::sin(2 * M_PI * step);
  return m;
}

std::optional<Footstep> Gait::advance(Command command, int turn_direction) {
  if (command == Command::Stop) {  // at once: the swing foot is put down where it is
    const bool mid_step = phase_ > 0;
    const double ahead = command_ == Command::Walk ? 0.5 * foot_.step_length : 0.0;
    command_ = Command::Stop;
    direction_ = 0;
    if (mid_step) return land(ahead);
    return std::nullopt;
  }
  if (phase_ == 0) {  // a new step
    command_ = command;
    direction_ = command == Command::Turn ? (turn_direction >= 0 ? 1 : -1) : 0;
  }
  const double per_frame = 1.0 / config_.step_frames;
  if (command_ == Command::Walk)
    pose_ = pose_.movedForward(foot_.step_length * per_frame);
  else
    pose_ = pose_.turned(direction_ * foot_.turn_step * kDeg * per_frame);
  if (++phase_ < config_.step_frames) return std::nullopt;
  // The swing foot lands: half a step ahead of the body when walking, beside it when turning.
  return land(command_ == Command::Walk ? 0.5 * foot_.step_length : 0.0);
}

Footstep Gait::land(double ahead) {
  Footstep landed;
  landed.foot = swing_;
  landed.body = pose_;
  landed.sole = soleAt(pose_, swing_, ahead, foot_);
  phase_ = 0;
  swing_ = otherFoot(swing_);
  return landed;
}

}  // namespace multislit
