// Building the reference on images of photometries the project was not tuned on (issue 13),
// judged against the simulator's ground truth: the slits' robust fit, and references taken at
// several spots of a textured floor.
#include "extraction_errors.h"
#include "multislit/reference.h"
#include "multislit/sim/photometry.h"
#include "multislit/sim/scenarios.h"
#include "multislit/sim/simulator.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

using namespace multislit;

namespace {

struct ReferenceErrors {
  std::vector<double> all;  // |reference u - true u| of every reference row with a crossing [px]
  double worst_slit = 0;    // the largest of them [px]
  std::size_t beyond(double limit) const {
    std::size_t n = 0;
    for (const double e : all) n += e > limit;
    return n;
  }
};

void printErrors(const char* what, const ReferenceErrors& e) {
  std::printf("%s: reference error median %.3f p99 %.3f worst %.2f px over %zu rows\n", what,
              quantile(e.all, 0.5), quantile(e.all, 0.99), e.worst_slit, e.all.size());
}

ReferenceErrors errorsOf(const Reference& ref, const std::vector<SlitCrossing>& truth) {
  ReferenceErrors out;
  for (const SlitCrossing& t : truth) {
    const ReferenceSlit& slit = ref.slits[static_cast<std::size_t>(t.slit)];
    if (t.row < slit.first_row || t.row > slit.lastRow()) continue;
    const double e = std::abs(slit.u[static_cast<std::size_t>(t.row - slit.first_row)] - t.u);
    if (!std::isfinite(e)) continue;
    out.all.push_back(e);
    out.worst_slit = std::max(out.worst_slit, e);
  }
  return out;
}

// `count` images of the bare floor at the reference pose, the robot moved by (37, 23) mm between
// them (each sees another part of the floor's texture), and the truth of the first.
std::vector<cv::Mat> floorImages(int variant, int count, std::vector<SlitCrossing>* truth) {
  Scene bare;
  const RenderConfig render =
      applyPhotometry(randomPhotometry(static_cast<std::uint64_t>(1000 + variant)), bare);
  const Simulator sim(SensorConfig{}, render);
  const Eigen::Isometry3d pose = sim.geometry().robotFromCamera(tableIPose(0));
  std::vector<cv::Mat> images;
  for (int k = 0; k < count; ++k) {
    Eigen::Isometry3d world = Eigen::Isometry3d::Identity();
    world.translation() = Eigen::Vector3d(0.037 * k, 0.023 * k, 0);
    RenderedFrame f = sim.render(bare, world * pose, 100 + static_cast<std::uint64_t>(k));
    if (k == 0) *truth = f.truth;
    images.push_back(f.image);
  }
  return images;
}

}  // namespace

// Variant 32 of the robustness test (a bright room, a dim laser, a wood floor): tracks of seven
// slits carried a piece of something else at one end, and the least-squares polynomial that
// started from all of a track's centres bent the whole slit by up to 68 px. The fit now starts
// from a parabola through the middle half of the centres and keeps those near each fit.
TEST(ReferenceBuild, AStrayPieceAtASlitsEndDoesNotBendTheSlit) {
  std::vector<SlitCrossing> truth;
  const Reference ref = Reference::fromImage(floorImages(32, 1, &truth)[0]);
  const ReferenceErrors e = errorsOf(ref, truth);
  printErrors("variant 32", e);
  EXPECT_GT(e.all.size(), 4000u);
  EXPECT_LT(e.worst_slit, 1.5);
  EXPECT_LT(quantile(e.all, 0.99), 0.5);
}

// A grout line running along a stripe moves its centre by pixels over a hundred rows or more, and
// that slit's own polynomial follows it; the other slits of the pattern show where it lies
// (slit_pattern.h). Judged over the nine tiled floors of the 40 random photometries whose speckle
// is under 0.3 (one image each, at the reference pose; only variants 15 and 36 under the
// sanitizers): at most 1 % of the rows more than 0.5 px off (3 % under the sanitizers), the 99th
// percentile of the error under 0.5 px.
TEST(ReferenceBuild, AStretchPulledAlongAGroutLineIsHeldByTheOtherSlits) {
  std::size_t beyond = 0, rows = 0;
  std::vector<double> all;
  for (const int variant : {9, 10, 15, 26, 28, 31, 34, 36, 38}) {
    if (kSanitized && variant != 36 && variant != 15) continue;
    std::vector<SlitCrossing> truth;
    const ReferenceErrors e =
        errorsOf(Reference::fromImage(floorImages(variant, 1, &truth)[0]), truth);
    std::printf("variant %d: rows beyond 0.5 px %zu of %zu, p99 %.3f px\n", variant, e.beyond(0.5),
                e.all.size(), quantile(e.all, 0.99));
    beyond += e.beyond(0.5), rows += e.all.size();
    all.insert(all.end(), e.all.begin(), e.all.end());
    if (variant == 36) {
      EXPECT_EQ(e.beyond(0.5), 0u);
    }
  }
  std::printf("tiles: rows beyond 0.5 px %zu of %zu, p99 %.3f px\n", beyond, rows,
              quantile(all, 0.99));
  EXPECT_LE(beyond * 100, rows * (kSanitized ? 3 : 1));
  if (!kSanitized) {
    EXPECT_LT(quantile(all, 0.99), 0.5);
  }
}

// A grout line or grain running along a stripe moves its centre over dozens of rows, and one
// reference image carries what the pattern does not hold into every frame measured with it. Five
// references at other spots of the floor average the texture out: measured, the rows more than
// 0.5 px off fall from 151 to 72 (variant 15, tiles) and 1229 to none (0, tiles under strong
// speckle); on variant 36 (tiles) none is off with one image or five. Before the pattern judged
// the slits: 308 to 85, 1341 to 66 and 206 to 3.
TEST(ReferenceBuild, ReferencesAtSeveralSpotsOfATexturedFloorAverageItOut) {
  for (const int variant : {15, 36, 0}) {
    if (kSanitized && variant != 36) continue;
    std::vector<SlitCrossing> truth;
    const std::vector<cv::Mat> images = floorImages(variant, 5, &truth);
    const ReferenceErrors one = errorsOf(Reference::fromImage(images[0]), truth);
    const ReferenceErrors five = errorsOf(Reference::fromImages(images), truth);
    std::printf("variant %d: rows beyond 0.5 px %zu of %zu from one image, %zu of %zu from five\n",
                variant, one.beyond(0.5), one.all.size(), five.beyond(0.5), five.all.size());
    EXPECT_LE(five.beyond(0.5) * 2, one.beyond(0.5)) << "variant " << variant;
    EXPECT_GE(five.all.size() * 100, one.all.size() * 99) << "variant " << variant;
  }
}

// Variant 32 (a wood floor in a bright room): one image calibrated, but the 16-bit mean of five
// was refused ("found 18 slits ... along the pattern's course"). Averaged, the grain's ridges run
// on unbroken, and a ridge above the pattern was joined to a slit 290 rows below: the parabola of
// the pattern's curvature through both ends fitted the slit's end and crossed the ridge, and the
// median over both ends called that one course. Each end must now lie on the joint course.
TEST(ReferenceBuild, TheMeanOfFiveImagesOfAGrainedFloorIsNotJoinedToItsGrain) {
  std::vector<SlitCrossing> truth;
  const std::vector<cv::Mat> images = floorImages(32, 5, &truth);
  Reference ref;
  ASSERT_NO_THROW(ref = Reference::fromImages(images));
  const ReferenceErrors e = errorsOf(ref, truth);
  printErrors("variant 32, five images", e);
  EXPECT_GT(e.all.size(), 4000u);
  EXPECT_LT(e.worst_slit, 1.0);
  EXPECT_LT(quantile(e.all, 0.99), 0.3);
}

// The dark-floor preset (albedo 0.25, a dim laser, 8 bits): the stripes of the two lowest slits
// stand 4 to 8 times the pixel noise above the floor, under the first contrast limit (8 times it).
// Where that limit finds fewer slits than the projector casts, the second (4 times it) finds all
// 15 from one image, and they lie on the truth.
TEST(ReferenceBuild, DimSlitsOnADarkFloorAreFoundFromOneImage) {
  Scene bare;
  const RenderConfig render = applyPhotometry(photometryPreset("dark-floor"), bare);
  const Simulator sim(SensorConfig{}, render);
  const RenderedFrame f = sim.renderReference(bare, tableIPose(0));
  Reference ref;
  ASSERT_NO_THROW(ref = Reference::fromImage(f.image));
  const ReferenceErrors e = errorsOf(ref, f.truth);
  printErrors("dark-floor, one image", e);
  EXPECT_EQ(ref.slits.size(), 15u);
  EXPECT_GT(e.all.size(), f.truth.size() * 98 / 100);
  EXPECT_LT(quantile(e.all, 0.99), 0.3);
  EXPECT_LT(e.worst_slit, 1.0);
}
