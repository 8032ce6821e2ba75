#include "shader.h"

#include <algorithm>
#include <cmath>

namespace multislit {

namespace {

// erf(z) and its antiderivative F(z) = z erf(z) + exp(-z^2) / sqrt(pi), tabulated on [0, 6] and
// interpolated by cubic Hermite polynomials with their exact derivatives (erf' = 2 exp(-z^2) /
// sqrt(pi), F' = erf): within 2e-11 of the exact values; beyond 6, erf = 1 to 2e-17.
class ErfTable {
 public:
  ErfTable() {
    for (int i = 0; i <= kNodes; ++i) {
      const double z = i * kStep;
      erf_[i] = std::erf(z);
      gauss_[i] = 2.0 / std::sqrt(M_PI) * std::exp(-z * z);
      F_[i] = z * erf_[i] + std::exp(-z * z) / std::sqrt(M_PI);
    }
  }
  double erf(double z) const {
    const double a = std::abs(z);
    if (!(a < kEnd)) return std::copysign(1.0, z);
    return std::copysign(hermite(erf_, gauss_, a), z);
  }
  double F(double z) const {
    const double a = std::abs(z);
    if (!(a < kEnd)) return a;
    return hermite(F_, erf_, a);
  }

 private:
  static constexpr int kNodes = 384;
  static constexpr double kEnd = 6.0, kStep = kEnd / kNodes;

  static double hermite(const double* value, const double* slope, double a) {
    const double x = a / kStep;
    const auto i = static_cast<std::size_t>(x);
    const double t = x - static_cast<double>(i), t2 = t * t, t3 = t2 * t;
    return (2 * t3 - 3 * t2 + 1) * value[i] + (t3 - 2 * t2 + t) * kStep * slope[i] +
           (-2 * t3 + 3 * t2) * value[i + 1] + (t3 - t2) * kStep * slope[i + 1];
  }

  double erf_[kNodes + 2] = {}, gauss_[kNodes + 2] = {}, F_[kNodes + 2] = {};
};

const ErfTable& erfTable() {
  static const ErfTable table;
  return table;
}

}  // namespace

double pixelMeanOfGaussian(double d0, double a, double b, double sigma) {
  a = std::abs(a);
  b = std::abs(b);
  if (a < b) std::swap(a, b);
  const double k = 1.0 / (sigma * std::sqrt(2.0));
  if (a < 0.02 * sigma) return std::exp(-0.5 * d0 * d0 / (sigma * sigma));
  const double scale = sigma * std::sqrt(M_PI / 2.0) / a;
  const ErfTable& e = erfTable();
  if (b < 0.02 * sigma) return scale * (e.erf(k * (d0 + a / 2)) - e.erf(k * (d0 - a / 2)));
  return scale / (b * k) *
         (e.F(k * (d0 + a / 2 + b / 2)) - e.F(k * (d0 - a / 2 + b / 2)) -
          e.F(k * (d0 + a / 2 - b / 2)) + e.F(k * (d0 - a / 2 - b / 2)));
}

Shader::Sample Shader::trace(double u, double v, double reach, int known_object,
                             double known_albedo) const {
  const Eigen::Vector3d ray_c = geometry.pixelRay(u, v).normalized();
  const Eigen::Vector3d ray_w = world_from_camera.linear() * ray_c;
  const Hit hit = scene.intersect(camera_centre, ray_w);
  if (!hit.valid()) return Sample{};
  return shade(hit, hit.distance * ray_c, camera_centre + hit.distance * ray_w, ray_w, reach,
               known_object, known_albedo);
}

Shader::Sample Shader::shade(const Hit& hit, const Eigen::Vector3d& point_c,
                             const Eigen::Vector3d& point_w, const Eigen::Vector3d& ray_w,
                             double reach, int known_object, double known_albedo) const {
  Sample s;
  s.object = static_cast<std::int16_t>(hit.object);
  const Eigen::Vector2d xy = geometry.toProjector(point_c);
  int slit = 0;
  s.offset = geometry.nearestSheetOffset(xy, &slit);
  s.slit = static_cast<std::int16_t>(slit);
  s.t = static_cast<float>(xy.y());
  surface(s, point_w, ray_w, known_object, known_albedo);
  illuminate(s, xy, hit.normal, point_w, reach);
  return s;
}

void Shader::illuminateNear(Sample& s, const Eigen::Vector2d& xy, const Eigen::Vector3d& normal,
                            const Eigen::Vector3d& point_w) const {
  const Eigen::Vector3d to_point = point_w - projector_centre;
  const double range = to_point.norm();
  const Eigen::Vector3d dir = to_point / range;
  const double incidence = -normal.dot(dir);
  if (incidence <= 0) return;
  const bool may_be_shadowed =
      !casters || std::any_of(casters->begin(), casters->end(),
                              [&](const ShadowBox& b) { return b.contains(xy); });
  if (may_be_shadowed && scene.intersect(projector_centre, dir, range * (1.0 - 1e-9)).valid())
    return;  // shadow
  // The sheet's power is kept when the surface widens it: its peak drops by the same factor.
  const double width = scene.stripeWidth(s.object);
  s.width = static_cast<float>(width);
  s.radiance =
      static_cast<float>(render.laser_peak * s.albedo * incidence * (0.5 / range) * (0.5 / range) *
                         (scene.laserAlbedo(s.object) / (render.stripe_width * width)));
}

}  // namespace multislit
