#include "walk_sweep.h"

#include "output_file.h"
#include "plot.h"

#include "multislit/sim/truth.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <string>
#include <vector>

namespace multislit::apps {

const SceneObject* objectNear(const std::vector<SceneObject>& objects,
                              const Eigen::Vector2d& centre, double size, double reach) {
  Footprint cell;
  cell.centre = centre;
  cell.length = cell.width = size;
  const SceneObject* best = nullptr;
  double nearest = reach;
  for (const SceneObject& o : objects) {
    const double d = clearance(cell, o);
    if (d <= nearest) {
      nearest = d;
      best = &o;
    }
  }
  return best;
}

bool mapped(const OccupancyMap& map, const SceneObject& o) {
  Eigen::Vector2d lo, hi;
  if (o.type == ShapeType::Cylinder) {
    lo = o.axis_start.head<2>().cwiseMin(o.axis_end.head<2>());
    hi = o.axis_start.head<2>().cwiseMax(o.axis_end.head<2>());
  } else {
    lo = hi = o.centre.head<2>();
  }
  const double reach = 0.01 + (o.type == ShapeType::Box ? 0.5 * o.size.head<2>().norm() : o.radius);
  for (const MapCell& c : map.occupiedInBox(Eigen::Vector3d(lo.x() - reach, lo.y() - reach, -1),
                                            Eigen::Vector3d(hi.x() + reach, hi.y() + reach, 1)))
    if (objectNear({o}, c.centre.head<2>(), c.size, 0.01)) return true;
  return false;
}

void measureSweep(WalkConfig& config) {
  SweepEvidenceConfig& sweep = config.pipeline.map.sweep;
  sweep.record_passes = true;
  sweep.tall_frames = sweep.min_passes = sweep.weak_passes = 1000;
  config.pipeline.walker.sudden_frames = 1000;
}

void writeSweepPassHeader(std::ostream& csv) {
  csv << "frame,x,y,above_frames,below_frames,above_run,below_run,above_sweep_mm,below_sweep_mm,"
         "max_height_mm,strong,verdict,object\n";
}

void writeSweepPasses(std::ostream& csv, const WalkFrame& f, const OccupancyMap& map,
                      SweepHistograms& histograms) {
  std::vector<SceneObject> objects;
  for (const ObjectView& o : f.objects) objects.push_back(o.object);
  const octomap::OcTree& tree = map.tree();
  const double res = tree.getResolution();
  static const char* const kVerdicts[] = {"pending", "above", "below"};
  for (const SweepPass& p : f.map.passes) {
    const Eigen::Vector2d centre(tree.keyToCoord(static_cast<octomap::key_type>(p.x)),
                                 tree.keyToCoord(static_cast<octomap::key_type>(p.y)));
    const SceneObject* o = objectNear(objects, centre, res, 0.015);
    char line[256];
    std::snprintf(line, sizeof line, "%llu,%.4f,%.4f,%d,%d,%d,%d,%.2f,%.2f,%.1f,%d,%s,%s\n",
                  static_cast<unsigned long long>(f.frame), centre.x(), centre.y(), p.above_frames,
                  p.below_frames, p.above_run, p.below_run, 1e3 * p.above_sweep,
                  1e3 * p.below_sweep, 1e3 * p.max_height, p.strong ? 1 : 0,
                  kVerdicts[static_cast<int>(p.verdict)], o ? o->name.c_str() : "none");
    csv << line;
    histograms.add(p, o != nullptr);
  }
}

void SweepHistograms::add(const SweepPass& p, bool on_object) {
  Counts& c = on_object ? object : floor;
  if (p.above_run > 0) ++c.run[std::min(p.above_run, kRunBins) - 1];
  const int frames = p.above_frames + p.below_frames;
  if (frames == 0) return;
  const double balance = static_cast<double>(p.above_frames - p.below_frames) / frames;
  ++c.balance[balance < -0.6   ? 0
              : balance < -0.2 ? 1
              : balance <= 0.2 ? 2
              : balance <= 0.6 ? 3
                               : 4];
  const double mm = 1e3 * (p.above_frames >= p.below_frames ? p.above_sweep : p.below_sweep);
  static constexpr double kEdges[] = {1, 2, 3, 5, 10};
  ++c.extent[std::upper_bound(std::begin(kEdges), std::end(kEdges), std::abs(mm)) -
             std::begin(kEdges)];
}

namespace {

/// One histogram of both kinds: its labels, the share of each kind's passes per bin, the counts.
struct Histogram {
  const char* name;
  const char* title;
  std::vector<const char*> bins;
  const std::size_t* floor;
  const std::size_t* object;
};

void drawHistogram(const std::string& path, const Histogram& h) {
  std::vector<std::string> labels;
  std::vector<double> shares;
  const auto add = [&](const char* kind, const std::size_t* counts) {
    std::size_t all = 0;
    for (std::size_t i = 0; i < h.bins.size(); ++i) all += counts[i];
    for (std::size_t i = 0; i < h.bins.size(); ++i) {
      labels.push_back(std::string(kind) + " " + h.bins[i]);
      shares.push_back(all > 0 ? 100.0 * static_cast<double>(counts[i]) / all : 0.0);
    }
  };
  add("F", h.floor);
  add("O", h.object);
  drawBarChart(path, std::string(h.title) + " (F: no object, O: on an object)",
               "% of the passes of the kind", labels, shares);
}

}  // namespace

void writeSweepHistograms(const std::string& folder, const SweepHistograms& s) {
  const Histogram histograms[] = {{"runs",
                                   "passes above the floor by their longest run of frames",
                                   {"1", "2", "3", "4", "5+"},
                                   s.floor.run,
                                   s.object.run},
                                  {"balance",
                                   "passes by (frames above - below) / frames",
                                   {"<-.6", "-.4", "0", ".4", ">.6"},
                                   s.floor.balance,
                                   s.object.balance},
                                  {"extent",
                                   "passes by the sweep of their longest run [mm]",
                                   {"<1", "1-2", "2-3", "3-5", "5-10", "10+"},
                                   s.floor.extent,
                                   s.object.extent}};
  OutputFile csv(std::filesystem::path(folder) / "sweep_histograms.csv");
  csv.stream() << "histogram,bin,floor_passes,object_passes\n";
  for (const Histogram& h : histograms) {
    drawHistogram(folder + "/sweep_" + h.name + ".png", h);
    for (std::size_t i = 0; i < h.bins.size(); ++i)
      csv.stream() << h.name << ',' << h.bins[i] << ',' << h.floor[i] << ',' << h.object[i] << '\n';
  }
  csv.commit();
}

std::size_t falseVoxels(const OccupancyMap& map, const std::vector<SceneObject>& objects) {
  const octomap::OcTree& tree = map.tree();
  std::size_t n = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const Eigen::Vector2d centre(it.getX(), it.getY());
    if (objectNear(objects, centre, it.getSize(), 0.01)) continue;
    const double voxels = it.getSize() / tree.getResolution();  // a pruned leaf holds n^3
    n += static_cast<std::size_t>(std::lround(voxels * voxels * voxels));
  }
  return n;
}

}  // namespace multislit::apps
