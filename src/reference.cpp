#include "multislit/reference.h"

#include "config_check.h"
#include "slit_tracks.h"
#include "yaml_fields.h"

#include <Eigen/Dense>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

namespace multislit {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// The widest constant region that overlaps no neighbour on any row (Fig. 7).
int widestRegion(const std::vector<ReferenceSlit>& slits, int image_height) {
  double min_gap = std::numeric_limits<double>::infinity();
  std::vector<float> on_row;
  for (int r = 0; r < image_height; ++r) {
    on_row.clear();
    for (const ReferenceSlit& s : slits)
      if (r >= s.first_row && r <= s.lastRow() &&
          std::isfinite(s.u[static_cast<std::size_t>(r - s.first_row)]))
        on_row.push_back(s.u[static_cast<std::size_t>(r - s.first_row)]);
    std::sort(on_row.begin(), on_row.end());
    for (std::size_t k = 1; k < on_row.size(); ++k)
      min_gap = std::min<double>(min_gap, on_row[k] - on_row[k - 1]);
  }
  // Regions [u - W/2, u + W/2] of neighbours share no column when W <= gap - 1.
  return std::isfinite(min_gap) ? static_cast<int>(std::floor(min_gap)) - 1 : 0;
}

// One reference point seen on the plane images: u_k = u_inf + K / Z_k.
struct PlaneObservation {
  std::size_t slit, row;
  std::vector<std::pair<double, double>> wu;  // (1 / Z, u)

  std::pair<double, double> means() const {  // of 1 / Z and of u
    double mw = 0, mu = 0;
    for (const auto& [w, u] : wu) mw += w, mu += u;
    mw /= static_cast<double>(wu.size());
    mu /= static_cast<double>(wu.size());
    return {mw, mu};
  }
};

/// A plane image's slit through `ref`'s lens: each recorded point's ideal pixel
/// (Reference::idealPoint), NaN where the slit has no point.
std::vector<Eigen::Vector2d> idealSlit(const Reference& ref, const ReferenceSlit& p) {
  std::vector<Eigen::Vector2d> ideal(p.u.size(), Eigen::Vector2d::Constant(kNaN));
  for (std::size_t k = 0; k < p.u.size(); ++k)
    if (std::isfinite(p.u[k])) ideal[k] = ref.idealPoint(p, k);
  return ideal;
}

/// The ideal column where a plane slit (`ideal`: idealSlit(), first recorded row `first_row`)
/// crosses ideal row `v`, linear between its two ideal points around it, searched near recorded
/// row `row`; NaN where it does not cross there.
double idealColumnAt(const std::vector<Eigen::Vector2d>& ideal, int first_row, double v, int row) {
  constexpr int kReach = 16;  // rows a lens moves a point at most, between ideal and recorded
  const long lo = std::max(0L, static_cast<long>(row) - first_row - kReach);
  const long hi =
      std::min(static_cast<long>(ideal.size()) - 1, static_cast<long>(row) - first_row + kReach);
  for (long k = lo; k < hi; ++k) {
    const Eigen::Vector2d& a = ideal[static_cast<std::size_t>(k)];
    const Eigen::Vector2d& b = ideal[static_cast<std::size_t>(k + 1)];
    if (!(a.allFinite() && b.allFinite()) || !((a.y() - v) * (b.y() - v) <= 0) || a.y() == b.y())
      continue;
    return a.x() + (v - a.y()) / (b.y() - a.y()) * (b.x() - a.x());
  }
  return kNaN;
}

// Every point of the reference `ref` as seen on the plane images at `depths` (`seen`: their
// slits, in the same order). Through a distorting lens, in the ideal image: a point at its ideal
// row, where the eq. u = u_inf + K / Z holds.
std::vector<PlaneObservation> observeOnPlanes(const Reference& ref,
                                              const std::vector<std::vector<ReferenceSlit>>& seen,
                                              const std::vector<double>& depths) {
  const bool ideal = ref.lens.distorted();
  std::vector<std::vector<std::vector<Eigen::Vector2d>>> ideal_seen(seen.size());
  if (ideal)
    for (std::size_t k = 0; k < seen.size(); ++k)
      for (const ReferenceSlit& p : seen[k]) ideal_seen[k].push_back(idealSlit(ref, p));
  std::vector<PlaneObservation> obs;
  for (std::size_t s = 0; s < ref.slits.size(); ++s)
    for (std::size_t r = 0; r < ref.slits[s].u.size(); ++r) {
      PlaneObservation o{s, r, {}};
      const int row = ref.slits[s].first_row + static_cast<int>(r);
      const double v = ideal ? ref.idealPoint(ref.slits[s], r).y() : 0.0;
      for (std::size_t k = 0; k < seen.size(); ++k) {
        const ReferenceSlit& p = seen[k][s];
        const double u =
            ideal ? idealColumnAt(ideal_seen[k][s], p.first_row, v, row)
            : row < p.first_row || row > p.lastRow()
                ? kNaN
                : static_cast<double>(p.u[static_cast<std::size_t>(row - p.first_row)]);
        if (std::isfinite(u)) o.wu.emplace_back(1.0 / depths[k], u);
      }
      obs.push_back(std::move(o));
    }
  return obs;
}

// The one K of u = u_inf + K / Z that fits every point seen at two depths or more (least
// squares, u_inf per point) [px m].
double fitDisparityConstant(const std::vector<PlaneObservation>& obs) {
  double num = 0, den = 0;
  for (const PlaneObservation& o : obs) {
    if (o.wu.size() < 2) continue;
    const auto [mw, mu] = o.means();
    for (const auto& [w, u] : o.wu) num += (u - mu) * (w - mw), den += (w - mw) * (w - mw);
  }
  if (!(den > 0) || !(num > 0))
    throw std::runtime_error(
        "calibration: the plane images do not constrain the scale (same depths?)");
  return num / den;
}

}  // namespace

void ReferenceConfig::validate() const {
  constexpr detail::FieldCheck require("ReferenceConfig");
  require(expected_slits >= 1 && expected_slits <= 64, "expected_slits", "must be in [1, 64]");
  require(region_width == 0 || (region_width >= 3 && region_width <= 16384), "region_width",
          "must be 0 (automatic) or in [3, 16384] px");
  require(min_contrast > 0 && min_contrast < 1, "min_contrast", "must be in (0, 1) of full scale");
  require(min_rows >= 3, "min_rows", "must be >= 3");
  require(max_gap >= 1, "max_gap", "must be >= 1");
  require(smoothing_degree >= 0 && smoothing_degree <= 8, "smoothing_degree", "must be in [0, 8]");
  require(full_scale == 0 || (full_scale >= 1 && full_scale <= 65535), "full_scale",
          "must be 0 (the image type's) or in [1, 65535] DN");
}

Reference Reference::fromImage(const cv::Mat& image, const ReferenceConfig& config) {
  config.validate();
  if (image.empty()) throw std::runtime_error("reference image is empty");
  if (image.channels() != 1 || (image.depth() != CV_8U && image.depth() != CV_16U))
    throw std::runtime_error("reference image must be 8- or 16-bit with one channel");
  Reference ref;
  ref.image_width = image.cols;
  ref.image_height = image.rows;
  DetectedSlits found = detectSlits(image, config, "reference image");
  ref.slits = std::move(found.slits);
  ref.profile_width = found.profile_width;
  ref.smoothing_rms = found.smoothing_rms;
  ref.joined_pieces = found.joined;
  ref.dropped_tracks = found.dropped;
  ref.full_scale = config.full_scale;
  ref.max_region_width = widestRegion(ref.slits, image.rows);
  if (ref.max_region_width < 3)
    throw std::runtime_error("reference image: the slits are too close for any assigned region");
  if (config.region_width > ref.max_region_width)
    throw std::invalid_argument("region_width " + std::to_string(config.region_width) +
                                " px would overlap the neighbours: at most " +
                                std::to_string(ref.max_region_width) + " px");
  ref.region_width = config.region_width > 0 ? config.region_width : ref.max_region_width;
  return ref;
}

Reference Reference::fromImages(const std::vector<cv::Mat>& images, const ReferenceConfig& config) {
  if (images.empty()) throw std::invalid_argument("reference: no image given");
  if (images.size() == 1) return fromImage(images.front(), config);
  const cv::Mat& first = images.front();
  cv::Mat sum = cv::Mat::zeros(first.size(), CV_64F);
  for (std::size_t k = 0; k < images.size(); ++k) {
    const cv::Mat& image = images[k];
    if (image.size() != first.size() || image.type() != first.type())
      throw std::invalid_argument("reference image " + std::to_string(k + 1) +
                                  ": size or type differs from the first image");
    cv::add(sum, image, sum, cv::noArray(), CV_64F);  // no double copy of the image
  }
  // The mean in 16-bit DN (8-bit images times 257): the averaging keeps its fractions.
  const double to16 = first.depth() == CV_8U ? 257.0 : 1.0;
  cv::Mat mean;
  sum.convertTo(mean, CV_16U, to16 / static_cast<double>(images.size()));
  ReferenceConfig mean_config = config;  // the full scale of the 16-bit mean
  mean_config.full_scale *= to16;
  Reference ref = fromImage(mean, mean_config);
  ref.full_scale = config.full_scale;
  return ref;
}

std::size_t Reference::pointCount() const {
  std::size_t n = 0;
  for (const ReferenceSlit& s : slits)
    n += static_cast<std::size_t>(
        std::count_if(s.u.begin(), s.u.end(), [](float u) { return std::isfinite(u); }));
  return n;
}

int Reference::maxSlitLength() const {
  int n = 0;
  for (const ReferenceSlit& s : slits) n = std::max(n, static_cast<int>(s.u.size()));
  return n;
}

void Reference::checkImage(const cv::Mat& image, const std::string& what) const {
  if (image.empty()) throw std::invalid_argument(what + ": empty image");
  if (image.channels() != 1 || (image.depth() != CV_8U && image.depth() != CV_16U))
    throw std::invalid_argument(what + ": must be an 8- or 16-bit image with one channel");
  if (image.cols != image_width || image.rows != image_height)
    throw std::invalid_argument(
        what + ": image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
        " but the reference was taken with a " + std::to_string(image_width) + "x" +
        std::to_string(image_height) + " camera");
  const double white = image.depth() == CV_8U ? 255.0 : 65535.0;
  if (full_scale > white)
    throw std::invalid_argument(
        what + ": the calibration's full_scale " + std::to_string(static_cast<int>(full_scale)) +
        " DN is above the white of this " + (image.depth() == CV_8U ? "8" : "16") + "-bit image");
}

Eigen::Vector2d Reference::idealPoint(const ReferenceSlit& s, std::size_t k) const {
  const Eigen::Vector2d recorded(s.u[k], s.first_row + static_cast<double>(k));
  return lens.distorted() ? lens.undistort(recorded) : recorded;
}

void Reference::setLens(const CameraConfig& camera) { lens = camera.lens(); }

void Reference::checkLens(const CameraConfig& camera, const std::string& what) const {
  const Lens other = camera.lens();
  bool same_distortion = true;
  for (const auto& [key, field] : kDistortionKeys)
    same_distortion = same_distortion && lens.distortion().*field == other.distortion().*field;
  const bool same_intrinsics = !lens.distorted() || (std::abs(lens.f() - other.f()) < 1e-6 &&
                                                     std::abs(lens.cx() - other.cx()) < 1e-6 &&
                                                     std::abs(lens.cy() - other.cy()) < 1e-6);
  if (same_distortion && same_intrinsics) return;
  throw std::invalid_argument(what + " was made for " +
                              (lens.distorted() ? "another lens" : "a lens without distortion") +
                              ", not the camera's: calibrate again with the same intrinsics");
}

void Reference::setNominalScale(const SensorConfig& sensor, const MountConfig& reference_mount) {
  if (sensor.camera.width != image_width || sensor.camera.height != image_height)
    throw std::invalid_argument("sensor config: camera is " + std::to_string(sensor.camera.width) +
                                "x" + std::to_string(sensor.camera.height) +
                                " but the reference image is " + std::to_string(image_width) + "x" +
                                std::to_string(image_height));
  const SensorGeometry g(sensor);
  setLens(sensor.camera);
  scale.f = sensor.camera.f();
  scale.cx = sensor.camera.cx();
  scale.cy = sensor.camera.cy();
  scale.disparity_constant = scale.f * sensor.projector.baseline;
  scale.source = "nominal";
  // The reference plane (the floor) in the camera frame: n . X = d.
  const Eigen::Isometry3d camera_from_robot = g.robotFromCamera(reference_mount).inverse();
  const Eigen::Vector3d n = camera_from_robot.linear() * Eigen::Vector3d::UnitZ();
  const double d = n.dot(camera_from_robot.translation());
  for (ReferenceSlit& s : slits) {
    s.u_inf.assign(s.u.size(), kNaN);
    for (std::size_t k = 0; k < s.u.size(); ++k) {
      const double depth = d / n.dot(g.pixelRay(s.u[k], s.first_row + static_cast<double>(k)));
      const double u = idealPoint(s, k).x();
      if (depth > 0) s.u_inf[k] = static_cast<float>(u - scale.disparity_constant / depth);
    }
  }
}

double Reference::calibrateWithPlanes(const std::vector<cv::Mat>& images,
                                      const std::vector<double>& depths, const CameraConfig& camera,
                                      const ReferenceConfig& config) {
  if (images.size() != depths.size() || images.size() < 2)
    throw std::invalid_argument("calibration needs images of a plane at two or more known depths");
  setLens(camera);
  std::vector<std::vector<ReferenceSlit>> seen;
  for (std::size_t k = 0; k < images.size(); ++k) {
    const std::string what =
        "plane image " + std::to_string(k + 1) + " (" + std::to_string(depths[k]) + " m)";
    checkImage(images[k], what);
    if (!(depths[k] > 0)) throw std::invalid_argument(what + ": depth must be > 0");
    seen.push_back(detectSlits(images[k], config, what).slits);
  }
  // u_k = u_inf + K / Z_k for every reference point: one K for all, u_inf per point.
  const std::vector<PlaneObservation> obs = observeOnPlanes(*this, seen, depths);
  const double k_fb = fitDisparityConstant(obs);
  double ss = 0;
  std::size_t m = 0;
  for (ReferenceSlit& s : slits) s.u_inf.assign(s.u.size(), kNaN);
  for (const PlaneObservation& o : obs) {
    if (o.wu.size() < 2) continue;
    const auto [mw, mu] = o.means();
    const double u_inf = mu - k_fb * mw;
    slits[o.slit].u_inf[o.row] = static_cast<float>(u_inf);
    for (const auto& [w, u] : o.wu) ss += (u - u_inf - k_fb * w) * (u - u_inf - k_fb * w), ++m;
  }
  scale.f = camera.f();
  scale.cx = camera.cx();
  scale.cy = camera.cy();
  scale.disparity_constant = k_fb;
  scale.source = "planes";
  return std::sqrt(ss / static_cast<double>(std::max<std::size_t>(m, 1)));
}

namespace {

// The keys of a calibration file, in the file's order: its values, then its sections.
const Field<Reference> kReferenceKeys[] = {{"image_width", &Reference::image_width},
                                           {"image_height", &Reference::image_height},
                                           {"camera_id", &Reference::camera_id},
                                           {"region_width", &Reference::region_width},
                                           {"max_region_width", &Reference::max_region_width},
                                           {"profile_width", &Reference::profile_width},
                                           {"smoothing_rms", &Reference::smoothing_rms},
                                           {"full_scale", &Reference::full_scale}};
constexpr const char* kScale = "scale";
constexpr const char* kLens = "lens";    // absent: a pinhole
constexpr const char* kSlits = "slits";  // a list, each with kSlitKeys
const Field<MetricScale> kScaleKeys[] = {{"source", &MetricScale::source},
                                         {"f", &MetricScale::f},
                                         {"cx", &MetricScale::cx},
                                         {"cy", &MetricScale::cy},
                                         {"disparity_constant", &MetricScale::disparity_constant}};
// The lens section: a Lens's intrinsics and distortion.
struct LensEntries {
  double f = 1, cx = 0, cy = 0;
  LensDistortion distortion;
};
const Field<LensEntries> kLensKeys[] = {{"f", &LensEntries::f},
                                        {"cx", &LensEntries::cx},
                                        {"cy", &LensEntries::cy},
                                        {"distortion", &LensEntries::distortion}};
const Field<ReferenceSlit> kSlitKeys[] = {{"first_row", &ReferenceSlit::first_row},
                                          {"u", &ReferenceSlit::u},
                                          {"u_inf", &ReferenceSlit::u_inf}};

// The lens section of a calibration file (absent: a pinhole).
Lens readLens(const cv::FileNode& node) {
  checkKeys(node, kLens, keysOf(kLensKeys));
  LensEntries l;
  readFields(node, kLensKeys, l);
  return Lens(l.f, l.cx, l.cy, l.distortion);
}

}  // namespace

void Reference::save(const std::string& path) const {
  validate();  // never a file that load() would refuse
  cv::FileStorage fs = openYamlForWrite(path, "calibration");
  writeFields(fs, kReferenceKeys, *this);
  fs << kScale << "{";
  writeFields(fs, kScaleKeys, scale);
  fs << "}";
  if (lens.distorted()) {  // a pinhole's file stays as it was
    fs << kLens << "{";
    writeFields(fs, kLensKeys, LensEntries{lens.f(), lens.cx(), lens.cy(), lens.distortion()});
    fs << "}";
  }
  fs << kSlits << "[";
  for (const ReferenceSlit& s : slits) {
    fs << "{";
    writeFields(fs, kSlitKeys, s);
    fs << "}";
  }
  fs << "]";
}

Reference Reference::load(const std::string& path) {
  cv::FileStorage fs = openYamlForRead(path, "calibration");
  Reference ref;
  try {
    const cv::FileNode root = fs.root();
    std::vector<std::string> known = keysOf(kReferenceKeys);
    known.insert(known.end(), {kScale, kLens, kSlits});
    checkKeys(root, "", known);
    checkKeys(fs[kScale], kScale, keysOf(kScaleKeys));
    ref.lens = readLens(fs[kLens]);
    readFields(root, kReferenceKeys, ref);
    readFields(fs[kScale], kScaleKeys, ref.scale);
    const cv::FileNode list = fs[kSlits];
    if (!list.isSeq() || list.size() == 0)
      throw std::invalid_argument("'slits' must be a non-empty list");
    for (const cv::FileNode& n : list) {
      checkKeys(n, std::string(kSlits) + "[" + std::to_string(ref.slits.size()) + "]",
                keysOf(kSlitKeys));
      ReferenceSlit s;
      readFields(n, kSlitKeys, s);
      ref.slits.push_back(std::move(s));
    }
    ref.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("calibration '" + path + "': " + e.what());
  } catch (const cv::Exception& e) {
    throw std::invalid_argument("calibration '" + path + "': " + e.err);
  }
  return ref;
}

}  // namespace multislit
