// How far a reference's slits bend away from the shape the projector model gives them: the hint
// that a camera's lens distortion is missing.
#pragma once

#include "multislit/reference.h"
#include "multislit/sensor.h"

namespace multislit {

/// Largest bend [px] calibrate lets pass without a warning: a pinhole camera's slits follow the
/// model to a few hundredths of a pixel, while a lens that moves the corners by 5 px bends them
/// by several pixels.
constexpr double kMaxSlitBend = 1.0;

/// The largest distance [px] of a reference slit's ideal points (Reference::idealPoint) from the
/// slit the sensor model casts on the reference plane (the floor seen from `mount`), after the
/// straight line (a + b v) that best fits each slit's differences is taken off: what a small
/// error of the pose or of the projector's angles does is nearly such a line, what a missing
/// lens distortion does is a bow. 0 when the reference's slits are not the sensor's slit count.
double slitBend(const Reference& reference, const SensorConfig& sensor, const MountConfig& mount);

}  // namespace multislit
