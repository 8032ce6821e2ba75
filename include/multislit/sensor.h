// The multi-slit range sensor of the paper (Sec. II): camera, laser projector, and its mount.
#pragma once

#include "multislit/lens.h"

#include <Eigen/Geometry>

#include <cmath>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace multislit {

/// Focal lengths in pixels a real camera has [px]: f bounded keeps image rows and columns of rays
/// (f times a tangent) in an int. Sensor files and calibrations are held to it.
constexpr double kMinFocalPx = 1.0, kMaxFocalPx = 1e6;
/// Longest projector baseline [m]; a calibration's (disparity_constant / f) is held to it too.
constexpr double kMaxBaseline = 1.0;

/// Pinhole camera with OpenCV's lens distortion (none by default). Pixel centres are at integer
/// coordinates (OpenCV). The pixels are square: one focal length f for both axes.
struct CameraConfig {
  int width = 1296;              ///< [px]
  int height = 964;              ///< [px]
  double pixel_size = 3.75e-6;   ///< square pixel pitch [m]
  double focal_length = 4.0e-3;  ///< lens focal length [m]
  double principal_x = -1.0;     ///< principal point u [px]; negative: image centre
  double principal_y = -1.0;     ///< principal point v [px]; negative: image centre
  LensDistortion distortion;     ///< OpenCV's coefficients; all zero: a pinhole

  double f() const { return focal_length / pixel_size; }  ///< focal length [px]
  double cx() const { return principal_x < 0 ? 0.5 * (width - 1) : principal_x; }
  double cy() const { return principal_y < 0 ? 0.5 * (height - 1) : principal_y; }
  Lens lens() const { return Lens(f(), cx(), cy(), distortion); }
};

/// Multi-slit laser projector (StockerYale Mini-715L in the paper). In its own frame a slit i is
/// the ruled surface of rays (tan(alpha_i) + curvature * t^2, t, 1), |t| <= tan(half_length).
struct ProjectorConfig {
  int slit_count = 15;             ///< number of light sheets [-]
  double slit_spacing = 2.3;       ///< angle between adjacent sheets [deg]
  double slit_half_length = 22.5;  ///< half the fan angle along a slit [deg]
  double curvature = 0.08;         ///< pattern distortion (curved slits), see above [-]
  double sheet_sigma = 1.2e-3;     ///< 1-sigma angular thickness of a light sheet [rad]
  double baseline = 0.060;         ///< projector centre on the camera's +x axis [m]
  double rotation = 70.0;          ///< slit pattern rotated about the optical axis (Fig. 3) [deg]
};

/// Pose of the sensor on the robot (Table I / Fig. 10). The robot frame is x forward, y left,
/// z up, origin on the floor midway between the feet.
struct MountConfig {
  double tilt = 66.0;  ///< theta: depression of the optical axis below the horizontal [deg]
  double roll =
      0.0;  ///< phi: roll about the optical axis, positive clockwise seen from behind [deg]
  double height = 0.445;  ///< h: camera centre above the floor [m]
  double forward = 0.03;  ///< camera centre ahead of the point between the feet [m]
};

struct SensorConfig {
  CameraConfig camera;
  ProjectorConfig projector;
  MountConfig mount;

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
  /// OpenCV FileStorage YAML. Missing keys keep their defaults; unknown or repeated keys and
  /// sections that are not maps are errors naming the key; the result is validated.
  static SensorConfig load(const std::string& path);
  void save(const std::string& path) const;
};

/// Precomputed geometry of a sensor: rays, projections, slit surfaces, mount transform.
/// Camera frame: x along image rows (and the baseline), y down the columns, z the optical axis.
class SensorGeometry {
 public:
  explicit SensorGeometry(const SensorConfig& config);

  const SensorConfig& config() const { return config_; }
  int slitCount() const { return config_.projector.slit_count; }
  /// tan(alpha_i) of slit i, alpha_i = (i - (n-1)/2) * spacing; slits ordered by increasing angle.
  double slitTan(int slit) const;
  /// Largest |t| of a slit (tan of its half length).
  double slitTMax() const { return t_max_; }

  /// Ray through pixel (u, v) of the recorded image in the camera frame, with z = 1 (through the
  /// lens's distortion, if any).
  Eigen::Vector3d pixelRay(double u, double v) const;
  /// Position of a camera-frame point (z > 0) in the recorded image (through the lens).
  Eigen::Vector2d project(const Eigen::Vector3d& p_camera) const;
  /// The camera's lens: between recorded and ideal (pinhole) pixels. rowOf(), slitParamForRow()
  /// and slitRows() speak of ideal rows, where the epipolar lines are rows.
  const Lens& lens() const { return lens_; }

  /// Projector centre in the camera frame.
  const Eigen::Vector3d& projectorCentre() const { return projector_centre_; }
  /// The projector's axes in the camera frame (a rotation about z by the pattern rotation).
  const Eigen::Matrix3d& cameraFromProjector() const { return camera_from_projector_; }
  /// Camera-frame point to normalized projector coordinates (x', y') = (x/z, y/z).
  Eigen::Vector2d toProjector(const Eigen::Vector3d& p_camera) const;
  /// Direction (camera frame, projector z = 1) of the ray of slit i at slit parameter t.
  Eigen::Vector3d slitRay(int slit, double t) const;
  /// Signed angular distance [rad] of normalized projector coordinates from slit i's sheet.
  double sheetOffset(int slit, const Eigen::Vector2d& xy_projector) const;
  /// Slit whose sheet is nearest to the projector coordinates.
  int nearestSlit(const Eigen::Vector2d& xy_projector) const;
  /// sheetOffset() of the nearest slit, which is stored in *slit (one atan instead of two).
  double nearestSheetOffset(const Eigen::Vector2d& xy_projector, int* slit) const {
    const double x =
        xy_projector.x() - config_.projector.curvature * xy_projector.y() * xy_projector.y();
    const std::size_t i = nearestSheet(x);
    *slit = static_cast<int>(i);
    // atan(x) - alpha_i = atan(d) with d = (x - tan alpha_i) / (1 + x tan alpha_i).
    const double d = tanFromSheet(x, slit_tan_[i]);
    return d * d > kSeriesLimit ? std::atan(d) : atanSeries(d);
  }
  /// Points farther than this from their nearest sheet [rad] lie outside the fan of sheets:
  /// between two sheets |offset| is at most half their spacing (0.020 rad for the default sensor).
  static constexpr double kFarOffset = 0.04;
  /// nearestSheetOffset() of the n points (x[i], y[i]) into offset[i] and slit[i], the same
  /// values: the tangent's series for every point in vector instructions, then atan where a
  /// point lies beyond its series' range (outside the fan of sheets). With `exact_far` false, a
  /// point farther than kFarOffset from its sheet keeps its series' value instead, of the same
  /// sign and beyond kFarOffset too (at least 0.83 of the tangent's): for callers that only ask
  /// whether a point is near a sheet. The points within kFarOffset and every slit[i] are the same.
  void nearestSheetOffsets(const double* x, const double* y, int n, double* offset, int* slit,
                           bool exact_far = true) const;
  /// Image row of every point lit by slit i at parameter t (independent of depth: the
  /// epipolar lines are rows).
  double rowOf(int slit, double t) const;
  /// The parameter t of slit i whose light falls on image row v, if the slit reaches that row.
  std::optional<double> slitParamForRow(int slit, double v) const;
  /// Rows [first, last] that slit i can light, clipped to the image; first > last when none.
  std::pair<int, int> slitRows(int slit) const;

  /// Camera frame to robot frame for a mount (see MountConfig).
  Eigen::Isometry3d robotFromCamera(const MountConfig& mount) const;
  Eigen::Isometry3d robotFromCamera() const { return robotFromCamera(config_.mount); }

 private:
  SensorConfig config_;
  double f_, cx_, cy_, t_max_;
  Lens lens_;
  Eigen::Matrix3d camera_from_projector_;  // rotation about z by the pattern rotation
  std::vector<double> slit_tan_;           // tan(alpha_i)
  std::vector<double> boundary_tan_;       // tan of the angles midway between adjacent slits
  // The count of boundaries below each cell of width lookup_step_ from lookup_low_: a cell holds
  // at most one boundary, so one comparison finds the nearest sheet.
  std::vector<int> boundary_lookup_;
  double lookup_low_ = 0, lookup_per_step_ = 1;
  Eigen::Vector3d projector_centre_;

  /// The slit whose sheet is nearest to x = x' - curvature y'^2, by its tangent (no atan): the
  /// boundaries between sheets are monotonic.
  std::size_t nearestSheet(double x) const {
    const double cell = (x - lookup_low_) * lookup_per_step_;
    if (cell >= static_cast<double>(boundary_lookup_.size())) return boundary_tan_.size();
    if (!(cell >= 0)) return 0;
    auto i = static_cast<std::size_t>(
        boundary_lookup_[static_cast<std::size_t>(static_cast<int>(cell))]);
    if (i < boundary_tan_.size() && x >= boundary_tan_[i]) ++i;
    if (i > 0 && x < boundary_tan_[i - 1]) --i;  // rounding at a cell's edge
    return i;
  }
  /// tan(atan(x) - atan(t)).
  static double tanFromSheet(double x, double t) { return (x - t) / (1.0 + x * t); }
  /// atan(d) for d^2 <= kSeriesLimit, to 1e-15: its series to d^9. Between two sheets |d| is a
  /// few hundredths.
  static constexpr double kSeriesLimit = 2.5e-3;
  static double atanSeries(double d) {
    const double d2 = d * d;
    return d * (1.0 - d2 * (1.0 / 3.0 - d2 * (1.0 / 5.0 - d2 * (1.0 / 7.0 - d2 * (1.0 / 9.0)))));
  }
  /// In place: x[i] (a point's x' - curvature y'^2) becomes atanSeries(tanFromSheet(x[i],
  /// tans[slit[i]])), in vector instructions (gathers included) where the CPU has them.
  static void seriesOfPoints(double* x, const int* slit, const double* tans, int n);
};

}  // namespace multislit
