// What `multislit map` writes while a real or recorded walk goes on: one row per frame
// (decisions.csv), one row per obstacle group (obstacles.csv), and at the end the OctoMap
// (map.bt), its top view, Fig. 14 and 15 and a summary. The two CSV files grow as
// decisions.csv.part and obstacles.csv.part (for `tail -f`), a whole row each time, and are
// renamed when the run ends; every file is whole or absent.
#pragma once

#include "output_file.h"

#include "multislit/pipeline.h"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace multislit::apps {

class MapRecorder {
 public:
  /// Opens the CSV files in `out` (created; given by `option`); throws std::runtime_error naming a
  /// file it cannot write, or when `out` is one of `inputs` or would hold an output of the name
  /// of one.
  MapRecorder(const std::filesystem::path& out, const std::string& option,
              const std::vector<NamedInput>& inputs);

  /// One processed frame: `seq` and `stamp_us` of the source, the CPU time of its extraction
  /// [s], the cloud given to the pipeline, what it gave and its map after the frame.
  void record(std::uint64_t seq, std::uint64_t stamp_us, double extract_seconds,
              const pcl::PointCloud<PointRDM>& cloud, const PipelineResult& result,
              const OccupancyMap& map);
  /// A frame that got no pose (skipped, not processed).
  void skip() { ++skipped_; }
  /// A frame file that could not be read (missing, unreadable, not a grey image): `what` names
  /// it; counted and listed in summary.txt.
  void unreadable(const std::string& what) { unreadable_.push_back(what); }

  /// map.bt, map_top.png, fig15_obstacle_points.png, rdmap_most_obstacles.png, summary.txt; the
  /// CSV files completed under their names. Returns the summary (also written). `heading`: what
  /// ran, on what.
  std::string finish(const Pipeline& pipeline, const std::string& heading, double seconds,
                     bool interrupted);

 private:
  std::filesystem::path out_;
  OutputFile frames_csv_, groups_csv_;  ///< decisions.csv and obstacles.csv
  std::vector<Pose2D> path_;
  std::vector<double> obstacle_points_;
  std::vector<std::string> events_, unreadable_;
  Command last_ = Command::Stop;
  std::size_t frames_ = 0, skipped_ = 0, no_floor_ = 0, dropped_ = 0, groups_ = 0;
  std::size_t decisions_[3] = {0, 0, 0};  ///< walk, turn, stop
  PipelineTimes sum_;
  double extract_sum_ = 0.0;    ///< [s]
  std::uint64_t best_seq_ = 0;  ///< the frame with most obstacle points (Fig. 14)
  std::size_t best_points_ = 0;
  pcl::PointCloud<PointRDM> best_cloud_;
  FloorResult best_floor_;
};

}  // namespace multislit::apps
