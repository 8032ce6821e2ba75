// CameraEmulator: Aravis's GigE Vision fake camera on 127.0.0.1, filled with our own images.
#include "multislit/sim/camera_emulator.h"
#include "aravis_util.h"
#include "emulator_genicam.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace multislit {

using aravis::GPtr;

namespace {

constexpr std::uint16_t kGvcpPort = 3956;

// Whether 127.0.0.1:3956 is free. Aravis's fake camera binds with SO_REUSEADDR, so a second one
// binds too and serves nothing; a socket without it fails to bind while any other holds the port.
bool gvcpPortFree() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) return true;  // cannot tell: let the camera try
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(kGvcpPort);
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool free = ::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0;
  ::close(fd);
  return free;
}

// The pixel types a camera serves (Mono8, Mono16).
void requireMono(int type) {
  if (type != CV_8UC1 && type != CV_16UC1)
    throw std::invalid_argument("CameraEmulator: images must be CV_8UC1 or CV_16UC1");
}

// `image` with its rows one after another in memory, as the camera's buffer copy needs it.
cv::Mat continuous(const cv::Mat& image) { return image.isContinuous() ? image : image.clone(); }

}  // namespace

void EmulatorConfig::validate() const {
  auto fail = [](const std::string& field, const std::string& what) {
    throw std::invalid_argument("EmulatorConfig." + field + " " + what);
  };
  if (serial.empty() || serial.size() > 15) fail("serial", "must have 1 to 15 characters");
  if (!(fps > 0 && fps <= 1000)) fail("fps", "must be in (0, 1000]");
  if (!(lost_packet_ratio >= 0 && lost_packet_ratio <= 1))
    fail("lost_packet_ratio", "must be in [0, 1]");
  if (!(std::abs(clock_offset_s) <= 86400)) fail("clock_offset_s", "must be in [-86400, 86400]");
}

// Live images: made on a thread of their own, a few ahead of the camera, taken in turn.
class LiveImages {
 public:
  // `first`: the image served until the next is made.
  LiveImages(CameraEmulator::ImageMaker make, const cv::Mat& first, std::size_t ahead)
      : make_(std::move(make)),
        size_(first.size()),
        type_(first.type()),
        ahead_(std::max<std::size_t>(1, ahead)),
        last_(first) {
    thread_ = std::thread([this] { run(); });
  }
  ~LiveImages() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    changed_.notify_all();
    thread_.join();  // after at most the image being made
  }

  // The next image, or the last one again when none is ready (late).
  cv::Mat take() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (ready_.empty()) {
      ++late_;
      return last_;
    }
    last_ = ready_.front();
    ready_.pop_front();
    changed_.notify_all();
    return last_;
  }
  std::uint64_t late() const { return late_; }
  std::uint64_t made() const { return made_; }
  std::size_t ready() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return ready_.size();
  }
  void setAhead(std::size_t ahead) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ahead_ = std::max<std::size_t>(1, ahead);
    }
    changed_.notify_all();
  }
  std::string error() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return error_;
  }

 private:
  void run() {
    for (;;) {
      {
        std::unique_lock<std::mutex> lock(mutex_);
        changed_.wait(lock, [&] { return stop_ || ready_.size() < ahead_; });
        if (stop_) return;
      }
      cv::Mat image;
      try {
        image = make_();
        if (image.size() != size_ || image.type() != type_)
          throw std::runtime_error("a live image of another size or type");
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(mutex_);
        error_ = e.what();
        return;
      }
      std::lock_guard<std::mutex> lock(mutex_);
      ready_.push_back(continuous(image));
      ++made_;
    }
  }

  CameraEmulator::ImageMaker make_;
  cv::Size size_;
  int type_;
  std::size_t ahead_;
  cv::Mat last_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<cv::Mat> ready_;
  bool stop_ = false;
  std::string error_;
  std::atomic<std::uint64_t> late_{0}, made_{0};
  std::thread thread_;  // last: it starts when everything else is in place
};

struct CameraEmulator::Impl {
  std::unique_ptr<LiveImages> live;                     // live images, or
  std::vector<cv::Mat> images;                          // continuous, same size and type
  ArvPixelFormat own_format = ARV_PIXEL_FORMAT_MONO_8;  // the images'
  bool keep_format = false;
  std::int64_t clock_offset_ns = 0;  // the camera clock's lead over the host's
  std::atomic<double> lost_ratio{0.0};
  std::atomic<std::uint64_t> served{0};
  // g_object_set() from the camera's thread refs the camera: never while it is being destroyed.
  std::mutex camera_use;
  bool closing = false;
  GPtr<ArvGvFakeCamera> camera;  // last: its thread stops before the images go

  std::size_t index(std::uint64_t frame_id) const { return imageIndex(frame_id, images.size()); }

  // Runs on the fake camera's thread for every frame. The buffer reports size 0 here: its
  // capacity is the payload the camera announced, width x height x bytes per pixel, which the
  // fake camera checked before calling.
  static void fill(ArvBuffer* buffer, void* user, guint32 /*exposure_us*/, guint32 /*gain*/,
                   ArvPixelFormat format) {
    auto* self = static_cast<Impl*>(user);
    if (self->clock_offset_ns != 0)  // the fake camera stamps with the host's clock
      arv_buffer_set_timestamp(
          buffer, static_cast<guint64>(static_cast<std::int64_t>(arv_buffer_get_timestamp(buffer)) +
                                       self->clock_offset_ns));
    // The lost packet ratio of this frame, set here, on the camera's thread that sends it. A
    // camera keeping its format sends no frame of another one, and takes its own back.
    const bool foreign = self->keep_format && format != self->own_format;
    {
      std::lock_guard<std::mutex> lock(self->camera_use);
      if (!self->closing)
        g_object_set(self->camera.get(), "gvsp-lost-ratio", foreign ? 1.0 : self->lost_ratio.load(),
                     nullptr);
    }
    if (foreign) {
      arv_fake_camera_write_register(arv_gv_fake_camera_get_fake_camera(self->camera.get()),
                                     ARV_FAKE_CAMERA_REGISTER_PIXEL_FORMAT, self->own_format);
      return;
    }
    if (format != ARV_PIXEL_FORMAT_MONO_8 && format != ARV_PIXEL_FORMAT_MONO_12 &&
        format != ARV_PIXEL_FORMAT_MONO_16)
      return;
    gint x = 0, y = 0, width = 0, height = 0;
    arv_buffer_get_image_region(buffer, &x, &y, &width, &height);
    std::size_t reported = 0;
    auto* out =
        static_cast<std::uint8_t*>(const_cast<void*>(arv_buffer_get_data(buffer, &reported)));
    if (out == nullptr || width <= 0 || height <= 0) return;
    const int out_depth = format == ARV_PIXEL_FORMAT_MONO_8 ? CV_8U : CV_16U;
    const cv::Mat image = self->live ? self->live->take()
                                     : self->images[self->index(arv_buffer_get_frame_id(buffer))];
    cv::Mat target(height, width, out_depth, out);
    target.setTo(0);
    // The requested region of the image, converted to the requested depth.
    const cv::Rect region = cv::Rect(x, y, width, height) & cv::Rect(0, 0, image.cols, image.rows);
    if (region.area() > 0) {
      const double white = format == ARV_PIXEL_FORMAT_MONO_8    ? 255.0
                           : format == ARV_PIXEL_FORMAT_MONO_12 ? 4095.0
                                                                : 65535.0;
      const double scale = white / (image.depth() == CV_8U ? 255.0 : 65535.0);
      image(region).convertTo(
          target(cv::Rect(region.x - x, region.y - y, region.width, region.height)), out_depth,
          scale);
    }
    ++self->served;
  }
};

CameraEmulator::CameraEmulator(std::vector<cv::Mat> images, const EmulatorConfig& config)
    : impl_(std::make_unique<Impl>()) {
  config.validate();
  if (images.empty()) throw std::invalid_argument("CameraEmulator: no images");
  for (cv::Mat& image : images) {
    requireMono(image.type());
    if (image.size() != images.front().size() || image.type() != images.front().type())
      throw std::invalid_argument("CameraEmulator: images must share size and type");
    impl_->images.push_back(continuous(image));
  }
  start(images.front().size(), images.front().type(), config);
}

CameraEmulator::CameraEmulator(ImageMaker make, cv::Size size, int type,
                               const EmulatorConfig& config, std::size_t ahead)
    : impl_(std::make_unique<Impl>()) {
  config.validate();
  requireMono(type);
  if (size.width <= 0 || size.height <= 0)
    throw std::invalid_argument("CameraEmulator: live images need a size");
  if (!make) throw std::invalid_argument("CameraEmulator: no image maker");
  // The first image before the camera answers: every frame it sends carries one.
  cv::Mat first = make();
  if (first.size() != size || first.type() != type)
    throw std::invalid_argument("CameraEmulator: the first live image has another size or type");
  impl_->images.push_back(continuous(first));
  impl_->live = std::make_unique<LiveImages>(std::move(make), impl_->images.front(), ahead);
  start(size, type, config);
}

void CameraEmulator::start(cv::Size size, int type, const EmulatorConfig& config) {
  // What the camera's thread reads, set before the camera (and its thread) starts.
  impl_->own_format =
      CV_MAT_DEPTH(type) == CV_8U ? ARV_PIXEL_FORMAT_MONO_8 : ARV_PIXEL_FORMAT_MONO_16;
  impl_->keep_format = config.keep_pixel_format;
  impl_->clock_offset_ns = std::llround(config.clock_offset_s * 1e9);
  if (!gvcpPortFree())
    throw std::runtime_error(std::string("cannot serve a GigE Vision camera on ") + kAddress +
                             ":3956: the port is taken (another multislit emulate or camera?)");
  const emulator::TemporaryFile genicam(emulator::emulatorGenicam(config.serial));
  impl_->camera.reset(
      arv_gv_fake_camera_new_full(kAddress, config.serial.c_str(), genicam.path().c_str()));
  if (!impl_->camera || !arv_gv_fake_camera_is_running(impl_->camera.get()))
    throw std::runtime_error(std::string("cannot serve a GigE Vision camera on ") + kAddress +
                             ":3956 (is another camera running there?)");

  // A sensor of the images' size, streaming all of it at the configured rate.
  ArvFakeCamera* fake = arv_gv_fake_camera_get_fake_camera(impl_->camera.get());
  const auto width = static_cast<guint32>(size.width);
  const auto height = static_cast<guint32>(size.height);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_SENSOR_WIDTH, width);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_SENSOR_HEIGHT, height);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_WIDTH, width);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_HEIGHT, height);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_PIXEL_FORMAT, impl_->own_format);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_ACQUISITION_FRAME_PERIOD_US,
                                 static_cast<guint32>(1e6 / config.fps));
  arv_fake_camera_write_register(fake, emulator::kPtpEnableRegister, config.ptp ? 1 : 0);
  arv_fake_camera_write_register(fake, emulator::kPtpStatusRegister,
                                 config.ptp ? emulator::kPtpStatusSlave : 0);
  arv_fake_camera_set_fill_pattern(fake, &Impl::fill, impl_.get());
  setLostPacketRatio(config.lost_packet_ratio);
}

CameraEmulator::~CameraEmulator() {
  {
    std::lock_guard<std::mutex> lock(impl_->camera_use);
    impl_->closing = true;
  }
  impl_->camera.reset();
}

std::size_t CameraEmulator::imageIndex(std::uint64_t frame_id) const {
  return impl_->index(frame_id);
}

std::size_t CameraEmulator::imageIndex(std::uint64_t frame_id, std::size_t image_count) {
  // Frame ids on the wire may have 16 bits (GigE Vision 1.x): use those on both ends.
  return static_cast<std::size_t>(frame_id & 0xffffu) % image_count;
}

std::uint64_t CameraEmulator::framesServed() const { return impl_->served; }

std::uint64_t CameraEmulator::framesLate() const { return impl_->live ? impl_->live->late() : 0; }

std::uint64_t CameraEmulator::imagesMade() const {
  return impl_->live ? impl_->live->made() + 1 : impl_->images.size();  // + the first
}

std::size_t CameraEmulator::imagesReady() const {
  return impl_->live ? impl_->live->ready() : impl_->images.size();
}

void CameraEmulator::setImagesAhead(std::size_t ahead) {
  if (impl_->live) impl_->live->setAhead(ahead);
}

std::string CameraEmulator::lastError() const {
  return impl_->live ? impl_->live->error() : std::string();
}

void CameraEmulator::setLostPacketRatio(double ratio) {
  if (!(ratio >= 0 && ratio <= 1))
    throw std::invalid_argument("CameraEmulator: lost packet ratio must be in [0, 1]");
  impl_->lost_ratio = ratio;  // the camera's thread applies it to each frame (fill)
}

}  // namespace multislit
