// What the robustness test (robustness_test.cpp) judges with: the scenes at a Table I pose, the
// tally of one frame against the simulator's ground truth and against the paper's method written
// plainly (paper_method.h), and one photometry's run.
#pragma once

#include "multislit/extractor.h"
#include "multislit/floor_detector.h"
#include "multislit/obstacles.h"
#include "multislit/sim/photometry.h"
#include "multislit/sim/scenarios.h"
#include "multislit/sim/simulator.h"
#include "multislit/sim/truth.h"
#include "paper_method.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace multislit::robustness {

constexpr double kMinContrast = 0.06;    // both methods' contrast limit [full scale]
constexpr double kRecallHeight = 0.005;  // the crossings that must be found [m]
constexpr double kOnTruth = 1.0;         // a point within this of its crossing is measured [px]
constexpr double kFoundOnTruth = 2.0;    // a crossing found by a point this near it [px]

enum class Kind { Floor, Ball, Cable, Screw };
inline const char* kindName(Kind k) {
  return k == Kind::Floor   ? "floor"
         : k == Kind::Ball  ? "ball"
         : k == Kind::Cable ? "cable"
                            : "screw";
}

// The object where the slits cross the floor at this pose (`bare`: the bare floor's truth
// there): the middle of their footprint.
inline Scene sceneOf(Kind kind, const std::vector<SlitCrossing>& bare) {
  Scene scene;
  if (kind == Kind::Floor) return scene;
  std::vector<double> xs, ys;
  for (const SlitCrossing& t : bare)
    xs.push_back(t.world_point.x()), ys.push_back(t.world_point.y());
  std::nth_element(xs.begin(), xs.begin() + static_cast<long>(xs.size() / 2), xs.end());
  std::nth_element(ys.begin(), ys.begin() + static_cast<long>(ys.size() / 2), ys.end());
  const double x = xs[xs.size() / 2], y = ys[ys.size() / 2];
  if (kind == Kind::Ball)
    scene.objects.push_back(SceneObject::sphere("ball", {x, y, 0.020}, 0.020));
  if (kind == Kind::Cable)
    scene.objects.push_back(
        SceneObject::cylinder("cable", {x, y - 0.3, 0.0035}, {x + 0.02, y + 0.3, 0.0035}, 0.0035));
  if (kind == Kind::Screw)  // a screw standing up, 8 mm high
    scene.objects.push_back(SceneObject::cylinder("screw", {x, y, 0.0}, {x, y, 0.008}, 0.003));
  return scene;
}

struct Tally {
  std::size_t clear = 0, measured = 0;  // crossings whose stripe clears the limit; measured
  std::size_t high = 0, found = 0;      // crossings >= 5 mm on an object; found as obstacle
  // Of the found, those whose point lies within kFoundOnTruth of the crossing: found by a measure
  // of the object, not by a maximum of noise or a neighbour's stripe that fell on it.
  std::size_t found_on_truth = 0;
  // Of them, those whose true shift off the floor's crossing exceeds the frame's threshold (what
  // a point-wise 3 sigma rule can find at all); found as obstacle.
  std::size_t above = 0, found_above = 0;
  std::size_t valid = 0, false_points = 0;  // our valid points; obstacle points off the object
  std::size_t false_near = 0;  // of the false points, those whose lit floor point is near an object
  std::size_t paper_valid = 0, paper_false = 0;
  std::size_t paper_found = 0;  // of the >= 5 mm crossings, those the paper's method calls obstacle
  // Valid points within kOnTruth of the crossing their slit makes on their row: points measured,
  // not merely given (a maximum of noise or of a neighbour's stripe is valid too).
  std::size_t on_truth = 0, paper_on_truth = 0;
  bool paper_floor = true;       // the paper's RANSAC found a floor (else it calls no obstacle)
  std::size_t false_groups = 0;  // obstacles on an empty floor
  // The >= 5 mm crossings missed: never measured, measured within the threshold of the floor,
  // off the floor but not in an accepted group.
  std::size_t miss_unmeasured = 0, miss_within = 0, miss_ungrouped = 0;
  double sigma = 0;
  std::string reference_error;  // why the reference could not be built
  std::string photometry;       // what the photometry is, in short (describe())
  std::size_t frames = 1;

  void add(const Tally& t) {
    clear += t.clear, measured += t.measured, high += t.high, found += t.found;
    found_on_truth += t.found_on_truth;
    above += t.above, found_above += t.found_above;
    valid += t.valid, false_points += t.false_points, false_near += t.false_near;
    paper_valid += t.paper_valid, paper_false += t.paper_false, frames += t.frames;
    paper_found += t.paper_found;
    on_truth += t.on_truth, paper_on_truth += t.paper_on_truth;
    false_groups += t.false_groups, miss_unmeasured += t.miss_unmeasured;
    miss_within += t.miss_within, miss_ungrouped += t.miss_ungrouped;
  }
};

// One row of docs/accuracy.md's table: the frames whose sigma lies in `name`'s range.
inline void printRow(const char* name, const Tally& s) {
  std::printf(
      "| %s | %zu | %.4f | %.3f (%zu/%zu) | %.3f | %.3f (%zu), %.3f | %.2f %% | %zu / %zu | %zu / "
      "%zu | %.2f %% | %.3f |\n",
      name, s.frames, static_cast<double>(s.measured) / static_cast<double>(s.clear),
      static_cast<double>(s.found) / static_cast<double>(s.high), s.found, s.high,
      static_cast<double>(s.found_on_truth) / static_cast<double>(s.high),
      static_cast<double>(s.above) / static_cast<double>(s.high), s.above,
      static_cast<double>(s.found_above) / static_cast<double>(s.above),
      100.0 * static_cast<double>(s.false_points) / static_cast<double>(s.valid), s.valid,
      s.paper_valid, s.on_truth, s.paper_on_truth,
      100.0 * static_cast<double>(s.paper_false) / static_cast<double>(s.paper_valid),
      static_cast<double>(s.paper_found) / static_cast<double>(s.high));
}

// The figures of frame `t` of variant `i` in one line.
inline void printFrame(int i, Kind kind, const Tally& t) {
  std::printf(
      "%2d %-5s sigma %.2f | measured %zu/%zu | found %zu/%zu, %zu on the truth (missed: %zu %zu "
      "%zu; above the "
      "threshold %zu/%zu) | false %zu (%zu near the object) of %zu (%zu on the truth), %zu "
      "groups | paper: valid %zu (%zu on the truth) found %zu false %zu%s | %s\n",
      i, kindName(kind), t.sigma, t.measured, t.clear, t.found, t.high, t.found_on_truth,
      t.miss_unmeasured, t.miss_within, t.miss_ungrouped, t.found_above, t.above, t.false_points,
      t.false_near, t.valid, t.on_truth, t.false_groups, t.paper_valid, t.paper_on_truth,
      t.paper_found, t.paper_false, t.paper_floor ? "" : " (no floor found)", t.photometry.c_str());
}

// The figures of `s` in one line.
inline void printSummary(const char* name, const Tally& s) {
  std::printf(
      "%s: measured %.4f of the crossings that clear the contrast limit, recall of >= 5 mm "
      "crossings %.4f (by a point within 2 px of the crossing %.4f; %zu of them shifted beyond "
      "the frame's threshold: %.3f of all, of them "
      "found %.4f), false %.3f%% of valid (%.3f%% within 15 mm of an object); paper: valid "
      "%zu (ours %zu), on the truth %zu (ours %zu), recall %.4f, false %.3f%%\n",
      name, static_cast<double>(s.measured) / static_cast<double>(s.clear),
      static_cast<double>(s.found) / static_cast<double>(s.high),
      static_cast<double>(s.found_on_truth) / static_cast<double>(s.high), s.above,
      static_cast<double>(s.above) / static_cast<double>(s.high),
      static_cast<double>(s.found_above) / static_cast<double>(s.above),
      100.0 * static_cast<double>(s.false_points) / static_cast<double>(s.valid),
      100.0 * static_cast<double>(s.false_near) / static_cast<double>(s.valid), s.paper_valid,
      s.valid, s.paper_on_truth, s.on_truth,
      static_cast<double>(s.paper_found) / static_cast<double>(s.high),
      100.0 * static_cast<double>(s.paper_false) / static_cast<double>(s.paper_valid));
}

// Whether the stripe of crossing `t` clears the contrast limit in `image`: its brightest pixel
// within 2 px of the true centre stands kMinContrast above the darkest of its assigned region.
inline bool clearsContrast(const cv::Mat& image, const SlitCrossing& t, double half_region) {
  const double full = image.depth() == CV_8U ? 255.0 : 65535.0;
  cv::Mat row;
  image.row(t.row).convertTo(row, CV_64F);
  const auto* p = row.ptr<double>();
  const int c = static_cast<int>(std::lround(t.u));
  double top = 0, low = full;
  for (int x = std::max(0, c - 2); x <= std::min(image.cols - 1, c + 2); ++x)
    top = std::max(top, p[x]);
  for (int x = std::max(0, static_cast<int>(c - half_region));
       x <= std::min(image.cols - 1, static_cast<int>(c + half_region)); ++x)
    low = std::min(low, p[x]);
  return top - low >= kMinContrast * full;
}

// A crossing that must be found: on an object, kRecallHeight or more above the floor.
inline bool isHigh(const SlitCrossing& t) { return t.object > 0 && t.height >= kRecallHeight; }

inline bool nearObject(const std::map<std::pair<int, int>, const SlitCrossing*>& truth, int slit,
                       int row) {
  for (int dv = -3; dv <= 3; ++dv) {
    const auto it = truth.find({slit, row + dv});
    if (it != truth.end() && it->second->object > 0) return true;
  }
  return false;
}

// Whether `centre` [px] lies within kOnTruth of the crossing of slit `slit` on image row `row`.
inline bool onTruth(const std::map<std::pair<int, int>, const SlitCrossing*>& truth, int slit,
                    int row, double centre) {
  const auto it = truth.find({slit, row});
  return it != truth.end() && std::abs(centre - it->second->u) <= kOnTruth;
}

// Whether the floor point that slit `slit` lights on `row` lies within kNearObject of an object
// seen from above: a false point there is an object's doing (the stripe partly hidden behind a
// cable, a neighbour's stripe on a ball), not one made of nothing.
constexpr double kNearObject = 0.015;  // [m]
inline bool litNearObject(const std::map<std::pair<int, int>, const SlitCrossing*>& truth,
                          const Scene& scene, int slit, int row) {
  const auto it = truth.find({slit, row});
  if (it == truth.end()) return false;
  Footprint point;
  point.centre = it->second->world_point.head<2>();
  for (const SceneObject& object : scene.objects)
    if (clearance(point, object) < kNearObject) return true;
  return false;
}

// The paper's way on the same image: plain measure, plain RANSAC at 0.9 px, every off-plane point
// an obstacle.
inline void judgePaper(const Reference& ref, const cv::Mat& image,
                       const std::map<std::pair<int, int>, const SlitCrossing*>& truth,
                       Tally* tally) {
  auto cloud = pcl::make_shared<pcl::PointCloud<PointRDM>>();
  for (const paper::PaperPoint& p : paper::paperExtract(ref, image, kMinContrast)) {
    if (!std::isfinite(p.dk)) continue;
    tally->paper_on_truth += onTruth(truth, p.slit, p.row, p.u + p.dk);
    PointRDM q;
    q.u = static_cast<float>(p.u), q.v = static_cast<float>(p.row), q.dk = static_cast<float>(p.dk);
    q.slit = p.slit;
    cloud->push_back(q);
  }
  FloorDetectorConfig paper;
  paper.estimate_sigma = false;
  paper.local_refit = false;
  const FloorResult floor = FloorDetector(paper).detect(cloud);
  tally->paper_valid += cloud->size();
  tally->paper_floor = floor.found;
  for (const int i : floor.obstacles) {
    const PointRDM& p = (*cloud)[static_cast<std::size_t>(i)];
    tally->paper_false += !nearObject(truth, p.slit, static_cast<int>(p.v));
    const auto it = truth.find({p.slit, static_cast<int>(p.v)});
    tally->paper_found += it != truth.end() && isHigh(*it->second);
  }
}

// Each crossing of frame `f`: whether its stripe clears the contrast limit and is measured, and
// for those >= 5 mm on an object, whether they were found, shifted beyond the frame's threshold off
// the floor's crossing (`bare`: the truth of the bare floor at the same pose) and why missed.
inline void judgeCrossings(const Reference& ref, const RenderedFrame& f,
                           const pcl::PointCloud<PointRDM>& cloud, const FloorResult& floor,
                           const std::set<int>& obstacle_points,
                           const std::vector<SlitCrossing>& bare, Tally* tally) {
  const std::set<int> off_floor(floor.obstacles.begin(), floor.obstacles.end());
  std::map<std::pair<int, int>, double> floor_u;  // where each slit crosses each row on the floor
  for (const SlitCrossing& t : bare) floor_u[{t.slit, t.row}] = t.u;
  for (const SlitCrossing& t : f.truth) {
    const ReferenceSlit& slit = ref.slits[static_cast<std::size_t>(t.slit)];
    if (t.row < slit.first_row || t.row > slit.lastRow()) continue;
    const std::size_t k = static_cast<std::size_t>(t.row - slit.first_row);
    const int cell = static_cast<int>(static_cast<std::size_t>(t.slit) * cloud.width + k);
    const bool measured = std::isfinite(cloud[static_cast<std::size_t>(cell)].dk);
    if (clearsContrast(f.image, t, 0.5 * ref.region_width))
      ++tally->clear, tally->measured += measured;
    if (isHigh(t)) {
      const bool found = obstacle_points.count(cell) > 0;
      ++tally->high, tally->found += found;
      const PointRDM& p = cloud[static_cast<std::size_t>(cell)];
      tally->found_on_truth += found && std::abs(p.u + p.dk - t.u) <= kFoundOnTruth;
      const auto on_floor = floor_u.find({t.slit, t.row});
      if (on_floor != floor_u.end() && std::abs(t.u - on_floor->second) > floor.threshold)
        ++tally->above, tally->found_above += found;
      if (!found && !measured) ++tally->miss_unmeasured;
      if (!found && measured)
        (off_floor.count(cell) ? tally->miss_ungrouped : tally->miss_within)++;
    }
  }
}

// The photometry in short: floor, bit depth, speckle, stripe width, laser and ambient light.
inline std::string describe(const Photometry& p) {
  const bool untextured = p.floor.texture_amplitude == 0 && p.floor.grout_albedo == p.floor.albedo;
  char text[160];
  std::snprintf(
      text, sizeof text, "%s, %d bit, speckle %.2f, stripe x%.2f, laser %.2f, ambient %.2f",
      untextured ? "one albedo" : floorTextureName(p.floor.texture), p.render.bit_depth,
      p.render.speckle_contrast, p.render.stripe_width, p.render.laser_peak, p.render.ambient);
  return text;
}

// One photometry: its reference, one frame of a scene at a Table I pose, both methods judged.
// `realization` draws other noise (of the reference and the frame) on the same images. Without
// `textured`, the floor is one albedo (no grain, tiles or grout) and all else is the photometry's.
inline Tally runVariant(int index, Kind kind, int realization, bool textured = true) {
  Photometry photometry = randomPhotometry(static_cast<std::uint64_t>(1000 + index));
  if (!textured) {
    photometry.floor.texture_amplitude = 0;
    photometry.floor.grout_albedo = photometry.floor.albedo;
  }
  Scene bare;
  const SensorConfig sensor;
  RenderConfig render = applyPhotometry(photometry, bare);
  render.seed += 7919 * static_cast<std::uint64_t>(realization);  // other noise, reference too
  const Simulator sim(sensor, render);
  const MountConfig reference_mount = tableIPose(0), mount = tableIPose(index % 7);
  const cv::Mat reference_image = sim.renderReference(bare, reference_mount).image;
  Tally tally;
  tally.photometry = describe(photometry);
  Reference ref;
  try {
    ref = Reference::fromImage(reference_image);
  } catch (const std::exception& e) {
    tally.reference_error = e.what();
    return tally;
  }
  ref.setNominalScale(sensor, reference_mount);
  const Eigen::Isometry3d pose = sim.geometry().robotFromCamera(mount);
  const std::vector<SlitCrossing> bare_truth = sim.groundTruth(Scene{}, pose);
  Scene scene = sceneOf(kind, bare_truth);
  applyPhotometry(photometry, scene);
  const RenderedFrame f = sim.render(scene, pose, static_cast<std::uint64_t>(index));

  const Extractor extractor(ref);
  const auto cloud = extractor.extract(f.image, 0, static_cast<std::uint32_t>(index));
  const FloorResult floor = FloorDetector().detect(cloud);
  EXPECT_TRUE(floor.found) << photometry.name << " " << kindName(kind);
  const ObstacleResult groups = ObstacleClusterer().cluster(cloud, floor, pose);
  std::set<int> obstacle_points;
  for (const Obstacle& o : groups.obstacles)
    obstacle_points.insert(o.indices.begin(), o.indices.end());

  tally.sigma = floor.sigma;
  std::map<std::pair<int, int>, const SlitCrossing*> truth;
  for (const SlitCrossing& t : f.truth) truth[{t.slit, t.row}] = &t;
  judgeCrossings(ref, f, *cloud, floor, obstacle_points, bare_truth, &tally);
  tally.valid = floor.valid_points;
  for (const PointRDM& p : cloud->points)
    if (std::isfinite(p.dk))
      tally.on_truth += onTruth(truth, p.slit, static_cast<int>(p.v), p.u + p.dk);
  for (const int i : obstacle_points) {
    const PointRDM& p = (*cloud)[static_cast<std::size_t>(i)];
    if (nearObject(truth, p.slit, static_cast<int>(p.v))) continue;
    ++tally.false_points;
    tally.false_near += litNearObject(truth, scene, p.slit, static_cast<int>(p.v));
  }
  if (kind == Kind::Floor) tally.false_groups = groups.obstacles.size();
  judgePaper(ref, f.image, truth, &tally);
  return tally;
}

}  // namespace multislit::robustness
