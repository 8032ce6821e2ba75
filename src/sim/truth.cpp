#include "multislit/sim/truth.h"
#include "multislit/units.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace multislit {

namespace {

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
