// What the sensor measures in advance (paper Sec. II-C): the slits in a reference image of a
// plane, the region assigned to each reference point, and the scale that turns disparity into
// metres (the paper's future work).
#pragma once

#include "multislit/sensor.h"
#include "multislit/slit_profile.h"

#include <opencv2/core/mat.hpp>

#include <string>
#include <vector>

namespace multislit {

struct ReferenceConfig {
  int expected_slits = 15;     ///< slits the projector casts; another count is an error
  int region_width = 0;        ///< assigned region width [px]; 0: the widest without overlap
  double min_contrast = 0.06;  ///< a slit's peak above its background [full scale]
  int min_rows = 40;           ///< shorter tracks are noise, not slits [rows]
  int max_gap = 25;            ///< rows a slit may be missing and still be one slit [rows]
  int smoothing_degree = 4;    ///< polynomial u(v) fitted along each slit; 0: raw centres
  Estimator estimator = Estimator::Gaussian;  ///< sub-pixel estimator for the centres
  /// The images' white [DN]: 4095 for 12-bit data in 16-bit images; 0: 255 for 8-bit images,
  /// 65535 for 16-bit ones.
  double full_scale = 0.0;

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// One slit of the reference: its centre on each row from first_row on (NaN: no point there).
struct ReferenceSlit {
  int first_row = 0;
  std::vector<float> u;      ///< reference column per row [px]
  std::vector<float> u_inf;  ///< column of the same ray at infinite depth [px] (metric scale)
  /// The last row (Reference::validate() keeps it inside the image, so it fits an int).
  int lastRow() const { return first_row + static_cast<int>(u.size()) - 1; }
};

/// Scale of the disparity: a point seen at column u' on a row of reference point (u, u_inf) lies
/// at depth Z = disparity_constant / (u' - u_inf) with x = (u' - cx) Z / f, y = (v - cy) Z / f.
/// With a distorting lens (Reference::lens) u', v, u and u_inf are ideal (undistorted) pixels.
struct MetricScale {
  double f = 0.0, cx = 0.0, cy = 0.0;  ///< camera intrinsics [px]
  double disparity_constant = 0.0;     ///< f times the baseline [px m]
  std::string source = "none";         ///< "nominal" (sensor model) or "planes" (calibrated)
  bool valid() const { return disparity_constant > 0 && f > 0; }
};

class Reference {
 public:
  int image_width = 0, image_height = 0;  ///< camera image the reference was taken with [px]
  std::string camera_id;                  ///< camera that took it, when known
  int region_width = 0;                   ///< assigned region width [px], constant (Fig. 7)
  int max_region_width = 0;               ///< the widest width that overlaps no neighbour [px]
  double profile_width = 0.0;             ///< median width of a slit across a row [px]
  double smoothing_rms = 0.0;             ///< rms of raw centres about the smoothed slits [px]
  int joined_pieces = 0;                  ///< slit pieces joined across gaps when found [-]
  int dropped_tracks = 0;                 ///< tracks found that were not slits (speckle) [-]
  double full_scale = 0.0;  ///< the camera's white [DN] (ReferenceConfig); 0: the image type's
  std::vector<ReferenceSlit> slits;  ///< as recorded: where the extractor looks for the slits
  MetricScale scale;
  /// The camera's lens. When it distorts, the RDMap and the metric step use the slits' ideal
  /// points (idealPoint()) and u_inf is an ideal column; a pinhole's points are the recorded ones.
  Lens lens;

  /// Finds the slits in an image of a plane (8- or 16-bit, one channel). Throws
  /// std::runtime_error saying what was found when the slits are not the expected ones.
  static Reference fromImage(const cv::Mat& image, const ReferenceConfig& config = {});
  /// Same, from several images of the same plane taken from the same pose (all of one size and
  /// type): their mean, in which speckle and noise are weaker than in any one of them.
  static Reference fromImages(const std::vector<cv::Mat>& images,
                              const ReferenceConfig& config = {});
  /// The ideal (undistorted) pixel of slit s's point on its k-th row: (u[k], first_row + k)
  /// through the lens.
  Eigen::Vector2d idealPoint(const ReferenceSlit& s, std::size_t k) const;
  /// The lens of `camera` (its focal length, principal point and distortion). setNominalScale()
  /// and calibrateWithPlanes() set it too.
  void setLens(const CameraConfig& camera);
  /// Throws std::invalid_argument unless `camera` has this reference's lens: the same
  /// distortion and, when it distorts, the same f, cx and cy (to 1e-6 px). A calibration's lens
  /// is the one it was made with (calibrate --intrinsics); another would misplace every point.
  void checkLens(const CameraConfig& camera, const std::string& what) const;
  /// Reference points with a position, and the longest slit (the RDMap cloud's width).
  std::size_t pointCount() const;
  int maxSlitLength() const;
  /// Throws std::invalid_argument when an image does not fit this reference (size, type).
  void checkImage(const cv::Mat& image, const std::string& what) const;

  /// Metric scale from the sensor model: the reference plane is the floor seen from `mount`.
  void setNominalScale(const SensorConfig& sensor, const MountConfig& reference_mount);
  /// Metric scale from images of a flat wall facing the sensor at known depths (>= 2), as
  /// measured along the optical axis with a tape. Returns the rms fit residual [px]. Through a
  /// distorting lens (camera.distortion) the planes' slits are undistorted first and the scale is
  /// fitted in the ideal image, where the RDMap's relation holds.
  double calibrateWithPlanes(const std::vector<cv::Mat>& images, const std::vector<double>& depths,
                             const CameraConfig& camera, const ReferenceConfig& config = {});

  /// Throws std::invalid_argument naming the field unless every value is in range: image sizes
  /// up to 16384 px, region_width in 3 .. image_width, finite widths and scale, slits inside
  /// the image, adjacent slits at least region_width apart (regions never overlap).
  void validate() const;

  void save(const std::string& path) const;
  /// Reads save()'s file and validates it; throws std::invalid_argument naming the file and the
  /// field (std::runtime_error when it cannot be read).
  static Reference load(const std::string& path);
};

}  // namespace multislit
