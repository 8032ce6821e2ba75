#include "object_bounds.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace multislit {
namespace {

// A sphere that bounds (part of) an object [m].
struct BoundingSphere {
  Eigen::Vector3d centre;
  double radius = 0;
};

// A margin on every bound, for rounding in the tests below [m].
constexpr double kBoundMargin = 1e-7;
constexpr int kMaxChain = 512;  // spheres per cylinder

// For each object of `scene`, spheres that together cover it (a cylinder by a chain of them along
// its axis, at most kMaxChain), in the frame of `frame_from_world`.
std::vector<std::vector<BoundingSphere>> objectBounds(const Scene& scene,
                                                      const Eigen::Isometry3d& frame_from_world) {
  std::vector<std::vector<BoundingSphere>> bounds;
  for (const SceneObject& o : scene.objects) {
    std::vector<BoundingSphere>& spheres = bounds.emplace_back();
    auto add = [&](const Eigen::Vector3d& centre_w, double radius) {
      spheres.push_back({frame_from_world * centre_w, radius * (1 + 1e-9) + kBoundMargin});
    };
    switch (o.type) {
      case ShapeType::Sphere:
        add(o.centre, o.radius);
        break;
      case ShapeType::Box:
        add(o.centre, 0.5 * o.size.norm());
        break;
      case ShapeType::Cylinder: {
        const Eigen::Vector3d axis = o.axis_end - o.axis_start;
        const double length = axis.norm();
        const int n = static_cast<int>(
            std::clamp(std::ceil(length / (2 * o.radius)), 1.0, static_cast<double>(kMaxChain)));
        const double half = 0.5 * length / n;
        for (int i = 0; i < n; ++i)
          add(o.axis_start + (i + 0.5) / n * axis, std::sqrt(o.radius * o.radius + half * half));
        break;
      }
    }
  }
  return bounds;
}

// Columns [first, last] of image row `row` whose pixel-centre rays may meet `sphere`, widened by
// a pixel.
ColumnSpan sphereColumns(const SensorGeometry& geometry, const BoundingSphere& sphere, int row) {
  const CameraConfig& camera = geometry.config().camera;
  const int width = camera.width;
  const Eigen::Vector3d& c = sphere.centre;
  const double k = c.squaredNorm() - sphere.radius * sphere.radius;
  const double f = camera.f(), y = (row - camera.cy()) / f;
  // The ray (x, y, 1) passes within the radius of the centre: k |ray|^2 - (c . ray)^2 <= 0.
  const double a = k - c.x() * c.x(), cyz = c.y() * y + c.z();
  if (k <= 0 || a <= 0) return {0, width - 1};
  const double b = -2 * c.x() * cyz, d = k * (y * y + 1) - cyz * cyz;
  const double disc = b * b - 4 * a * d;
  if (disc < 0) return {};
  const double x0 = (-b - std::sqrt(disc)) / (2 * a), x1 = (-b + std::sqrt(disc)) / (2 * a);
  const double lo = std::floor(camera.cx() + f * x0) - 1, hi = std::ceil(camera.cx() + f * x1) + 1;
  if (hi < 0 || lo > width - 1) return {};
  return {static_cast<int>(std::max(lo, 0.0)), static_cast<int>(std::min<double>(hi, width - 1))};
}

// Rows [first, last] whose plane of rays (through the camera centre and the row's pixel centres)
// may meet `sphere`, widened by a row; first > last when none.
ColumnSpan sphereRows(const SensorGeometry& geometry, const BoundingSphere& sphere) {
  const int height = geometry.config().camera.height;
  const Eigen::Vector3d& c = sphere.centre;
  const double r2 = sphere.radius * sphere.radius;
  // Row plane y' = y z with normal (0, 1, -y): (cy - y cz)^2 <= r^2 (1 + y^2).
  const double a = c.z() * c.z() - r2;
  if (a <= 0 || c.squaredNorm() <= r2) return {0, height - 1};  // the camera sees it all around
  const double disc = r2 * (c.y() * c.y() + a);
  if (disc < 0) return {};
  const double f = geometry.config().camera.f(), cy = geometry.config().camera.cy();
  const double y0 = (c.y() * c.z() - std::sqrt(disc)) / a,
               y1 = (c.y() * c.z() + std::sqrt(disc)) / a;
  const double lo = std::floor(cy + f * y0) - 1, hi = std::ceil(cy + f * y1) + 1;
  if (hi < 0 || lo > height - 1) return {};
  return {static_cast<int>(std::max(lo, 0.0)), static_cast<int>(std::min<double>(hi, height - 1))};
}

}  // namespace

// Sorted, merged spans of the columns where some object may be, per row.
std::vector<std::vector<ColumnSpan>> objectColumns(const Shader& shader) {
  const SensorGeometry& geometry = shader.geometry;
  std::vector<std::vector<ColumnSpan>> rows(
      static_cast<std::size_t>(geometry.config().camera.height));
  for (const std::vector<BoundingSphere>& spheres :
       objectBounds(shader.scene, shader.world_from_camera.inverse())) {
    for (const BoundingSphere& b : spheres) {
      const ColumnSpan span = sphereRows(geometry, b);
      for (int r = span.first; r <= span.last; ++r) {
        const ColumnSpan cols = sphereColumns(geometry, b, r);
        if (cols.first <= cols.last) rows[static_cast<std::size_t>(r)].push_back(cols);
      }
    }
  }
  for (std::vector<ColumnSpan>& spans : rows) {
    std::sort(spans.begin(), spans.end(),
              [](const ColumnSpan& a, const ColumnSpan& b) { return a.first < b.first; });
    std::vector<ColumnSpan> merged;
    for (const ColumnSpan& s : spans) {
      if (!merged.empty() && s.first <= merged.back().last + 1)
        merged.back().last = std::max(merged.back().last, s.last);
      else
        merged.push_back(s);
    }
    spans.swap(merged);
  }
  return rows;
}

std::vector<ShadowBox> shadowBoxes(const Shader& shader) {
  const SensorGeometry& g = shader.geometry;
  Eigen::Isometry3d projector_from_camera = Eigen::Isometry3d::Identity();
  projector_from_camera.linear() = g.cameraFromProjector().transpose();
  projector_from_camera.translation() =
      -(g.cameraFromProjector().transpose() * g.projectorCentre());
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<ShadowBox> boxes;
  for (const std::vector<BoundingSphere>& spheres :
       objectBounds(shader.scene, projector_from_camera * shader.world_from_camera.inverse())) {
    ShadowBox box{inf, -inf, inf, -inf};
    for (const BoundingSphere& b : spheres) {
      const Eigen::Vector3d& q = b.centre;
      if (q.z() <= b.radius) {  // around or behind the projector: anywhere
        box = {-inf, inf, -inf, inf};
        break;
      }
      // The tangents of the rays in the x-z (y-z) plane that touch the sphere's shadow there.
      auto range = [&](double lateral, double& lo, double& hi) {
        const double rho = std::hypot(lateral, q.z()), theta = std::atan2(lateral, q.z());
        const double beta = std::asin(b.radius / rho);
        lo = std::min(lo, std::tan(theta - beta));
        hi = std::max(hi, std::tan(theta + beta));
      };
      range(q.x(), box.x0, box.x1);
      range(q.y(), box.y0, box.y1);
    }
    boxes.push_back(box);
  }
  return boxes;
}

}  // namespace multislit
