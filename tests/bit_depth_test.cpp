// Bit depths: 16-bit images measure as 8-bit ones, and 12-bit data in 16-bit images (values up
// to 4095) measures with its full scale, which the calibration keeps.
#include "batched_profiles.h"
#include "extraction_errors.h"
#include "multislit/extractor.h"
#include "multislit/sim/scenarios.h"
#include "multislit/sim/simulator.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <filesystem>
#include <string>

using namespace multislit;

namespace {

RenderedFrame renderScenario(const Scenario& s, uint64_t frame, const Simulator& sim) {
  return sim.render(s.scene, s.worldFromRobot(frame) * sim.geometry().robotFromCamera(s.mount),
                    frame);
}

const Simulator& simulator16() {
  static const Simulator sim = [] {
    RenderConfig rc;
    rc.bit_depth = 16;
    return Simulator{SensorConfig{}, rc};
  }();
  return sim;
}

cv::Mat referenceImage16() {
  const Scenario s = makeScenario("reference");
  const Simulator& sim = simulator16();
  return sim.render(s.scene, sim.geometry().robotFromCamera(s.reference_mount), 1000).image;
}

// 98 % of the crossings measured, sub-pixel error median <= 0.1 px, 95 % <= 0.3 px.
void expectMeasuredAsTheTruth(const Extractor& ex, const cv::Mat& image,
                              const std::vector<SlitCrossing>& truth) {
  pcl::PointCloud<PointRDM> cloud;
  ex.extract(image, cloud);
  const Errors e = compare(cloud, truth);
  EXPECT_GE(static_cast<double>(e.subpixel.size()), 0.98 * static_cast<double>(e.truth));
  EXPECT_LE(quantile(e.subpixel, 0.5), 0.1);
  EXPECT_LE(quantile(e.subpixel, 0.95), 0.3);
}

}  // namespace

// 16-bit profiles, eight at a time in float lanes where the CPU has AVX2 and FMA, against the
// measure one by one in double: floats hold every 16-bit pixel exactly, and the same profiles are
// found and placed within float rounding, at the extractor's window and wider ones.
TEST(Extractor, SixteenBitBatchedProfilesMatchTheScalarMeasure) {
  const Reference ref = Reference::fromImage(referenceImage16());
  ProfileParams p = Extractor(ref).profileParams(CV_16U);
  BatchedAgreement agreement;
  const Simulator& sim16 = simulator16();
  const RenderedFrame frames[] = {renderScenario(makeScenario("cond3"), 4, sim16),
                                  renderScenario(makeScenario("cable"), 60, sim16)};
  for (const int half_window : {p.half_window, 13, 20})
    for (const RenderedFrame& f : frames) {
      ASSERT_EQ(f.image.type(), CV_16UC1);
      p.half_window = half_window;
      addBatchedAgreement<std::uint16_t>(ref, f.image, p, agreement);
    }
  expectBatchedAgreement(agreement);
}

TEST(Extractor, SixteenBitImagesMeasureAsWell) {
  const Simulator& sim16 = simulator16();
  const Extractor ex(Reference::fromImage(referenceImage16()));
  const RenderedFrame f = renderScenario(makeScenario("cond4"), 9, sim16);
  expectMeasuredAsTheTruth(ex, f.image, f.truth);
}

// 12-bit data in 16-bit images (values up to 4095): without the full scale the stripes are under
// any share of 65535 and calibration says so; with --full-scale 4095 they measure as 16-bit ones.
TEST(Extractor, TwelveBitDataMeasuresWithItsFullScale) {
  const auto twelve = [](const cv::Mat& image) {
    cv::Mat out;
    image.convertTo(out, CV_16U, 1.0 / 16.0);
    return out;
  };
  const cv::Mat ref_image = twelve(referenceImage16());
  try {
    Reference::fromImage(ref_image);
    FAIL() << "12-bit data calibrated as 16-bit";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("--full-scale 4095"), std::string::npos) << e.what();
  }
  ReferenceConfig config;
  config.full_scale = 4095;
  const Reference ref = Reference::fromImage(ref_image, config);
  EXPECT_EQ(ref.full_scale, 4095);
  const Extractor ex(ref);
  const RenderedFrame f = renderScenario(makeScenario("cond4"), 9, simulator16());
  expectMeasuredAsTheTruth(ex, twelve(f.image), f.truth);
  // The full scale goes through the calibration file.
  const std::string path = tempPath("multislit_twelve_bit.yaml");
  ref.save(path);
  EXPECT_EQ(Reference::load(path).full_scale, 4095);
  std::filesystem::remove(path);
}
