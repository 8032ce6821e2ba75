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

/// The passes of a measurement, where no object lies (the floor) and on an object, counted three
/// ways: passes with evidence above the floor by their longest run of consecutive frames above it
/// (1, 2, 3, 4, 5 or more); every pass by its sign balance, (frames above - frames below) /
/// (frames with evidence); and every pass by the sweep its longest run of the pass's main sign
/// covered [mm].
struct SweepHistograms {
  static constexpr int kRunBins = 5;
  static constexpr int kBalanceBins =
      5;  ///< [-1, -0.6), [-0.6, -0.2), [-0.2, 0.2], (0.2, 0.6], (0.6, 1]
  static constexpr int kExtentBins = 6;  ///< [0, 1), [1, 2), [2, 3), [3, 5), [5, 10), >= 10 mm
  struct Counts {
    std::size_t run[kRunBins] = {}, balance[kBalanceBins] = {}, extent[kExtentBins] = {};
  };
  Counts floor, object;
  void add(const SweepPass& pass, bool on_object);
};

void writeSweepPassHeader(std::ostream& csv);
/// The passes that ended in frame `f`, each with the object within 15 mm of its place, if any;
/// counted into `histograms`.
void writeSweepPasses(std::ostream& csv, const WalkFrame& f, const OccupancyMap& map,
                      SweepHistograms& histograms);
/// The three histograms as bar charts (PNG) in `folder`: sweep_runs.png, sweep_balance.png and
/// sweep_extent.png, each bar the share of its kind's passes; and their counts in
/// sweep_histograms.csv (histogram, bin, passes on the floor, passes on an object).
void writeSweepHistograms(const std::string& folder, const SweepHistograms& histograms);

/// The object nearest to a square cell of edge `size` at `centre`, seen from above, within
/// `reach` [m]; nullptr when there is none.
const SceneObject* objectNear(const std::vector<SceneObject>& objects,
                              const Eigen::Vector2d& centre, double size, double reach);

/// Whether the map holds an occupied voxel within 1 cm of the object, seen from above.
bool mapped(const OccupancyMap& map, const SceneObject& object);

/// Occupied voxels of `map` farther than 1 cm from every object, seen from above.
std::size_t falseVoxels(const OccupancyMap& map, const std::vector<SceneObject>& objects);

}  // namespace multislit::apps
