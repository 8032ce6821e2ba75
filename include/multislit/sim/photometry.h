// Photometric variety for the simulator: named presets and random draws of what real sensors and
// floors give (laser power, ambient light, speckle, stripe width, blur, noise, gamma, bit depth,
// floor texture and gloss, object surfaces). The ground truth never depends on any of it.
#pragma once

#include "multislit/lens.h"
#include "multislit/sim/scene.h"
#include "multislit/sim/simulator.h"

#include <cstdint>
#include <string>
#include <vector>

namespace multislit {

/// Everything photometric about a simulated frame: the camera's rendering, the floor's surface
/// and the objects' surfaces, and the lens the image is seen through. Geometry (scene shapes,
/// sensor, pose) is not part of it.
struct Photometry {
  std::string name = "default";      ///< preset name, or "random-<seed>"
  RenderConfig render;               ///< laser, ambient, speckle, stripe width, blur, noise, gamma
  FloorConfig floor;                 ///< texture, albedo, gloss, stripe width on the floor
  double object_albedo = -1.0;       ///< every object's albedo; < 0 keeps each object's own [-]
  double object_stripe_width = 1.0;  ///< every object's stripe width factor (SceneObject) [-]
  /// The camera lens's distortion (OpenCV's coefficients, keys k1 .. k6, p1, p2); all zero keeps
  /// the sensor file's lens. Replaces the sensor's in `simulate` and `walk`.
  LensDistortion distortion;

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// default (today's images), bright-room, dark-floor, saturated, narrow, defocus, speckle, tiles,
/// carpet, glossy, 16bit, gamma, noisy, translucent-objects.
std::vector<std::string> photometryPresetNames();
/// A named preset; throws std::invalid_argument listing the known names.
Photometry photometryPreset(const std::string& name);

/// Every parameter drawn from the ranges of real sensors, floors and objects (see photometry.cpp),
/// redrawn until the stripe on the floor's far rows stays measurable (a few times the noise above
/// the background). Deterministic: the same seed gives the same photometry, render.seed = seed.
Photometry randomPhotometry(uint64_t seed);

/// What a command line names: a preset, "random" (randomPhotometry(seed)) or the path of a
/// photometry YAML (.yaml or .yml, from savePhotometry). Throws std::invalid_argument listing the
/// presets for any other name.
Photometry choosePhotometry(const std::string& choice, uint64_t seed);
/// Whether that choice names a photometry YAML (.yaml or .yml), not a preset or "random".
bool isPhotometryFile(const std::string& choice);

/// Sets every object's albedo to `albedo` and its stripe width factor to `stripe_width`; a value
/// < 0 leaves each object its own.
void setObjectSurfaces(std::vector<SceneObject>& objects, double albedo, double stripe_width);

/// Puts the floor and the object surfaces of `photometry` into `scene` (shapes untouched) and
/// returns the render configuration to use with it.
RenderConfig applyPhotometry(const Photometry& photometry, Scene& scene);

/// YAML (OpenCV FileStorage): every field, so that a run can be reproduced.
void savePhotometry(const Photometry& photometry, const std::string& path);
/// Reads savePhotometry()'s file; missing keys keep the defaults; the result is validated.
Photometry loadPhotometry(const std::string& path);

}  // namespace multislit
