// MultiSlitGrabber: PCL signals, headers, back-pressure, stop() from callbacks and with sources
// that hang (end to end over GigE Vision: grabber_gige_test).
#include "multislit/grabber.h"
#include "camera_test_support.h"
#include "grabber_test_support.h"
#include "multislit/intrinsics_file.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <functional>
#include <thread>

namespace multislit {
namespace {

using namespace test;
using std::chrono::milliseconds;
using RdmapPtr = pcl::PointCloud<PointRDM>::ConstPtr;
using XyzPtr = pcl::PointCloud<pcl::PointXYZ>::ConstPtr;
using FramePtr = std::shared_ptr<const Frame>;

// Fifteen straight slits: a cheap image the reference finds slits in (no rendering).
cv::Mat slitImage(double shift) {
  cv::Mat image(240, 480, CV_8UC1);
  for (int u = 0; u < image.cols; ++u) {
    double value = 20;
    for (int k = 0; k < 15; ++k) {
      const double d = u - (30.0 + 30.0 * k + shift);
      value += 200 * std::exp(-0.5 * d * d / (1.3 * 1.3));
    }
    image.col(u).setTo(std::min(255.0, value));
  }
  return image;
}

const Reference& slitReference() {
  static const Reference reference = Reference::fromImage(slitImage(0));
  return reference;
}

// A source in memory: images in turn at a rate (0: at once), optionally finite, throwing or
// hanging on purpose.
class MemorySource : public FrameSource {
 public:
  MemorySource(std::vector<cv::Mat> images, double fps, bool live)
      : images_(std::move(images)), fps_(fps), live_(live) {}

  std::uint64_t frames = 0;  ///< finite: stop after this many; 0: endless
  int throw_every = 0;       ///< next() throws on every n-th call; 0: never
  int hang_after = -1;       ///< next() blocks hang_ms ignoring everything after this many frames
  int hang_ms = 0;
  std::atomic<int> starts{0}, stops{0};

  void start() override {
    resetWaits();
    started_ = Clock::now();
    count_ = 0;
    ++starts;
  }
  std::optional<Frame> next(milliseconds timeout) override {
    if (throw_every > 0 && ++calls_ % throw_every == 0) throw std::runtime_error("read failed");
    if (hang_after >= 0 && count_ >= static_cast<std::uint64_t>(hang_after)) {
      std::this_thread::sleep_for(milliseconds(hang_ms));  // a driver call that hangs
      return std::nullopt;
    }
    if (finished()) return std::nullopt;
    if (fps_ > 0) {
      const auto due = started_ + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(count_ / fps_));
      if (due > Clock::now() + timeout) {
        sleepUntil(Clock::now() + timeout);
        return std::nullopt;
      }
      if (!sleepUntil(due)) return std::nullopt;
    }
    const std::uint64_t seq = count_++;
    ++delivered_;
    return Frame{images_[seq % images_.size()], 1700000000000000 + seq * 1000, seq, Clock::now()};
  }
  void stop() override { ++stops; }
  std::string name() const override { return "memory"; }
  SourceStats stats() const override {
    SourceStats s;
    s.frames = delivered_;
    return s;
  }
  bool live() const override { return live_; }
  bool finished() const override { return frames > 0 && count_ >= frames; }

 private:
  std::vector<cv::Mat> images_;
  double fps_;
  bool live_;
  Clock::time_point started_{};
  std::atomic<std::uint64_t> count_{0}, delivered_{0};
  int calls_ = 0;
};

std::size_t residentBytes() {
  std::ifstream statm("/proc/self/statm");
  std::size_t pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
}

// --- the PCL face ----------------------------------------------------------------------------

TEST(MultiSlitGrabber, OffersPclSignals) {
  auto source = std::make_shared<MemorySource>(std::vector<cv::Mat>{slitImage(0)}, 0, true);
  MultiSlitGrabber grabber(source, slitReference());
  EXPECT_EQ(grabber.getName(), "MultiSlitGrabber");
  EXPECT_FALSE(grabber.isRunning());
  EXPECT_TRUE(grabber.providesCallback<MultiSlitGrabber::sig_cb_rdmap>());
  EXPECT_TRUE(grabber.providesCallback<MultiSlitGrabber::sig_cb_frame>());
  // No metric scale, no metric cloud.
  EXPECT_FALSE(grabber.providesCallback<MultiSlitGrabber::sig_cb_xyz>());
  std::function<MultiSlitGrabber::sig_cb_xyz> xyz = [](const XyzPtr&) {};
  EXPECT_THROW(grabber.registerCallback(xyz), pcl::IOException);
  EXPECT_EQ(grabber.getFramesPerSecond(), 0.0f);

  Reference scaled = slitReference();
  scaled.scale.f = 1000;
  scaled.scale.disparity_constant = 64;
  MultiSlitGrabber metric(source, scaled);
  EXPECT_TRUE(metric.providesCallback<MultiSlitGrabber::sig_cb_xyz>());

  GrabberConfig bad;
  bad.poll_ms = 0;
  EXPECT_THROW((MultiSlitGrabber{source, slitReference(), bad}), std::invalid_argument);
  EXPECT_THROW((MultiSlitGrabber{nullptr, slitReference()}), std::invalid_argument);
}

// GrabberConfig::intrinsics: the reference must carry the camera calibration's lens.
TEST(MultiSlitGrabber, RefusesAReferenceOfAnotherLens) {
  auto source = std::make_shared<MemorySource>(std::vector<cv::Mat>{slitImage(0)}, 0, true);
  Reference reference = slitReference();
  const std::string path = tempPath("camera_info.yaml");
  std::ofstream(path) << "image_width: " << reference.image_width
                      << "\nimage_height: " << reference.image_height
                      << "\ncamera_matrix: {rows: 3, cols: 3, data: [300, 0, 240, 0, 300, 120, 0, "
                         "0, 1]}\ndistortion_model: plumb_bob\n"
                         "distortion_coefficients: {rows: 1, cols: 5, data: [-0.1, 0, 0, 0, 0]}\n";
  GrabberConfig config;
  config.intrinsics = path;
  EXPECT_THROW((MultiSlitGrabber{source, reference, config}), std::invalid_argument);
  reference.setLens(intrinsicsForImage(reference.image_width, reference.image_height, path));
  EXPECT_NO_THROW((MultiSlitGrabber{source, reference, config}));
  config.intrinsics = tempPath("absent.yaml");
  EXPECT_THROW((MultiSlitGrabber{source, reference, config}), std::runtime_error);
}

TEST(MultiSlitGrabber, DeliversEveryFrameOfASourceThatWaitsInOrder) {
  const std::vector<cv::Mat> images = {slitImage(0), slitImage(2.5), slitImage(-3)};
  auto source = std::make_shared<MemorySource>(images, 0, /*live=*/false);
  source->frames = 12;
  GrabberConfig config;
  config.frame_id = "test_camera";
  MultiSlitGrabber grabber(source, slitReference(), config);
  std::vector<RdmapPtr> clouds;
  std::function<MultiSlitGrabber::sig_cb_rdmap> on_cloud = [&](const RdmapPtr& cloud) {
    std::this_thread::sleep_for(milliseconds(5));  // slower than the source: it must wait
    clouds.push_back(cloud);
  };
  grabber.registerCallback(on_cloud);
  grabber.start();
  EXPECT_TRUE(waitFor([&] { return !grabber.isRunning(); }));  // the source finished
  grabber.stop();

  ASSERT_EQ(clouds.size(), 12u);
  const Extractor extractor(slitReference());
  for (std::size_t i = 0; i < clouds.size(); ++i) {
    const pcl::PointCloud<PointRDM>& c = *clouds[i];
    EXPECT_EQ(c.header.seq, i);
    EXPECT_EQ(c.header.stamp, 1700000000000000 + i * 1000);
    EXPECT_EQ(c.header.frame_id, "test_camera");
    EXPECT_EQ(c.width, static_cast<std::uint32_t>(slitReference().maxSlitLength()));
    EXPECT_EQ(c.height, 15u);
    EXPECT_FALSE(c.is_dense);
    pcl::PointCloud<PointRDM> direct;
    extractor.extract(images[i % images.size()], direct);
    EXPECT_TRUE(sameBits(dkOf(c), dkOf(direct)));
  }
  const GrabberStats s = grabber.getStats();
  EXPECT_EQ(s.frames_received, 12u);
  EXPECT_EQ(s.frames_processed, 12u);
  EXPECT_EQ(s.frames_dropped, 0u);
  // The shifted slits moved by their shift.
  const auto valid = std::count_if(clouds[1]->begin(), clouds[1]->end(),
                                   [](const PointRDM& p) { return std::abs(p.dk - 2.5f) < 0.05f; });
  EXPECT_GT(valid, static_cast<long>(clouds[1]->size() / 2));
}

TEST(MultiSlitGrabber, ComputesOnlyWhatIsConnected) {
  // Images that do not fit the reference: extracting them fails, delivering them does not.
  cv::Mat wrong(100, 100, CV_8UC1, cv::Scalar(0));
  auto source = std::make_shared<MemorySource>(std::vector<cv::Mat>{wrong}, 200, true);
  MultiSlitGrabber grabber(source, slitReference());
  std::atomic<int> frames{0};
  std::function<MultiSlitGrabber::sig_cb_frame> on_frame = [&](const FramePtr& f) {
    EXPECT_EQ(f->image.cols, 100);
    ++frames;
  };
  grabber.registerCallback(on_frame);
  grabber.start();
  EXPECT_TRUE(waitFor([&] { return frames >= 10; }));
  EXPECT_EQ(grabber.getStats().extraction_errors, 0u);  // no cloud slot: no extraction

  std::function<MultiSlitGrabber::sig_cb_rdmap> on_cloud = [](const RdmapPtr&) {};
  grabber.registerCallback(on_cloud);
  EXPECT_TRUE(waitFor([&] { return grabber.getStats().extraction_errors >= 5; }));
  EXPECT_TRUE(grabber.isRunning());
  grabber.stop();
  EXPECT_GT(grabber.getStats().frames_processed, 10u);
}

// --- back-pressure, errors, stop and destruction ---------------------------------------------

TEST(MultiSlitGrabber, SlowCallbackDropsFramesWithBoundedMemory) {
  auto source = std::make_shared<MemorySource>(std::vector<cv::Mat>{slitImage(0)}, 200, true);
  MultiSlitGrabber grabber(source, slitReference());
  std::atomic<int> calls{0};
  std::function<MultiSlitGrabber::sig_cb_rdmap> slow = [&](const RdmapPtr&) {
    std::this_thread::sleep_for(milliseconds(50));
    ++calls;
  };
  grabber.registerCallback(slow);
  const std::size_t rss_before = residentBytes();
  grabber.start();
  // 200 frames/s arrive, at most 20/s can be processed: ~1.5 s when the machine is idle.
  EXPECT_TRUE(waitFor([&] { return grabber.getStats().frames_dropped > 100 && calls >= 10; }));
  grabber.stop();
  const std::size_t rss_after = residentBytes();
  const GrabberStats s = grabber.getStats();
  EXPECT_GT(s.frames_dropped, 100u);
  EXPECT_LT(s.frames_processed * 3, s.frames_received);  // ~1 in 10 at nominal rates
  EXPECT_EQ(s.frames_processed, static_cast<std::uint64_t>(calls));
  // One slot between the threads: nothing else can be waiting. Neither processed nor dropped at
  // stop(): the frame in the slot and the one being extracted (it goes to no callback).
  EXPECT_LE(s.frames_received - s.frames_processed - s.frames_dropped, 2u);
  EXPECT_LT(rss_after, rss_before + (64u << 20));
  // Each callback sleeps 50 ms: never more than 20 per second.
  EXPECT_GT(s.frames_per_second, 0.0);
  EXPECT_LE(s.frames_per_second, 21.0);
}

TEST(MultiSlitGrabber, StopFromInsideACallback) {
  auto source = std::make_shared<MemorySource>(std::vector<cv::Mat>{slitImage(0)}, 100, true);
  MultiSlitGrabber grabber(source, slitReference());
  std::atomic<int> calls{0};
  std::atomic<double> stop_ms{-1};
  std::function<MultiSlitGrabber::sig_cb_rdmap> stopper = [&](const RdmapPtr&) {
    if (++calls == 1) {
      const auto t0 = Clock::now();
      grabber.stop();
      stop_ms = msSince(t0);
      EXPECT_FALSE(grabber.isRunning());
    }
  };
  grabber.registerCallback(stopper);
  grabber.start();
  ASSERT_TRUE(waitFor([&] { return stop_ms >= 0; })) << "stop() from a callback deadlocked";
  EXPECT_LT(stop_ms, 1000.0);
  std::this_thread::sleep_for(milliseconds(200));
  EXPECT_EQ(calls, 1);
  EXPECT_FALSE(grabber.isRunning());
  // And it starts again.
  grabber.start();
  EXPECT_TRUE(waitFor([&] { return calls >= 2; }));
  grabber.stop();
  EXPECT_TRUE(waitFor([&] { return source->stops == source->starts; }));
}

TEST(MultiSlitGrabber, HundredStartStopCycles) {
  auto source = std::make_shared<MemorySource>(std::vector<cv::Mat>{slitImage(0)}, 500, true);
  MultiSlitGrabber grabber(source, slitReference());
  std::atomic<int> clouds{0};
  std::function<MultiSlitGrabber::sig_cb_rdmap> count = [&](const RdmapPtr&) { ++clouds; };
  grabber.registerCallback(count);
  double worst_stop_ms = 0;
  for (int cycle = 0; cycle < 100; ++cycle) {
    const int before = clouds;
    grabber.start();
    EXPECT_TRUE(grabber.isRunning());
    std::this_thread::sleep_for(milliseconds(cycle % 3));
    // Every tenth cycle stops only after a cloud went through: a loaded machine may deliver none
    // within 0-2 ms, and stop() must also be quick while clouds flow.
    if (cycle % 10 == 9) {
      EXPECT_TRUE(waitFor([&] { return clouds > before; })) << "cycle " << cycle;
    }
    const auto t = Clock::now();
    grabber.stop();
    worst_stop_ms = std::max(worst_stop_ms, msSince(t));
    EXPECT_FALSE(grabber.isRunning());
  }
  EXPECT_LT(worst_stop_ms, 1000.0);
  EXPECT_EQ(source->starts, 100);
  EXPECT_EQ(source->stops, 100);
  EXPECT_GE(clouds, 10);
}

TEST(MultiSlitGrabber, SourceErrorsAreCountedNotThrown) {
  auto source = std::make_shared<MemorySource>(std::vector<cv::Mat>{slitImage(0)}, 200, true);
  source->throw_every = 3;
  MultiSlitGrabber grabber(source, slitReference());
  std::atomic<int> clouds{0};
  std::function<MultiSlitGrabber::sig_cb_rdmap> count = [&](const RdmapPtr&) { ++clouds; };
  grabber.registerCallback(count);
  grabber.start();
  EXPECT_TRUE(waitFor([&] { return clouds >= 10; }));
  grabber.stop();
  EXPECT_GT(grabber.getStats().source_errors, 3u);
}

TEST(MultiSlitGrabber, StopReturnsWithinASecondWhenTheSourceHangs) {
  auto source = std::make_shared<MemorySource>(std::vector<cv::Mat>{slitImage(0)}, 100, true);
  source->hang_after = 3;
  source->hang_ms = 1500;
  std::weak_ptr<MemorySource> weak = source;
  auto grabber = std::make_unique<MultiSlitGrabber>(source, slitReference());
  source.reset();
  std::atomic<int> clouds{0};
  std::function<MultiSlitGrabber::sig_cb_rdmap> count = [&](const RdmapPtr&) { ++clouds; };
  grabber->registerCallback(count);
  grabber->start();
  // The source delivered its 3 frames (a busy callback may have seen fewer: the source is live,
  // and a frame arriving while one is processed replaces the waiting one).
  ASSERT_TRUE(waitFor([&] { return grabber->getStats().frames_received >= 3 && clouds >= 1; }));
  std::this_thread::sleep_for(milliseconds(100));  // now inside the hanging call
  auto t0 = Clock::now();
  grabber->stop();
  EXPECT_LT(msSince(t0), 1000.0);
  EXPECT_FALSE(grabber->isRunning());
  // A restart waits for the stuck call to end, then runs.
  grabber->start();
  EXPECT_TRUE(grabber->isRunning());
  std::this_thread::sleep_for(milliseconds(100));
  t0 = Clock::now();
  grabber->stop();
  EXPECT_LT(msSince(t0), 1000.0);
  // Destroyed while the source hangs: the destructor waits at most release_timeout_ms; the stuck
  // thread keeps what it uses alive until the call returns.
  grabber.reset();
  EXPECT_TRUE(waitFor([&] { return weak.expired(); }));
}

TEST(MultiSlitGrabber, DestructionWhileRunningIsSafe) {
  for (int i = 0; i < 10; ++i) {
    auto source = std::make_shared<MemorySource>(std::vector<cv::Mat>{slitImage(0)}, 300, true);
    auto grabber = std::make_unique<MultiSlitGrabber>(source, slitReference());
    std::function<MultiSlitGrabber::sig_cb_rdmap> rdmap = [](const RdmapPtr&) {};
    std::function<MultiSlitGrabber::sig_cb_frame> frame = [](const FramePtr&) {};
    grabber->registerCallback(rdmap);
    grabber->registerCallback(frame);
    grabber->start();
    std::this_thread::sleep_for(milliseconds(i * 3));
    grabber.reset();
    EXPECT_EQ(source->starts, source->stops);
  }
}

}  // namespace
}  // namespace multislit
