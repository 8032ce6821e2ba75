#include "multislit/slit_bend.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

namespace multislit {

namespace {

// The model's column of slit `i` on ideal row v, where it meets the plane n . X = d; NaN where
// the slit does not reach that row or meets the plane behind the camera.
double modelColumn(const SensorGeometry& g, int i, double v, const Eigen::Vector3d& n, double d) {
  const std::optional<double> t = g.slitParamForRow(i, v);
  if (!t) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Vector3d ray = g.slitRay(i, *t), origin = g.projectorCentre();
  const double s = (d - n.dot(origin)) / n.dot(ray);
  const Eigen::Vector3d x = origin + s * ray;
  if (!(s > 0 && x.z() > 0)) return std::numeric_limits<double>::quiet_NaN();
  const CameraConfig& c = g.config().camera;
  return c.cx() + c.f() * x.x() / x.z();
}

// Largest |e - (a + b v)| of the points (v, e) about their least-squares line.
double bendOfLine(const std::vector<Eigen::Vector2d>& points) {
  if (points.size() < 3) return 0;
  Eigen::MatrixXd a(points.size(), 2);
  Eigen::VectorXd e(points.size());
  for (std::size_t k = 0; k < points.size(); ++k) {
    a(static_cast<Eigen::Index>(k), 0) = 1;
    a(static_cast<Eigen::Index>(k), 1) = points[k].x();
    e(static_cast<Eigen::Index>(k)) = points[k].y();
  }
  const Eigen::Vector2d line = a.colPivHouseholderQr().solve(e);
  return (e - a * line).cwiseAbs().maxCoeff();
}

}  // namespace

double slitBend(const Reference& reference, const SensorConfig& sensor, const MountConfig& mount) {
  if (static_cast<int>(reference.slits.size()) != sensor.projector.slit_count) return 0;
  const SensorGeometry g(sensor);
  const Eigen::Isometry3d camera_from_robot = g.robotFromCamera(mount).inverse();
  const Eigen::Vector3d n = camera_from_robot.linear() * Eigen::Vector3d::UnitZ();
  const double d = n.dot(camera_from_robot.translation());
  double bend = 0;
  for (std::size_t i = 0; i < reference.slits.size(); ++i) {
    const ReferenceSlit& slit = reference.slits[i];
    std::vector<Eigen::Vector2d> differences;  // (v, measured u - model u)
    for (std::size_t k = 0; k < slit.u.size(); ++k) {
      if (!std::isfinite(slit.u[k])) continue;
      const Eigen::Vector2d ideal = reference.idealPoint(slit, k);
      const double u = modelColumn(g, static_cast<int>(i), ideal.y(), n, d);
      if (std::isfinite(u)) differences.emplace_back(ideal.y(), ideal.x() - u);
    }
    bend = std::max(bend, bendOfLine(differences));
  }
  return bend;
}

}  // namespace multislit
