// What the simulated sensor looks at: a textured floor (z = 0, world frame, z up) and objects.
#pragma once

#include <Eigen/Core>

#include <limits>
#include <string>
#include <vector>

namespace multislit {

enum class ShapeType { Sphere, Cylinder, Box };

/// One object on the floor. All positions in the world frame [m].
struct SceneObject {
  std::string name;
  ShapeType type = ShapeType::Sphere;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();      ///< sphere / box centre [m]
  Eigen::Vector3d axis_start = Eigen::Vector3d::Zero();  ///< cylinder axis, first end [m]
  Eigen::Vector3d axis_end = Eigen::Vector3d::Zero();    ///< cylinder axis, second end [m]
  Eigen::Vector3d size = Eigen::Vector3d::Zero();        ///< box edge lengths along its x, y, z [m]
  double radius = 0.0;                                   ///< sphere / cylinder radius [m]
  double yaw = 0.0;                                      ///< box rotation about the vertical [deg]
  double albedo = 0.7;                                   ///< diffuse reflectance at 660 nm [-]

  static SceneObject sphere(const std::string& name, const Eigen::Vector3d& centre, double radius);
  /// A capped cylinder (a cable, a screw standing up).
  static SceneObject cylinder(const std::string& name, const Eigen::Vector3d& start,
                              const Eigen::Vector3d& end, double radius);
  static SceneObject box(const std::string& name, const Eigen::Vector3d& centre,
                         const Eigen::Vector3d& size, double yaw_deg = 0.0);
  void validate() const;  ///< throws std::invalid_argument naming the field
  double top() const;     ///< highest z of the object [m]
};

/// The floor: a Lambertian plane with a wood-like albedo texture.
struct FloorConfig {
  double albedo = 0.55;             ///< mean reflectance at 660 nm [-]
  double texture_amplitude = 0.15;  ///< relative albedo variation of the grain [-]
  double texture_scale = 0.012;     ///< size of the grain features [m]
  unsigned texture_seed = 7;        ///< which floor
};

/// Result of a ray cast.
struct Hit {
  double distance = std::numeric_limits<double>::infinity();  ///< along the unit ray [m]
  int object = -1;                                    ///< -1: nothing, 0: floor, k + 1: objects[k]
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit surface normal, facing the ray
  bool valid() const { return object >= 0; }
};

class Scene {
 public:
  FloorConfig floor;
  std::vector<SceneObject> objects;

  /// First surface hit by origin + s * direction (direction unit), for s in (0, max_distance).
  Hit intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                double max_distance = std::numeric_limits<double>::infinity()) const;
  /// Reflectance at a world point on the given surface.
  double albedo(int object, const Eigen::Vector3d& point) const;
  /// "floor", the object's name, or "none".
  std::string objectName(int object) const;

  void validate() const;
  /// YAML (OpenCV FileStorage): floor {albedo, ...} and objects [{type, name, ...}].
  static Scene load(const std::string& path);
  void save(const std::string& path) const;
};

}  // namespace multislit
