// AravisSource: GigE Vision and USB3 Vision cameras through Aravis, opened directly by address
// or USB identity (never by network discovery), reopened with back-off when lost.
#include "aravis_camera.h"
#include "multislit/sources.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace multislit {

using aravis::Error;
using aravis::GPtr;

namespace {

void onControlLost(ArvDevice*, gpointer flag) {
  static_cast<std::atomic<bool>*>(flag)->store(true);
}

// Why a buffer is not a frame: "" when it is a complete image of the shape asked; `incomplete`
// when it lost packets on the way.
struct BufferCheck {
  bool incomplete = false;
  std::string problem;
};

BufferCheck checkBuffer(ArvBuffer* buffer, const aravis::FrameShape& asked) {
  switch (arv_buffer_get_status(buffer)) {
    case ARV_BUFFER_STATUS_SUCCESS:
      break;
    case ARV_BUFFER_STATUS_MISSING_PACKETS:  // still missing when the frame timed out, ...
    case ARV_BUFFER_STATUS_TIMEOUT:
    case ARV_BUFFER_STATUS_WRONG_PACKET_ID:
    case ARV_BUFFER_STATUS_ABORTED:
      return {true, "a frame lost packets"};
    case ARV_BUFFER_STATUS_SIZE_MISMATCH:
      return {false, "sends frames larger than the payload it announced"};
    default:
      return {false, "a buffer had an unknown status"};
  }
  if (arv_buffer_get_payload_type(buffer) != ARV_BUFFER_PAYLOAD_TYPE_IMAGE)
    return {false, "sends buffers that are not images"};
  const aravis::FrameShape shape{arv_buffer_get_image_width(buffer),
                                 arv_buffer_get_image_height(buffer),
                                 arv_buffer_get_image_pixel_format(buffer)};
  if (shape.width != asked.width || shape.height != asked.height || shape.format != asked.format)
    return {false, "sends " + aravis::describe(shape) + " frames, not the " +
                       aravis::describe(asked) + " asked"};
  std::size_t size = 0;
  const std::size_t bytes = asked.format == ARV_PIXEL_FORMAT_MONO_8 ? 1 : 2;
  if (arv_buffer_get_image_data(buffer, &size) == nullptr ||
      size < static_cast<std::size_t>(shape.width) * static_cast<std::size_t>(shape.height) * bytes)
    return {false, "sends frames shorter than " + aravis::describe(asked)};
  return {};
}

// A checked buffer's image as a Frame (its pixels copied).
Frame copyFrame(ArvBuffer* buffer, std::chrono::steady_clock::time_point arrival, bool camera_clock,
                std::int64_t camera_lead_ns) {
  const int width = arv_buffer_get_image_width(buffer);
  const int height = arv_buffer_get_image_height(buffer);
  const int type =
      arv_buffer_get_image_pixel_format(buffer) == ARV_PIXEL_FORMAT_MONO_8 ? CV_8UC1 : CV_16UC1;
  std::size_t size = 0;
  const void* data = arv_buffer_get_image_data(buffer, &size);
  // The camera's clock when PTP gives it the epoch (less its lead over UTC), else the host's at
  // the buffer's arrival.
  std::uint64_t host_ns = arv_buffer_get_system_timestamp(buffer);
  if (host_ns == 0)
    host_ns = static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                             std::chrono::system_clock::now().time_since_epoch())
                                             .count());
  Frame frame;
  frame.image = cv::Mat(height, width, type, const_cast<void*>(data)).clone();
  frame.camera_stamp_ns = arv_buffer_get_timestamp(buffer);
  const FrameStamp stamp =
      chooseFrameStamp(camera_clock, frame.camera_stamp_ns, host_ns, camera_lead_ns);
  frame.stamp_us = stamp.stamp_us;
  frame.stamp_source = stamp.source;
  frame.seq = arv_buffer_get_frame_id(buffer);
  frame.arrival = arrival;
  return frame;
}

}  // namespace

const char* pixelFormatName(PixelFormat format) {
  switch (format) {
    case PixelFormat::Mono8:
      return "Mono8";
    case PixelFormat::Mono12:
      return "Mono12";
    case PixelFormat::Mono16:
      break;
  }
  return "Mono16";
}

std::optional<PixelFormat> parsePixelFormat(const std::string& name) {
  for (PixelFormat f : {PixelFormat::Mono8, PixelFormat::Mono12, PixelFormat::Mono16})
    if (name == pixelFormatName(f)) return f;
  return std::nullopt;
}

void AravisConfig::validate() const {
  auto fail = [](const std::string& field, const std::string& what) {
    throw std::invalid_argument("AravisConfig." + field + " " + what);
  };
  if (camera.empty()) fail("camera", "must not be empty");
  if (!(exposure_us >= 0)) fail("exposure_us", "must be >= 0");
  if (!(frame_rate >= 0)) fail("frame_rate", "must be >= 0");
  if (!(std::abs(ptp_utc_offset_s) <= 86400))
    fail("ptp_utc_offset_s", "must be in [-86400, 86400]");
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

// The opened camera: device control, its stream, the heartbeat's "control lost" flag and the
// frames it was set to send.
struct AravisSource::Camera {
  GPtr<ArvCamera> camera;
  GPtr<ArvStream> stream;
  gulong lost_handler = 0;
  std::atomic<bool> control_lost{false};
  aravis::FrameShape shape;

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
  return (aravis::isUsb(config_.camera) ? "USB3 Vision camera " : "GigE Vision camera ") +
         config_.camera;
}

SourceStats AravisSource::stats() const {
  SourceStats s;
  s.frames = frames_;
  s.bad_buffers = bad_buffers_;
  s.incomplete = incomplete_;
  s.read_errors = read_errors_;
  s.reconnects = reconnects_;
  s.losses = losses_;
  return s;
}

// Opens, checks and configures the camera, gives its stream buffers and starts the acquisition.
void AravisSource::open() {
  auto cam = std::make_unique<Camera>();
  GPtr<ArvDevice> device = aravis::openDevice(config_.camera);
  Error error;
  cam->camera.reset(arv_camera_new_with_device(device.get(), error.out()));
  error.check("cannot open camera " + config_.camera);
  ArvCamera* c = cam->camera.get();
  cam->lost_handler =
      g_signal_connect(device.get(), "control-lost", G_CALLBACK(onControlLost), &cam->control_lost);

  aravis::checkCameraId(c, config_);
  cam->shape = aravis::configureCamera(c, config_);

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

  stamp_source_ = config_.camera_clock && aravis::ptpSynchronized(device.get())
                      ? StampSource::Camera
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
  } catch (const std::exception& e) {
    ++read_errors_;
    setLastError(e.what());
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
    // Triggered: look for new trigger() calls every 10 ms. A frame due: wake when it is lost.
    const bool due = config_.trigger == TriggerMode::FreeRunning || trigger_outstanding_;
    const Clock::time_point lost_at =
        last_frame_ + std::chrono::milliseconds(config_.lost_after_ms);
    auto wait = std::chrono::duration_cast<std::chrono::microseconds>(
        (due ? std::min(deadline, lost_at) : deadline) - now);
    if (config_.trigger == TriggerMode::Software)
      wait = std::min<std::chrono::microseconds>(wait, std::chrono::milliseconds(10));
    ArvBuffer* buffer = arv_stream_timeout_pop_buffer(
        stream, static_cast<guint64>(std::max<long long>(1, static_cast<long long>(wait.count()))));
    now = Clock::now();
    if (buffer == nullptr) {
      if (camera_->control_lost || (due && now >= lost_at)) {
        release(true);
        reconnect_at_ = now + std::chrono::milliseconds(reconnect_delay_ms_);
        return std::nullopt;
      }
      continue;
    }
    // Any buffer, even a broken one, says the camera is there: only silence makes it lost.
    last_frame_ = now;
    trigger_outstanding_ = false;
    const BufferCheck check = checkBuffer(buffer, camera_->shape);
    std::optional<Frame> frame;
    if (check.problem.empty())
      frame = copyFrame(buffer, now, stamp_source_ == StampSource::Camera,
                        std::llround(config_.ptp_utc_offset_s * 1e9));
    arv_stream_push_buffer(stream, buffer);
    if (!frame) {
      ++bad_buffers_;
      incomplete_ += check.incomplete;
      if (!check.incomplete) setLastError(check.problem);  // lost packets have their count
      continue;
    }
    frame->seq = unwrap(frame->seq);
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
