// Floor and obstacles in an RDMap (paper Sec. III-B): RANSAC on the plane dk = A u + B v + C
// (eq. 1) with q iterations from eq. (3), least-squares refit on the inliers (eq. 2), then every
// point farther than the threshold from the plane is an obstacle. By default each new best RANSAC
// plane is refit on its inliers before it is scored (LO-RANSAC), and the threshold follows the
// noise measured in each frame's own floor residuals, see FloorDetectorConfig.
#pragma once

#include "multislit/point_types.h"

#include <pcl/point_cloud.h>
#include <pcl/types.h>

#include <Eigen/Core>

#include <cstddef>
#include <limits>
#include <vector>

namespace multislit {

/// eq. (3) solved for q: the number of RANSAC iterations that draw at least one sample free of
/// outliers with probability `probability`, q = ceil(log(1 - P) / log(1 - (1 - eps)^F)), with eps
/// = `outlier_ratio` and F = `sample_size`. 35 for P = 0.99, eps = 0.5, F = 3 (the paper's q).
/// Throws std::invalid_argument unless 0 < P < 1, 0 <= eps < 1 and F >= 1.
int ransacIterations(double probability, double outlier_ratio, int sample_size = 3);

struct FloorDetectorConfig {
  /// std of the relative disparity of the sensor (Sec. IV: 0.3 px): RANSAC's threshold is
  /// threshold_sigmas * sigma; with estimate_sigma false, also the final split's.
  double sigma = 0.3;             ///< [px]
  double threshold_sigmas = 3.0;  ///< floor / obstacle threshold, in sigmas (3 sigma = 0.9 px) [-]
  /// Measure each frame's sigma from its own floor: 1.4826 x the median |residual| of the points
  /// within band_sigmas * max_sigma of the RANSAC plane, then again within band_sigmas x that
  /// estimate, each corrected for the cut (FloorResult::sigma_estimate), clamped to [min_sigma,
  /// max_sigma]. The split into floor and obstacles and the refit (eq. 2) then use threshold_sigmas
  /// x that sigma. false: the paper's fixed sigma for every frame.
  bool estimate_sigma = true;
  /// Lower bound of the estimated sigma. Rendered bare floors of the simulator measure 0.108 to
  /// 0.129 px (7 Table I poses x 4 frames), but their residuals are heavier-tailed than a Gaussian
  /// and correlated along a slit: with no bound (threshold about 0.35 px) those 28 frames give 919
  /// off-plane points of 125 k (0.73 %, a Gaussian gives 0.27 %) and 572 of them in groups of 3 or
  /// more, i.e. false obstacles; with 0.2 px, 16 and 3; with 0.3 px, none. 0.3 px keeps the
  /// paper's 0.9 px as the smallest threshold: the estimate raises it on noisier sensors.
  double min_sigma = 0.3;  ///< [px]
  /// Upper bound of the estimated sigma: 1 px gives a 3 px threshold, which already hides
  /// objects lower than about 12 mm (0.9 px is 3.5 mm for the default sensor), the 7 mm LAN cable
  /// among them. A frame noisier than that is a fault to look at (sigma_estimate shows it), not
  /// noise to adapt to.
  double max_sigma = 1.0;         ///< [px]
  double band_sigmas = 3.0;       ///< residuals beyond band_sigmas * max_sigma are not noise [-]
  double probability = 0.99;      ///< P of eq. (3): chance of drawing one clean sample [-]
  double outlier_ratio = 0.5;     ///< eps of eq. (3): assumed share of non-floor points [-]
  int max_iterations = 0;         ///< RANSAC iterations q; 0: from eq. (3) (35 by default) [-]
  int min_points = 50;            ///< fewer valid points: the floor is not found [-]
  double min_inlier_ratio = 0.3;  ///< fewer floor points than this share of valid: not found [-]
  unsigned seed = 12345u;         ///< seed of the sample draws; a seed and a cloud give one result
  /// Refit each new best RANSAC plane on its inliers (eq. 2) and score the refit (LO-RANSAC);
  /// false: the paper's plain RANSAC, which picks a wrong plane more often when obstacles are
  /// large.
  bool local_refit = true;
  /// Step 6: look for runs along each slit. An object lifts a run of neighbouring rows of one slit
  /// (the 7 mm cable dozens, the ball up to a hundred), while the noise is correlated only over a
  /// speckle grain: the median residual of a window of 7, 15, 31 rows (min_window, 2 w + 1, ...
  /// up to max_window), taken over the floor points only (so the points already off the floor do
  /// not lift their neighbours' windows), shows a shift that no single point shows above the
  /// frame's noise. A floor point is an obstacle when more than half of the floor points of one of
  /// its windows (its median) lie beyond window_sigmas times the noise of that window length,
  /// measured on the frame (1.4826 x the median |window median| over the floor: the correlation
  /// along a slit is measured, not assumed), and beyond min_window_shift, on the side of its own
  /// residual. Organized RDMaps
  /// only. false: each point on its own (the paper's rule).
  bool multiscale = true;
  int min_window = 7;   ///< shortest window along a slit, odd [rows]
  int max_window = 31;  ///< longest window along a slit: 7, 15, 31 by default [rows]
  /// A window's threshold in sigmas of its length. The window medians of rendered floors are far
  /// heavier-tailed than a Gaussian (texture and grout bias the centres over dozens of rows): over
  /// the 40 random photometries of robustness_test, where the point rule alone gives 4.28 % false
  /// points and a recall of >= 5 mm crossings of 0.749, 3 sigma gives 5.62 % and 0.856, 4 sigma
  /// 4.89 % and 0.851, 6 sigma 4.52 % and 0.851, 8 sigma 4.35 % and 0.819.
  double window_sigmas = 6.0;  ///< [-]
  /// A window's threshold is at least this: 0.6 px is 2.4 mm for the default sensor, above the
  /// 2 mm screw head (about 0.5 px) no single frame should report (occupancy_map_test) and the
  /// tenths of a pixel the extractor is biased by at a slit's ends, below the 5 mm crossings that
  /// must be found (0.8 px loses a third of those the windows find at 0.35 < sigma <= 0.7 px).
  double min_window_shift = 0.6;  ///< [px]

  /// The configured threshold, sigma * threshold_sigmas: RANSAC's, and the split's when
  /// estimate_sigma is false. The threshold a frame used is FloorResult::threshold. [px]
  double threshold() const { return sigma * threshold_sigmas; }
  /// q: max_iterations, or eq. (3) when it is 0.
  int iterations() const;
  void validate() const;  ///< throws std::invalid_argument naming the field
};

struct FloorResult {
  bool found = false;  ///< false: no floor (too few points, or too few on one plane); no guess
  Eigen::Vector3d plane = Eigen::Vector3d::Zero();  ///< (A, B, C): dk = A u + B v + C [-, -, px]
  /// cloud indices of the floor points: |residual| <= threshold, and (with
  /// FloorDetectorConfig::multiscale) no window of rows about them off the floor
  pcl::Indices inliers;
  /// cloud indices of the valid points off the floor: |residual| > threshold first, then the
  /// run_obstacles points found off the floor by their windows
  pcl::Indices obstacles;
  /// Signed residual dk - (A u + B v + C) of each obstacle, parallel to `obstacles` [px];
  /// > 0: above the floor (nearer to the sensor), < 0: below it (a hole or a step down).
  std::vector<float> obstacle_residuals;
  double residual_std = std::numeric_limits<double>::quiet_NaN();  ///< RMS over the floor [px]
  /// The noise of this frame used for the split: sigma_estimate clamped to [min_sigma,
  /// max_sigma], or FloorDetectorConfig::sigma when estimate_sigma is false. NaN: not found. [px]
  double sigma = std::numeric_limits<double>::quiet_NaN();
  /// The floor / obstacle threshold used: threshold_sigmas * sigma. NaN: not found. [px]
  double threshold = std::numeric_limits<double>::quiet_NaN();
  /// The robust estimate of the floor noise before clamping (1.4826 MAD, corrected for the band);
  /// NaN when estimate_sigma is false or the floor was not found, +infinity when the residuals
  /// fill the band as evenly as a uniform spread or more (then sigma = max_sigma). [px]
  double sigma_estimate = std::numeric_limits<double>::quiet_NaN();
  /// Of the obstacles, how many only their windows of rows put off the floor (the last ones).
  std::size_t run_obstacles = 0;
  /// The measured noise of the window median per window length (min_window, 2 w + 1, ... up to
  /// max_window; NaN: too few windows); empty without multiscale, unorganized or not found. [px]
  std::vector<double> window_noise;
  std::size_t valid_points = 0;  ///< points with finite u, v and dk
  int iterations = 0;            ///< RANSAC iterations run
};

/// The floor of an RDMap and the points off it. Thread-safe: detect()'s result depends
/// only on its arguments (its scratch buffers are per thread).
class FloorDetector {
 public:
  explicit FloorDetector(const FloorDetectorConfig& config = {});  ///< validates `config`

  const FloorDetectorConfig& config() const { return config_; }

  /// Floor and obstacles among all valid points of `cloud`.
  FloorResult detect(const pcl::PointCloud<PointRDM>::ConstPtr& cloud) const;
  /// Floor and obstacles among the valid points of cloud[indices]; result indices index `cloud`.
  FloorResult detect(const pcl::PointCloud<PointRDM>::ConstPtr& cloud,
                     const pcl::Indices& indices) const;

 private:
  FloorDetectorConfig config_;
  int iterations_ = 0;
};

}  // namespace multislit
