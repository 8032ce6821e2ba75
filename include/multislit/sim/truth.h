// Judging against the simulator's ground truth: how far a sole (or any rectangle on the floor)
// stays from a true object of the scene.
#pragma once

#include "multislit/feet.h"
#include "multislit/sim/scene.h"

namespace multislit {

/// Horizontal clearance between a sole and an object seen from above (sphere: a disc; cylinder:
/// a capsule around its axis; box: a rectangle): 0 when they overlap [m].
double clearance(const Footprint& sole, const SceneObject& object);

}  // namespace multislit
