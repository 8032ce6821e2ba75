// Image formation of the multi-slit sensor, with exact ground truth for every slit crossing.
#pragma once

#include "multislit/sensor.h"
#include "multislit/sim/scene.h"

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace multislit {

class RenderPool;  // the simulator's buffers (private)

/// How the laser speckle's intensity is distributed (per pixel, mean 1, std speckle_contrast).
enum class SpeckleModel {
  Gaussian,  ///< 1 + contrast x a correlated Gaussian field, clamped at 0 (contrast < 1)
  Gamma,     ///< gamma of shape k = 1 / contrast^2 (any real k >= 1); contrast 1: exponential
             ///< intensity, fully developed speckle. A correlated Gaussian field mapped through
             ///< the gamma quantile (Gaussian copula): exact marginal, any k, one field's cost.
};

/// How the pixel centres are traced: the same samples either way, to rounding.
enum class RenderMethod {
  Culled,      ///< each object only on the pixels its bounding spheres cover, the floor elsewhere
               ///< in closed form
  Exhaustive,  ///< every pixel's ray against every object (the renderer before: a yardstick)
};

/// Radiometry and noise of the camera. Intensities are fractions of the sensor's full scale.
struct RenderConfig {
  double laser_peak = 0.9;  ///< sheet centre on albedo 1, facing the projector, at 0.5 m [FS]
  double ambient = 0.10;    ///< ambient light through the red filter on albedo 1 [FS]
  SpeckleModel speckle_model = SpeckleModel::Gaussian;  ///< intensity distribution of speckle
  double speckle_contrast = 0.04;  ///< std / mean of the laser speckle per pixel [-]
  double speckle_grain = 0.8;      ///< speckle correlation length (Gaussian sigma) [px]
  double blur_sigma = 0.5;         ///< lens point spread function (Gaussian sigma) [px]
  double full_well = 12000.0;      ///< electrons at full scale, sets the shot noise [e-]
  double read_noise = 0.004;       ///< read noise [FS]
  int bit_depth = 8;               ///< 8 (CV_8U) or 16 (CV_16U)
  int supersample = 4;             ///< samples per pixel and axis near the slits [-]
  /// Factor on the sheet's width (projector.sheet_sigma) as rendered: focus. The sheet's power
  /// is kept, so its peak scales by 1 / stripe_width; the ground truth does not change [-]
  double stripe_width = 1.0;
  double gamma = 1.0;  ///< output = value^(1 / gamma) before quantization; 1: linear [-]
  bool noise = true;   ///< false: no speckle, shot or read noise (a noise-free image)
  RenderMethod method = RenderMethod::Culled;  ///< how the pixel centres are traced
  uint64_t seed = 1;  ///< the same seed and frame index give the same bytes

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// Where slit `slit` crosses image row `row`: the exact centre of its light on that row. Through
/// a distorting lens (CameraConfig::distortion) row and u are the ideal (undistorted) image's.
struct SlitCrossing {
  int slit = 0;                                            ///< 0 .. slit_count-1, by angle
  int row = 0;                                             ///< image row v [px]
  double u = 0.0;                                          ///< sub-pixel column on row v [px]
  Eigen::Vector3d camera_point = Eigen::Vector3d::Zero();  ///< the lit point, camera frame [m]
  Eigen::Vector3d world_point = Eigen::Vector3d::Zero();   ///< the lit point, world frame [m]
  int object = 0;                                          ///< 0 floor, k + 1 scene.objects[k]
  double height = 0.0;                                     ///< above the floor [m]
};

/// Where one render's time went, wall clock [s].
struct RenderTimes {
  double centres = 0;  ///< every pixel centre's surface, ambient light and nearest sheet
  double laser = 0;    ///< laser light integrated over the pixels near a sheet
  double noise = 0;    ///< speckle, lens blur, shot and read noise, quantization
  double truth = 0;    ///< the ground truth of every slit crossing
  double total() const { return centres + laser + noise + truth; }
};

struct RenderedFrame {
  cv::Mat image;                    ///< CV_8UC1 or CV_16UC1, camera size
  std::vector<SlitCrossing> truth;  ///< every visible crossing, by slit then row
};

class Simulator {
 public:
  explicit Simulator(const SensorConfig& sensor, const RenderConfig& render = {});

  const SensorGeometry& geometry() const { return geometry_; }
  const RenderConfig& renderConfig() const { return render_; }

  /// Renders what the camera at `world_from_camera` sees of `scene`. `frame` selects the noise.
  /// `times`, when given, receives where the time went.
  RenderedFrame render(const Scene& scene, const Eigen::Isometry3d& world_from_camera,
                       uint64_t frame = 0, RenderTimes* times = nullptr) const;
  /// The frame number of reference images: their noise is drawn apart from every sequence's.
  static constexpr uint64_t kReferenceFrame = 1u << 30;
  /// The reference image (Sec. II-C): `floor`, a scene of the plane alone, seen by the camera at
  /// `reference_mount` on the robot at the world origin, with the noise of kReferenceFrame.
  RenderedFrame renderReference(const Scene& floor, const MountConfig& reference_mount) const;
  /// Only the ground truth (no image): for each slit and row, the first surface its light hits,
  /// kept when the camera sees that point.
  std::vector<SlitCrossing> groundTruth(const Scene& scene,
                                        const Eigen::Isometry3d& world_from_camera) const;

 private:
  SensorGeometry geometry_;
  RenderConfig render_;
  std::vector<float> gamma_quantiles_;  // SpeckleModel::Gamma: intensity per Gaussian quantile
  std::shared_ptr<RenderPool> pool_;    // buffers reused from render to render
};

/// Ground truth as CSV: slit,row,u,x,y,z (camera) ,wx,wy,wz (world),object,height.
void writeGroundTruthCsv(const std::string& path, const std::vector<SlitCrossing>& truth,
                         const Scene& scene);

}  // namespace multislit
