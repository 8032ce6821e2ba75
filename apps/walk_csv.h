// obstacles.csv of multislit walk: one row per frame with the robot's pose, the decision, the
// floor, the obstacles, the map's size and what the ground truth says of the ball and the cable.
#pragma once

#include "multislit/occupancy_map.h"
#include "multislit/sim/walk.h"

#include <ostream>

namespace multislit::apps {

void writeWalkCsvHeader(std::ostream& csv);
/// The row of frame `f`, `map` after it; `fps` gives its time.
void writeWalkCsvLine(std::ostream& csv, const WalkFrame& f, const OccupancyMap& map, double fps);

}  // namespace multislit::apps
