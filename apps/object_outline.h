// The simulator's objects as the top view draws them (walk_figures.h: ObjectOutline).
#pragma once

#include "walk_figures.h"

#include "multislit/sim/scene.h"

namespace multislit::apps {

/// `object` seen from above: a sphere or a standing cylinder as a circle, a lying cylinder and a
/// box as their outlines.
ObjectOutline outlineOf(const SceneObject& object);

}  // namespace multislit::apps
