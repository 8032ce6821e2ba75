// Robust on images of many photometries (issue 13): randomized lasers, rooms, floors, speckle,
// focus, noise and bit depths at the poses of Table I, judged against the simulator's ground truth
// and against the paper's method written plainly (paper_method.h) on the same images.
#include "multislit/extractor.h"
#include "multislit/floor_detector.h"
#include "multislit/obstacles.h"
#include "multislit/sim/photometry.h"
#include "multislit/sim/scenarios.h"
#include "multislit/sim/simulator.h"
#include "multislit/sim/truth.h"
#include "paper_method.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <set>

using namespace multislit;

namespace {

constexpr double kMinContrast = 0.06;    // both methods' contrast limit [full scale]
constexpr double kRecallHeight = 0.005;  // the crossings that must be found [m]
constexpr double kOnTruth = 1.0;         // a point within this of its crossing is measured [px]

enum class Kind { Floor, Ball, Cable, Screw };
const char* kindName(Kind k) {
  return k == Kind::Floor   ? "floor"
         : k == Kind::Ball  ? "ball"
         : k == Kind::Cable ? "cable"
                            : "screw";
}

// The object where the slits cross the floor at this pose (`bare`: the bare floor's truth
// there): the middle of their footprint.
Scene sceneOf(Kind kind, const std::vector<SlitCrossing>& bare) {
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
  // Of them, those whose true shift off the floor's crossing exceeds the frame's threshold (what
  // a point-wise 3 sigma rule can find at all); found as obstacle.
  std::size_t above = 0, found_above = 0;
  std::size_t valid = 0, false_points = 0;  // our valid points; obstacle points off the object
  std::size_t false_near = 0;  // of the false points, those whose lit floor point is near an object
  std::size_t paper_valid = 0, paper_false = 0;
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
  std::size_t frames = 1;

  void add(const Tally& t) {
    clear += t.clear, measured += t.measured, high += t.high, found += t.found;
    above += t.above, found_above += t.found_above;
    valid += t.valid, false_points += t.false_points, false_near += t.false_near;
    paper_valid += t.paper_valid, paper_false += t.paper_false, frames += t.frames;
    on_truth += t.on_truth, paper_on_truth += t.paper_on_truth;
    false_groups += t.false_groups, miss_unmeasured += t.miss_unmeasured;
    miss_within += t.miss_within, miss_ungrouped += t.miss_ungrouped;
  }
};

// One row of the README's table: the frames whose sigma lies in `name`'s range.
void printRow(const char* name, const Tally& s) {
  std::printf(
      "| %s | %zu | %.4f | %.3f (%zu/%zu) | %.3f (%zu), %.3f | %.2f %% | %zu / %zu | %zu / "
      "%zu | %.2f %% |\n",
      name, s.frames, static_cast<double>(s.measured) / static_cast<double>(s.clear),
      static_cast<double>(s.found) / static_cast<double>(s.high), s.found, s.high,
      static_cast<double>(s.above) / static_cast<double>(s.high), s.above,
      static_cast<double>(s.found_above) / static_cast<double>(s.above),
      100.0 * static_cast<double>(s.false_points) / static_cast<double>(s.valid), s.valid,
      s.paper_valid, s.on_truth, s.paper_on_truth,
      100.0 * static_cast<double>(s.paper_false) / static_cast<double>(s.paper_valid));
}

// Whether the stripe of crossing `t` clears the contrast limit in `image`: its brightest pixel
// within 2 px of the true centre stands kMinContrast above the darkest of its assigned region.
bool clearsContrast(const cv::Mat& image, const SlitCrossing& t, double half_region) {
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

bool nearObject(const std::map<std::pair<int, int>, const SlitCrossing*>& truth, int slit,
                int row) {
  for (int dv = -3; dv <= 3; ++dv) {
    const auto it = truth.find({slit, row + dv});
    if (it != truth.end() && it->second->object > 0) return true;
  }
  return false;
}

// Whether `centre` [px] lies within kOnTruth of the crossing of slit `slit` on image row `row`.
bool onTruth(const std::map<std::pair<int, int>, const SlitCrossing*>& truth, int slit, int row,
             double centre) {
  const auto it = truth.find({slit, row});
  return it != truth.end() && std::abs(centre - it->second->u) <= kOnTruth;
}

// Whether the floor point that slit `slit` lights on `row` lies within kNearObject of an object
// seen from above: a false point there is an object's doing (the stripe partly hidden behind a
// cable, a neighbour's stripe on a ball), not one made of nothing.
constexpr double kNearObject = 0.015;  // [m]
bool litNearObject(const std::map<std::pair<int, int>, const SlitCrossing*>& truth,
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
void judgePaper(const Reference& ref, const cv::Mat& image,
                const std::map<std::pair<int, int>, const SlitCrossing*>& truth, Tally* tally) {
  auto cloud = pcl::make_shared<pcl::PointCloud<PointRDM>>();
  for (const test::PaperPoint& p : test::paperExtract(ref, image, kMinContrast)) {
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
  }
}

// Each crossing of frame `f`: whether its stripe clears the contrast limit and is measured, and
// for those >= 5 mm on an object, whether they were found, shifted beyond the frame's threshold off
// the floor's crossing (`bare`: the truth of the bare floor at the same pose) and why missed.
void judgeCrossings(const Reference& ref, const RenderedFrame& f,
                    const pcl::PointCloud<PointRDM>& cloud, const FloorResult& floor,
                    const std::set<int>& obstacle_points, const std::vector<SlitCrossing>& bare,
                    Tally* tally) {
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
    if (t.object > 0 && t.height >= kRecallHeight) {
      const bool found = obstacle_points.count(cell) > 0;
      ++tally->high, tally->found += found;
      const auto on_floor = floor_u.find({t.slit, t.row});
      if (on_floor != floor_u.end() && std::abs(t.u - on_floor->second) > floor.threshold)
        ++tally->above, tally->found_above += found;
      if (!found && !measured) ++tally->miss_unmeasured;
      if (!found && measured)
        (off_floor.count(cell) ? tally->miss_ungrouped : tally->miss_within)++;
    }
  }
}

// One photometry: its reference, one frame of a scene at a Table I pose, both methods judged.
// `realization` draws other noise (of the reference and the frame) on the same images.
Tally runVariant(int index, Kind kind, int realization) {
  const Photometry photometry = randomPhotometry(static_cast<std::uint64_t>(1000 + index));
  Scene bare;
  const SensorConfig sensor;
  RenderConfig render = applyPhotometry(photometry, bare);
  render.seed += 7919 * static_cast<std::uint64_t>(realization);  // other noise, reference too
  const Simulator sim(sensor, render);
  const MountConfig reference_mount = tableIPose(0), mount = tableIPose(index % 7);
  const cv::Mat reference_image = sim.renderReference(bare, reference_mount).image;
  Tally tally;
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

}  // namespace

// 40 random photometries (8 under the sanitizers), each with its own reference, of the floor,
// the ball, the cable and a screw at the seven poses of Table I; two noise realizations of each
// (one under the sanitizers).
//
// What holds today is asserted; the targets that do not (recall of >= 5 mm crossings
// 0.98 and false points 0.1 % over every photometry) are printed and left to the README's table.
// The slit's centre is measured across the stripe (ExtractorConfig::across_stripe), not along
// the row, which the rotated camera lays nearly along it: a tile's edge or grout crossing the
// stripe no longer moves the centre by pixels, and the reference's slits are fitted robustly (a
// piece of something else at a slit's end pulled whole slits by up to 68 px). With both, the
// false points over the 40 fell from 4.22 % to 1.77 % of valid (the paper's method 17.4 %) and
// the frames that measure the paper's sigma (<= 0.35 px) grew from 30 to 58 of the 80, for the
// recall 0.808 -> 0.819. The extractor's contrast limit then went from the paper's 0.06 to 0.03
// of full scale (a dark cable under a weak laser was not measured at all): recall 0.819 -> 0.891,
// false points 1.77 -> 1.74 %, valid points 348 964 -> 351 122 (the paper's method 350 969); the
// laser-off test below holds at 0.03. The reference's slits judged as one pattern (a stretch of
// one slit that grout pulled sideways is held by the others, slit_pattern.h): false points
// 1.73 -> 1.49 % (quiet frames 1.49 -> 1.24 %), recall 0.892 (one crossing fewer), valid points
// 351 208 -> 350 751. What is left (per draw of the 40, over 20 draws): 75 of the
// ~930 >= 5 mm crossings missed on cables (19 never measured, 55 measured within the threshold of
// the floor), 20 on balls (7 and 14). Where a cable runs nearly along a slit (variants 18 and 38)
// the sheet's thickness blends its flank with the floor, so the measured shift is a third of the
// true one; strong speckle (sigma at its 1 px bound) hides the 7 mm cable under the threshold;
// and grout lines or grain running along a stripe darken one flank of it over dozens of rows as
// an object would shift it (tiles of variant 36: 8 of the ~18 false groups on empty floors).
TEST(Robustness, FortyPhotometriesAgainstGroundTruthAndThePapersMethod) {
  const int variants = frameCount(40, 8), realizations = frameCount(2, 1);
  Tally all, quiet;  // quiet: the frames whose sigma is the paper's 0.3 px or near it
  Tally middle, noisy;
  all.frames = quiet.frames = middle.frames = noisy.frames = 0;
  for (int n = 0; n < variants * realizations; ++n) {
    const int i = n % variants, realization = n / variants;
    const Kind kind = static_cast<Kind>(i % 4);
    const Tally t = runVariant(i, kind, realization);
    EXPECT_EQ(t.reference_error, "") << "variant " << i;  // the reference is built on every one
    if (!t.reference_error.empty()) continue;
    std::printf(
        "%2d %-5s sigma %.2f | measured %zu/%zu | found %zu/%zu (missed: %zu %zu %zu; above the "
        "threshold %zu/%zu) | false %zu (%zu near the object) of %zu (%zu on the truth), %zu "
        "groups | paper: valid %zu (%zu on the truth) false %zu%s\n",
        i, kindName(kind), t.sigma, t.measured, t.clear, t.found, t.high, t.miss_unmeasured,
        t.miss_within, t.miss_ungrouped, t.found_above, t.above, t.false_points, t.false_near,
        t.valid, t.on_truth, t.false_groups, t.paper_valid, t.paper_on_truth, t.paper_false,
        t.paper_floor ? "" : " (no floor found)");
    // Over 20 draws of the 40: at least 0.991 of the crossings that clear the paper's contrast
    // limit measured on every variant, and at least 0.983 of the paper's valid points (variant
    // 31; 238 of the 800 below the paper's count, the others at or above it).
    EXPECT_GE(t.measured * 100, t.clear * 98) << "variant " << i;
    EXPECT_GE(t.valid * 100, t.paper_valid * 97) << "variant " << i;
    // The points the paper's method gives and ours does not are not measures: of 372 over the
    // 80 frames, 14 lie within 1 px of their crossing (variant 31: 0 of 123). Counted on the
    // truth, ours measures at least as many points as the paper's method on every variant: of
    // 400 frames (10 draws), the least was variant 27's equal count (4490 and 4490).
    EXPECT_GE(t.on_truth, t.paper_on_truth) << "variant " << i;
    // Fewer false points than the paper's method wherever it finds a floor (where it finds none,
    // variants 0, 1 and 25 under strong speckle, it calls no obstacle at all); of 400 draws at the
    // 0.06 contrast limit and 800 at 0.03, no other variant had more.
    if (t.paper_floor) {
      EXPECT_LE(t.false_points, t.paper_false) << "variant " << i;
    }
    all.add(t);
    (t.sigma <= 0.35 ? quiet : t.sigma <= 0.7 ? middle : noisy).add(t);
  }
  printRow("0.30-0.35 px (the paper's sensor)", quiet);
  printRow("0.35-0.7 px", middle);
  printRow("0.7-1.0 px (strong speckle, defocus)", noisy);
  printRow("all", all);
  for (const Tally* sum : {&all, &quiet})
    std::printf(
        "%s: measured %.4f of the crossings that clear the contrast limit, recall of >= 5 mm "
        "crossings %.4f (%zu of them shifted beyond the frame's threshold: %.3f of all, of them "
        "found %.4f), false %.3f%% of valid (%.3f%% within 15 mm of an object); paper: valid "
        "%zu (ours %zu), on the truth %zu (ours %zu), false %.3f%%\n",
        sum == &all ? "all" : "sigma <= 0.35 px",
        static_cast<double>(sum->measured) / static_cast<double>(sum->clear),
        static_cast<double>(sum->found) / static_cast<double>(sum->high), sum->above,
        static_cast<double>(sum->above) / static_cast<double>(sum->high),
        static_cast<double>(sum->found_above) / static_cast<double>(sum->above),
        100.0 * static_cast<double>(sum->false_points) / static_cast<double>(sum->valid),
        100.0 * static_cast<double>(sum->false_near) / static_cast<double>(sum->valid),
        sum->paper_valid, sum->valid, sum->paper_on_truth, sum->on_truth,
        100.0 * static_cast<double>(sum->paper_false) / static_cast<double>(sum->paper_valid));
  EXPECT_GE(all.measured * 1000, all.clear * 998);     // 0.9995 - 0.9996 over 20 draws
  EXPECT_GE(all.valid * 1000, all.paper_valid * 995);  // 1.0002 - 1.0007 (pairs)
  // Points on the truth, ours over the paper's method's: 1.138 - 1.142 over 10 draws of the 40,
  // 1.249 - 1.266 of the first 8.
  EXPECT_GE(all.on_truth * 100, all.paper_on_truth * (kSanitized ? 120 : 112));
  EXPECT_LE(all.false_points * 6, all.paper_false);  // a sixth of the paper's false points or less
  // The bounds hold for any noise: measured over 10 pairs of realizations (20 single draws; all
  // 40 variants, and the first 8, as the sanitizers run them) at mean - 3 standard deviations of
  // a pair (Release) or of one draw (the sanitizers). One reference image per variant and
  // realization weighs on every frame, so one draw is no guide. Pairs: recall 0.897 +- 0.010 over
  // all 40 (0.881 - 0.912), 0.921 +- 0.011 over the quiet frames; the first 8, single draws:
  // recall 0.836 +- 0.036, quiet 0.954 +- 0.029. The false points, since the slits are judged as
  // one pattern, over 6 pairs (12 single draws): 1.49 +- 0.035 % of valid (1.44 - 1.54 %), quiet
  // 1.25 +- 0.013 %; the first 8, single draws: 1.39 +- 0.11 %, quiet 0.06 +- 0.04 % (recall
  // 0.890 - 0.902 over all 40, 0.831 +- 0.024 of the first 8: as before). Bounds at mean + 3 sd.
  // Since points in no run join one group at most 2 links from a run (max_hops), 6 pairs: false
  // points 1.43 +- 0.038 % (1.375 - 1.483 %), quiet 1.19 +- 0.016 %, recall 0.892 +- 0.004,
  // quiet 0.918 +- 0.010; the sanitizers' bounds were kept.
  EXPECT_GE(quiet.found * 100, quiet.high * (kSanitized ? 86 : 88));
  EXPECT_GE(all.found * 100, all.high * (kSanitized ? 72 : 86));
  EXPECT_LE(all.false_points * 10000, all.valid * (kSanitized ? 200 : 155));
  EXPECT_LE(quiet.false_points * 10000, quiet.valid * (kSanitized ? 30 : 125));
}

// The laser off, over random photometries (textured, glossy, speckled, bright floors, 8 and 16
// bit), each frame judged with the reference its photometry gives with the laser on. Texture
// passes the profile tests where no stripe is brighter (on a high-contrast carpet most rows of a
// region hold a blob as bright and as wide as a stripe), so the cloud is not empty; what must hold
// is that nothing is made of it: no floor, hence no obstacle and no step decided on it. At the
// paper's contrast limit (0.06 of full scale) one of the 40 gave a "floor" of 78 of 164 points.
TEST(Robustness, LaserOffFramesGiveNoFloorAndNoObstacle) {
  std::size_t offered = 0, valid = 0, floors = 0;
  for (int i = 0; i < frameCount(40, 8); ++i) {
    const Photometry photometry = randomPhotometry(static_cast<std::uint64_t>(1000 + i));
    Scene bare;
    RenderConfig render = applyPhotometry(photometry, bare);
    Reference ref;
    try {
      ref = Reference::fromImage(Simulator({}, render).renderReference(bare, tableIPose(0)).image);
    } catch (const std::exception&) {
      continue;  // the other test asserts that every reference is built
    }
    render.laser_peak = 0;
    const Simulator dark({}, render);
    const Eigen::Isometry3d pose = dark.geometry().robotFromCamera(tableIPose(i % 7));
    auto cloud = pcl::make_shared<pcl::PointCloud<PointRDM>>();
    const ExtractionStats stats = Extractor(ref).extract(dark.render(bare, pose, 1).image, *cloud);
    const FloorResult floor = FloorDetector().detect(cloud);
    const ObstacleResult groups = ObstacleClusterer().cluster(cloud, floor, pose);
    offered += stats.reference_points, valid += stats.valid, floors += floor.found;
    EXPECT_FALSE(floor.found) << photometry.name << ": " << floor.inliers.size() << " of "
                              << stats.valid << " points";
    EXPECT_TRUE(groups.obstacles.empty()) << photometry.name;
  }
  std::printf("laser off: %zu valid of %zu reference points (texture), %zu floors found\n", valid,
              offered, floors);
}
