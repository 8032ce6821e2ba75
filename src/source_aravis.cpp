// AravisSource: GigE Vision and USB3 Vision cameras through Aravis, opened directly by address
// or USB identity (never by network discovery), reopened with back-off when lost.
#include "aravis_util.h"
#include "multislit/sources.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace multislit {

using aravis::Error;
using aravis::GPtr;

namespace {

constexpr int kGvcpPort = 3956;

// The local address the kernel routes to `device` from (connecting a UDP socket sends nothing).
std::string localAddressFor(const std::string& device) {
  if (device.rfind("127.", 0) == 0) return "127.0.0.1";
  sockaddr_in remote{};
  remote.sin_family = AF_INET;
  remote.sin_port = htons(kGvcpPort);
  if (inet_pton(AF_INET, device.c_str(), &remote.sin_addr) != 1)
    throw std::invalid_argument("AravisConfig.camera '" + device + "' is not an IPv4 address");
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) throw std::runtime_error("cannot create a socket to find the route to " + device);
  sockaddr_in local{};
  socklen_t length = sizeof local;
  const bool ok = connect(fd, reinterpret_cast<const sockaddr*>(&remote), sizeof remote) == 0 &&
                  getsockname(fd, reinterpret_cast<sockaddr*>(&local), &length) == 0;
  close(fd);
  char text[INET_ADDRSTRLEN] = {};
  if (!ok || inet_ntop(AF_INET, &local.sin_addr, text, sizeof text) == nullptr)
    throw std::runtime_error("no route to camera " + device);
  return text;
}

bool isUsb(const std::string& camera) { return camera.rfind("usb3:", 0) == 0; }

GPtr<ArvDevice> openDevice(const std::string& camera) {
  Error error;
  ArvDevice* device = nullptr;
  if (isUsb(camera)) {
    // usb3:VENDOR:MODEL:SERIAL, matched against the local USB devices.
    std::string fields[3];
    std::size_t begin = 5;
    for (int i = 0; i < 3; ++i) {
      const std::size_t end = i < 2 ? camera.find(':', begin) : camera.size();
      if (end == std::string::npos)
        throw std::invalid_argument("AravisConfig.camera '" + camera +
                                    "' must be usb3:VENDOR:MODEL:SERIAL");
      fields[i] = camera.substr(begin, end - begin);
      begin = end + 1;
    }
    device =
        arv_uv_device_new(fields[0].c_str(), fields[1].c_str(), fields[2].c_str(), error.out());
  } else {
    GPtr<GInetAddress> device_address(g_inet_address_new_from_string(camera.c_str()));
    if (!device_address)
      throw std::invalid_argument("AravisConfig.camera '" + camera + "' is not an IPv4 address");
    GPtr<GInetAddress> interface_address(
        g_inet_address_new_from_string(localAddressFor(camera).c_str()));
    device = arv_gv_device_new(interface_address.get(), device_address.get(), error.out());
  }
  GPtr<ArvDevice> owned(device);
  error.check("cannot open camera " + camera);
  if (!owned) throw std::runtime_error("cannot open camera " + camera);
  return owned;
}

void onControlLost(ArvDevice*, gpointer flag) {
  static_cast<std::atomic<bool>*>(flag)->store(true);
}

// Whether the camera's clock is synchronized by PTP (IEEE 1588): SFNC's PtpEnable or the older
// GevIEEE1588 on, and its status (PtpStatus, GevIEEE1588Status) Master or Slave where it has one.
bool ptpSynchronized(ArvDevice* device) {
  const std::pair<const char*, const char*> features[] = {{"PtpEnable", "PtpStatus"},
                                                          {"GevIEEE1588", "GevIEEE1588Status"}};
  for (const auto& [enable, status] : features) {
    if (arv_device_get_feature(device, enable) == nullptr) continue;
    Error error;
    const bool on = arv_device_get_boolean_feature_value(device, enable, error.out());
    if (error || !on) continue;
    if (arv_device_get_feature(device, status) == nullptr) return true;
    const char* state = arv_device_get_string_feature_value(device, status, error.out());
    const std::string s = error || state == nullptr ? "" : state;
    if (s == "Master" || s == "Slave") return true;
  }
  return false;
}

// A complete Mono8 / Mono16 image buffer as a Frame (its pixels copied); nullopt otherwise.
std::optional<Frame> copyFrame(ArvBuffer* buffer, std::chrono::steady_clock::time_point arrival,
                               bool camera_clock) {
  if (arv_buffer_get_status(buffer) != ARV_BUFFER_STATUS_SUCCESS ||
      arv_buffer_get_payload_type(buffer) != ARV_BUFFER_PAYLOAD_TYPE_IMAGE)
    return std::nullopt;
  const ArvPixelFormat format = arv_buffer_get_image_pixel_format(buffer);
  if (format != ARV_PIXEL_FORMAT_MONO_8 && format != ARV_PIXEL_FORMAT_MONO_16) return std::nullopt;
  const int width = arv_buffer_get_image_width(buffer);
  const int height = arv_buffer_get_image_height(buffer);
  const int type = format == ARV_PIXEL_FORMAT_MONO_8 ? CV_8UC1 : CV_16UC1;
  std::size_t size = 0;
  const void* data = arv_buffer_get_image_data(buffer, &size);
  const std::size_t needed = static_cast<std::size_t>(width) * static_cast<std::size_t>(height) *
                             (type == CV_8UC1 ? 1 : 2);
  if (data == nullptr || width <= 0 || height <= 0 || size < needed) return std::nullopt;
  // The camera's clock when PTP gives it the epoch, else the host's at the buffer's arrival.
  std::uint64_t host_ns = arv_buffer_get_system_timestamp(buffer);
  if (host_ns == 0)
    host_ns = static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                             std::chrono::system_clock::now().time_since_epoch())
                                             .count());
  Frame frame;
  frame.image = cv::Mat(height, width, type, const_cast<void*>(data)).clone();
  frame.camera_stamp_ns = arv_buffer_get_timestamp(buffer);
  const FrameStamp stamp = chooseFrameStamp(camera_clock, frame.camera_stamp_ns, host_ns);
  frame.stamp_us = stamp.stamp_us;
  frame.stamp_source = stamp.source;
  frame.seq = arv_buffer_get_frame_id(buffer);
  frame.arrival = arrival;
  return frame;
}

// Acquisition mode, pixel format, region, exposure, gain, rate or trigger and packet size, as the
// config asks; throws std::runtime_error naming the feature the camera refused.
void configureCamera(ArvCamera* c, const AravisConfig& config) {
  Error error;
  arv_camera_stop_acquisition(c, error.out());  // settings may be locked while acquiring
  arv_camera_set_acquisition_mode(c, ARV_ACQUISITION_MODE_CONTINUOUS, error.out());
  error.check("AcquisitionMode");
  arv_camera_set_pixel_format(c,
                              config.pixel_format == PixelFormat::Mono8 ? ARV_PIXEL_FORMAT_MONO_8
                                                                        : ARV_PIXEL_FORMAT_MONO_16,
                              error.out());
  error.check("PixelFormat");
  if (config.roi_width > 0 && config.roi_height > 0) {
    arv_camera_set_region(c, config.roi_x, config.roi_y, config.roi_width, config.roi_height,
                          error.out());
    error.check("region of interest");
  }
  if (config.exposure_us > 0) {
    arv_camera_set_exposure_time(c, config.exposure_us, error.out());
    error.check("ExposureTime");
  }
  if (config.gain_db >= 0) {
    arv_camera_set_gain(c, config.gain_db, error.out());
    error.check("Gain");
  }
  if (config.trigger == TriggerMode::FreeRunning) {
    if (config.frame_rate > 0) {
      arv_camera_set_frame_rate(c, config.frame_rate, error.out());
      error.check("AcquisitionFrameRate");
    }
    arv_camera_clear_triggers(c, error.out());  // not every camera has triggers
  } else {
    arv_camera_set_trigger(c, "Software", error.out());
    error.check("software trigger");
  }
  if (arv_camera_is_gv_device(c) && config.packet_size > 0) {
    arv_camera_gv_set_packet_size(c, config.packet_size, error.out());
    error.check("GevSCPSPacketSize");
  }
}

}  // namespace

void AravisConfig::validate() const {
  auto fail = [](const std::string& field, const std::string& what) {
    throw std::invalid_argument("AravisConfig." + field + " " + what);
  };
  if (camera.empty()) fail("camera", "must not be empty");
  if (!(exposure_us >= 0)) fail("exposure_us", "must be >= 0");
  if (!(frame_rate >= 0)) fail("frame_rate", "must be >= 0");
  if (roi_x < 0 || roi_y < 0) fail("roi_x", "and roi_y must be >= 0");
  if (roi_width < 0 || roi_height < 0) fail("roi_width", "and roi_height must be >= 0");
  if (buffer_count < 2) fail("buffer_count", "must be >= 2");
  if (socket_buffer_bytes < 0) fail("socket_buffer_bytes", "must be >= 0");
  if (packet_size < 0) fail("packet_size", "must be >= 0");
  if (lost_after_ms < 1) fail("lost_after_ms", "must be >= 1");
  if (reconnect_delay_ms < 1) fail("reconnect_delay_ms", "must be >= 1");
  if (reconnect_max_delay_ms < reconnect_delay_ms)
    fail("reconnect_max_delay_ms", "must be >= reconnect_delay_ms");
}

// The opened camera: device control, its stream, and the heartbeat's "control lost" flag.
struct AravisSource::Camera {
  GPtr<ArvCamera> camera;
  GPtr<ArvStream> stream;
  gulong lost_handler = 0;
  std::atomic<bool> control_lost{false};

  ~Camera() {
    if (lost_handler != 0)
      g_signal_handler_disconnect(arv_camera_get_device(camera.get()), lost_handler);
    stream.reset();  // before the device it streams from
    camera.reset();
  }
};

AravisSource::AravisSource(const AravisConfig& config) : config_(config) { config_.validate(); }

AravisSource::~AravisSource() { release(false); }

std::string AravisSource::name() const {
  return (isUsb(config_.camera) ? "USB3 Vision camera " : "GigE Vision camera ") + config_.camera;
}

SourceStats AravisSource::stats() const {
  SourceStats s;
  s.frames = frames_;
  s.bad_buffers = bad_buffers_;
  s.read_errors = read_errors_;
  s.reconnects = reconnects_;
  s.losses = losses_;
  return s;
}

// Opens and configures the camera, gives its stream buffers and starts the acquisition.
void AravisSource::open() {
  auto cam = std::make_unique<Camera>();
  GPtr<ArvDevice> device = openDevice(config_.camera);
  Error error;
  cam->camera.reset(arv_camera_new_with_device(device.get(), error.out()));
  error.check("cannot open camera " + config_.camera);
  ArvCamera* c = cam->camera.get();
  cam->lost_handler =
      g_signal_connect(device.get(), "control-lost", G_CALLBACK(onControlLost), &cam->control_lost);

  configureCamera(c, config_);

  cam->stream.reset(arv_camera_create_stream(c, nullptr, nullptr, error.out()));
  error.check("cannot open the stream of camera " + config_.camera);
  if (ARV_IS_GV_STREAM(cam->stream.get()) && config_.socket_buffer_bytes > 0)
    g_object_set(cam->stream.get(), "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_FIXED,
                 "socket-buffer-size", config_.socket_buffer_bytes, nullptr);
  const guint payload = arv_camera_get_payload(c, error.out());
  error.check("PayloadSize");
  for (int i = 0; i < config_.buffer_count; ++i)
    arv_stream_push_buffer(cam->stream.get(), arv_buffer_new(payload, nullptr));
  arv_camera_start_acquisition(c, error.out());
  error.check("AcquisitionStart");

  stamp_source_ = config_.camera_clock && ptpSynchronized(device.get()) ? StampSource::Camera
                                                                        : StampSource::Host;
  camera_ = std::move(cam);
  connected_ = true;
  last_frame_ = Clock::now();
  trigger_outstanding_ = false;
}

// A lost camera is not told to stop: its control requests would only time out.
void AravisSource::release(bool camera_lost) {
  connected_ = false;
  if (!camera_) return;
  losses_ += camera_lost;
  if (!camera_lost) {
    Error error;
    arv_camera_stop_acquisition(camera_->camera.get(), error.out());
  }
  camera_.reset();
}

void AravisSource::start() {
  resetWaits();
  reconnect_delay_ms_ = config_.reconnect_delay_ms;
  if (!camera_) open();
  last_frame_ = Clock::now();
}

void AravisSource::stop() { release(false); }

std::optional<Frame> AravisSource::next(std::chrono::milliseconds timeout) {
  const Clock::time_point deadline = Clock::now() + timeout;
  if (camera_) return take(deadline);
  // Lost: reopen when the back-off has passed, doubling it after each failure.
  if (Clock::now() < reconnect_at_) {
    sleepUntil(std::min(deadline, reconnect_at_));
    return std::nullopt;
  }
  if (interrupted()) return std::nullopt;
  try {
    open();
    ++reconnects_;
    reconnect_delay_ms_ = config_.reconnect_delay_ms;
  } catch (const std::exception&) {
    ++read_errors_;
    reconnect_at_ = Clock::now() + std::chrono::milliseconds(reconnect_delay_ms_);
    reconnect_delay_ms_ = std::min(2 * reconnect_delay_ms_, config_.reconnect_max_delay_ms);
    return std::nullopt;
  }
  return take(deadline);
}

// Waits for a complete buffer until `deadline`; buffers with an error status are skipped.
std::optional<Frame> AravisSource::take(Clock::time_point deadline) {
  ArvCamera* c = camera_->camera.get();
  ArvStream* stream = camera_->stream.get();
  for (;;) {
    Clock::time_point now = Clock::now();
    if (now >= deadline || interrupted()) return std::nullopt;
    if (config_.trigger == TriggerMode::Software && takeTrigger(now)) {
      Error error;
      arv_camera_software_trigger(c, error.out());
      if (error) ++read_errors_;
      if (!trigger_outstanding_) last_frame_ = now;  // a frame is due from now on
      trigger_outstanding_ = true;
    }
    // Triggered: look for new trigger() calls every 10 ms.
    auto wait = std::chrono::duration_cast<std::chrono::microseconds>(deadline - now);
    if (config_.trigger == TriggerMode::Software)
      wait = std::min<std::chrono::microseconds>(wait, std::chrono::milliseconds(10));
    ArvBuffer* buffer = arv_stream_timeout_pop_buffer(
        stream, static_cast<guint64>(std::max<long long>(1, static_cast<long long>(wait.count()))));
    now = Clock::now();
    if (buffer == nullptr) {
      const bool due = config_.trigger == TriggerMode::FreeRunning || trigger_outstanding_;
      if (camera_->control_lost ||
          (due && now - last_frame_ > std::chrono::milliseconds(config_.lost_after_ms))) {
        release(true);
        reconnect_at_ = now + std::chrono::milliseconds(reconnect_delay_ms_);
        return std::nullopt;
      }
      continue;
    }
    std::optional<Frame> frame = copyFrame(buffer, now, stamp_source_ == StampSource::Camera);
    arv_stream_push_buffer(stream, buffer);
    if (!frame) {
      ++bad_buffers_;  // missing packets, timeout, wrong size or format
      continue;
    }
    frame->seq = unwrap(frame->seq);
    last_frame_ = now;
    trigger_outstanding_ = false;
    ++frames_;
    return frame;
  }
}

std::uint64_t AravisSource::unwrap(std::uint64_t frame_id) {
  const std::uint64_t last = last_id_ & 0xffffu;
  if (frame_id <= 0xffffu && frames_ > 0 && frame_id < last && last - frame_id > 0x8000u)
    id_wraps_ += 0x10000u;
  last_id_ = frame_id;
  return frame_id + id_wraps_;
}

}  // namespace multislit
