// Where frames come from: a camera (Aravis: GigE Vision, USB3 Vision) or recorded PNG images (the
// simulator's source is in multislit::sim, sim/simulated_source.h). MultiSlitGrabber reads any
// FrameSource on its acquisition thread.
#pragma once

#include "multislit/frame.h"
#include "multislit/reference.h"
#include "multislit/sensor.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace multislit {

/// Counts kept by a source; errors of one frame are counted here, never thrown.
struct SourceStats {
  std::uint64_t frames = 0;  ///< frames delivered by next()
  /// Camera buffers skipped: incomplete ones, and frames of another size or pixel format than
  /// asked (lastError() says which).
  std::uint64_t bad_buffers = 0;
  /// Of those, frames that lost packets on the way (Aravis: missing packets, a frame timeout, a
  /// wrong packet id, an aborted frame); never delivered, so a cloud is never made of a torn image.
  std::uint64_t incomplete = 0;
  std::uint64_t read_errors = 0;  ///< failed reads: unreadable files, failed camera (re)opens
  std::uint64_t reconnects = 0;   ///< times a lost camera was opened again
  std::uint64_t losses = 0;       ///< times the camera was lost (no frame while one was due)
};

/// A stream of frames. start(), next() and stop() are called from one thread at a time;
/// interrupt(), trigger(), stats() and the queries from any thread.
class FrameSource {
 public:
  using Clock = std::chrono::steady_clock;

  FrameSource() = default;
  FrameSource(const FrameSource&) = delete;
  FrameSource& operator=(const FrameSource&) = delete;
  virtual ~FrameSource() = default;

  /// Opens the device or the files; throws std::runtime_error when that fails.
  virtual void start() = 0;
  /// The next frame, waiting at most about `timeout`; nullopt when none came in time, after
  /// interrupt(), or when finished().
  virtual std::optional<Frame> next(std::chrono::milliseconds timeout) = 0;
  /// Releases the device. Never throws.
  virtual void stop() = 0;
  virtual std::string name() const = 0;
  virtual SourceStats stats() const = 0;
  /// True when frames come on the source's own clock (a camera, a paced replay): a consumer that
  /// is too slow loses frames. False when the next frame waits until it is asked for.
  virtual bool live() const = 0;
  /// True when no more frames will come (the end of a sequence played once).
  virtual bool finished() const { return false; }
  /// False while the device is lost and not yet opened again (a camera that stopped sending);
  /// files and the simulator are always connected.
  virtual bool connected() const { return true; }
  /// The latest error the source counted instead of throwing (a file it could not read, a camera
  /// it could not reopen, frames of another size or pixel format than asked); "" when none.
  std::string lastError() const;

  /// Makes a waiting and every later next() return at once, until the next start().
  void interrupt();
  /// Asks for one frame in triggered mode (software trigger, stepping through files).
  void trigger();

 protected:
  /// Clears interrupt() and pending triggers; sources call it first in start().
  void resetWaits();
  bool interrupted() const;
  /// Sleeps until `deadline`; false when interrupted.
  bool sleepUntil(Clock::time_point deadline);
  /// Paced replay: waits until frame `index` of a stream that began at `start` at `fps` is due;
  /// false when it is due after `deadline` (having slept until then) or when interrupted.
  bool waitUntilDue(Clock::time_point start, std::uint64_t index, double fps,
                    Clock::time_point deadline);
  /// Takes one pending trigger, waiting for it until `deadline`; false when none came.
  bool takeTrigger(Clock::time_point deadline);
  /// Keeps `what` as lastError().
  void setLastError(std::string what);

 private:
  mutable std::mutex error_mutex_;
  std::string last_error_;
  mutable std::mutex wait_mutex_;
  std::condition_variable wait_cv_;
  bool interrupted_ = false;
  std::uint64_t triggers_ = 0;
};

// --- cameras ---------------------------------------------------------------------------------

/// Mono12 comes unpacked, as 16-bit images of values 0..4095: give its reference full_scale 4095.
enum class PixelFormat { Mono8, Mono12, Mono16 };
/// "Mono8", "Mono12" or "Mono16" (GenICam's PixelFormat entries).
const char* pixelFormatName(PixelFormat format);
/// The format of that name; nullopt for any other.
std::optional<PixelFormat> parsePixelFormat(const std::string& name);
enum class TriggerMode { FreeRunning, Software };

struct AravisConfig {
  /// GigE Vision camera: its IPv4 address ("127.0.0.1" for `multislit emulate`). USB3 Vision:
  /// "usb3:VENDOR:MODEL:SERIAL". Cameras are opened directly, never by network discovery.
  std::string camera = "127.0.0.1";
  /// Exposure time (GenICam ExposureTime, or ExposureTimeAbs) [us]; 0: keep the camera's.
  double exposure_us = 0.0;
  /// Gain (GenICam Gain [dB]; cameras with only GainRaw take it in their raw units) [dB];
  /// negative: keep the camera's.
  double gain_db = -1.0;
  double frame_rate = 30.0;  ///< acquisition rate in free-running mode [Hz]; 0: keep the camera's
  PixelFormat pixel_format = PixelFormat::Mono8;
  int roi_x = 0;       ///< region of interest: left column [px]
  int roi_y = 0;       ///< region of interest: top row [px]
  int roi_width = 0;   ///< region of interest width [px]; 0: keep the camera's region
  int roi_height = 0;  ///< region of interest height [px]; 0: keep the camera's region
  TriggerMode trigger = TriggerMode::FreeRunning;
  int buffer_count = 8;                       ///< stream buffers [-]
  int socket_buffer_bytes = 4 * 1024 * 1024;  ///< GigE stream socket receive buffer [B]
  int packet_size = 0;                        ///< GigE stream packet size [B]; 0: keep the camera's
  /// Nothing from the camera, not even a broken frame, for this long while a frame is due: the
  /// camera is lost (connected() false, a status signal of the grabber) and reopened with
  /// back-off. [ms]
  int lost_after_ms = 800;
  int reconnect_delay_ms = 100;       ///< first wait before reopening a lost camera [ms]
  int reconnect_max_delay_ms = 2000;  ///< the wait doubles after each failure up to this [ms]
  /// Stamp frames with the camera's own clock when PTP synchronizes it (PtpEnable or
  /// GevIEEE1588 on, status Master or Slave); false, or no PTP: the host's arrival time.
  bool camera_clock = true;
  /// How far the camera's PTP clock runs ahead of UTC, subtracted from every stamp taken from it
  /// [s]. PTP's default time scale is TAI, 37 s ahead (ptp4l and GigE Vision cameras keep it
  /// unless the grandmaster serves an arbitrary time scale); 0 for a camera whose PTP time is
  /// UTC. Host stamps are UTC already and keep their value.
  double ptp_utc_offset_s = kTaiUtcOffsetS;
  /// When not empty, the camera's serial number (DeviceSerialNumber) or DeviceID must equal this
  /// (a calibration's camera_id, `multislit calibrate --camera-id`): another camera at the
  /// address is refused, with an error naming both.
  std::string camera_id;

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// A GigE Vision or USB3 Vision camera through Aravis. A camera that disappears is reopened with
/// back-off (stats().reconnects); buffers with an error status are counted and skipped. The
/// camera must give the region and pixel format asked: one that does not (a smaller sensor, a
/// format it does not take) is refused when opened, and frames of another size or format are
/// skipped, each named with what was asked in lastError(). Frame
/// seq is the camera's frame id (16-bit ids of GigE Vision 1.x unwrapped); stamp_us the camera's
/// PTP-synchronized clock at exposure when it has one (AravisConfig::camera_clock), less
/// AravisConfig::ptp_utc_offset_s, else the
/// host's clock when the buffer arrived; Frame::stamp_source says which, camera_stamp_ns keeps
/// the camera's own timestamp either way.
class AravisSource : public FrameSource {
 public:
  explicit AravisSource(const AravisConfig& config = {});
  ~AravisSource() override;

  void start() override;
  std::optional<Frame> next(std::chrono::milliseconds timeout) override;
  void stop() override;
  std::string name() const override;
  SourceStats stats() const override;
  bool live() const override { return config_.trigger == TriggerMode::FreeRunning; }
  bool connected() const override { return connected_; }
  const AravisConfig& config() const { return config_; }
  /// The clock of the frames' stamps: Camera when the opened camera's clock is PTP-synchronized.
  StampSource stampSource() const { return stamp_source_; }

 private:
  struct Camera;  // the opened Aravis objects
  void open();
  void release(bool camera_lost);
  std::optional<Frame> take(Clock::time_point deadline);
  std::uint64_t unwrap(std::uint64_t frame_id);

  AravisConfig config_;
  std::unique_ptr<Camera> camera_;
  Clock::time_point last_frame_{}, reconnect_at_{};
  int reconnect_delay_ms_ = 0;
  bool trigger_outstanding_ = false;
  std::uint64_t last_id_ = 0, id_wraps_ = 0;  // 16-bit GigE Vision frame ids made monotonic
  std::atomic<StampSource> stamp_source_{StampSource::Host};
  std::atomic<std::uint64_t> frames_{0}, bad_buffers_{0}, incomplete_{0}, read_errors_{0},
      reconnects_{0}, losses_{0};
  std::atomic<bool> connected_{false};
};

// --- recorded images -------------------------------------------------------------------------

struct ImageSequenceConfig {
  /// Folder of PNG images: the files of its frames.csv (from `multislit simulate`) when present,
  /// else every *.png but reference.png, in name order.
  std::string folder;
  std::vector<std::string> files;  ///< or these files in this order (used when not empty)
  double fps = 0.0;                ///< replay rate [Hz]; 0: as fast as the consumer takes them
  bool triggered = false;          ///< one frame per trigger() (fps is then ignored)
  bool repeat = false;             ///< start over after the last file
  double stamp_rate = 30.0;        ///< rate of synthetic time stamps for files without any [Hz]

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// Time stamp carried by a file name, as PCL's ImageGrabber writes them:
/// "frame_20261123T120000.123456.png" (UTC, up to 6 fraction digits) -> microseconds since the
/// epoch; nullopt when the name carries none.
std::optional<std::uint64_t> stampFromFileName(const std::string& file_name);

/// Recorded images. Time stamps: from the file names, else frames.csv's stamp_us, else
/// synthetic (start time + index / stamp_rate). seq is the position in the sequence.
class ImageSequenceSource : public FrameSource {
 public:
  explicit ImageSequenceSource(const ImageSequenceConfig& config);

  void start() override;
  std::optional<Frame> next(std::chrono::milliseconds timeout) override;
  void stop() override;
  std::string name() const override;
  SourceStats stats() const override;
  bool live() const override { return config_.fps > 0 && !config_.triggered; }
  bool finished() const override { return finished_; }
  /// The files and their time stamps (after start()).
  const std::vector<std::string>& files() const { return files_; }
  const std::vector<std::uint64_t>& stamps() const { return stamps_; }

 private:
  void listFiles();
  void assignStamps();

  ImageSequenceConfig config_;
  std::vector<std::string> files_;
  std::vector<std::uint64_t> stamps_;
  std::uint64_t position_ = 0;
  Clock::time_point started_{};
  std::atomic<bool> finished_{false};
  std::atomic<std::uint64_t> frames_{0}, read_errors_{0};
};

}  // namespace multislit
