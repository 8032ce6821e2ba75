#include "multislit/sensor.h"
#include "multislit/image_file.h"
#include "multislit/units.h"

#include "avx2_clones.h"
#include "config_check.h"
#include "yaml_fields.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace multislit {

void SensorConfig::validate() const {
  const auto require = [](bool ok, const std::string& field, const std::string& rule) {
    if (!ok) detail::require(false, "sensor config: " + field, rule);  // the text only on failure
  };
  const CameraConfig& c = camera;
  const std::string sides = "must be in [16, " + std::to_string(kMaxImageSide) + "] px";
  require(c.width >= 16 && c.width <= kMaxImageSide, "camera.width", sides);
  require(c.height >= 16 && c.height <= kMaxImageSide, "camera.height", sides);
  require(c.pixel_size > 0 && c.pixel_size < 1e-3, "camera.pixel_size", "must be in (0, 1e-3) m");
  require(c.focal_length > 0 && c.focal_length < 1.0, "camera.focal_length", "must be in (0, 1) m");
  require(c.f() >= kMinFocalPx && c.f() <= kMaxFocalPx, "camera.focal_length",
          "over pixel_size (f, the focal length in pixels) must be in [1, 1e6] px");
  require(c.principal_x < c.width, "camera.principal_x", "must lie inside the image");
  require(c.principal_y < c.height, "camera.principal_y", "must lie inside the image");
  c.distortion.validate("sensor config: camera");
  require(c.lens().monotonicOver(c.width, c.height), "camera.k1",
          "to k6 fold the image: the radial distortion must rise out to the image's corners");
  const ProjectorConfig& p = projector;
  require(p.slit_count >= 1 && p.slit_count <= 64, "projector.slit_count", "must be in [1, 64]");
  require(p.slit_spacing > 0 && p.slit_spacing * (p.slit_count - 1) < 120, "projector.slit_spacing",
          "must be > 0 deg with the whole fan under 120 deg");
  require(p.slit_half_length > 0 && p.slit_half_length < 80, "projector.slit_half_length",
          "must be in (0, 80) deg");
  require(p.sheet_sigma > 0 && p.sheet_sigma < 0.05, "projector.sheet_sigma",
          "must be in (0, 0.05) rad");
  require(p.baseline > 0 && p.baseline < kMaxBaseline, "projector.baseline", "must be in (0, 1) m");
  require(p.rotation >= 0 && p.rotation < 89, "projector.rotation", "must be in [0, 89) deg");
  // Each slit must cross every row at most once: dv/dt = f (cos(rho) + 2 sin(rho) k t) > 0.
  const double t_max = std::tan(p.slit_half_length * kDeg);
  require(std::cos(p.rotation * kDeg) >
              2.0 * std::abs(p.curvature) * std::sin(p.rotation * kDeg) * t_max,
          "projector.curvature", "is too large for the rotation: a slit would cross a row twice");
  const MountConfig& m = mount;
  require(m.tilt >= 0 && m.tilt <= 90, "mount.tilt", "must be in [0, 90] deg");
  require(std::abs(m.roll) <= 45, "mount.roll", "must be in [-45, 45] deg");
  require(m.height > 0 && m.height < 10, "mount.height", "must be in (0, 10) m");
  require(std::abs(m.forward) < 1, "mount.forward", "must be in (-1, 1) m");
}

namespace {

// The keys of each section of a sensor file, in the file's order.
const Field<CameraConfig> kCameraKeys[] = {{"width", &CameraConfig::width},
                                           {"height", &CameraConfig::height},
                                           {"pixel_size", &CameraConfig::pixel_size},
                                           {"focal_length", &CameraConfig::focal_length},
                                           {"principal_x", &CameraConfig::principal_x},
                                           {"principal_y", &CameraConfig::principal_y},
                                           {"distortion", &CameraConfig::distortion}};
const Field<ProjectorConfig> kProjectorKeys[] = {
    {"slit_count", &ProjectorConfig::slit_count},
    {"slit_spacing", &ProjectorConfig::slit_spacing},
    {"slit_half_length", &ProjectorConfig::slit_half_length},
    {"curvature", &ProjectorConfig::curvature},
    {"sheet_sigma", &ProjectorConfig::sheet_sigma},
    {"baseline", &ProjectorConfig::baseline},
    {"rotation", &ProjectorConfig::rotation}};
const Field<MountConfig> kMountKeys[] = {{"tilt", &MountConfig::tilt},
                                         {"roll", &MountConfig::roll},
                                         {"height", &MountConfig::height},
                                         {"forward", &MountConfig::forward}};

// visit(name, keys, section) for the sections of a sensor file, in the file's order.
template <typename Sensor, typename Visit>
void forEachSection(Sensor& s, Visit&& visit) {
  visit("camera", kCameraKeys, s.camera);
  visit("projector", kProjectorKeys, s.projector);
  visit("mount", kMountKeys, s.mount);
}

}  // namespace

SensorConfig SensorConfig::load(const std::string& path) {
  cv::FileStorage fs = openYamlForRead(path, "sensor config");
  SensorConfig s;
  try {
    std::vector<std::string> sections;
    forEachSection(s, [&](const char* name, const auto&, auto&) { sections.push_back(name); });
    checkKeys(fs.root(), "", sections);
    forEachSection(s, [&](const char* name, const auto& keys, auto&) {
      checkKeys(fs[name], name, keysOf(keys));
    });
    forEachSection(s, [&](const char* name, const auto& keys, auto& section) {
      readFields(fs[name], keys, section);
    });
    s.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
  return s;
}

void SensorConfig::save(const std::string& path) const {
  cv::FileStorage fs = openYamlForWrite(path, "sensor config");
  forEachSection(*this, [&](const char* name, const auto& keys, const auto& section) {
    fs << name << "{";
    writeFields(fs, keys, section);
    fs << "}";
  });
}

SensorGeometry::SensorGeometry(const SensorConfig& config) : config_(config) {
  config_.validate();
  f_ = config_.camera.f();
  cx_ = config_.camera.cx();
  cy_ = config_.camera.cy();
  lens_ = config_.camera.lens();
  t_max_ = std::tan(config_.projector.slit_half_length * kDeg);
  camera_from_projector_ =
      Eigen::AngleAxisd(config_.projector.rotation * kDeg, Eigen::Vector3d::UnitZ())
          .toRotationMatrix();
  projector_centre_ = Eigen::Vector3d(config_.projector.baseline, 0.0, 0.0);
  const ProjectorConfig& p = config_.projector;
  for (int i = 0; i < p.slit_count; ++i) {
    slit_tan_.push_back(slitTan(i));
    if (i + 1 < p.slit_count)
      boundary_tan_.push_back(std::tan((i + 1 - 0.5 * p.slit_count) * p.slit_spacing * kDeg));
  }
  double step = 1;
  if (boundary_tan_.size() >= 2) {
    double gap = boundary_tan_[1] - boundary_tan_[0];
    for (std::size_t i = 2; i < boundary_tan_.size(); ++i)
      gap = std::min(gap, boundary_tan_[i] - boundary_tan_[i - 1]);
    step = 0.5 * gap;
  }
  lookup_per_step_ = 1.0 / step;
  lookup_low_ = boundary_tan_.empty() ? 0.0 : boundary_tan_.front() - step;
  const double high = boundary_tan_.empty() ? 0.0 : boundary_tan_.back() + step;
  const auto cells = static_cast<int>(std::ceil((high - lookup_low_) * lookup_per_step_)) + 1;
  for (int k = 0; k < cells; ++k) {
    // The cell's start as the lookup computes it: (x - low) / step = k exactly there.
    const double start = lookup_low_ + k * step;
    boundary_lookup_.push_back(
        static_cast<int>(std::upper_bound(boundary_tan_.begin(), boundary_tan_.end(), start) -
                         boundary_tan_.begin()));
  }
}

double SensorGeometry::slitTan(int slit) const {
  const ProjectorConfig& p = config_.projector;
  return std::tan((slit - 0.5 * (p.slit_count - 1)) * p.slit_spacing * kDeg);
}

Eigen::Vector3d SensorGeometry::pixelRay(double u, double v) const {
  if (lens_.distorted()) {
    const Eigen::Vector2d ideal = lens_.undistort(Eigen::Vector2d(u, v));
    u = ideal.x(), v = ideal.y();
  }
  return Eigen::Vector3d((u - cx_) / f_, (v - cy_) / f_, 1.0);
}

Eigen::Vector2d SensorGeometry::project(const Eigen::Vector3d& p) const {
  const Eigen::Vector2d ideal(cx_ + f_ * p.x() / p.z(), cy_ + f_ * p.y() / p.z());
  return lens_.distorted() ? lens_.distort(ideal) : ideal;
}

Eigen::Vector2d SensorGeometry::toProjector(const Eigen::Vector3d& p_camera) const {
  const Eigen::Vector3d q = camera_from_projector_.transpose() * (p_camera - projector_centre_);
  return Eigen::Vector2d(q.x() / q.z(), q.y() / q.z());
}

Eigen::Vector3d SensorGeometry::slitRay(int slit, double t) const {
  const double k = config_.projector.curvature;
  return camera_from_projector_ * Eigen::Vector3d(slitTan(slit) + k * t * t, t, 1.0);
}

double SensorGeometry::sheetOffset(int slit, const Eigen::Vector2d& xy) const {
  const ProjectorConfig& p = config_.projector;
  const double alpha = (slit - 0.5 * (p.slit_count - 1)) * p.slit_spacing * kDeg;
  return std::atan(xy.x() - p.curvature * xy.y() * xy.y()) - alpha;
}

int SensorGeometry::nearestSlit(const Eigen::Vector2d& xy) const {
  const ProjectorConfig& p = config_.projector;
  const double alpha = std::atan(xy.x() - p.curvature * xy.y() * xy.y());
  const long i = std::lround(alpha / (p.slit_spacing * kDeg) + 0.5 * (p.slit_count - 1));
  return static_cast<int>(std::clamp<long>(i, 0, p.slit_count - 1));
}

MULTISLIT_AVX2_CLONES void SensorGeometry::seriesOfPoints(double* __restrict x,
                                                          const int* __restrict slit,
                                                          const double* __restrict tans, int n) {
  for (int i = 0; i < n; ++i) x[i] = atanSeries(tanFromSheet(x[i], tans[slit[i]]));
}

void SensorGeometry::nearestSheetOffsets(const double* x, const double* y, int n, double* offset,
                                         int* slit, bool exact_far) const {
  const double curvature = config_.projector.curvature;
  for (int i = 0; i < n; ++i) offset[i] = x[i] - curvature * y[i] * y[i];
  // The sheet: nearestSheet() of the first point, then from each point's to the next one's,
  // which lies near it (a row of pixels moves monotonically across the sheets). The same
  // sheet: the count of boundaries at or below the point.
  const double* boundary = boundary_tan_.data();
  const auto boundaries = static_cast<int>(boundary_tan_.size());
  int k = n > 0 ? static_cast<int>(nearestSheet(offset[0])) : 0;
  for (int i = 0; i < n; ++i) {
    const double v = offset[i];
    if (v != v) {  // NaN: nearestSheet() gives the first sheet
      slit[i] = 0;
      continue;
    }
    while (k < boundaries && v >= boundary[k]) ++k;
    while (k > 0 && v < boundary[k - 1]) --k;
    slit[i] = k;
  }
  seriesOfPoints(offset, slit, slit_tan_.data(), n);
  // The series serves |d| <= 0.05 (kSeriesLimit), where it is <= 0.0500; beyond, it is >= 0.83
  // |d| > 0.0415 (its polynomial in d^2 stays above 0.83): those points are done again, where
  // their exact value is wanted (atan(d) >= atan(0.05) > kFarOffset there).
  static_assert(kFarOffset < 0.0415 && kSeriesLimit == 2.5e-3, "the series' bounds");
  if (!exact_far) return;
  for (int i = 0; i < n; ++i)
    if (std::abs(offset[i]) > kFarOffset)
      offset[i] = nearestSheetOffset(Eigen::Vector2d(x[i], y[i]), &slit[i]);
}

double SensorGeometry::rowOf(int slit, double t) const {
  return cy_ + f_ * slitRay(slit, t).y();  // slitRay has z = 1: rotation is about z
}

std::optional<double> SensorGeometry::slitParamForRow(int slit, double v) const {
  // v = cy + f (sin(rho) (a + k t^2) + cos(rho) t): a quadratic in t, one root in range.
  const double rho = config_.projector.rotation * kDeg;
  const double qa = std::sin(rho) * config_.projector.curvature;
  const double qb = std::cos(rho);
  const double qc = std::sin(rho) * slitTan(slit) + (cy_ - v) / f_;
  double t;
  if (std::abs(qa) < 1e-15) {
    t = -qc / qb;
  } else {
    const double disc = qb * qb - 4.0 * qa * qc;
    if (disc < 0) return std::nullopt;
    const double q = -0.5 * (qb + std::copysign(std::sqrt(disc), qb));
    t = qc / q;  // the root that tends to -c/b as the curvature vanishes
  }
  if (std::abs(t) > t_max_) return std::nullopt;
  return t;
}

std::pair<int, int> SensorGeometry::slitRows(int slit) const {
  const double a = rowOf(slit, -t_max_);
  const double b = rowOf(slit, t_max_);
  const int first = std::max(0, static_cast<int>(std::ceil(std::min(a, b))));
  const int last =
      std::min(config_.camera.height - 1, static_cast<int>(std::floor(std::max(a, b))));
  return {first, last};
}

Eigen::Isometry3d SensorGeometry::robotFromCamera(const MountConfig& mount) const {
  // Body frame B: x right, y down, z forward, with the slits along x (across the walking
  // direction). The camera is turned about the optical axis by the pattern rotation + 90 deg,
  // so that the slits' long axis (projector y) is the body's x axis.
  Eigen::Matrix3d robot_from_level;
  robot_from_level.col(0) = Eigen::Vector3d(0, -1, 0);  // right
  robot_from_level.col(1) = Eigen::Vector3d(0, 0, -1);  // down
  robot_from_level.col(2) = Eigen::Vector3d(1, 0, 0);   // forward
  const Eigen::Matrix3d body =
      robot_from_level *
      Eigen::AngleAxisd(-mount.tilt * kDeg, Eigen::Vector3d::UnitX()).toRotationMatrix() *
      Eigen::AngleAxisd(mount.roll * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d body_from_camera =
      Eigen::AngleAxisd(-(config_.projector.rotation + 90.0) * kDeg, Eigen::Vector3d::UnitZ())
          .toRotationMatrix();
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = body * body_from_camera;
  t.translation() = Eigen::Vector3d(mount.forward, 0.0, mount.height);
  return t;
}

}  // namespace multislit
