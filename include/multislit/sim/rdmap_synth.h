// The RDMap of a scene without an image: the simulator's exact slit crossings measured against a
// Reference the way the Extractor measures them, plus the extractor's noise. It is the fast path
// for long simulated walks (thousands of frames in tests); rendering and extracting an image is the
// slow, complete one.
#pragma once

#include "multislit/point_types.h"
#include "multislit/reference.h"
#include "multislit/sim/simulator.h"

#include <pcl/point_cloud.h>

#include <Eigen/Geometry>

#include <cstdint>
#include <string>
#include <vector>

namespace multislit {

struct RDMapSynthesizerConfig {
  /// Gaussian noise of the measured slit centre. 0.08 px is what the Extractor shows on rendered
  /// images of the default sensor (floor residual std of detection_test); the paper's sensor has
  /// 0.3 px (Sec. IV).
  double noise_sigma = 0.08;  ///< [px]
  double dropout = 0.0;       ///< share of points lost at random (speckle, dark texture) [-]
  std::uint64_t seed = 1;     ///< the same seed and frame give the same cloud
  std::string frame_id = "multislit_camera";  ///< header.frame_id, as ExtractorConfig::frame_id

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// The reference of the bare floor (`floor`: its albedo, texture and gloss) seen from
/// `reference_mount`: slits found in a rendered image, with the sensor model's metric scale
/// (Reference::setNominalScale). What the Extractor and the synthesizer of a simulated walk use;
/// costs one rendering.
Reference renderFloorReference(const SensorConfig& sensor, const MountConfig& reference_mount,
                               const RenderConfig& render = {}, const FloorConfig& floor = {});

/// Builds the organized cloud Extractor::extract() would give for a frame, from
/// Simulator::groundTruth(): one cloud row per reference slit, one column per reference row; a
/// crossing is measured by the reference point on its row whose assigned region holds it (as the
/// Extractor searches), dk = u(frame) + noise - u(reference), and x, y, z come from the noisy
/// column with the reference's metric scale (the Extractor's formula). NaN where nothing was
/// measured.
class RDMapSynthesizer {
 public:
  /// `reference` is the one the Extractor would use (from a rendered image of the bare floor).
  RDMapSynthesizer(const SensorConfig& sensor, Reference reference,
                   const RDMapSynthesizerConfig& config = {});

  const Reference& reference() const { return reference_; }
  const Simulator& simulator() const { return simulator_; }

  /// The RDMap of `scene` seen by the camera at `world_from_camera`; `frame` selects the noise
  /// and is the header's seq; header.stamp = frame * 1e6 / 30 us (30 Hz). The simulator's
  /// crossings are stored in `truth` when given.
  pcl::PointCloud<PointRDM>::Ptr synthesize(const Scene& scene,
                                            const Eigen::Isometry3d& world_from_camera,
                                            std::uint64_t frame,
                                            std::vector<SlitCrossing>* truth = nullptr) const;

 private:
  Simulator simulator_;
  Reference reference_;
  RDMapSynthesizerConfig config_;
  pcl::PointCloud<PointRDM> layout_;  ///< the Extractor's cloud of a frame without slits
};

}  // namespace multislit
