// Frame sources: recorded images (time stamps, pacing, stepping), the simulator, and a GigE
// Vision camera through Aravis, served on 127.0.0.1 by CameraEmulator (never discovered).
#include "multislit/sources.h"
#include "camera_test_support.h"
#include "multislit/sim/simulated_source.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <thread>

namespace multislit {
namespace {

namespace fs = std::filesystem;
using namespace test;
using std::chrono::milliseconds;

fs::path freshFolder(const std::string& name) {
  const fs::path dir = tempPath("multislit_sources_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<cv::Mat> noiseImages(int count, int width, int height, int type) {
  std::vector<cv::Mat> images;
  cv::RNG rng(7);
  for (int i = 0; i < count; ++i) {
    cv::Mat image(height, width, type);
    rng.fill(image, cv::RNG::UNIFORM, 0, type == CV_8UC1 ? 256 : 65536);
    images.push_back(image);
  }
  return images;
}

bool identical(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() &&
         cv::countNonZero(a.reshape(1) != b.reshape(1)) == 0;
}

AravisConfig cameraConfig(const cv::Mat& image, double fps) {
  AravisConfig c;
  c.camera = CameraEmulator::kAddress;
  c.roi_width = image.cols;
  c.roi_height = image.rows;
  c.frame_rate = fps;
  c.pixel_format = image.depth() == CV_8U ? PixelFormat::Mono8 : PixelFormat::Mono16;
  return c;
}

// --- time stamps in file names ---------------------------------------------------------------

TEST(StampFromFileName, ParsesPclImageGrabberNames) {
  // 2026-11-23T12:00:00Z is 1795435200 s after the epoch.
  EXPECT_EQ(stampFromFileName("frame_20261123T120000.123456.png"), 1795435200123456ULL);
  EXPECT_EQ(stampFromFileName("/data/run/frame_20261123T120000.5.png"), 1795435200500000ULL);
  EXPECT_EQ(stampFromFileName("20261123T120000.png"), 1795435200000000ULL);
  // A leap day: 2000-02-29T23:59:59Z is 951868799 s.
  EXPECT_EQ(stampFromFileName("rgb_20000229T235959.000001.png"), 951868799000001ULL);
  EXPECT_FALSE(stampFromFileName("frame_000012.png"));
  EXPECT_FALSE(stampFromFileName("frame_20261323T120000.png"));  // month 13
}

// --- recorded images -------------------------------------------------------------------------

TEST(ImageSequenceSource, TakesStampsFromFileNames) {
  const fs::path dir = freshFolder("names");
  const std::vector<std::string> names = {"frame_20261123T120000.000000.png",
                                          "frame_20261123T120000.033333.png",
                                          "frame_20261123T120000.066667.png"};
  const std::vector<cv::Mat> images = noiseImages(3, 64, 48, CV_8UC1);
  for (std::size_t i = 0; i < names.size(); ++i)
    ASSERT_TRUE(cv::imwrite((dir / names[i]).string(), images[i]));
  ImageSequenceConfig config;
  config.folder = dir.string();
  ImageSequenceSource source(config);
  source.start();
  for (std::size_t i = 0; i < names.size(); ++i) {
    const std::optional<Frame> frame = source.next(milliseconds(100));
    ASSERT_TRUE(frame);
    EXPECT_EQ(frame->stamp_us, *stampFromFileName(names[i]));
    EXPECT_EQ(frame->seq, i);
    EXPECT_TRUE(identical(frame->image, images[i]));
  }
  EXPECT_FALSE(source.next(milliseconds(10)));
  EXPECT_TRUE(source.finished());
  EXPECT_EQ(source.stats().frames, 3u);
  EXPECT_FALSE(source.live());
}

TEST(ImageSequenceSource, ReadsFramesCsvOfSimulate) {
  // The layout `multislit simulate` writes: frames.csv names the files and their stamps.
  const fs::path dir = freshFolder("csv");
  const std::vector<cv::Mat> images = noiseImages(3, 64, 48, CV_16UC1);
  ASSERT_TRUE(cv::imwrite((dir / "reference.png").string(), images[0]));
  std::ofstream csv(dir / "frames.csv");
  csv << "frame,file,stamp_us,robot_x\n";
  for (int i = 0; i < 3; ++i) {
    const std::string name = "frame_00000" + std::to_string(i) + ".png";
    ASSERT_TRUE(cv::imwrite((dir / name).string(), images[static_cast<std::size_t>(i)]));
    csv << i << ',' << name << ',' << 1700000000000000 + 33333 * i << ",0\n";
  }
  csv.close();
  ImageSequenceConfig config;
  config.folder = dir.string();
  ImageSequenceSource source(config);
  source.start();
  ASSERT_EQ(source.files().size(), 3u);  // not reference.png
  for (int i = 0; i < 3; ++i) {
    const std::optional<Frame> frame = source.next(milliseconds(100));
    ASSERT_TRUE(frame);
    EXPECT_EQ(frame->stamp_us, static_cast<std::uint64_t>(1700000000000000 + 33333 * i));
    EXPECT_EQ(frame->image.type(), CV_16UC1);
    EXPECT_TRUE(identical(frame->image, images[static_cast<std::size_t>(i)]));
  }
}

TEST(ImageSequenceSource, SyntheticStampsRepeatAndReadErrors) {
  const fs::path dir = freshFolder("synthetic");
  const std::vector<cv::Mat> images = noiseImages(2, 32, 24, CV_8UC1);
  ASSERT_TRUE(cv::imwrite((dir / "a.png").string(), images[0]));
  ASSERT_TRUE(cv::imwrite((dir / "b.png").string(), images[1]));
  std::ofstream(dir / "c.png") << "not a png";
  ImageSequenceConfig config;
  config.folder = dir.string();
  config.repeat = true;
  config.stamp_rate = 10.0;
  ImageSequenceSource source(config);
  const std::uint64_t before = nowMicros();
  source.start();
  std::vector<Frame> frames;
  for (int call = 0; call < 6; ++call)
    if (std::optional<Frame> f = source.next(milliseconds(100))) frames.push_back(*f);
  ASSERT_EQ(frames.size(), 4u);  // a b (c fails) a b
  EXPECT_EQ(source.stats().read_errors, 2u);
  EXPECT_GE(frames[0].stamp_us, before);
  EXPECT_LE(frames[0].stamp_us, nowMicros());
  EXPECT_EQ(frames[1].stamp_us - frames[0].stamp_us, 100000u);  // 1 / stamp_rate
  for (std::size_t i = 1; i < frames.size(); ++i) {
    EXPECT_GT(frames[i].stamp_us, frames[i - 1].stamp_us);  // later loops go on in time
    EXPECT_GT(frames[i].seq, frames[i - 1].seq);
  }
  EXPECT_TRUE(identical(frames[2].image, images[0]));
  EXPECT_FALSE(source.finished());
}

TEST(ImageSequenceSource, PacedTriggeredAndInterrupted) {
  const fs::path dir = freshFolder("paced");
  const std::vector<cv::Mat> images = noiseImages(4, 32, 24, CV_8UC1);
  std::vector<std::string> files;
  for (int i = 0; i < 4; ++i) {
    files.push_back((dir / ("f" + std::to_string(i) + ".png")).string());
    ASSERT_TRUE(cv::imwrite(files.back(), images[static_cast<std::size_t>(i)]));
  }
  {  // 20 Hz: four frames take 150 ms from the first.
    ImageSequenceConfig config;
    config.files = files;
    config.fps = 20.0;
    ImageSequenceSource source(config);
    EXPECT_TRUE(source.live());
    source.start();
    const auto t0 = Clock::now();
    int got = 0;
    while (got < 4 && msSince(t0) < kDeadlineMs) got += source.next(milliseconds(50)).has_value();
    EXPECT_EQ(got, 4);
    EXPECT_GE(msSince(t0), 140.0);
  }
  {  // Triggered: nothing without trigger(), one frame per trigger().
    ImageSequenceConfig config;
    config.files = files;
    config.triggered = true;
    ImageSequenceSource source(config);
    source.start();
    EXPECT_FALSE(source.next(milliseconds(50)));
    source.trigger();
    const std::optional<Frame> frame = source.next(milliseconds(50));
    ASSERT_TRUE(frame);
    EXPECT_EQ(frame->seq, 0u);
    EXPECT_FALSE(source.next(milliseconds(50)));
  }
  {  // interrupt() ends a long wait: next() returns long before its timeout or the next frame.
    ImageSequenceConfig config;
    config.files = files;
    config.fps = 0.02;
    ImageSequenceSource source(config);
    source.start();
    ASSERT_TRUE(source.next(milliseconds(100)));  // the first is due at once, the next in 50 s
    std::thread interrupter([&] {
      std::this_thread::sleep_for(milliseconds(100));
      source.interrupt();
    });
    const auto t0 = Clock::now();
    EXPECT_FALSE(source.next(milliseconds(40000)));
    EXPECT_LT(msSince(t0), 20000.0);
    interrupter.join();
  }
}

TEST(ImageSequenceSource, MissingFolderThrowsAtStart) {
  ImageSequenceConfig config;
  config.folder = "/nonexistent/multislit";
  ImageSequenceSource source(config);
  EXPECT_THROW(source.start(), std::runtime_error);
  EXPECT_THROW(ImageSequenceSource{ImageSequenceConfig{}}, std::invalid_argument);
}

// --- the simulator ---------------------------------------------------------------------------

TEST(SimulatorSource, RendersTheWalkFrameByFrame) {
  SimulatorSourceConfig config;
  config.scenario = "ball";
  config.render.supersample = 1;  // fast
  config.first_frame = 3;
  config.frames = 2;
  SimulatorSource source(config);
  source.start();
  const std::optional<Frame> frame = source.next(milliseconds(100));
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->seq, 3u);
  const Scenario& s = source.scenario();
  const cv::Mat expected =
      source.simulator()
          .render(s.scene,
                  s.worldFromRobot(3) * source.simulator().geometry().robotFromCamera(s.mount), 3)
          .image;
  EXPECT_TRUE(identical(frame->image, expected));
  EXPECT_TRUE(source.next(milliseconds(100)));
  EXPECT_TRUE(source.finished());
  EXPECT_FALSE(source.next(milliseconds(100)));
  EXPECT_EQ(source.stats().frames, 2u);

  const Reference reference = source.makeReference();
  EXPECT_EQ(reference.slits.size(), 15u);
  EXPECT_TRUE(reference.scale.valid());
  EXPECT_NO_THROW(reference.checkImage(frame->image, "frame"));
}

// --- a GigE Vision camera on 127.0.0.1 -------------------------------------------------------

void expectServedImages(int type) {
  const std::vector<cv::Mat> images = noiseImages(4, 320, 240, type);
  EmulatorConfig ec;
  ec.fps = 60;
  const std::unique_ptr<CameraEmulator> emulator = makeEmulator(images, ec);
  REQUIRE_EMULATOR(emulator);
  AravisSource source(cameraConfig(images[0], 60));
  EXPECT_TRUE(source.live());
  source.start();
  int got = 0;
  const auto t0 = Clock::now();
  while (got < 12 && msSince(t0) < kDeadlineMs) {
    const std::optional<Frame> frame = source.next(milliseconds(200));
    if (!frame) continue;
    ++got;
    EXPECT_TRUE(identical(frame->image, images[emulator->imageIndex(frame->seq)]))
        << "frame id " << frame->seq;
    EXPECT_NEAR(static_cast<double>(frame->stamp_us), static_cast<double>(nowMicros()), 5e6);
    // Aravis's fake camera has no PTP: the host's arrival time, the camera's own stamp kept.
    EXPECT_EQ(frame->stamp_source, StampSource::Host);
    EXPECT_GT(frame->camera_stamp_ns, 0u);
  }
  EXPECT_EQ(source.stampSource(), StampSource::Host);
  source.stop();
  EXPECT_EQ(got, 12);
  EXPECT_EQ(source.stats().frames, 12u);
}

// A frame's stamp: the camera's clock, less its lead over UTC, only when PTP gives it the epoch;
// the host's otherwise.
TEST(FrameStamp, CameraClockWhenPtpSynchronizedHostOtherwise) {
  const std::uint64_t camera_ns = 1800000000123456789ull, host_ns = 1800000000200000000ull;
  const FrameStamp ptp = chooseFrameStamp(true, camera_ns, host_ns, 0);
  EXPECT_EQ(ptp.source, StampSource::Camera);
  EXPECT_EQ(ptp.stamp_us, 1800000000123456u);
  const FrameStamp tai = chooseFrameStamp(true, camera_ns, host_ns, 37000000000);
  EXPECT_EQ(tai.stamp_us, 1799999963123456u);  // 37 s earlier: UTC
  const FrameStamp free_running = chooseFrameStamp(false, 5000000000ull, host_ns, 37000000000);
  EXPECT_EQ(free_running.source, StampSource::Host);    // 5 s since the camera's power-up
  EXPECT_EQ(free_running.stamp_us, 1800000000200000u);  // the host's UTC: no offset
  EXPECT_EQ(chooseFrameStamp(true, 0, host_ns, 0).source, StampSource::Host);  // no camera stamp
  EXPECT_STREQ(stampSourceName(StampSource::Camera), "camera (PTP)");
  EXPECT_EQ(timeBaseText(StampSource::Camera, 37), "camera PTP clock, TAI-UTC offset 37 s applied");
  EXPECT_EQ(timeBaseText(StampSource::Host, 37), "host clock");
}

TEST(AravisSource, DeliversTheServedImagesMono8) { expectServedImages(CV_8UC1); }
TEST(AravisSource, DeliversTheServedImagesMono16) { expectServedImages(CV_16UC1); }

TEST(AravisSource, CountsAndSkipsBuffersWithLostPackets) {
  const std::vector<cv::Mat> images = noiseImages(2, 320, 240, CV_8UC1);
  EmulatorConfig ec;
  ec.lost_packet_ratio = 0.02;  // about 56 packets per frame: two frames in three are broken
  const std::unique_ptr<CameraEmulator> emulator = makeEmulator(images, ec);
  REQUIRE_EMULATOR(emulator);
  AravisSource source(cameraConfig(images[0], 100));
  source.start();
  int good = 0;
  const auto t0 = Clock::now();
  while ((good < 3 || source.stats().bad_buffers == 0) && msSince(t0) < kDeadlineMs) {
    if (const std::optional<Frame> frame = source.next(milliseconds(100))) {
      ++good;
      EXPECT_TRUE(identical(frame->image, images[emulator->imageIndex(frame->seq)]));
    }
  }
  source.stop();
  const SourceStats s = source.stats();
  EXPECT_GT(good, 0);
  EXPECT_GT(s.bad_buffers, 0u);
  EXPECT_EQ(s.incomplete, s.bad_buffers);  // every one lost packets
  EXPECT_EQ(s.frames, static_cast<std::uint64_t>(good));
  EXPECT_EQ(s.losses, 0u);
}

TEST(AravisSource, SoftwareTriggerDeliversOneFramePerTrigger) {
  const std::vector<cv::Mat> images = noiseImages(2, 160, 120, CV_8UC1);
  const std::unique_ptr<CameraEmulator> emulator = makeEmulator(images);
  REQUIRE_EMULATOR(emulator);
  AravisConfig config = cameraConfig(images[0], 0);
  config.trigger = TriggerMode::Software;
  AravisSource source(config);
  EXPECT_FALSE(source.live());
  source.start();
  EXPECT_FALSE(source.next(milliseconds(300)));
  source.trigger();
  std::optional<Frame> frame;
  const auto t0 = Clock::now();
  while (!frame && msSince(t0) < kDeadlineMs) frame = source.next(milliseconds(100));
  EXPECT_TRUE(frame);
  EXPECT_FALSE(source.next(milliseconds(300)));
  source.stop();
  EXPECT_EQ(source.stats().reconnects, 0u);
}

// Aravis's fake camera binds with SO_REUSEADDR, so a second one would bind too and serve nothing
// while saying it runs: the emulator refuses a taken port instead.
TEST(CameraEmulator, ASecondOneOnTheSamePortIsRefused) {
  const std::vector<cv::Mat> images = noiseImages(1, 64, 48, CV_8UC1);
  const std::unique_ptr<CameraEmulator> first = makeEmulator(images);
  REQUIRE_EMULATOR(first);
  try {
    CameraEmulator second(images);
    FAIL() << "a second camera on 127.0.0.1:3956 was started";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("taken"), std::string::npos) << e.what();
  }
}

TEST(AravisSource, SurvivesTheCameraDisappearingAndComingBack) {
  const std::vector<cv::Mat> images = noiseImages(2, 160, 120, CV_8UC1);
  std::unique_ptr<CameraEmulator> emulator = makeEmulator(images);
  REQUIRE_EMULATOR(emulator);
  AravisConfig config = cameraConfig(images[0], 50);
  config.lost_after_ms = 300;
  AravisSource source(config);
  source.start();
  std::atomic<int> frames{0};
  std::atomic<bool> done{false};
  std::thread reader([&] {
    while (!done) frames += source.next(milliseconds(50)).has_value();
    source.stop();
  });
  const auto wait_for = [&](int count, double ms) {
    const auto t0 = Clock::now();
    while (frames < count && msSince(t0) < ms) std::this_thread::sleep_for(milliseconds(20));
    return frames >= count;
  };
  EXPECT_TRUE(wait_for(5, kDeadlineMs));
  emulator.reset();  // the camera goes away ...
  // ... the source notices (no frame for lost_after_ms) and fails to reopen it ...
  const auto t0 = Clock::now();
  while (source.stats().read_errors == 0 && msSince(t0) < kDeadlineMs)
    std::this_thread::sleep_for(milliseconds(20));
  EXPECT_GE(source.stats().read_errors, 1u) << "the source did not notice the camera was gone";
  EXPECT_FALSE(source.connected());
  EXPECT_EQ(source.stats().losses, 1u);
  const int before = frames;
  emulator = makeEmulator(images);  // ... and comes back
  ASSERT_TRUE(emulator) << "the port was taken while the camera was away";
  EXPECT_TRUE(wait_for(before + 5, kDeadlineMs)) << "no frames after the camera came back";
  EXPECT_TRUE(source.connected());
  done = true;
  reader.join();
  EXPECT_GE(source.stats().reconnects, 1u);
}

}  // namespace
}  // namespace multislit
