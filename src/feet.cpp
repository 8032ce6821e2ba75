#include "multislit/feet.h"

#include "config_check.h"

#include <cmath>

namespace multislit {

void FootConfig::validate() const {
  constexpr detail::FieldCheck require("FootConfig");
  require(foot_length > 0 && foot_length < 1, "foot_length", "must be in (0, 1) m");
  require(foot_width > 0 && foot_width < 1, "foot_width", "must be in (0, 1) m");
  require(foot_separation >= foot_width, "foot_separation", "must be >= foot_width (feet apart)");
  require(step_length > 0 && step_length < 0.5, "step_length", "must be in (0, 0.5) m");
  require(turn_step > 0 && turn_step <= 45, "turn_step", "must be in (0, 45] deg");
}

Pose2D Pose2D::onFloor(const Eigen::Isometry3d& world_from_robot) {
  const Eigen::Vector3d t = world_from_robot.translation();
  const Eigen::Vector3d forward = world_from_robot.linear().col(0);
  return Pose2D{t.x(), t.y(), std::atan2(forward.y(), forward.x())};
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

Footprint Footprint::inflated(double margin) const {
  Footprint f = *this;
  f.length += 2 * margin;
  f.width += 2 * margin;
  return f;
}

std::array<Eigen::Vector2d, 4> Footprint::corners() const {
  const Eigen::Vector2d along(std::cos(yaw), std::sin(yaw)), across(-along.y(), along.x());
  const Eigen::Vector2d a = 0.5 * length * along, b = 0.5 * width * across;
  return {centre + a + b, centre - a + b, centre - a - b, centre + a - b};
}

bool Footprint::contains(const Eigen::Vector2d& p) const {
  const Eigen::Vector2d d = p - centre;
  const double along = d.x() * std::cos(yaw) + d.y() * std::sin(yaw);
  const double across = -d.x() * std::sin(yaw) + d.y() * std::cos(yaw);
  return std::abs(along) <= 0.5 * length && std::abs(across) <= 0.5 * width;
}

}  // namespace multislit
