// FrameSource: the interruptible waits every source shares.
#include "multislit/sources.h"

#include <utility>

namespace multislit {

const char* stampSourceName(StampSource source) {
  return source == StampSource::Camera ? "camera (PTP)" : "host";
}

FrameStamp chooseFrameStamp(bool camera_clock_synchronized, std::uint64_t camera_ns,
                            std::uint64_t host_ns) {
  if (camera_clock_synchronized && camera_ns > 0) return {camera_ns / 1000, StampSource::Camera};
  return {host_ns / 1000, StampSource::Host};
}

std::string FrameSource::lastError() const {
  std::lock_guard<std::mutex> lock(error_mutex_);
  return last_error_;
}

void FrameSource::setLastError(std::string what) {
  std::lock_guard<std::mutex> lock(error_mutex_);
  last_error_ = std::move(what);
}

void FrameSource::interrupt() {
  {
    std::lock_guard<std::mutex> lock(wait_mutex_);
    interrupted_ = true;
  }
  wait_cv_.notify_all();
}

void FrameSource::trigger() {
  {
    std::lock_guard<std::mutex> lock(wait_mutex_);
    ++triggers_;
  }
  wait_cv_.notify_all();
}

void FrameSource::resetWaits() {
  std::lock_guard<std::mutex> lock(wait_mutex_);
  interrupted_ = false;
  triggers_ = 0;
}

bool FrameSource::interrupted() const {
  std::lock_guard<std::mutex> lock(wait_mutex_);
  return interrupted_;
}

bool FrameSource::sleepUntil(Clock::time_point deadline) {
  std::unique_lock<std::mutex> lock(wait_mutex_);
  wait_cv_.wait_until(lock, deadline, [this] { return interrupted_; });
  return !interrupted_;
}

bool FrameSource::waitUntilDue(Clock::time_point start, std::uint64_t index, double fps,
                               Clock::time_point deadline) {
  const auto due = start + std::chrono::duration_cast<Clock::duration>(
                               std::chrono::duration<double>(static_cast<double>(index) / fps));
  if (due > deadline) {
    sleepUntil(deadline);
    return false;
  }
  return sleepUntil(due);
}

bool FrameSource::takeTrigger(Clock::time_point deadline) {
  std::unique_lock<std::mutex> lock(wait_mutex_);
  wait_cv_.wait_until(lock, deadline, [this] { return interrupted_ || triggers_ > 0; });
  if (interrupted_ || triggers_ == 0) return false;
  --triggers_;
  return true;
}

}  // namespace multislit
