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
  printSummary("all", all);
  printSummary("sigma <= 0.35 px", quiet);
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
  // Over 6 draws of the 40 (10 of the first 8, as the sanitizers run them), frames of sigma
  // <= 0.7 px: false points away from the objects 0.036 +- 0.009 % of valid (first 8: 0.039 +-
  // 0.030 %), all false points 0.215 +- 0.008 % (the rest lit within 15 mm of an object); recall
  // of >= 5 mm crossings 0.924 +- 0.009 (first 8: 0.976 +- 0.009), the paper's method 0.909 +-
  // 0.008 with 5.5 % false points. All frames: 0.347 +- 0.024 % false points, recall 0.895 +-
  // 0.010.
  EXPECT_LE((quiet.false_points - quiet.false_near) * 10000, quiet.valid * (kSanitized ? 15 : 10));
  EXPECT_GE(quiet.found * 100, quiet.high * (kSanitized ? 95 : 89));
  if (!kSanitized) {
    EXPECT_LE(all.false_points * 10000, all.valid * 42);
  }
}
