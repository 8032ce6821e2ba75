#include "map_outputs.h"
#include "multislit/units.h"

#include "output_file.h"
#include "plot.h"
#include "walk_figures.h"

#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace multislit::apps {

namespace {

/// The files `map` writes into its output folder.
const std::vector<std::string> kMapFiles{"decisions.csv",
                                         "obstacles.csv",
                                         "map.bt",
                                         "map_top.png",
                                         "fig15_obstacle_points.png",
                                         "rdmap_most_obstacles.png",
                                         "summary.txt"};

/// `out`, checked against the inputs and created.
const std::filesystem::path& preparedFolder(const std::filesystem::path& out,
                                            const std::string& option,
                                            const std::vector<NamedInput>& inputs) {
  refuseOutputFolder(out, option, kMapFiles, inputs);
  std::filesystem::create_directories(out);
  return out;
}

}  // namespace

MapRecorder::MapRecorder(const std::filesystem::path& out, const std::string& option,
                         const std::vector<NamedInput>& inputs)
    : out_(preparedFolder(out, option, inputs)),
      frames_csv_(out / "decisions.csv", OutputFile::Temporary::Live),
      groups_csv_(out / "obstacles.csv", OutputFile::Temporary::Live) {
  frames_csv_.stream() << "seq,stamp_us,x_m,y_m,yaw_deg,decision,reason,floor_found,valid_points,"
                          "sigma_px,obstacle_points,groups,nearest_m,map_occupied,extract_ms,"
                          "floor_ms,obstacles_ms,map_ms,walker_ms\n";
  groups_csv_.stream() << "seq,stamp_us,group,points,slits,x_m,y_m,z_m,world_x_m,world_y_m,"
                          "length_m,width_m,height_m,distance_m\n";
}

void MapRecorder::record(std::uint64_t seq, std::uint64_t stamp_us, double extract_seconds,
                         const pcl::PointCloud<PointRDM>& cloud, const PipelineResult& r,
                         const OccupancyMap& map) {
  const auto seq_ll = static_cast<unsigned long long>(seq);
  const auto stamp_ll = static_cast<unsigned long long>(stamp_us);
  const std::vector<Obstacle>& groups = r.obstacles.obstacles;
  char line[512];
  std::snprintf(
      line, sizeof line,
      "%llu,%llu,%.4f,%.4f,%.2f,%s,%s,%d,%zu,%.4f,%zu,%zu,%.4f,%zu,%.4f,%.4f,%.4f,%.4f,%.4f\n",
      seq_ll, stamp_ll, r.body.x, r.body.y, r.body.yaw / kDeg, commandName(r.walker.command),
      reasonName(r.walker.reason), r.floor.found ? 1 : 0, r.floor.valid_points, r.floor.sigma,
      r.obstacles.pointCount(), groups.size(), groups.empty() ? NAN : groups[0].distance,
      map.occupiedCount(), 1e3 * extract_seconds, 1e3 * r.times.floor, 1e3 * r.times.obstacles,
      1e3 * r.times.map, 1e3 * r.times.walker);
  frames_csv_.stream() << line;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const Obstacle& o = groups[g];
    const Eigen::Vector2d world = r.body.toWorld(o.centroid.head<2>());
    std::snprintf(line, sizeof line,
                  "%llu,%llu,%zu,%zu,%d,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f\n", seq_ll,
                  stamp_ll, g, o.pointCount(), o.slits, o.centroid.x(), o.centroid.y(),
                  o.centroid.z(), world.x(), world.y(), o.length, o.width, o.height, o.distance);
    groups_csv_.stream() << line;
  }
  // Whole rows reach the files each frame, groups first: `tail -f decisions.csv.part` follows a
  // live run, and a row read there has its groups in obstacles.csv.part already.
  groups_csv_.stream().flush();
  frames_csv_.stream().flush();
  ++frames_;
  groups_ += groups.size();
  no_floor_ += !r.floor.found;
  ++decisions_[static_cast<int>(r.walker.command)];
  extract_sum_ += extract_seconds;
  sum_.floor += r.times.floor, sum_.obstacles += r.times.obstacles;
  sum_.map += r.times.map, sum_.walker += r.times.walker;
  path_.push_back(r.body);
  obstacle_points_.push_back(static_cast<double>(r.obstacles.pointCount()));
  if (!r.dropped.empty() && dropped_++ == 0)  // the first is told; all are counted
    events_.push_back("frame " + std::to_string(seq) + " dropped: " + r.dropped);
  if (frames_ == 1 || r.walker.command != last_) {
    events_.push_back("frame " + std::to_string(seq) + ": " + commandName(r.walker.command) + " (" +
                      reasonName(r.walker.reason) + ")");
    last_ = r.walker.command;
  }
  if (r.obstacles.pointCount() > best_points_ || frames_ == 1) {
    best_points_ = r.obstacles.pointCount();
    best_seq_ = seq;
    best_cloud_ = cloud;
    best_floor_ = r.floor;
  }
}

std::string MapRecorder::finish(const Pipeline& pipeline, const std::string& heading,
                                double seconds, bool interrupted) {
  groups_csv_.commit();
  frames_csv_.commit();
  const OccupancyMap& map = pipeline.map();
  writeWhole(out_ / "map.bt", [&map](const std::string& p) { map.save(p); });
  TopViewContent top;
  top.path = path_;
  drawTopView((out_ / "map_top.png").string(), map, top);
  drawLinePlot((out_ / "fig15_obstacle_points.png").string(),
               "Fig. 15: points detected as obstacles in each frame", "frame", "points",
               {Series{"obstacle points", obstacle_points_, 0xd03030}});
  if (!best_cloud_.empty()) {
    char title[160];
    std::snprintf(title, sizeof title, "Fig. 14: RDMap of frame %llu, the floor and obstacles",
                  static_cast<unsigned long long>(best_seq_));
    drawRDMapFigure((out_ / "rdmap_most_obstacles.png").string(), title, best_cloud_, best_floor_);
  }
  const double n = static_cast<double>(std::max<std::size_t>(frames_, 1));
  std::ostringstream o;
  char s[640];
  std::snprintf(
      s, sizeof s,
      "%s\n"
      "  frames: %zu processed%s, %zu skipped without a pose, %zu without a floor (%zu of "
      "them dropped: implausible numbers)\n"
      "  decisions: walk %zu, turn %zu, stop %zu; obstacle groups: %zu\n"
      "  map: %zu occupied voxels of %.0f mm, %zu voxels, %.0f kB\n"
      "  per frame (CPU): extraction %.3f ms, floor %.3f ms, obstacles %.3f ms, map "
      "%.3f ms, footsteps and decision %.3f ms; %.1f s in all\n",
      heading.c_str(), frames_, interrupted ? " (interrupted)" : "", skipped_, no_floor_, dropped_,
      decisions_[0], decisions_[1], decisions_[2], groups_, map.occupiedCount(),
      1e3 * pipeline.config().map.resolution, map.leafCount(), map.memoryUsage() / 1e3,
      1e3 * extract_sum_ / n, 1e3 * sum_.floor / n, 1e3 * sum_.obstacles / n, 1e3 * sum_.map / n,
      1e3 * sum_.walker / n, seconds);
  o << s;
  if (!unreadable_.empty()) o << "  frames that could not be read: " << unreadable_.size() << "\n";
  for (std::size_t k = 0; k < unreadable_.size() && k < 20; ++k)
    o << "    " << unreadable_[k] << "\n";
  if (unreadable_.size() > 20) o << "    ... and " << unreadable_.size() - 20 << " more\n";
  o << "what the robot was told:\n";
  for (const std::string& e : events_) o << "  " << e << "\n";
  o << "outputs in " << out_.string() << ":";
  for (std::size_t k = 0; k < kMapFiles.size(); ++k) o << (k ? ", " : " ") << kMapFiles[k];
  o << "\n";
  OutputFile summary(out_ / "summary.txt");
  summary.stream() << o.str();
  summary.commit();
  return o.str();
}

}  // namespace multislit::apps
