// What multislit walk measures of the map against the truth: every pass of the slits over a place
// with evidence (sweep_passes.csv, --measure-sweep), the occupied voxels on an object and those
// where no object lies.
#pragma once

#include "multislit/occupancy_map.h"
#include "multislit/sim/walk.h"

#include <cstddef>
#include <ostream>
#include <string>
#include <vector>

namespace multislit::apps {

/// The walk of a measurement: every pass recorded, and nothing ever occupied or stopping the
/// robot, so that it walks straight over whatever its floor shows.
void measureSweep(WalkConfig& config);

/// The passes of a measurement with evidence above the floor, counted by their longest run of
/// consecutive frames above it (1, 2, 3, 4, 5 or more), where no object lies and on an object.
struct SweepRuns {
  static constexpr int kBins = 5;
  std::size_t floor[kBins] = {}, object[kBins] = {};
};

void writeSweepPassHeader(std::ostream& csv);
/// The passes that ended in frame `f`, each with the object within 15 mm of its place, if any;
/// counted into `runs`.
void writeSweepPasses(std::ostream& csv, const WalkFrame& f, const OccupancyMap& map,
                      SweepRuns& runs);
/// The histogram of `runs` as a bar chart (PNG): each bar the share of its kind's passes.
void drawSweepRuns(const std::string& path, const SweepRuns& runs);

/// The object nearest to a square cell of edge `size` at `centre`, seen from above, within
/// `reach` [m]; nullptr when there is none.
const SceneObject* objectNear(const std::vector<SceneObject>& objects,
                              const Eigen::Vector2d& centre, double size, double reach);

/// Whether the map holds an occupied voxel within 1 cm of the object, seen from above.
bool mapped(const OccupancyMap& map, const SceneObject& object);

/// Occupied voxels of `map` farther than 1 cm from every object, seen from above.
std::size_t falseVoxels(const OccupancyMap& map, const std::vector<SceneObject>& objects);

}  // namespace multislit::apps
