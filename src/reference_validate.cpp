// Reference::validate: the rules every reference obeys, whether found in an image or loaded from a
// calibration file (which anyone can edit): sizes within the camera, finite values, slits inside
// the image and apart from each other by at least the assigned region.
#include "multislit/reference.h"

#include "multislit/image_file.h"
#include "multislit/sensor.h"

#include "config_check.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace multislit {

using detail::require;

namespace {

/// Farthest a reference point may lie [m]: the plane a reference is taken of is a floor or a wall
/// near the sensor.
constexpr double kMaxReferenceDepth = 100.0;
/// Farthest the reference points may lie off one plane: rms over their median depth [-].
constexpr double kMaxPlaneRms = 0.05;

/// `v` in at most 4 significant digits (1e+308, not 309 digits).
std::string brief(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", v);
  return text;
}

/// Rows of slit `s` as [first, last], in 64 bits (a corrupt first_row must not overflow).
long long lastRowOf(const ReferenceSlit& s) {
  return static_cast<long long>(s.first_row) + static_cast<long long>(s.u.size()) - 1;
}

void validateSlit(const Reference& ref, std::size_t k) {
  const ReferenceSlit& s = ref.slits[k];
  const std::string name = "slits[" + std::to_string(k) + "]";
  require(!s.u.empty(), name + ".u", "must not be empty");
  require(s.u_inf.empty() || s.u_inf.size() == s.u.size(), name + ".u_inf",
          "must have as many values as u");
  require(s.first_row >= 0 && lastRowOf(s) < ref.image_height, name + ".first_row",
          "and the length of u must keep the slit's rows inside the image (0 .. " +
              std::to_string(ref.image_height - 1) + ")");
  std::size_t measured = 0;
  for (std::size_t j = 0; j < s.u.size(); ++j) {
    const float u = s.u[j];
    if (std::isnan(u)) continue;  // no point on that row
    require(std::isfinite(u) && u >= 0 && u <= static_cast<float>(ref.image_width - 1),
            name + ".u[" + std::to_string(j) + "]",
            "must be a column inside the image or .nan (is " + std::to_string(u) + ")");
    // .nan: no metric point there (a wall calibration that saw the point on fewer than two walls)
    require(s.u_inf.empty() || !std::isinf(s.u_inf[j]), name + ".u_inf[" + std::to_string(j) + "]",
            "must be finite or .nan where u is");
    ++measured;
  }
  require(measured > 0, name + ".u", "must hold at least one measured column");
}

/// Adjacent slits are at least a region apart on every row they share: regions never overlap.
void validateSpacing(const Reference& ref, std::size_t k) {
  const ReferenceSlit &a = ref.slits[k - 1], &b = ref.slits[k];
  const long long first = std::max(a.first_row, b.first_row);
  const long long last = std::min(lastRowOf(a), lastRowOf(b));
  double closest = std::numeric_limits<double>::infinity();
  for (long long row = first; row <= last; ++row) {
    const float ua = a.u[static_cast<std::size_t>(row - a.first_row)];
    const float ub = b.u[static_cast<std::size_t>(row - b.first_row)];
    if (!std::isnan(ua) && !std::isnan(ub)) closest = std::min(closest, std::abs(double(ub - ua)));
  }
  require(closest >= ref.region_width - 1.0, "slits[" + std::to_string(k) + "]",
          "must lie at least region_width (" + std::to_string(ref.region_width) +
              " px) from slits[" + std::to_string(k - 1) + "] on the rows they share (closest " +
              std::to_string(closest) + " px): the same slit twice, or regions that overlap");
}

/// A distorting lens is a real one, which maps the image one to one, with the scale's intrinsics.
void validateLens(const Reference& ref) {
  const Lens& lens = ref.lens;
  if (!lens.distorted()) return;
  require(std::isfinite(lens.f()) && lens.f() >= kMinFocalPx && lens.f() <= kMaxFocalPx, "lens.f",
          "must be in [1, 1e6] px (a real lens)");
  require(std::isfinite(lens.cx()) && lens.cx() >= -0.5 && lens.cx() <= ref.image_width - 0.5,
          "lens.cx", "must lie inside the image");
  require(std::isfinite(lens.cy()) && lens.cy() >= -0.5 && lens.cy() <= ref.image_height - 0.5,
          "lens.cy", "must lie inside the image");
  lens.distortion().validate("lens");
  require(lens.monotonicOver(ref.image_width, ref.image_height), "lens.k1",
          "to k6 fold the image: the radial distortion must rise out to the image's corners");
  const MetricScale& s = ref.scale;
  require(s.f == 0 || (s.f == lens.f() && s.cx == lens.cx() && s.cy == lens.cy()), "lens.f",
          "cx and cy must be the scale's f, cx and cy");
}

/// The metric scale describes a real sensor (a calibration file can be edited): f of a real lens,
/// the principal point inside the image, a baseline of 1 mm to kMaxBaseline, and every reference
/// point in front of the sensor within kMaxReferenceDepth. Else rdmap wrote points at +-inf and
/// map decided on them.
void validateScale(const Reference& ref) {
  const MetricScale& s = ref.scale;
  require(std::isfinite(s.f) && s.f >= 0, "scale.f", "must be finite and >= 0 px");
  require(std::isfinite(s.cx) && std::isfinite(s.cy), "scale.cx", "and cy must be finite");
  require(std::isfinite(s.disparity_constant) && s.disparity_constant >= 0,
          "scale.disparity_constant", "must be finite and >= 0 px m");
  require(s.source == "none" || s.valid(), "scale.f",
          "and disparity_constant must be > 0 when scale.source is '" + s.source + "'");
  if (s.f == 0 && s.disparity_constant == 0) return;  // no metric scale
  require(s.f >= kMinFocalPx && s.f <= kMaxFocalPx, "scale.f",
          "must be in [1, 1e6] px (a real lens), not " + brief(s.f));
  require(s.cx >= -0.5 && s.cx <= ref.image_width - 0.5, "scale.cx",
          "must lie inside the image (-0.5 .. " + std::to_string(ref.image_width) + " - 0.5 px)");
  require(s.cy >= -0.5 && s.cy <= ref.image_height - 0.5, "scale.cy",
          "must lie inside the image (-0.5 .. " + std::to_string(ref.image_height) + " - 0.5 px)");
  const double baseline = s.disparity_constant / s.f;
  require(baseline >= 1e-3 && baseline <= kMaxBaseline, "scale.disparity_constant",
          "over f (the baseline) must be in [0.001, 1] m, not " + brief(baseline) + " m");
  for (std::size_t k = 0; k < ref.slits.size(); ++k) {
    const ReferenceSlit& slit = ref.slits[k];
    for (std::size_t j = 0; j < slit.u_inf.size() && j < slit.u.size(); ++j) {
      if (!std::isfinite(slit.u[j]) || !std::isfinite(slit.u_inf[j])) continue;
      const double depth = s.disparity_constant / (ref.idealPoint(slit, j).x() - slit.u_inf[j]);
      require(depth > 0 && depth <= kMaxReferenceDepth,
              "slits[" + std::to_string(k) + "].u_inf[" + std::to_string(j) + "]",
              "with scale.disparity_constant puts the reference point at " + brief(depth) +
                  " m: it must be in front of the sensor, within " +
                  std::to_string(static_cast<int>(kMaxReferenceDepth)) + " m");
    }
  }
}

/// The reference points in 3D (MetricScale's equations) lie on one plane, as the plane they were
/// taken of: their rms distance from the plane fitted to them may be at most kMaxPlaneRms of
/// their median depth. A file whose u_inf, scale or slits were edited apart is refused.
void validatePlane(const Reference& ref) {
  const MetricScale& s = ref.scale;
  std::vector<Eigen::Vector3d> points;
  std::vector<double> depths;
  for (const ReferenceSlit& slit : ref.slits)
    for (std::size_t j = 0; j < slit.u.size() && j < slit.u_inf.size(); ++j) {
      if (!std::isfinite(slit.u[j]) || !std::isfinite(slit.u_inf[j])) continue;
      const Eigen::Vector2d ideal = ref.idealPoint(slit, j);
      const double z = s.disparity_constant / (ideal.x() - slit.u_inf[j]);
      points.emplace_back((ideal.x() - s.cx) * z / s.f, (ideal.y() - s.cy) * z / s.f, z);
      depths.push_back(z);
    }
  if (points.size() < 3) return;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : points) covariance += (p - mean) * (p - mean).transpose();
  covariance /= static_cast<double>(points.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  const double rms = std::sqrt(std::max(0.0, solver.eigenvalues()[0]));  // the smallest
  std::nth_element(depths.begin(), depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2),
                   depths.end());
  const double median = depths[depths.size() / 2];
  require(rms <= kMaxPlaneRms * median, "slits",
          "with scale put the reference points " + brief(1e3 * rms) +
              " mm rms off one plane (at most " + brief(100 * kMaxPlaneRms) + " % of their " +
              brief(median) + " m median depth): u_inf, the scale or the slits were changed");
}

}  // namespace

void Reference::validate() const {
  require(image_width > 0 && image_width <= kMaxImageSide && image_height > 0 &&
              image_height <= kMaxImageSide,
          "image_width",
          "and image_height must be in 1 .. " + std::to_string(kMaxImageSide) + " px");
  require(region_width >= 3 && region_width <= image_width, "region_width",
          "must be in 3 .. image_width (" + std::to_string(image_width) + ") px");
  require(max_region_width >= 0 && max_region_width <= image_width, "max_region_width",
          "must be in 0 .. image_width px");
  require(std::isfinite(profile_width) && profile_width > 0 && profile_width <= region_width,
          "profile_width", "must be finite, > 0 and <= region_width px");
  require(full_scale == 0 || (full_scale >= 1 && full_scale <= 65535), "full_scale",
          "must be 0 (the image type's) or in [1, 65535] DN");
  require(std::isfinite(smoothing_rms) && smoothing_rms >= 0, "smoothing_rms",
          "must be finite and >= 0 px");
  validateLens(*this);
  validateScale(*this);
  require(!slits.empty() && slits.size() <= 256, "slits", "must hold 1 .. 256 slits");
  for (std::size_t k = 0; k < slits.size(); ++k) validateSlit(*this, k);
  for (std::size_t k = 1; k < slits.size(); ++k) validateSpacing(*this, k);
  if (scale.valid()) validatePlane(*this);
}

}  // namespace multislit
