// From a camera image to the relative disparity map (paper Sec. III-A) as an organized PCL cloud.
#pragma once

#include "multislit/point_types.h"
#include "multislit/reference.h"
#include "multislit/slit_profile.h"

#include <pcl/point_cloud.h>

#include <cstdint>
#include <string>
#include <vector>

namespace multislit {

struct ExtractorConfig {
  Estimator estimator = Estimator::Gaussian;  ///< measured: docs/sensor-and-calibration.md
  /// Slit peak above its background [full scale]: half the paper's 0.06, so that a dark object
  /// under a weak laser is still measured; what it gives over random photometries is in
  /// docs/accuracy.md. With the laser off, texture still passes (the cloud is not empty), but no
  /// floor and no obstacle is found on it (tests/robustness_test.cpp).
  double min_contrast = 0.03;
  double max_width_factor = 2.5;  ///< widest valid profile, times the reference's width [-]
  /// Narrowest valid profile (pixels above half its contrast): a lone hot or speckle pixel is
  /// narrower. Absolute, not relative to the floor's stripe: on a glossy or small object the
  /// stripe may be half as wide as on the floor, and it is still the slit [px].
  double min_width = 1.5;
  int max_saturated = 16;  ///< longest saturated run still measured [px]
  /// Where the slit crosses a row nearly along it (the rotated camera's 20 deg), measure its
  /// centre across the stripe, from a few columns' profiles, rather than along the row: the
  /// row's centre is pulled along the stripe by any change of the floor's brightness there (tile
  /// edges, grout, grain). The row's profile still finds the slit and decides its validity.
  bool across_stripe = true;
  /// Where a stripe is lost (dark grout, a dark object), the region's brightest blob is noise
  /// anywhere in it, and neighbouring rows share it: a run of up to this many points of a slit
  /// that jumps by more than stray_step px of dk from the points on both sides is no surface
  /// and is not measured (src/stray_runs.h). What it gives: docs/accuracy.md. 0: keep them [points]
  int stray_run = 3;
  /// A surface changes dk by at most 3.5 px from one row to the next (ball, box, tennis ball) [px]
  double stray_step = 6.0;
  /// The image's white [DN]; 0: the reference's (calibrate --full-scale), else 255 for 8-bit
  /// and 65535 for 16-bit images.
  double full_scale = 0.0;
  std::string frame_id = "multislit_camera";  ///< header.frame_id of the clouds

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// Counts of one extraction.
struct ExtractionStats {
  std::size_t reference_points = 0;  ///< points the reference offers
  std::size_t valid = 0;             ///< points measured
};

class Extractor {
 public:
  explicit Extractor(Reference reference, const ExtractorConfig& config = {});

  const Reference& reference() const { return reference_; }
  const ExtractorConfig& config() const { return config_; }
  /// The profile tests and window for images of this depth (CV_8U or CV_16U).
  ProfileParams profileParams(int depth) const;

  /// The RDMap of `image`: one cloud row per slit, one column per reference row of that slit
  /// (column j of slit i is image row first_row_i + j); NaN where nothing valid was measured.
  /// x, y, z in metres in the camera frame when the reference has a metric scale (else NaN).
  /// Through a distorting lens (Reference::lens) the centre found on recorded row first_row_i + j
  /// is undistorted to (u', v') of the ideal image, where the slit's epipolar lines are rows
  /// again: the point's u and v are the reference slit's ideal point on ideal row v' (v' is not
  /// a whole number; linear along the slit from the reference point) and dk = u' - u, so that a
  /// plane stays a plane in (u, v, dk) (eq. 1-3). The cell stays the recorded row's: column j of
  /// slit i. Throws std::invalid_argument when the image does not fit the reference.
  ExtractionStats extract(const cv::Mat& image, pcl::PointCloud<PointRDM>& cloud) const;
  /// Same, with the PCL header set: stamp in microseconds since the epoch, seq, frame_id.
  pcl::PointCloud<PointRDM>::Ptr extract(const cv::Mat& image, std::uint64_t stamp_us,
                                         std::uint32_t seq) const;

 private:
  /// One reference point, prepared once: its assigned region on its image row (Fig. 7) and
  /// where its measure goes.
  struct Task {
    int row = 0;               ///< image row [px]
    int first = 0, last = 0;   ///< assigned region: first and last column [px]
    std::uint32_t cell = 0;    ///< index of the point in the cloud
    float u = 0;               ///< reference column [px]
    float u_inf = 0;           ///< column of the ray at infinite depth [px]; NaN: no metric scale
    float slope = 0;           ///< the reference slit's du/dv here [-]
    int across_half_rows = 0;  ///< rows each side of a column's crossing, across the stripe [px]
    std::uint32_t lens = 0;    ///< index into ideal_tasks_ (distorting lens only)
  };
  /// Through a distorting lens, per task: the ideal point of a centre at column c of its
  /// recorded row, a cubic in s = (c - u) / reach (u the task's reference column) exact at
  /// s = -1, -1/3, 1/3, 1; and its reference slit near its reference point in the ideal image,
  /// linear in the ideal row (a centre's ideal row lies within a row or two of it). A few
  /// multiplications a point, no search and no branch.
  struct IdealTask {
    Eigen::Matrix<double, 2, 4> cubic;  ///< coefficients of s^0 .. s^3, ideal u and v
    double inverse_reach = 0;           ///< 1 / reach [1/px]
    double u = 0, v = 0, du_dv = 0;     ///< the reference point (ideal) and its slit's slope
    double u_inf = 0, du_inf_dv = 0;    ///< its u_inf (NaN: none) and that's slope
  };

  /// Point `p` of task `t` from its slit's centre: dk and, with a metric scale, x, y, z. False,
  /// and `p` left unmeasured, when the centre lies beyond the image's edge (a fit pulled past it).
  bool finish(const cv::Mat& image, const Task& t, double centre, PointRDM* p) const;
  /// The centres of tasks along_slits_[begin, end) (one slit, in order along it), measured again
  /// across the stripe (ExtractorConfig::across_stripe), the columns shared between its points.
  template <typename T>
  void acrossSlit(const cv::Mat& image, const ProfileParams& params, std::size_t begin,
                  std::size_t end, double* centres) const;
  /// The centres of tasks along_slits_[begin, end) (one slit) without its stray runs
  /// (ExtractorConfig::stray_run).
  void dropStrays(std::size_t begin, std::size_t end, double* centres) const;
  /// finish()'s last step through a distorting lens: the centre on task t's recorded row to
  /// the ideal image, the reference there, dk and x, y, z. False where the ideal row lies beyond
  /// the reference slit's ends.
  bool finishIdeal(const Task& t, double centre, PointRDM* p) const;
  /// Half the row's profile window [px], from the reference's stripe width.
  int halfWindow() const;
  /// Each task's IdealTask.
  void prepareIdeal();
  template <typename T>
  void measureAll(const cv::Mat& image, const ProfileParams& params,
                  pcl::PointCloud<PointRDM>& cloud, ExtractionStats& stats) const;

  Reference reference_;
  ExtractorConfig config_;
  std::vector<Task> tasks_;  ///< by image row, then column: the image is read top to bottom once
  std::vector<std::uint32_t> along_slits_;       ///< tasks_ by cell: slit by slit, along each
  std::vector<IdealTask> ideal_tasks_;           ///< distorting lens only
  pcl::PointCloud<PointRDM>::VectorType blank_;  ///< the cloud before anything is measured
};

}  // namespace multislit
