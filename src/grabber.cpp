// MultiSlitGrabber: a source feeding a single-slot mailbox on one thread, extraction and the PCL
// callbacks on another.
#include "multislit/grabber.h"
#include "multislit/intrinsics_file.h"

#include "config_check.h"
#include "grabber_counters.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <optional>
#include <stdexcept>
#include <system_error>
#include <thread>
#include <utility>

namespace multislit {

namespace {

using Clock = std::chrono::steady_clock;

// The extractor's settings, with the grabber's frame_id; validates the whole config.
ExtractorConfig extractorConfig(const GrabberConfig& config) {
  config.validate();
  ExtractorConfig e = config.extractor;
  e.frame_id = config.frame_id;
  return e;
}

pcl::PointCloud<pcl::PointXYZ>::Ptr toXYZ(const pcl::PointCloud<PointRDM>& rdmap) {
  auto xyz = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>(rdmap.width, rdmap.height);
  xyz->header = rdmap.header;
  xyz->is_dense = false;
  for (std::size_t i = 0; i < rdmap.size(); ++i) {
    xyz->points[i].x = rdmap.points[i].x;
    xyz->points[i].y = rdmap.points[i].y;
    xyz->points[i].z = rdmap.points[i].z;
  }
  return xyz;
}

}  // namespace

void GrabberConfig::validate() const {
  constexpr detail::FieldCheck require("GrabberConfig");
  require(!frame_id.empty(), "frame_id", "must not be empty");
  require(poll_ms >= 1 && poll_ms <= 1000, "poll_ms", "must be in [1, 1000]");
  require(stop_timeout_ms >= poll_ms, "stop_timeout_ms", "must be >= poll_ms");
  require(release_timeout_ms >= 0, "release_timeout_ms", "must be >= 0");
  extractor.validate();
}

// One start() .. stop(): the single-slot mailbox between acquisition and processing, and the two
// threads. The acquisition thread touches only this, the source and the counters, so it may
// outlive the grabber when a source call hangs.
struct MultiSlitGrabber::Run {
  std::mutex mutex;
  std::condition_variable changed;
  std::optional<Frame> mailbox;  // the newest frame not yet taken by processing
  bool stop = false;
  bool status_changed = false;  // the source was lost or came back: processing tells at once
  bool acquisition_done = false;
  bool processing_done = false;
  std::thread acquisition, processing;

  // Sets one of the flags above under the mutex and wakes the threads waiting on them.
  void raise(bool& flag) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      flag = true;
    }
    changed.notify_all();
  }
};

// The acquisition thread: source -> mailbox. Never throws; source errors are counted.
void MultiSlitGrabber::acquisitionLoop(std::shared_ptr<Run> run,
                                       std::shared_ptr<FrameSource> source,
                                       std::shared_ptr<Counters> counters, int poll_ms) {
  const auto poll = std::chrono::milliseconds(poll_ms);
  const bool live = source->live();
  bool connected = source->connected();
  for (;;) {
    {
      // A source that is not live hands out the next frame only once the last one was taken.
      std::unique_lock<std::mutex> lock(run->mutex);
      while (!live && !run->stop && run->mailbox) run->changed.wait_for(lock, poll);
      if (run->stop) break;
    }
    std::optional<Frame> frame;
    std::string error;
    try {
      frame = source->next(poll);
    } catch (const std::exception& e) {
      error = e.what();
    } catch (...) {
      error = "unknown error";
    }
    if (source->connected() != connected) {
      connected = !connected;
      run->raise(run->status_changed);
    }
    if (!error.empty()) {
      counters->error(counters->source_errors, source->name() + ": " + error);
      std::unique_lock<std::mutex> lock(run->mutex);
      run->changed.wait_for(lock, poll, [&] { return run->stop; });  // no busy loop on errors
      continue;
    }
    if (!frame) {
      if (source->finished()) break;
      continue;
    }
    {
      std::lock_guard<std::mutex> lock(run->mutex);
      if (run->stop) break;  // a frame that comes after stop() is not received
      ++counters->received;
      if (run->mailbox) ++counters->dropped;
      run->mailbox = std::move(frame);
    }
    run->changed.notify_all();
  }
  try {
    source->stop();
  } catch (...) {
    ++counters->source_errors;
  }
  run->raise(run->acquisition_done);
}

MultiSlitGrabber::MultiSlitGrabber(std::shared_ptr<FrameSource> source, Reference reference,
                                   const GrabberConfig& config)
    : source_(std::move(source)),
      config_(config),
      extractor_(std::move(reference), extractorConfig(config)),
      counters_(std::make_shared<Counters>()) {
  if (!source_) throw std::invalid_argument("MultiSlitGrabber: the source is null");
  if (!config_.intrinsics.empty()) {
    const Reference& ref = extractor_.reference();
    ref.checkLens(intrinsicsForImage(ref.image_width, ref.image_height, config_.intrinsics),
                  "MultiSlitGrabber: the reference");
  }
  rdmap_signal_ = createSignal<sig_cb_rdmap>();
  frame_signal_ = createSignal<sig_cb_frame>();
  status_signal_ = createSignal<sig_cb_status>();
  if (extractor_.reference().scale.valid()) xyz_signal_ = createSignal<sig_cb_xyz>();
}

MultiSlitGrabber::~MultiSlitGrabber() noexcept {
  stop();
  std::vector<std::shared_ptr<Run>> runs;
  {
    std::lock_guard<std::mutex> lock(control_mutex_);
    runs.swap(retired_);
  }
  const auto deadline = Clock::now() + std::chrono::milliseconds(config_.release_timeout_ms);
  for (const std::shared_ptr<Run>& run : runs) {
    const bool self = run->processing.get_id() == std::this_thread::get_id();
    std::unique_lock<std::mutex> lock(run->mutex);
    while (!self && !run->processing_done)
      run->changed.wait_for(lock, std::chrono::milliseconds(config_.poll_ms));
    run->changed.wait_until(lock, deadline, [&] { return run->acquisition_done; });
    const bool acquisition_done = run->acquisition_done;
    lock.unlock();
    if (run->processing.joinable()) self ? run->processing.detach() : run->processing.join();
    // A source call stuck beyond release_timeout_ms keeps only the run, source and counters.
    if (run->acquisition.joinable())
      acquisition_done ? run->acquisition.join() : run->acquisition.detach();
  }
  disconnect_all_slots<sig_cb_rdmap>();
  disconnect_all_slots<sig_cb_xyz>();
  disconnect_all_slots<sig_cb_frame>();
  disconnect_all_slots<sig_cb_status>();
}

void MultiSlitGrabber::start() {
  std::lock_guard<std::mutex> lock(control_mutex_);
  if (current_) return;
  // The source serves one run at a time: an earlier run's stop() may still be in it.
  const auto deadline = Clock::now() + std::chrono::milliseconds(config_.release_timeout_ms);
  for (const std::shared_ptr<Run>& run : retired_) {
    std::unique_lock<std::mutex> run_lock(run->mutex);
    if (!run->changed.wait_until(run_lock, deadline, [&] { return run->acquisition_done; }))
      PCL_THROW_EXCEPTION(pcl::IOException,
                          "[MultiSlitGrabber] " << source_->name() << " is still busy stopping");
  }
  reap();
  try {
    source_->start();
  } catch (const std::exception& e) {
    counters_->error(counters_->source_errors, source_->name() + ": " + e.what());
    PCL_THROW_EXCEPTION(pcl::IOException,
                        "[MultiSlitGrabber] cannot start " << source_->name() << ": " << e.what());
  }
  auto run = std::make_shared<Run>();
  run->acquisition = std::thread(acquisitionLoop, run, source_, counters_, config_.poll_ms);
  try {
    run->processing = std::thread([this, run] { processLoop(run); });
  } catch (const std::system_error& e) {
    {
      std::lock_guard<std::mutex> run_lock(run->mutex);
      run->stop = true;
    }
    source_->interrupt();
    run->acquisition.join();
    PCL_THROW_EXCEPTION(pcl::IOException, "[MultiSlitGrabber] no thread: " << e.what());
  }
  current_ = std::move(run);
}

void MultiSlitGrabber::stop() {
  std::shared_ptr<Run> run;
  bool self = false;
  {
    std::lock_guard<std::mutex> lock(control_mutex_);
    if (!current_) return;
    run = std::move(current_);
    current_.reset();
    retired_.push_back(run);
    self = run->processing.get_id() == std::this_thread::get_id();
  }
  run->raise(run->stop);
  source_->interrupt();

  // No callback runs after stop() returns, unless stop() was called from one (then the
  // processing thread ends after it and is joined later). The source gets stop_timeout_ms.
  const auto deadline = Clock::now() + std::chrono::milliseconds(config_.stop_timeout_ms);
  {
    std::unique_lock<std::mutex> lock(run->mutex);
    while (!self && !run->processing_done)
      run->changed.wait_for(lock, std::chrono::milliseconds(config_.poll_ms));
    run->changed.wait_until(lock, deadline, [&] { return run->acquisition_done; });
  }
  std::lock_guard<std::mutex> lock(control_mutex_);
  reap();
}

// Joins the threads of stopped runs that have ended; control_mutex_ is held.
void MultiSlitGrabber::reap() {
  const std::thread::id self = std::this_thread::get_id();
  for (const std::shared_ptr<Run>& run : retired_) {
    bool processing_done = false, acquisition_done = false;
    {
      std::lock_guard<std::mutex> lock(run->mutex);
      processing_done = run->processing_done;
      acquisition_done = run->acquisition_done;
    }
    if (processing_done && run->processing.joinable() && run->processing.get_id() != self)
      run->processing.join();
    if (acquisition_done && run->acquisition.joinable()) run->acquisition.join();
  }
  retired_.erase(std::remove_if(retired_.begin(), retired_.end(),
                                [](const std::shared_ptr<Run>& run) {
                                  return !run->processing.joinable() &&
                                         !run->acquisition.joinable();
                                }),
                 retired_.end());
}

bool MultiSlitGrabber::isRunning() const {
  std::lock_guard<std::mutex> lock(control_mutex_);
  if (!current_) return false;
  std::lock_guard<std::mutex> run_lock(current_->mutex);
  return !(current_->acquisition_done && current_->processing_done);
}

float MultiSlitGrabber::getFramesPerSecond() const { return static_cast<float>(counters_->fps()); }

GrabberStats MultiSlitGrabber::getStats() const {
  GrabberStats s;
  s.frames_received = counters_->received;
  s.frames_processed = counters_->processed;
  s.frames_dropped = counters_->dropped;
  s.source_errors = counters_->source_errors;
  s.extraction_errors = counters_->extraction_errors;
  s.callback_errors = counters_->callback_errors;
  s.frames_per_second = counters_->fps();
  std::tie(s.latency_median_ms, s.latency_p99_ms) = counters_->latencyPercentiles();
  s.source = source_->stats();
  s.connected = source_->connected();
  s.last_error = counters_->lastError();
  return s;
}

// The processing thread: mailbox -> extraction -> callbacks.
void MultiSlitGrabber::processLoop(const std::shared_ptr<Run>& run) {
  const auto poll = std::chrono::milliseconds(config_.poll_ms);
  SourceStatus said;  // what the status signal said last: connected, no new error
  said.error = counters_->lastError();
  std::string source_error = source_->lastError();
  for (;;) {
    reportStatus(said, source_error);
    std::optional<Frame> frame;
    {
      std::unique_lock<std::mutex> lock(run->mutex);
      run->changed.wait_for(lock, poll, [&] {
        return run->stop || run->mailbox || run->acquisition_done || run->status_changed;
      });
      run->status_changed = false;  // reportStatus() at the top of the loop tells it
      if (run->stop) break;
      if (!run->mailbox) {
        if (run->acquisition_done) break;
        continue;
      }
      frame = std::move(run->mailbox);
      run->mailbox.reset();
    }
    run->changed.notify_all();  // a source that is not live may now read the next frame
    try {
      process(*frame, *run);
    } catch (...) {
      ++counters_->callback_errors;  // a callback threw; the thread goes on
    }
  }
  run->raise(run->processing_done);
}

// Takes up a new error of the source (`source_error`: the last one seen), then fires the status
// signal when the connection or the latest error changed since `said`.
void MultiSlitGrabber::reportStatus(SourceStatus& said, std::string& source_error) {
  std::string from_source = source_->lastError();
  if (from_source != source_error) {
    source_error = std::move(from_source);
    if (!source_error.empty()) counters_->note(source_->name() + ": " + source_error);
  }
  const bool connected = source_->connected();
  std::string error = counters_->lastError();
  if (connected == said.connected && error == said.error) return;
  said.connected = connected;
  said.error = std::move(error);
  if (status_signal_->num_slots() == 0) return;
  const SourceStats stats = source_->stats();
  said.losses = stats.losses;
  said.reconnects = stats.reconnects;
  said.source = source_->name();
  try {
    (*status_signal_)(said);
  } catch (...) {
    ++counters_->callback_errors;
  }
}

void MultiSlitGrabber::process(Frame& frame, Run& run) {
  auto stopping = [&run] {
    std::lock_guard<std::mutex> lock(run.mutex);
    return run.stop;
  };
  const bool want_rdmap = num_slots<sig_cb_rdmap>() > 0;
  const bool want_xyz = xyz_signal_ != nullptr && num_slots<sig_cb_xyz>() > 0;
  const bool want_frame = num_slots<sig_cb_frame>() > 0;

  pcl::PointCloud<PointRDM>::Ptr rdmap;
  if (want_rdmap || want_xyz) {
    try {
      rdmap =
          extractor_.extract(frame.image, frame.stamp_us, static_cast<std::uint32_t>(frame.seq));
    } catch (const std::exception& e) {  // the image does not fit the reference
      counters_->error(counters_->extraction_errors,
                       std::string("frames do not fit the calibration: ") + e.what());
    }
  }
  const Clock::time_point now = Clock::now();
  counters_->record(now, std::chrono::duration<double, std::milli>(now - frame.arrival).count());

  // stop() during the extraction: the frame goes to no callback and is not counted as processed
  // (frames_processed counts frames handed to the callbacks).
  if (stopping()) return;
  if (want_frame) (*frame_signal_)(std::make_shared<const Frame>(std::move(frame)));
  if (rdmap && want_rdmap) (*rdmap_signal_)(rdmap);
  if (rdmap && want_xyz && !stopping()) (*xyz_signal_)(toXYZ(*rdmap));  // a callback may stop
  ++counters_->processed;
}

}  // namespace multislit
