// The RDMap synthesizer against the real thing: the same frame rendered and extracted.
#include "multislit/sim/rdmap_synth.h"
#include "default_reference.h"
#include "multislit/extractor.h"
#include "multislit/floor_detector.h"
#include "multislit/sim/scenarios.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

using namespace multislit;

namespace {

const Reference& reference() { return test::defaultReference(); }

struct Comparison {
  std::size_t extracted = 0, synthesized = 0, both = 0;
  std::size_t cut = 0;   // points whose dk differs by more than kCut
  double dk_rms = 0.0;   // [px] over the others
  double xyz_rms = 0.0;  // [m]
};

// The extractor measures profiles cut by an object's silhouette too (narrow, their centre pulled
// by px), which the synthesizer places exactly: those are counted, not averaged into the rms.
constexpr double kCut = 2.0;  // [px]

Comparison compare(const pcl::PointCloud<PointRDM>& a, const pcl::PointCloud<PointRDM>& b) {
  Comparison c;
  double dk = 0, xyz = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const bool in_a = std::isfinite(a[i].dk), in_b = std::isfinite(b[i].dk);
    c.extracted += in_a;
    c.synthesized += in_b;
    if (!in_a || !in_b) continue;
    ++c.both;
    if (std::abs(a[i].dk - b[i].dk) > kCut) {
      ++c.cut;
      continue;
    }
    dk += std::pow(a[i].dk - b[i].dk, 2);
    xyz += (a[i].getVector3fMap() - b[i].getVector3fMap()).squaredNorm();
  }
  c.dk_rms = std::sqrt(dk / static_cast<double>(c.both));
  c.xyz_rms = std::sqrt(xyz / static_cast<double>(c.both));
  return c;
}

}  // namespace

TEST(RDMapSynthesizer, MatchesTheExtractorOnRenderedFrames) {
  const Simulator simulator{SensorConfig{}};
  const Extractor extractor(reference());
  const RDMapSynthesizer synth(SensorConfig{}, reference());
  for (const char* name : {"floor", "ball"}) {
    const Scenario s = makeScenario(name);
    const Eigen::Isometry3d pose = simulator.geometry().robotFromCamera(s.mount);
    const auto extracted = extractor.extract(simulator.render(s.scene, pose, 3).image, 0, 3);
    const auto synthesized = synth.synthesize(s.scene, pose, 3);
    ASSERT_EQ(extracted->width, synthesized->width);
    ASSERT_EQ(extracted->height, synthesized->height);
    const Comparison c = compare(*extracted, *synthesized);
    // The same points are measured; dk differs by two independent noises of ~0.08 px.
    EXPECT_GE(static_cast<double>(c.both), 0.99 * static_cast<double>(c.extracted)) << name;
    EXPECT_GE(static_cast<double>(c.both), 0.99 * static_cast<double>(c.synthesized)) << name;
    EXPECT_LT(c.dk_rms, 0.25) << name;
    EXPECT_LE(c.cut * 200, c.both) << name;  // at most 0.5 %
    EXPECT_LT(c.xyz_rms, 0.0015) << name;
    const FloorDetector detector;
    const FloorResult fe = detector.detect(extracted), fs = detector.detect(synthesized);
    EXPECT_NEAR(fs.residual_std, fe.residual_std, 0.03) << name;
    EXPECT_NEAR(static_cast<double>(fs.obstacles.size()), static_cast<double>(fe.obstacles.size()),
                0.2 * static_cast<double>(fe.obstacles.size()) + 2)
        << name;
    std::printf(
        "%s: %zu extracted, %zu synthesized, dk rms difference %.3f px (%zu cut profiles), xyz "
        "%.2f mm\n",
        name, c.extracted, c.synthesized, c.dk_rms, c.cut, 1e3 * c.xyz_rms);
  }
}

TEST(RDMapSynthesizer, NoiseIsSeededAndHasTheConfiguredSigma) {
  RDMapSynthesizerConfig config;
  config.noise_sigma = 0.3;
  const RDMapSynthesizer synth(SensorConfig{}, reference(), config);
  const Scenario s = makeScenario("floor");
  const Eigen::Isometry3d pose = synth.simulator().geometry().robotFromCamera(s.mount);
  const auto a = synth.synthesize(s.scene, pose, 7), b = synth.synthesize(s.scene, pose, 7);
  const auto c = synth.synthesize(s.scene, pose, 8);
  EXPECT_EQ(compare(*a, *b).dk_rms, 0.0);
  // Two frames' noises differ by sqrt(2) sigma.
  EXPECT_NEAR(compare(*a, *c).dk_rms, std::sqrt(2.0) * 0.3, 0.03);
  EXPECT_EQ(a->header.seq, 7u);
  EXPECT_FALSE(a->is_dense);
}

TEST(RDMapSynthesizer, ConfigErrorsNameTheField) {
  RDMapSynthesizerConfig config;
  config.noise_sigma = -1;
  try {
    config.validate();
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("noise_sigma"), std::string::npos);
  }
  config = {};
  config.dropout = 1.0;
  EXPECT_THROW(config.validate(), std::invalid_argument);
}
