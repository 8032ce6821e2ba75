// The multi-slit sensor as a PCL grabber: frames from any FrameSource become organized RDMap
// clouds (paper Sec. III-A) on the grabber's own thread, delivered to PCL callbacks.
#pragma once

#include "multislit/extractor.h"
#include "multislit/frame.h"
#include "multislit/point_types.h"
#include "multislit/reference.h"
#include "multislit/sources.h"

#include <pcl/io/grabber.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace multislit {

struct GrabberConfig {
  std::string frame_id = "multislit_camera";  ///< header.frame_id of the clouds
  ExtractorConfig extractor;  ///< slit extraction; its frame_id is replaced by frame_id
  int poll_ms = 50;           ///< longest single wait for the source; bounds stop()'s reaction [ms]
  int stop_timeout_ms = 500;  ///< stop() waits at most this for the source to let go [ms]
  int release_timeout_ms = 15000;  ///< start() and the destructor wait at most this for a source
                                   ///< still stuck in a call from an earlier run [ms]
  /// The camera's OpenCV or ROS camera_info calibration YAML; when given, the reference must have
  /// been made with its lens (Reference::checkLens), which the reference carries. "": unchecked.
  std::string intrinsics;

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// Counts since construction; read any time with getStats().
struct GrabberStats {
  std::uint64_t frames_received = 0;    ///< frames the source delivered
  std::uint64_t frames_processed = 0;   ///< frames handed to the callbacks
  std::uint64_t frames_dropped = 0;     ///< frames replaced unprocessed by a newer one (busy)
  std::uint64_t source_errors = 0;      ///< source calls that threw
  std::uint64_t extraction_errors = 0;  ///< frames that do not fit the reference
  std::uint64_t callback_errors = 0;    ///< callbacks that threw (caught, the grabber goes on)
  double frames_per_second = 0.0;       ///< processed frames over the last second [Hz]
  double latency_median_ms = 0.0;       ///< host arrival to the callbacks, last 256 frames [ms]
  double latency_p99_ms = 0.0;          ///< 99th percentile of the same [ms]
  SourceStats source;                   ///< the source's own counts (bad buffers, reconnects)
  bool connected = true;                ///< FrameSource::connected() now
  /// The latest error, "" when none: a source call that threw, the source's own
  /// (FrameSource::lastError(): a camera that cannot be reopened, frames of another size or
  /// pixel format than asked), frames that do not fit the calibration, or a failed start().
  std::string last_error;
};

/// The source's state, as the status signal reports each change of `connected` or `error`.
struct SourceStatus {
  bool connected = true;         ///< false: the camera stopped sending and is being reopened
  std::uint64_t losses = 0;      ///< times it was lost so far
  std::uint64_t reconnects = 0;  ///< times it came back
  std::string source;            ///< FrameSource::name()
  /// The latest source or extraction error, as GrabberStats::last_error ("" when none yet).
  std::string error;
};

/// A pcl::Grabber for the multi-slit sensor. Signals (each computed only while connected):
///  - sig_cb_rdmap: the organized RDMap cloud (one row per slit, NaN where nothing was measured);
///  - sig_cb_xyz: the same points in metres in the camera frame, organized, NaN kept; offered
///    only when the reference has a metric scale;
///  - sig_cb_frame: the raw image;
///  - sig_cb_status: the source lost (a camera that stops sending, noticed after
///    AravisConfig::lost_after_ms) or back, at once, or a new last_error, within poll_ms; from
///    the processing thread.
/// header.stamp is the frame's time in microseconds since the epoch, header.seq the source's
/// frame number. A live source's frames that arrive while a callback is still busy replace the
/// waiting one (one slot, counted as dropped); other sources wait for the consumer.
/// stop() may be called from a callback; it returns within about stop_timeout_ms whatever the
/// source does. Destroying the grabber from inside its own callback is not supported.
class MultiSlitGrabber : public pcl::Grabber {
 public:
  using sig_cb_rdmap = void(const pcl::PointCloud<PointRDM>::ConstPtr&);
  using sig_cb_xyz = void(const pcl::PointCloud<pcl::PointXYZ>::ConstPtr&);
  using sig_cb_frame = void(const std::shared_ptr<const Frame>&);
  using sig_cb_status = void(const SourceStatus&);

  /// Throws std::invalid_argument for a bad config or a reference without slits.
  MultiSlitGrabber(std::shared_ptr<FrameSource> source, Reference reference,
                   const GrabberConfig& config = {});
  ~MultiSlitGrabber() noexcept override;

  /// Opens the source and starts the threads; throws pcl::IOException when the source cannot
  /// start (kept as GrabberStats::last_error too) or an earlier run's source call is still stuck.
  void start() override;
  void stop() override;
  /// True from start() to stop(), and until a finished source's last frame was delivered.
  bool isRunning() const override;
  std::string getName() const override { return "MultiSlitGrabber"; }
  float getFramesPerSecond() const override;

  /// One frame from a triggered source (software trigger, stepping through files).
  void trigger() { source_->trigger(); }
  GrabberStats getStats() const;
  const Reference& getReference() const { return extractor_.reference(); }
  const GrabberConfig& getConfig() const { return config_; }
  FrameSource& getSource() { return *source_; }

 private:
  struct Run;       // one start() .. stop(): the mailbox and its threads
  struct Counters;  // shared with the threads, outlive a stuck source call

  static void acquisitionLoop(std::shared_ptr<Run> run, std::shared_ptr<FrameSource> source,
                              std::shared_ptr<Counters> counters, int poll_ms);
  void processLoop(const std::shared_ptr<Run>& run);
  void process(Frame& frame, Run& run);
  void reportStatus(SourceStatus& said, std::string& source_error);
  void reap();

  std::shared_ptr<FrameSource> source_;
  GrabberConfig config_;
  Extractor extractor_;
  std::shared_ptr<Counters> counters_;

  boost::signals2::signal<sig_cb_rdmap>* rdmap_signal_ = nullptr;
  boost::signals2::signal<sig_cb_xyz>* xyz_signal_ = nullptr;
  boost::signals2::signal<sig_cb_frame>* frame_signal_ = nullptr;
  boost::signals2::signal<sig_cb_status>* status_signal_ = nullptr;

  mutable std::mutex control_mutex_;           // guards current_ and retired_
  std::shared_ptr<Run> current_;               // the running run, if any
  std::vector<std::shared_ptr<Run>> retired_;  // stopped runs whose threads are not joined yet
};

}  // namespace multislit
