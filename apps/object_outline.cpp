#include "object_outline.h"

#include "multislit/feet.h"

#include <cmath>

namespace multislit::apps {

ObjectOutline outlineOf(const SceneObject& o) {
  ObjectOutline outline;
  outline.centre = o.centre.head<2>();
  outline.radius = o.radius;
  if (o.type == ShapeType::Sphere) return outline;
  if (o.type == ShapeType::Cylinder) {
    const Eigen::Vector2d a = o.axis_start.head<2>(), b = o.axis_end.head<2>();
    outline.centre = 0.5 * (a + b);
    if ((b - a).norm() < o.radius) return outline;  // standing: a disc
    const Eigen::Vector2d d = (b - a).normalized() * o.radius;
    const Eigen::Vector2d side(-d.y(), d.x());
    outline.polygon = {a + side, b + side, b - side, a - side};
    return outline;
  }
  Footprint box;
  box.centre = o.centre.head<2>();
  box.yaw = o.yaw * M_PI / 180;
  box.length = o.size.x();
  box.width = o.size.y();
  for (const Eigen::Vector2d& c : box.corners()) outline.polygon.push_back(c);
  return outline;
}

}  // namespace multislit::apps
