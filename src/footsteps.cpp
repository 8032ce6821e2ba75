#include "multislit/footsteps.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace multislit {

Footprint soleAt(const Pose2D& body, Foot foot, double ahead, const FootConfig& config) {
  const double side = (foot == Foot::Left ? 0.5 : -0.5) * config.foot_separation;
  Footprint sole;
  sole.centre = body.toWorld(Eigen::Vector2d(ahead, side));
  sole.yaw = body.yaw;
  sole.length = config.foot_length;
  sole.width = config.foot_width;
  return sole;
}

std::vector<Footstep> planStraight(const Pose2D& body, Foot first, int count,
                                   const FootConfig& config) {
  std::vector<Footstep> steps;
  Foot foot = first;
  for (int j = 1; j <= count; ++j, foot = otherFoot(foot)) {
    Footstep s;
    s.foot = foot;
    s.body = body.movedForward(j * config.step_length);
    s.sole = soleAt(s.body, foot, 0.5 * config.step_length, config);
    steps.push_back(s);
  }
  return steps;
}

FootstepCheck checkFootsteps(const std::vector<Footstep>& steps, const OccupancyMap& map,
                             double margin, double min_height, double max_height) {
  FootstepCheck check;
  for (std::size_t j = 0; j < steps.size(); ++j) {
    check.cells = map.occupiedUnder(steps[j].sole.inflated(margin), min_height, max_height);
    if (check.cells.empty()) continue;
    check.free = false;
    check.first_blocked = static_cast<int>(j);
    return check;
  }
  return check;
}

}  // namespace multislit
