// A PCL user's program with both an OpenNI 2 camera and the multi-slit sensor: linking
// multislit::multislit must leave PCL's OpenNI2Grabber in place (issue 40). The multi-slit grabber
// turns one image of 15 slits into a cloud of 15 rows; the OpenNI 2 camera is opened only when
// MULTISLIT_OPENNI2_DEVICE names one ("" any), as there is none here. Exits non-zero otherwise.
#include <multislit/grabber.h>
#include <pcl/io/openni2_grabber.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <type_traits>

static_assert(std::is_base_of_v<pcl::Grabber, pcl::io::OpenNI2Grabber>);
static_assert(std::is_base_of_v<pcl::Grabber, multislit::MultiSlitGrabber>);

namespace {

// 15 vertical slits 30 px apart on a plane, as the reference sees them.
cv::Mat slitImage() {
  cv::Mat image(240, 480, CV_8UC1);
  for (int u = 0; u < image.cols; ++u) {
    double value = 20;
    for (int k = 0; k < 15; ++k) {
      const double d = u - (30.0 + 30.0 * k);
      value += 200 * std::exp(-0.5 * d * d / (1.3 * 1.3));
    }
    image.col(u).setTo(std::min(255.0, value));
  }
  return image;
}

// One frame, then finished.
class OneFrameSource : public multislit::FrameSource {
 public:
  void start() override { resetWaits(); }
  std::optional<multislit::Frame> next(std::chrono::milliseconds) override {
    if (finished_) return std::nullopt;
    finished_ = true;
    multislit::Frame frame;
    frame.image = slitImage();
    frame.arrival = Clock::now();
    return frame;
  }
  void stop() override {}
  std::string name() const override { return "one frame"; }
  multislit::SourceStats stats() const override { return {}; }
  bool live() const override { return false; }
  bool finished() const override { return finished_; }

 private:
  std::atomic<bool> finished_{false};
};

// Either grabber, through PCL's interface: the first point cloud within 10 s, or null.
template <typename Point>
typename pcl::PointCloud<Point>::ConstPtr firstCloud(pcl::Grabber& grabber) {
  std::mutex mutex;
  std::condition_variable arrived;
  typename pcl::PointCloud<Point>::ConstPtr first;
  const std::function<void(const typename pcl::PointCloud<Point>::ConstPtr&)> callback =
      [&](const typename pcl::PointCloud<Point>::ConstPtr& cloud) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!first) first = cloud;
        arrived.notify_all();
      };
  const boost::signals2::connection connection = grabber.registerCallback(callback);
  grabber.start();
  {
    std::unique_lock<std::mutex> lock(mutex);
    arrived.wait_for(lock, std::chrono::seconds(10), [&] { return first != nullptr; });
  }
  grabber.stop();
  connection.disconnect();
  const std::string got =
      first ? std::to_string(first->width) + " x " + std::to_string(first->height) + " cloud"
            : "no cloud";
  std::printf("%s: %s\n", grabber.getName().c_str(), got.c_str());
  return first;
}

}  // namespace

int main() {
  multislit::MultiSlitGrabber slits(std::make_shared<OneFrameSource>(),
                                    multislit::Reference::fromImage(slitImage()));
  const auto rdmap = firstCloud<multislit::PointRDM>(slits);
  if (!rdmap || rdmap->height != 15) return 1;

  if (const char* device = std::getenv("MULTISLIT_OPENNI2_DEVICE")) {
    pcl::io::OpenNI2Grabber camera(device);
    if (!firstCloud<pcl::PointXYZ>(camera)) return 1;
  } else {
    std::printf("OpenNI2Grabber: linked; no camera opened (MULTISLIT_OPENNI2_DEVICE unset)\n");
  }
  return 0;
}
