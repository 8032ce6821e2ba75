// What the simulated sensor looks at: a textured floor (z = 0, world frame, z up) and objects.
#pragma once

#include <Eigen/Core>

#include <cstddef>
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
  /// Factor on the laser sheet's width as seen on this surface, its power kept (subsurface
  /// scattering, e.g. a ping-pong ball: > 1, wider and dimmer); symmetric about the sheet [-]
  double stripe_width = 1.0;

  static SceneObject sphere(const std::string& name, const Eigen::Vector3d& centre, double radius);
  /// A capped cylinder (a cable, a screw standing up).
  static SceneObject cylinder(const std::string& name, const Eigen::Vector3d& start,
                              const Eigen::Vector3d& end, double radius);
  static SceneObject box(const std::string& name, const Eigen::Vector3d& centre,
                         const Eigen::Vector3d& size, double yaw_deg = 0.0);
  void validate() const;  ///< throws std::invalid_argument naming the field
  double top() const;     ///< highest z of the object [m]
};

/// Albedo pattern of the floor.
enum class FloorTexture {
  Wood,    ///< grain along world x, features of texture_scale
  Tiles,   ///< square tiles of edge texture_scale, dark grout lines between them
  Carpet,  ///< fine high-contrast fibres of size texture_scale
};

/// The floor: a Lambertian plane with an albedo texture, optionally glossy.
struct FloorConfig {
  FloorTexture texture = FloorTexture::Wood;  ///< the albedo pattern
  double albedo = 0.55;                       ///< mean reflectance at 660 nm [-]
  double texture_amplitude = 0.15;  ///< relative albedo variation (grain, tile to tile, fibres) [-]
  double texture_scale = 0.012;     ///< grain feature size, tile edge or fibre size [m]
  unsigned texture_seed = 7;        ///< which floor
  double grout_width = 0.004;       ///< tiles: width of the grout lines [m]
  double grout_albedo = 0.10;       ///< tiles: reflectance of the grout [-]
  double laser_albedo =
      1.0;             ///< share of the diffuse reflectance the laser gets back (glossy < 1) [-]
  double gloss = 0.0;  ///< glare of a ceiling lamp mirrored by the floor, peak over albedo [-]
  double stripe_width = 1.0;  ///< factor on the sheet's width as seen on the floor (carpet > 1) [-]

  void validate()
      const;  ///< throws std::invalid_argument naming the field ("scene: floor.<field>")
};

/// "wood", "tiles", "carpet"; and back (throws std::invalid_argument for other names).
const char* floorTextureName(FloorTexture texture);
FloorTexture floorTextureFromName(const std::string& name);

/// Result of a ray cast.
struct Hit {
  double distance = std::numeric_limits<double>::infinity();  ///< along the unit ray [m]
  int object = -1;                                    ///< -1: nothing, 0: floor, k + 1: objects[k]
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit surface normal, facing the ray
  bool valid() const { return object >= 0; }
};

class Scene {
 public:
  /// Every object is tested by every ray: 20 000 objects took minutes per frame.
  static constexpr std::size_t kMaxObjects = 1000;

  FloorConfig floor;
  std::vector<SceneObject> objects;

  /// First surface hit by origin + s * direction (direction unit), for s in (0, max_distance).
  Hit intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                double max_distance = std::numeric_limits<double>::infinity()) const;
  /// Reflectance at a world point on the given surface.
  double albedo(int object, const Eigen::Vector3d& point) const;
  /// Share of the diffuse reflectance that returns laser light (the floor's laser_albedo, else 1).
  double laserAlbedo(int object) const;
  /// Factor on the laser sheet's width on the given surface (FloorConfig / SceneObject).
  double stripeWidth(int object) const;
  /// Ambient glare seen along the unit world ray `ray` where it meets the floor at `point`,
  /// relative to the ambient light on albedo 1: a ceiling lamp's mirror image (0 without gloss).
  double floorGlare(const Eigen::Vector3d& point, const Eigen::Vector3d& ray) const;
  /// floorGlare() as a float, the same bits as converting it, mostly without std::pow: what the
  /// renderer keeps per pixel.
  float floorGlareAsFloat(const Eigen::Vector3d& point, const Eigen::Vector3d& ray) const;
  /// "floor", the object's name, or "none".
  std::string objectName(int object) const;

  /// Throws std::invalid_argument naming the field: every value finite and in range, at most
  /// kMaxObjects objects.
  void validate() const;
  /// YAML (OpenCV FileStorage): floor {albedo, ...} and objects [{type, name, ...}].
  static Scene load(const std::string& path);
  void save(const std::string& path) const;
};

}  // namespace multislit
