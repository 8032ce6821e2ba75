#include "multislit/sim/scene.h"
#include "multislit/sim/floor_albedo.h"
#include "multislit/units.h"

#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace multislit {
namespace {

constexpr double kEps = 1e-9;
// A ceiling lamp that a glossy floor mirrors into the camera [m, world frame], and the width of
// its mirror image (Phong exponent of the gloss lobe).
const Eigen::Vector3d kLamp(0.9, 0.25, 2.4);
constexpr double kGlossExponent = 40.0;

/// The cosine between the unit ray mirrored in the floor and the direction from `point` (on the
/// floor) to the lamp.
double glareCosine(const Eigen::Vector3d& point, const Eigen::Vector3d& ray) {
  const Eigen::Vector3d mirrored(ray.x(), ray.y(), -ray.z());
  return mirrored.dot((kLamp - point).normalized());
}

void keepNearest(Hit& best, double s, int object, const Eigen::Vector3d& normal) {
  if (s > kEps && s < best.distance) {
    best.distance = s;
    best.object = object;
    best.normal = normal;
  }
}

void intersectSphere(const SceneObject& o, int id, const Eigen::Vector3d& p,
                     const Eigen::Vector3d& d, Hit& best) {
  const Eigen::Vector3d m = p - o.centre;
  const double b = m.dot(d), c = m.squaredNorm() - o.radius * o.radius;
  const double disc = b * b - c;
  if (disc < 0) return;
  const double r = std::sqrt(disc);
  for (double s : {-b - r, -b + r}) {
    if (s > kEps && s < best.distance) {
      keepNearest(best, s, id, (p + s * d - o.centre) / o.radius);
      return;
    }
  }
}

void intersectCylinder(const SceneObject& o, int id, const Eigen::Vector3d& p,
                       const Eigen::Vector3d& d, Hit& best) {
  const Eigen::Vector3d axis = o.axis_end - o.axis_start;
  const double length = axis.norm();
  const Eigen::Vector3d w = axis / length;
  const Eigen::Vector3d delta = p - o.axis_start;
  const Eigen::Vector3d d_perp = d - d.dot(w) * w;
  const Eigen::Vector3d delta_perp = delta - delta.dot(w) * w;
  const double a = d_perp.squaredNorm();
  if (a > 1e-18) {  // mantle
    const double b = delta_perp.dot(d_perp);
    const double c = delta_perp.squaredNorm() - o.radius * o.radius;
    const double disc = b * b - a * c;
    if (disc >= 0) {
      const double r = std::sqrt(disc);
      for (double s : {(-b - r) / a, (-b + r) / a}) {
        const double h = (delta + s * d).dot(w);
        if (s > kEps && h >= 0 && h <= length) {
          const Eigen::Vector3d q = p + s * d - o.axis_start - h * w;
          keepNearest(best, s, id, q / o.radius);
          break;
        }
      }
    }
  }
  const double dw = d.dot(w);
  if (std::abs(dw) > 1e-15) {  // caps
    for (double h0 : {0.0, length}) {
      const double s = (h0 - delta.dot(w)) / dw;
      const Eigen::Vector3d q = delta + s * d - h0 * w;
      if (q.squaredNorm() <= o.radius * o.radius) keepNearest(best, s, id, h0 > 0 ? w : -w);
    }
  }
}

void intersectBox(const SceneObject& o, int id, const Eigen::Vector3d& p, const Eigen::Vector3d& d,
                  Hit& best) {
  const Eigen::Matrix3d r =
      Eigen::AngleAxisd(o.yaw * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d lp = r.transpose() * (p - o.centre), ld = r.transpose() * d;
  const Eigen::Vector3d half = 0.5 * o.size;
  double s_in = -std::numeric_limits<double>::infinity(), s_out = -s_in;
  int axis_in = 0;
  double sign_in = 1.0;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(ld[k]) < 1e-15) {
      if (std::abs(lp[k]) > half[k]) return;
      continue;
    }
    double s0 = (-half[k] - lp[k]) / ld[k], s1 = (half[k] - lp[k]) / ld[k];
    double sign = -1.0;  // entering through the -k face
    if (s0 > s1) {
      std::swap(s0, s1);
      sign = 1.0;
    }
    if (s0 > s_in) {
      s_in = s0;
      axis_in = k;
      sign_in = sign;
    }
    s_out = std::min(s_out, s1);
  }
  if (s_in > s_out || s_out < kEps) return;
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  n[axis_in] = sign_in;
  keepNearest(best, s_in, id, r * n);
}

}  // namespace

SceneObject SceneObject::sphere(const std::string& name, const Eigen::Vector3d& centre,
                                double radius) {
  SceneObject o;
  o.name = name;
  o.type = ShapeType::Sphere;
  o.centre = centre;
  o.radius = radius;
  return o;
}

SceneObject SceneObject::cylinder(const std::string& name, const Eigen::Vector3d& start,
                                  const Eigen::Vector3d& end, double radius) {
  SceneObject o;
  o.name = name;
  o.type = ShapeType::Cylinder;
  o.axis_start = start;
  o.axis_end = end;
  o.centre = 0.5 * (start + end);
  o.radius = radius;
  return o;
}

SceneObject SceneObject::box(const std::string& name, const Eigen::Vector3d& centre,
                             const Eigen::Vector3d& size, double yaw_deg) {
  SceneObject o;
  o.name = name;
  o.type = ShapeType::Box;
  o.centre = centre;
  o.size = size;
  o.yaw = yaw_deg;
  return o;
}

namespace {

// Every coordinate of a scene within this distance of the origin, every size within kMaxSize: the
// sensor sees 1.5 m at most, and a NaN or infinite value would make the object vanish.
constexpr double kMaxCoordinate = 1000.0;  // [m]
constexpr double kMaxSize = 100.0;         // [m]

void requireInRange(const Eigen::Vector3d& v, double limit, const std::string& who,
                    const char* field) {
  if (!(v.array().abs() <= limit).all())
    throw std::invalid_argument(who + field + " must be finite and within +-" +
                                std::to_string(static_cast<int>(limit)) + " m");
}

}  // namespace

void SceneObject::validate() const {
  const std::string who = "scene object '" + name + "': ";
  requireInRange(centre, kMaxCoordinate, who, "centre");
  requireInRange(axis_start, kMaxCoordinate, who, "axis_start");
  requireInRange(axis_end, kMaxCoordinate, who, "axis_end");
  requireInRange(size, kMaxSize, who, "size");
  if (!(std::abs(radius) <= kMaxSize)) throw std::invalid_argument(who + "radius must be <= 100 m");
  if (!(std::abs(yaw) <= 360)) throw std::invalid_argument(who + "yaw must be in [-360, 360] deg");
  if (!(albedo >= 0 && albedo <= 1)) throw std::invalid_argument(who + "albedo must be in [0, 1]");
  if (!(stripe_width >= 0.25 && stripe_width <= 4))
    throw std::invalid_argument(who + "stripe_width must be in [0.25, 4]");
  switch (type) {
    case ShapeType::Sphere:
    case ShapeType::Cylinder:
      if (!(radius > 0)) throw std::invalid_argument(who + "radius must be > 0");
      if (type == ShapeType::Cylinder && (axis_end - axis_start).norm() <= 0)
        throw std::invalid_argument(who + "axis_start and axis_end must differ");
      break;
    case ShapeType::Box:
      if (!(size.minCoeff() > 0))
        throw std::invalid_argument(who + "size must be > 0 on every axis");
      break;
  }
}

double SceneObject::top() const {
  switch (type) {
    case ShapeType::Sphere:
      return centre.z() + radius;
    case ShapeType::Cylinder:
      return std::max(axis_start.z(), axis_end.z()) + radius;
    case ShapeType::Box:
      return centre.z() + 0.5 * size.z();
  }
  return 0;
}

Hit Scene::intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                     double max_distance) const {
  Hit best;
  best.distance = max_distance;
  if (direction.z() < 0)
    keepNearest(best, -origin.z() / direction.z(), 0, Eigen::Vector3d::UnitZ());
  for (size_t k = 0; k < objects.size(); ++k) {
    const SceneObject& o = objects[k];
    const int id = static_cast<int>(k) + 1;
    switch (o.type) {
      case ShapeType::Sphere:
        intersectSphere(o, id, origin, direction, best);
        break;
      case ShapeType::Cylinder:
        intersectCylinder(o, id, origin, direction, best);
        break;
      case ShapeType::Box:
        intersectBox(o, id, origin, direction, best);
        break;
    }
  }
  if (best.object < 0) best.distance = std::numeric_limits<double>::infinity();
  if (best.normal.dot(direction) > 0) best.normal = -best.normal;
  return best;
}

double Scene::albedo(int object, const Eigen::Vector3d& point) const {
  if (object == 0) return FloorAlbedo(floor).at(point.x(), point.y());
  if (object > 0 && object <= static_cast<int>(objects.size())) return objects[object - 1].albedo;
  return 0.0;
}

double Scene::laserAlbedo(int object) const { return object == 0 ? floor.laser_albedo : 1.0; }

double Scene::stripeWidth(int object) const {
  if (object == 0) return floor.stripe_width;
  if (object > 0 && object <= static_cast<int>(objects.size()))
    return objects[object - 1].stripe_width;
  return 1.0;
}

double Scene::floorGlare(const Eigen::Vector3d& point, const Eigen::Vector3d& ray) const {
  if (!(floor.gloss > 0)) return 0.0;
  const double c = glareCosine(point, ray);
  return c > 0 ? floor.gloss * std::pow(c, kGlossExponent) : 0.0;
}

float Scene::floorGlareAsFloat(const Eigen::Vector3d& point, const Eigen::Vector3d& ray) const {
  if (!(floor.gloss > 0)) return 0.0f;
  const double c = glareCosine(point, ray);
  if (!(c > 0)) return 0.0f;
  // c^40 by six products has a relative error below 40 x 2^-53 (c >= 2^-20: every power is a
  // normal double), and std::pow below one ulp, so the two products with the gloss differ by less
  // than 1e-14 of either. Where no float's rounding boundary lies within kSettled of the fast one,
  // both round to the same float; elsewhere (one in 10^5) floorGlare() decides.
  static_assert(kGlossExponent == 40.0, "the six products make c^40");
  constexpr double kSettled = 1e-12;
  if (c >= 0x1p-20) {
    const double c2 = c * c, c4 = c2 * c2, c5 = c4 * c, c10 = c5 * c5, c20 = c10 * c10;
    const double glare = floor.gloss * (c20 * c20);
    if (static_cast<float>(glare * (1 - kSettled)) == static_cast<float>(glare * (1 + kSettled)))
      return static_cast<float>(glare);
  }
  return static_cast<float>(floorGlare(point, ray));
}

std::string Scene::objectName(int object) const {
  if (object == 0) return "floor";
  if (object > 0 && object <= static_cast<int>(objects.size())) return objects[object - 1].name;
  return "none";
}

void FloorConfig::validate() const {
  if (!(albedo > 0 && albedo <= 1))
    throw std::invalid_argument("scene: floor.albedo must be in (0, 1]");
  if (!(texture_amplitude >= 0 && texture_amplitude < 1))
    throw std::invalid_argument("scene: floor.texture_amplitude must be in [0, 1)");
  if (!(texture_scale > 0 && texture_scale <= kMaxSize))
    throw std::invalid_argument("scene: floor.texture_scale must be in (0, 100] m");
  if (!(grout_width >= 0 && (texture != FloorTexture::Tiles || grout_width < 0.5 * texture_scale)))
    throw std::invalid_argument("scene: floor.grout_width must be in [0, texture_scale / 2)");
  if (!(grout_albedo >= 0 && grout_albedo <= 1))
    throw std::invalid_argument("scene: floor.grout_albedo must be in [0, 1]");
  if (!(laser_albedo > 0 && laser_albedo <= 1))
    throw std::invalid_argument("scene: floor.laser_albedo must be in (0, 1]");
  if (!(gloss >= 0 && gloss <= 10))
    throw std::invalid_argument("scene: floor.gloss must be in [0, 10]");
  if (!(stripe_width >= 0.25 && stripe_width <= 4))
    throw std::invalid_argument("scene: floor.stripe_width must be in [0.25, 4]");
}

void Scene::validate() const {
  floor.validate();
  if (objects.size() > kMaxObjects)
    throw std::invalid_argument("scene: " + std::to_string(objects.size()) +
                                " objects, more than the limit of " + std::to_string(kMaxObjects));
  for (const SceneObject& o : objects) o.validate();
}

}  // namespace multislit
