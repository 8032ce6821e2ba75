#include "multislit/walker.h"
#include "multislit/units.h"

#include "config_check.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace multislit {

const char* commandName(Command command) {
  switch (command) {
    case Command::Walk:
      return "walk";
    case Command::Turn:
      return "turn";
    case Command::Stop:
      return "stop";
  }
  return "?";
}

const char* reasonName(Reason reason) {
  switch (reason) {
    case Reason::PathClear:
      return "path clear";
    case Reason::PathBlocked:
      return "path blocked";
    case Reason::SuddenObstacle:
      return "sudden obstacle";
    case Reason::NoFloor:
      return "no floor";
  }
  return "?";
}

void WalkerConfig::validate() const {
  constexpr detail::FieldCheck require("WalkerConfig");
  require(lookahead_steps >= 1, "lookahead_steps", "must be >= 1");
  require(turn_lookahead_steps >= 1, "turn_lookahead_steps", "must be >= 1");
  require(margin >= 0, "margin", "must be >= 0 m");
  require(max_height > min_height, "max_height", "must be > min_height");
  require(stop_frames >= 1, "stop_frames", "must be >= 1");
  require(near_distance >= 0, "near_distance", "must be >= 0 m");
  require(known_margin >= 0, "known_margin", "must be >= 0 m");
  require(std::isfinite(sudden_min_height) && sudden_min_height >= 0 && sudden_min_height <= 1,
          "sudden_min_height", "must be in [0, 1] m");
  require(sudden_min_points >= 1 && sudden_min_points <= 100000, "sudden_min_points",
          "must be in [1, 100000]");
  require(sudden_frames >= 1 && sudden_frames <= 1000, "sudden_frames", "must be in [1, 1000]");
  require(max_turn > 0 && max_turn <= 180, "max_turn", "must be in (0, 180] deg");
}

Walker::Walker(const WalkerConfig& config, const FootConfig& foot) : config_(config), foot_(foot) {
  config_.validate();
  foot_.validate();
}

namespace {

/// `o`'s box on the floor, in the world, for the body at `body`.
Walker::Box worldBox(const Obstacle& o, const Pose2D& body) {
  Walker::Box box{Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()),
                  Eigen::Vector2d::Constant(-std::numeric_limits<double>::infinity())};
  for (const double x : {o.min.x(), o.max.x()})
    for (const double y : {o.min.y(), o.max.y()}) {
      const Eigen::Vector2d w = body.toWorld(Eigen::Vector2d(x, y));
      box.lo = box.lo.cwiseMin(w);
      box.hi = box.hi.cwiseMax(w);
    }
  return box;
}

bool near(const Walker::Box& a, const Walker::Box& b, double margin) {
  return (a.lo.array() <= b.hi.array() + margin).all() &&
         (b.lo.array() <= a.hi.array() + margin).all();
}

}  // namespace

std::optional<Obstacle> Walker::findSudden(const ObstacleResult& obstacles, const OccupancyMap& map,
                                           const Pose2D& body) {
  const double corridor = foot_.halfWidth() + config_.margin;
  const double m = config_.known_margin;
  const auto points = static_cast<std::size_t>(config_.sudden_min_points);
  // Lines below the floor, this frame and the last: a dark line on the floor along the slits
  // pulls the stripes beside it below the floor and above it, on neighbouring slits and in
  // neighbouring frames; an object on the floor lifts its slits only. A line is a group's surface
  // points below the floor, wherever the group's highest point lies: its two lobes may join one.
  std::vector<Box> lines;
  for (const Obstacle& b : obstacles.obstacles)
    if (b.surfacePointsBelow(0.0) >= points) lines.push_back(worldBox(b, body));
  const auto besideLine = [&](const Box& box) {
    for (const std::vector<Box>* frame : {&lines, &lines_before_})
      for (const Box& line : *frame)
        if (near(box, line, m)) return true;
    return false;
  };
  std::vector<Candidate> seen;
  std::optional<Obstacle> sudden;
  for (const Obstacle& o : obstacles.obstacles) {  // nearest first
    if (!(o.distance <= config_.near_distance)) break;
    if (o.max.y() < -corridor || o.min.y() > corridor || o.max.x() < 0) continue;
    // A texture lobe reaches less high; speckle where a stripe is lost makes no surface.
    if (o.surfacePointsAbove(config_.sudden_min_height) < points) continue;
    Candidate c{worldBox(o, body), 1};
    if (besideLine(c.box)) continue;
    // Unknown to the map: no occupied voxel around its box before this frame.
    if (!map.occupiedInBox(Eigen::Vector3d(c.box.lo.x() - m, c.box.lo.y() - m, -1.0),
                           Eigen::Vector3d(c.box.hi.x() + m, c.box.hi.y() + m, 1.0))
             .empty())
      continue;
    // Seen in the frames before: a candidate of the last frame overlaps it.
    for (const Candidate& before : candidates_)
      if (near(c.box, before.box, m)) c.frames = std::max(c.frames, before.frames + 1);
    if (!sudden && c.frames >= config_.sudden_frames) sudden = o;
    seen.push_back(c);
  }
  candidates_ = std::move(seen);
  lines_before_ = std::move(lines);
  return sudden;
}

WalkerResult Walker::step(const OccupancyMap& map, const Pose2D& body, Foot next_foot,
                          const WalkerObservation& seen) {
  WalkerResult r;
  // Fail safe: no floor, no step.
  if (!seen.floor_found) {
    r.reason = Reason::NoFloor;
    return r;
  }
  // An obstacle appeared very near: stop for stop_frames (Sec. V), then look again.
  if (stop_left_ == 0 && seen.sudden) {
    stop_left_ = config_.stop_frames;
    r.obstacle = seen.sudden;
  }
  if (stop_left_ > 0) {
    r.reason = Reason::SuddenObstacle;
    r.stop_frames_left = --stop_left_;
    turning_ = 0;
    return r;
  }
  // Walk while the next footsteps are free; else turn, keeping the side until they are.
  r.check = checkAhead(map, body, next_foot, config_.lookahead_steps, &r.planned);
  if (r.check.free) {
    turning_ = 0;
    r.command = Command::Walk;
    r.reason = Reason::PathClear;
    return r;
  }
  if (turning_ == 0) turning_ = chooseTurn(map, body, next_foot);
  r.command = Command::Turn;
  r.reason = Reason::PathBlocked;
  r.turn_direction = turning_;
  return r;
}

FootstepCheck Walker::checkAhead(const OccupancyMap& map, const Pose2D& body, Foot next_foot,
                                 int steps_ahead, std::vector<Footstep>* planned) const {
  std::vector<Footstep> steps = planStraight(body, next_foot, steps_ahead, foot_);
  FootstepCheck check =
      checkFootsteps(steps, map, config_.margin, config_.min_height, config_.max_height);
  if (planned) *planned = std::move(steps);
  return check;
}

int Walker::chooseTurn(const OccupancyMap& map, const Pose2D& body, Foot next_foot) const {
  // The side whose smallest turn frees the footsteps over the whole view; the preferred side on a
  // tie or when neither does within max_turn.
  const int first = config_.prefer_left ? 1 : -1;
  const int turns = static_cast<int>(std::floor(config_.max_turn / foot_.turn_step));
  for (int k = 1; k <= turns; ++k)
    for (const int side : {first, -first})
      if (checkAhead(map, body.turned(side * k * foot_.turn_step * kDeg), next_foot,
                     config_.turn_lookahead_steps)
              .free)
        return side;
  return first;
}

}  // namespace multislit
