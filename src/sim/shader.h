// What one camera ray sees (private to the simulator): its surface, albedo, ambient glare and,
// near a laser sheet, the sheet's radiance before its profile. Shared by both ways of tracing the
// pixel centres (RenderMethod) and by the sub-pixel samples of the laser's integration.
#pragma once

#include "multislit/sensor.h"
#include "multislit/sim/floor_albedo.h"
#include "multislit/sim/scene.h"
#include "multislit/sim/simulator.h"

#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace multislit {

/// Mean of exp(-x^2 / 2 sigma^2) over a pixel on which x = d0 + a p + b q, p and q uniform in
/// [-1/2, 1/2]: a Gaussian sheet profile integrated exactly over a pixel where the sheet offset
/// is linear.
double pixelMeanOfGaussian(double d0, double a, double b, double sigma);

/// Where an object may cast a shadow, in normalized projector coordinates (x/z, y/z): the rays
/// of the projector outside every box meet no object.
struct ShadowBox {
  double x0, x1, y0, y1;
  bool contains(const Eigen::Vector2d& xy) const {
    return xy.x() >= x0 && xy.x() <= x1 && xy.y() >= y0 && xy.y() <= y1;
  }
};

/// Everything needed to shade one ray, in world coordinates.
struct Shader {
  const Scene& scene;
  const SensorGeometry& geometry;
  const RenderConfig& render;
  Eigen::Isometry3d world_from_camera;
  Eigen::Vector3d camera_centre, projector_centre;
  double sigma;  ///< the sheet's width as rendered, before the surface's factor [rad]
  /// Where objects may shadow the laser; null: every light ray is tested against every object.
  const std::vector<ShadowBox>* casters = nullptr;
  /// The floor's albedo, made once per render; null: Scene::albedo() point by point.
  const FloorAlbedo* floor_albedo = nullptr;

  /// What one ray sees: the laser's radiance is 0 when shadowed, facing away or beyond the
  /// slit's end.
  struct Sample {
    std::int16_t object = -1;  ///< -1 nothing, 0 floor, k + 1 scene.objects[k] (at most 1000)
    std::int16_t slit = 0;     ///< the nearest sheet's slit
    float t = 0;               ///< position along the slit (projector y / z)
    double offset = std::numeric_limits<double>::infinity();  ///< from the nearest sheet [rad]
    float albedo = 0;                                         ///< at 660 nm
    float radiance = 0;                                       ///< laser at the sheet's centre [FS]
    float glare = 0;  ///< ambient mirrored by a glossy floor, relative to albedo 1
    float width = 1;  ///< factor on the sheet's width on this surface
  };
  static_assert(sizeof(Sample) == 32, "a frame holds 1.25 million samples");
  static_assert(Scene::kMaxObjects < 32767, "Sample::object is 16 bits");

  /// The ray through pixel position (u, v). `known_object` and `known_albedo` pass the pixel
  /// centre's albedo to its sub-samples: the floor's grain is many pixels wide. Light is traced
  /// only within `reach` [rad] of a sheet.
  Sample trace(double u, double v, double reach, int known_object = -2,
               double known_albedo = 0) const;
  /// The sample of a ray along world direction `ray_w` (any length) that meets `hit` at
  /// `point_c` (camera frame) = `point_w` (world): what trace() gives once the hit is known.
  Sample shade(const Hit& hit, const Eigen::Vector3d& point_c, const Eigen::Vector3d& point_w,
               const Eigen::Vector3d& ray_w, double reach, int known_object = -2,
               double known_albedo = 0) const;
  /// The parts of shade(). surface(): the albedo and glare at `point_w` of `s.object`;
  /// illuminate(): the laser's radiance at the point, seen at projector coordinates `xy`, within
  /// `reach` [rad] of a sheet (`s` has its offset and t).
  void surface(Sample& s, const Eigen::Vector3d& point_w, const Eigen::Vector3d& ray_w,
               int known_object = -2, double known_albedo = 0) const {
    s.albedo = static_cast<float>(s.object == known_object ? known_albedo
                                  : s.object == 0 && floor_albedo
                                      ? floor_albedo->at(point_w.x(), point_w.y())
                                      : scene.albedo(s.object, point_w));
    glare(s, point_w, ray_w);
  }
  /// The glare part of surface().
  void glare(Sample& s, const Eigen::Vector3d& point_w, const Eigen::Vector3d& ray_w) const {
    if (s.object == 0 && scene.floor.gloss > 0)
      s.glare = scene.floorGlareAsFloat(point_w, ray_w.normalized());
  }
  void illuminate(Sample& s, const Eigen::Vector2d& xy, const Eigen::Vector3d& normal,
                  const Eigen::Vector3d& point_w, double reach) const {
    if (std::abs(s.offset) <= reach && std::abs(s.t) <= geometry.slitTMax())
      illuminateNear(s, xy, normal, point_w);
  }
  /// illuminate() once the point is known to be near a sheet.
  void illuminateNear(Sample& s, const Eigen::Vector2d& xy, const Eigen::Vector3d& normal,
                      const Eigen::Vector3d& point_w) const;
  /// The sheet's light at the sample's offset.
  double laser(const Sample& s) const {
    const double sheet = sigma * s.width;
    return s.radiance * std::exp(-0.5 * s.offset * s.offset / (sheet * sheet));
  }
};

}  // namespace multislit
