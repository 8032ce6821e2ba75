// Footsteps of the HOAP-2: where its soles land when it walks straight or turns in place, checked
// against the occupancy map.
#pragma once

#include "multislit/feet.h"
#include "multislit/occupancy_map.h"

#include <Eigen/Geometry>

#include <vector>

namespace multislit {

struct Footstep {
  Foot foot = Foot::Left;
  Pose2D body;     ///< the body when the foot is down
  Footprint sole;  ///< where the sole is, world frame
};

/// The sole of `foot` with the body at `body`, the foot `ahead` metres in front of the body (half
/// a step when walking, 0 when turning in place).
Footprint soleAt(const Pose2D& body, Foot foot, double ahead, const FootConfig& config);

/// The next `count` footsteps of walking straight from `body`, `first` foot first.
std::vector<Footstep> planStraight(const Pose2D& body, Foot first, int count,
                                   const FootConfig& config);

/// Occupied voxels under planned footsteps (each sole grown by a margin).
struct FootstepCheck {
  bool free = true;            ///< no footstep touches an occupied voxel
  int first_blocked = -1;      ///< index of the first footstep that does
  std::vector<MapCell> cells;  ///< the occupied voxels under that footstep
};

/// Checks footsteps against the map: voxels between min_height and max_height (map frame, the
/// floor at 0) under each sole grown by `margin` [m].
FootstepCheck checkFootsteps(const std::vector<Footstep>& steps, const OccupancyMap& map,
                             double margin, double min_height, double max_height);

}  // namespace multislit
