#include "multislit/footsteps.h"

#include "config_check.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace multislit {

namespace {

constexpr double kDeg = M_PI / 180.0;

constexpr detail::FieldCheck require("FootConfig");

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

double pointToSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                      const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

bool segmentsCross(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                   const Eigen::Vector2d& d) {
  const double d1 = cross(b - a, c - a), d2 = cross(b - a, d - a);
  const double d3 = cross(d - c, a - c), d4 = cross(d - c, b - c);
  return ((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0)) && d1 != 0 && d2 != 0 && d3 != 0 &&
         d4 != 0;
}

double segmentToSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                        const Eigen::Vector2d& c, const Eigen::Vector2d& d) {
  if (segmentsCross(a, b, c, d)) return 0.0;
  return std::min({pointToSegment(a, c, d), pointToSegment(b, c, d), pointToSegment(c, a, b),
                   pointToSegment(d, a, b)});
}

/// Distance from the segment [a, b] to the rectangle (0 when it touches or enters it).
double segmentToRect(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Footprint& rect) {
  if (rect.contains(a) || rect.contains(b)) return 0.0;
  const auto c = rect.corners();
  double d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < c.size(); ++i)
    d = std::min(d, segmentToSegment(a, b, c[i], c[(i + 1) % 4]));
  return d;
}

double rectToRect(const Footprint& r, const Footprint& s) {
  const auto rc = r.corners(), sc = s.corners();
  for (const auto& p : rc)
    if (s.contains(p)) return 0.0;
  double d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < sc.size(); ++i)
    d = std::min(d, segmentToRect(sc[i], sc[(i + 1) % 4], r));
  return d;
}

}  // namespace

void FootConfig::validate() const {
  require(foot_length > 0 && foot_length < 1, "foot_length", "must be in (0, 1) m");
  require(foot_width > 0 && foot_width < 1, "foot_width", "must be in (0, 1) m");
  require(foot_separation >= foot_width, "foot_separation", "must be >= foot_width (feet apart)");
  require(step_length > 0 && step_length < 0.5, "step_length", "must be in (0, 0.5) m");
  require(turn_step > 0 && turn_step <= 45, "turn_step", "must be in (0, 45] deg");
}

Eigen::Vector2d Pose2D::toWorld(const Eigen::Vector2d& robot) const {
  const double c = std::cos(yaw), s = std::sin(yaw);
  return {x + c * robot.x() - s * robot.y(), y + s * robot.x() + c * robot.y()};
}

Pose2D Pose2D::movedForward(double distance) const {
  return Pose2D{x + distance * std::cos(yaw), y + distance * std::sin(yaw), yaw};
}

Pose2D Pose2D::turned(double angle) const {
  return Pose2D{x, y, std::remainder(yaw + angle, 2 * M_PI)};
}

Eigen::Isometry3d Pose2D::isometry() const {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(x, y, 0.0);
  return t;
}

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

double clearance(const Footprint& sole, const SceneObject& object) {
  switch (object.type) {
    case ShapeType::Sphere: {
      const Eigen::Vector2d c = object.centre.head<2>();
      return std::max(0.0, segmentToRect(c, c, sole) - object.radius);
    }
    case ShapeType::Cylinder:
      return std::max(0.0,
                      segmentToRect(object.axis_start.head<2>(), object.axis_end.head<2>(), sole) -
                          object.radius);
    case ShapeType::Box: {
      Footprint box;
      box.centre = object.centre.head<2>();
      box.yaw = object.yaw * kDeg;
      box.length = object.size.x();
      box.width = object.size.y();
      return rectToRect(sole, box);
    }
  }
  return std::numeric_limits<double>::infinity();
}

}  // namespace multislit
