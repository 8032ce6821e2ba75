// Robust on images of many photometries (issue 13): randomized lasers, rooms, floors, speckle,
// focus, noise and bit depths at the poses of Table I, judged against the simulator's ground truth
// and against the paper's method written plainly (paper_method.h) on the same images.
#include "robustness_support.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cstdio>

using namespace multislit;
using namespace multislit::robustness;

// 40 random photometries (8 under the sanitizers), each with its own reference, of the floor,
// the ball, the cable and a screw at the seven poses of Table I; two noise realizations of each
// (one under the sanitizers).
//
// What holds today is asserted; the targets that do not (recall of >= 5 mm crossings
// 0.98 and false points 0.1 % over every photometry) are printed and left to the table of
// docs/accuracy.md.
// What limits it (the figures: docs/accuracy.md): where a cable runs nearly along a slit
// (variants 18 and 38) the sheet's thickness blends its flank with the floor, so the measured shift
// is a third of the true one; strong speckle (sigma at its 1 px bound) hides the 7 mm cable under
// the threshold; and grout lines or grain running along a stripe darken one flank of it over
// dozens of rows as an object would shift it (tiles of variant 36).
TEST(Robustness, FortyPhotometriesAgainstGroundTruthAndThePapersMethod) {
  const int variants = frameCount(40, 8), realizations = frameCount(2, 1);
  Tally all, quiet, middle, noisy;  // quiet: sigma is the paper's 0.3 px or near it
  all.frames = quiet.frames = middle.frames = noisy.frames = 0;
  for (int n = 0; n < variants * realizations; ++n) {
    const int i = n % variants, realization = n / variants;
    const Kind kind = static_cast<Kind>(i % 4);
    const Tally t = runVariant(i, kind, realization);
    EXPECT_EQ(t.reference_error, "") << "variant " << i;  // the reference is built on every one
    if (!t.reference_error.empty()) continue;
    printFrame(i, kind, t);
    // Over 12 draws of the 40: at least 0.952 of the crossings that clear the paper's contrast
    // limit measured on every variant, and at least 0.952 of the paper's valid points. The least
    // are where a stripe is lost and its stray runs are dropped (ExtractorConfig::stray_run):
    // variant 9 loses 191 points of 4161 to the rule, 14 of them within 1 px of the truth.
    EXPECT_GE(t.measured * 100, t.clear * 94) << "variant " << i;
    EXPECT_GE(t.valid * 100, t.paper_valid * 94) << "variant " << i;
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
  printSummary("all", all);
  printSummary("sigma <= 0.35 px", quiet);
  EXPECT_GE(all.measured * 1000, all.clear * 996);     // 0.9973 - 0.9974 over 6 pairs
  EXPECT_GE(all.valid * 1000, all.paper_valid * 995);  // 0.9977 - 0.9979 (pairs)
  // Points on the truth, ours over the paper's method's: 1.138 - 1.142 over 10 draws of the 40,
  // 1.249 - 1.266 of the first 8.
  EXPECT_GE(all.on_truth * 100, all.paper_on_truth * (kSanitized ? 120 : 112));
  EXPECT_LE(all.false_points * 6, all.paper_false);  // a sixth of the paper's false points or less
  // The bounds hold for any noise: measured over 6 pairs of realizations (12 single draws; all
  // 40 variants, and the first 8, as the sanitizers run them) at mean -+ 3 standard deviations of
  // a pair (Release) or of one draw (the sanitizers). One reference image per variant and
  // realization weighs on every frame, so one draw is no guide. Pairs: recall 0.849 +- 0.007,
  // quiet 0.883 +- 0.014; by a point within 2 px of the crossing 0.756 +- 0.009, quiet 0.798 +-
  // 0.013; false points 1.25 +- 0.04 % of valid, quiet 1.05 +- 0.02 %. The first 8: recall 0.794
  // +- 0.029, quiet 0.865 +- 0.046; within 2 px 0.743 +- 0.028, quiet 0.774 +- 0.030; false points
  // 1.04 +- 0.10 %, quiet 0.05 +- 0.03 %. Keeping the stray runs (ExtractorConfig::stray_run 0)
  // gives recall 0.892 +- 0.004 but within 2 px 0.762 +- 0.011, and 1.43 +- 0.04 % false points:
  // nearly every crossing they add is found by noise, not by a measure of the object.
  EXPECT_GE(quiet.found * 100, quiet.high * (kSanitized ? 72 : 84));
  EXPECT_GE(all.found * 100, all.high * (kSanitized ? 70 : 82));
  EXPECT_GE(quiet.found_on_truth * 100, quiet.high * (kSanitized ? 68 : 75));
  EXPECT_GE(all.found_on_truth * 100, all.high * (kSanitized ? 66 : 72));
  EXPECT_LE(all.false_points * 10000, all.valid * (kSanitized ? 140 : 135));
  EXPECT_LE(quiet.false_points * 10000, quiet.valid * (kSanitized ? 30 : 110));
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

// The same photometries on floors of one albedo (no grain, tiles or grout): what is left is the
// noise (speckle, shot, read), the stripe's width and blur, and the objects themselves. Where
// the noise is at most 0.7 px, the noise rule meets issue 13's target of 0.1 % false points away
// from the objects; on the textured floors of the test above, grout and grain running along a
// stripe pull it as an object would, and no frame noise rule tells the two apart.
TEST(Robustness, FortyPhotometriesOnUntexturedFloors) {
  Tally all, quiet, noisy;
  all.frames = quiet.frames = noisy.frames = 0;
  for (int i = 0; i < frameCount(40, 8); ++i) {
    const Kind kind = static_cast<Kind>(i % 4);
    const Tally t = runVariant(i, kind, 0, false);
    EXPECT_EQ(t.reference_error, "") << "variant " << i;
    if (!t.reference_error.empty()) continue;
    printFrame(i, kind, t);
    all.add(t);
    (t.sigma <= 0.7 ? quiet : noisy).add(t);
  }
  printRow("untextured floors", all);
  printSummary("untextured, all", all);
  printSummary("untextured, sigma <= 0.7 px", quiet);
  printSummary("untextured, sigma > 0.7 px", noisy);
  // Over 12 draws of the 40 (and of the first 8, as the sanitizers run them), frames of sigma
  // <= 0.7 px: false points away from the objects 0.04 +- 0.01 % of valid (first 8: 0.04 +- 0.03
  // %), all false points 0.22 +- 0.01 % (the rest lit within 15 mm of an object); recall of >= 5
  // mm crossings 0.899 +- 0.009 (first 8: 0.931 +- 0.011), by a point within 2 px of the crossing
  // 0.824 +- 0.006 (first 8: 0.886 +- 0.009). All frames: 0.34 +- 0.03 % false points, recall
  // 0.852 +- 0.012. Bounds at mean -+ 3 sd.
  EXPECT_LE((quiet.false_points - quiet.false_near) * 10000, quiet.valid * (kSanitized ? 15 : 10));
  EXPECT_GE(quiet.found * 100, quiet.high * (kSanitized ? 89 : 87));
  EXPECT_GE(quiet.found_on_truth * 100, quiet.high * (kSanitized ? 85 : 80));
  if (!kSanitized) {
    EXPECT_LE(all.false_points * 10000, all.valid * 44);
  }
}
