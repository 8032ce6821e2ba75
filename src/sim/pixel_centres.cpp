#include "pixel_centres.h"

#include "object_bounds.h"
#include "parallel_rows.h"

#include "avx2_clones.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace multislit {
namespace {

// A row's rays: column c's world ray w + c d from the camera centre o, its projector ray g + c h,
// the projector centre m (in projector axes).
struct RowRays {
  double wx, wy, wz, dx, dy, dz, ox, oy, oz, gx, gy, gz, hx, hy, hz, mx, my, mz;
};

// Where each column's ray meets the floor: its world z (depth, < 0 when it meets it), the floor
// point (px, py; 0 where it does not: a point the texture's tables hold) and its normalized
// projector coordinates (x, y). No dependencies between columns: a loop the compiler vectorizes.
MULTISLIT_AVX2_CLONES void projectRow(const RowRays r, int width, double* __restrict depth,
                                      double* __restrict px, double* __restrict py,
                                      double* __restrict x, double* __restrict y) {
  for (int c = 0; c < width; ++c) {
    depth[c] = r.wz + c * r.dz;
    const double s = -r.oz / depth[c];
    const bool floor = depth[c] < 0;
    px[c] = floor ? r.ox + s * (r.wx + c * r.dx) : 0.0;
    py[c] = floor ? r.oy + s * (r.wy + c * r.dy) : 0.0;
    const double qz = s * (r.gz + c * r.hz) - r.mz;
    x[c] = (s * (r.gx + c * r.hx) - r.mx) / qz;
    y[c] = (s * (r.gy + c * r.hy) - r.my) / qz;
  }
}

// One row's outputs of traceCentres(), and how a pixel's sample gives them.
struct RowOut {
  Shader::Sample* samples;
  float* ambient;
  uchar* near;
  double light, reach, t_near;  // the ambient light; the reach and |t| of a pixel near a sheet
  void finish(std::size_t k) const {  // the ambient light, and whether a sheet may light it
    const Shader::Sample& s = samples[k];
    ambient[k] = static_cast<float>(light * (s.albedo + s.glare));
    near[k] = std::abs(s.offset) < reach && std::abs(s.t) < t_near;
  }
};

// The floor along a row's pixel centres: each column's sample as trace() gives it where no object
// is on the ray, in closed form. project() has no dependencies between columns, so the compiler
// vectorizes it.
class FloorRow {
 public:
  FloorRow(const Shader& shader, const FloorAlbedo& albedo)
      : shader_(shader), albedo_(albedo), width_(shader.geometry.config().camera.width) {
    for (std::vector<double>* v : {&depth_, &x_, &y_, &px_, &py_, &offset_, &albedo_row_})
      v->resize(static_cast<std::size_t>(width_));
    slit_.resize(static_cast<std::size_t>(width_));
  }

  void project(int r) {
    const CameraConfig& camera = shader_.geometry.config().camera;
    const double f = camera.f();
    const Eigen::Vector3d first(-camera.cx() / f, (r - camera.cy()) / f, 1.0);  // column 0's ray
    const Eigen::Matrix3d& world = shader_.world_from_camera.linear();
    const Eigen::Matrix3d projector = shader_.geometry.cameraFromProjector().transpose();
    w0_ = world * first;
    w1_ = world.col(0) / f;
    const Eigen::Vector3d g0 = projector * first, g1 = projector.col(0) / f,
                          m = projector * shader_.geometry.projectorCentre();
    const Eigen::Vector3d& o = shader_.camera_centre;
    const RowRays rays{w0_.x(), w0_.y(), w0_.z(), w1_.x(), w1_.y(), w1_.z(), o.x(), o.y(), o.z(),
                       g0.x(),  g0.y(),  g0.z(),  g1.x(),  g1.y(),  g1.z(),  m.x(), m.y(), m.z()};
    double* px = px_.data();
    double* py = py_.data();
    double* x = x_.data();
    double* y = y_.data();
    projectRow(rays, width_, depth_.data(), px, py, x, y);
    albedo_.row(px, py, floorBox(), albedo_row_.data(), width_);
    // The nearest sheets, the whole row at once; a pixel outside the fan only needs to be seen to
    // be far from every sheet (the light's reach is a few milliradians).
    const SensorGeometry& geometry = shader_.geometry;
    geometry.nearestSheetOffsets(x, y, width_, offset_.data(), slit_.data(), false);
  }

  /// A box around the row's floor points (px, py) of project(): (0, 0) where the ray misses the
  /// floor. The floor's columns are those of depth < 0, one run (depth is linear in the column),
  /// along which the point moves monotonically (a ratio of linear functions without a pole), so
  /// the run's ends bound it.
  FloorAlbedo::RowBox floorBox() const {
    int first = 0, last = width_ - 1;
    while (first <= last && !(depth_[static_cast<std::size_t>(first)] < 0)) ++first;
    while (last >= first && !(depth_[static_cast<std::size_t>(last)] < 0)) --last;
    FloorAlbedo::RowBox box;  // (0, 0)
    if (first > last) return box;
    const double ends_x[] = {px_[static_cast<std::size_t>(first)],
                             px_[static_cast<std::size_t>(last)]};
    const double ends_y[] = {py_[static_cast<std::size_t>(first)],
                             py_[static_cast<std::size_t>(last)]};
    box = FloorAlbedo::boxOf(ends_x, ends_y, 2);
    if (first > 0 || last < width_ - 1) {  // and the zeros of the columns off the floor
      box.lo_x = std::min(box.lo_x, 0.0), box.hi_x = std::max(box.hi_x, 0.0);
      box.lo_y = std::min(box.lo_y, 0.0), box.hi_y = std::max(box.hi_y, 0.0);
    }
    return box;
  }

  /// Writes column c's sample into `s`.
  void at(int c, double reach, Shader::Sample& s) const {
    const auto k = static_cast<std::size_t>(c);
    if (!(depth_[k] < 0) || !(shader_.camera_centre.z() > 0)) {  // above the horizon
      s = Shader::Sample{};
      return;
    }
    s.object = 0;
    s.slit = static_cast<std::int16_t>(slit_[k]);
    s.t = static_cast<float>(y_[k]);
    s.offset = offset_[k];
    s.albedo = static_cast<float>(albedo_row_[k]);
    s.radiance = 0;
    s.glare = 0;
    s.width = 1;
    if (glossy_ || std::abs(s.offset) <= reach) {
      const Eigen::Vector3d point_w(px_[k], py_[k], 0.0);
      shader_.glare(s, point_w, w0_ + c * w1_);
      shader_.illuminate(s, Eigen::Vector2d(x_[k], y_[k]), Eigen::Vector3d::UnitZ(), point_w,
                         reach);
    }
  }

  /// at() and RowOut::finish() of columns [first, end), no object on their rays. Most lie far
  /// from every sheet (beyond `lit`), where at() lights nothing: their sample in one store.
  void run(int first, int end, double lit, const RowOut& out) const {
    const bool sky = !(shader_.camera_centre.z() > 0);
    for (int c = first; c < end; ++c) {
      const auto k = static_cast<std::size_t>(c);
      const double offset = offset_[k];
      if (sky || !(depth_[k] < 0) || glossy_ || !(std::abs(offset) > lit)) {
        at(c, lit, out.samples[k]);
        out.finish(k);
        continue;
      }
      Shader::Sample s;
      s.object = 0;
      s.slit = static_cast<std::int16_t>(slit_[k]);
      s.t = static_cast<float>(y_[k]);
      s.offset = offset;
      s.albedo = static_cast<float>(albedo_row_[k]);
      s.radiance = s.glare = 0;
      s.width = 1;
      out.samples[k] = s;
      out.finish(k);
    }
  }

  /// Column c's sample where an object may be on the ray (r the row that project() was given):
  /// the object's when the ray meets one before the floor, else at()'s.
  void traced(int c, int r, double reach, Shader::Sample& s) const {
    const Eigen::Vector3d ray_c = shader_.geometry.pixelRay(c, r).normalized();
    const Eigen::Vector3d ray_w = shader_.world_from_camera.linear() * ray_c;
    const Hit hit = shader_.scene.intersect(shader_.camera_centre, ray_w);
    if (hit.object > 0)
      s = shader_.shade(hit, hit.distance * ray_c, shader_.camera_centre + hit.distance * ray_w,
                        ray_w, reach);
    else
      at(c, reach, s);
  }

 private:
  const Shader& shader_;
  const FloorAlbedo& albedo_;
  bool glossy_ = shader_.scene.floor.gloss > 0;
  int width_;
  Eigen::Vector3d w0_, w1_;  // the world ray of column c: w0 + c w1
  std::vector<double> depth_, x_, y_, px_, py_, offset_, albedo_row_;
  std::vector<int> slit_;
};

}  // namespace

Eigen::AlignedBox2d floorInView(const Shader& shader) {
  const CameraConfig& camera = shader.geometry.config().camera;
  const Eigen::Vector3d& o = shader.camera_centre;
  Eigen::AlignedBox2d region;
  for (int r = 0; r < camera.height + 7; r += 8) {
    for (int c = 0; c < camera.width + 7; c += 8) {
      const Eigen::Vector3d ray =
          shader.world_from_camera.linear() *
          shader.geometry.pixelRay(std::min(c, camera.width - 1), std::min(r, camera.height - 1));
      if (!(ray.z() < 0) || !(o.z() > 0)) continue;
      const Eigen::Vector3d hit = o - o.z() / ray.z() * ray;
      if ((hit - o).norm() < 5.0) region.extend(hit.head<2>());
    }
  }
  return region;
}

void traceCentres(const Shader& shader, double reach, double pixel, RenderMethod method,
                  CentreSamples& centre) {
  const SensorGeometry& geometry = shader.geometry;
  const int width = geometry.config().camera.width, height = geometry.config().camera.height;
  centre.width = width;
  centre.height = height;
  centre.samples.resize(static_cast<std::size_t>(width) * height);  // every one is written
  centre.ambient.create(height, width, CV_32F);
  centre.near.create(height, width, CV_8U);
  const std::vector<std::vector<ColumnSpan>> objects =
      method == RenderMethod::Culled
          ? objectColumns(shader)
          : std::vector<std::vector<ColumnSpan>>(static_cast<std::size_t>(height),
                                                 {ColumnSpan{0, width - 1}});
  // The light is traced a little beyond `reach`: the neighbours of a pixel near a sheet then have
  // their radiance, and the pixel's offset can be seen to be linear (no sub-pixel samples).
  const double lit = reach + 3 * pixel, t_near = geometry.slitTMax() + 2 * pixel;
  parallelRows(height, [&](const cv::Range& rows) {
    FloorRow floor(shader, *shader.floor_albedo);
    for (int r = rows.start; r < rows.end; ++r) {
      if (method == RenderMethod::Culled) floor.project(r);  // Exhaustive traces every ray
      Shader::Sample* row = &centre.samples[static_cast<std::size_t>(r) * width];
      const RowOut out{row,
                       centre.ambient.ptr<float>(r),
                       centre.near.ptr<uchar>(r),
                       shader.render.ambient,
                       reach,
                       t_near};
      int c = 0;
      for (const ColumnSpan& span : objects[static_cast<std::size_t>(r)]) {
        floor.run(c, span.first, lit, out);
        for (c = std::max(c, span.first); c <= span.last; ++c) {
          if (method == RenderMethod::Culled)
            floor.traced(c, r, lit, row[c]);
          else
            row[c] = shader.trace(c, r, lit);
          out.finish(static_cast<std::size_t>(c));
        }
      }
      floor.run(c, width, lit, out);
    }
  });
  // Catch pixels split by an edge.
  cv::dilate(centre.near, centre.near, cv::Mat::ones(3, 3, CV_8U));
}

}  // namespace multislit
