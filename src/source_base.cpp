// FrameSource: the interruptible waits every source shares.
#include "multislit/sources.h"

#include <cstdio>
#include <utility>

namespace multislit {

const char* stampSourceName(StampSource source) {
  return source == StampSource::Camera ? "camera (PTP)" : "host";
}

FrameStamp chooseFrameStamp(bool camera_clock_synchronized, std::uint64_t camera_ns,
                            std::uint64_t host_ns, std::int64_t camera_lead_ns) {
  if (camera_clock_synchronized && camera_ns > 0) {
    const auto utc_ns = static_cast<std::int64_t>(camera_ns) - camera_lead_ns;
    if (utc_ns > 0) return {static_cast<std::uint64_t>(utc_ns) / 1000, StampSource::Camera};
  }
  return {host_ns / 1000, StampSource::Host};
}

std::string timeBaseText(StampSource source, double camera_lead_s) {
  if (source == StampSource::Host) return "host clock";
  if (camera_lead_s == 0) return "camera PTP clock, taken as UTC (no offset applied)";
  char text[96];
  std::snprintf(text, sizeof text, "camera PTP clock, %s offset %g s applied",
                camera_lead_s == kTaiUtcOffsetS ? "TAI-UTC" : "UTC", camera_lead_s);
  return text;
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
