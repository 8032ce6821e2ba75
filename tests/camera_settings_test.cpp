// What a camera is set to: pixel format Mono12, exposure and gain (refused with the camera's
// range when out of it), and the time base of its stamps: a PTP clock on TAI, 37 s ahead of UTC,
// brought to UTC by AravisConfig::ptp_utc_offset_s. On the emulated camera on 127.0.0.1.
#include "camera_test_support.h"
#include "multislit/sources.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <cmath>
#include <string>
#include <vector>

namespace multislit {
namespace {

using namespace test;
using std::chrono::milliseconds;

constexpr int kWidth = 160, kHeight = 120;

std::vector<cv::Mat> rampImages(int type) {
  std::vector<cv::Mat> images;
  for (int i = 0; i < 3; ++i) {
    cv::Mat image(kHeight, kWidth, type);
    cv::RNG rng(11 + i);
    rng.fill(image, cv::RNG::UNIFORM, 0, type == CV_8UC1 ? 256 : 65536);
    images.push_back(image);
  }
  return images;
}

AravisConfig cameraConfig(PixelFormat format) {
  AravisConfig c;
  c.camera = CameraEmulator::kAddress;
  c.roi_width = kWidth;
  c.roi_height = kHeight;
  c.frame_rate = 30;
  c.pixel_format = format;
  return c;
}

/// The first frames of `config`'s camera (at most `count`, within the deadline).
std::vector<Frame> takeFrames(const AravisConfig& config, int count) {
  AravisSource source(config);
  source.start();
  std::vector<Frame> frames;
  const auto t0 = Clock::now();
  while (static_cast<int>(frames.size()) < count && msSince(t0) < kDeadlineMs)
    if (std::optional<Frame> frame = source.next(milliseconds(200))) frames.push_back(*frame);
  source.stop();
  return frames;
}

/// The message start() throws for `config`, "" when it starts.
std::string startError(const AravisConfig& config) {
  AravisSource source(config);
  try {
    source.start();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// Mono12 comes as 16-bit images of values 0..4095: the served 16-bit images scaled to 12 bits.
TEST(CameraSettings, Mono12ComesAsTwelveBitValuesInSixteen) {
  const std::vector<cv::Mat> images = rampImages(CV_16UC1);
  const auto emulator = makeEmulator(images);
  REQUIRE_EMULATOR(emulator);
  const std::vector<Frame> frames = takeFrames(cameraConfig(PixelFormat::Mono12), 4);
  ASSERT_EQ(frames.size(), 4u);
  for (const Frame& frame : frames) {
    ASSERT_EQ(frame.image.type(), CV_16UC1);
    cv::Mat expected;
    images[emulator->imageIndex(frame.seq)].convertTo(expected, CV_16U, 4095.0 / 65535.0);
    EXPECT_EQ(cv::countNonZero(frame.image != expected), 0) << "frame " << frame.seq;
    double max = 0;
    cv::minMaxLoc(frame.image, nullptr, &max);
    EXPECT_LE(max, 4095.0);
    EXPECT_GE(max, 4000.0);  // uniform noise reaches near the white of 12 bits
  }
}

// Exposure and gain within the camera's range are taken; beyond it, start() names the feature,
// the range and the config field.
TEST(CameraSettings, ExposureAndGainInRangeTakenOutOfRangeRefused) {
  const auto emulator = makeEmulator(rampImages(CV_8UC1));
  REQUIRE_EMULATOR(emulator);
  AravisConfig config = cameraConfig(PixelFormat::Mono8);
  config.exposure_us = 500;
  config.gain_db = 3;
  EXPECT_EQ(takeFrames(config, 2).size(), 2u);

  config.exposure_us = 5;  // Aravis's fake camera takes 10 us to 10 s
  const std::string exposure = startError(config);
  EXPECT_NE(exposure.find("ExposureTime"), std::string::npos) << exposure;
  EXPECT_NE(exposure.find("from 10 to 1e+07 us"), std::string::npos) << exposure;
  EXPECT_NE(exposure.find("AravisConfig.exposure_us 5 us"), std::string::npos) << exposure;

  config.exposure_us = 500;
  config.gain_db = 50;  // its GainRaw goes from 0 to 10
  const std::string gain = startError(config);
  EXPECT_NE(gain.find("from 0 to 10 dB"), std::string::npos) << gain;
  EXPECT_NE(gain.find("AravisConfig.gain_db 50"), std::string::npos) << gain;
}

// A camera whose PTP clock runs on TAI, 37 s ahead of UTC: with the default offset the stamps
// are the host's UTC within the frame's way to the host; taken as UTC (offset 0) they are 37 s
// ahead, what breaks every odometry and TF lookup.
TEST(CameraSettings, PtpClockOnTaiGivesUtcStamps) {
  EmulatorConfig ec;
  ec.ptp = true;
  ec.clock_offset_s = kTaiUtcOffsetS;
  const auto emulator = makeEmulator(rampImages(CV_8UC1), ec);
  REQUIRE_EMULATOR(emulator);
  AravisConfig config = cameraConfig(PixelFormat::Mono8);
  EXPECT_EQ(config.ptp_utc_offset_s, 37.0);  // the documented default
  for (const double offset : {37.0, 0.0}) {
    config.ptp_utc_offset_s = offset;
    const std::uint64_t before = nowMicros();
    const std::vector<Frame> frames = takeFrames(config, 5);
    const std::uint64_t after = nowMicros();
    ASSERT_EQ(frames.size(), 5u);
    for (const Frame& frame : frames) {
      EXPECT_EQ(frame.stamp_source, StampSource::Camera);
      const double utc_s = (static_cast<double>(frame.stamp_us) - 1e6 * (37.0 - offset)) / 1e6;
      // Taken between start() and the last frame, on the host's UTC clock.
      EXPECT_GE(utc_s, static_cast<double>(before) / 1e6 - 0.5) << "offset " << offset;
      EXPECT_LE(utc_s, static_cast<double>(after) / 1e6 + 0.5) << "offset " << offset;
      // The camera's own stamp stays on its own clock (TAI).
      EXPECT_NEAR(static_cast<double>(frame.camera_stamp_ns) / 1e9,
                  static_cast<double>(frame.stamp_us) / 1e6 + offset, 1e-5);
    }
  }
}

// Without PTP the camera clock is not the epoch's: the host's clock, no offset applied.
TEST(CameraSettings, NoPtpHostClockUntouched) {
  EmulatorConfig ec;
  ec.clock_offset_s = kTaiUtcOffsetS;
  const auto emulator = makeEmulator(rampImages(CV_8UC1), ec);
  REQUIRE_EMULATOR(emulator);
  const std::uint64_t before = nowMicros();
  const std::vector<Frame> frames = takeFrames(cameraConfig(PixelFormat::Mono8), 3);
  ASSERT_EQ(frames.size(), 3u);
  for (const Frame& frame : frames) {
    EXPECT_EQ(frame.stamp_source, StampSource::Host);
    EXPECT_GE(frame.stamp_us, before);
    EXPECT_LE(frame.stamp_us, nowMicros());
  }
}

TEST(CameraSettings, PixelFormatNamesAndOffsetRange) {
  EXPECT_EQ(parsePixelFormat("Mono12"), PixelFormat::Mono12);
  EXPECT_STREQ(pixelFormatName(PixelFormat::Mono16), "Mono16");
  EXPECT_FALSE(parsePixelFormat("mono12"));
  AravisConfig config;
  config.ptp_utc_offset_s = 1e6;
  EXPECT_THROW(config.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace multislit
