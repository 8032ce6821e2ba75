// The counts a MultiSlitGrabber keeps (private to grabber.cpp): frames, errors, the processed
// frames' times for the rate, and a ring of latencies for the percentiles. Shared with the
// grabber's threads; it outlives a source call that hangs.
#pragma once

#include "multislit/grabber.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace multislit {

struct MultiSlitGrabber::Counters {
  using Clock = std::chrono::steady_clock;
  static constexpr std::size_t kLatencyWindow = 256;  // frames kept for the percentiles

  std::atomic<std::uint64_t> received{0}, processed{0}, dropped{0}, source_errors{0},
      extraction_errors{0}, callback_errors{0};
  std::mutex timing_mutex;
  std::deque<Clock::time_point> done;  // when frames were processed, the last two seconds
  std::vector<double> latency_ms;      // ring of the last kLatencyWindow latencies
  std::size_t latency_next = 0;
  std::string last_error;  // the latest source or extraction error (guarded by timing_mutex)

  void error(std::atomic<std::uint64_t>& count, const std::string& what) {
    ++count;
    note(what);
  }

  void note(const std::string& what) {
    std::lock_guard<std::mutex> lock(timing_mutex);
    last_error = what;
  }

  std::string lastError() {
    std::lock_guard<std::mutex> lock(timing_mutex);
    return last_error;
  }

  void record(Clock::time_point now, double latency) {
    std::lock_guard<std::mutex> lock(timing_mutex);
    done.push_back(now);
    while (!done.empty() && now - done.front() > std::chrono::seconds(2)) done.pop_front();
    if (latency_ms.size() < kLatencyWindow)
      latency_ms.push_back(latency);
    else
      latency_ms[latency_next] = latency;
    latency_next = (latency_next + 1) % kLatencyWindow;
  }

  // Frames per second over the last second; over the last two frames when slower than 1 Hz.
  double fps() {
    std::lock_guard<std::mutex> lock(timing_mutex);
    const Clock::time_point now = Clock::now();
    while (!done.empty() && now - done.front() > std::chrono::seconds(2)) done.pop_front();
    const auto first = std::find_if(done.begin(), done.end(), [&](Clock::time_point t) {
      return now - t <= std::chrono::seconds(1);
    });
    const auto in_window = std::distance(first, done.end());
    auto seconds = [](Clock::duration d) { return std::chrono::duration<double>(d).count(); };
    if (in_window >= 2) return static_cast<double>(in_window - 1) / seconds(done.back() - *first);
    if (done.size() >= 2) return 1.0 / seconds(done.back() - done[done.size() - 2]);
    return 0.0;
  }

  std::pair<double, double> latencyPercentiles() {
    std::vector<double> v;
    {
      std::lock_guard<std::mutex> lock(timing_mutex);
      v = latency_ms;
    }
    if (v.empty()) return {0.0, 0.0};
    auto at = [&v](double q) {
      const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5);
      std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
      return v[k];
    };
    const double median = at(0.5);
    return {median, at(0.99)};
  }
};

}  // namespace multislit
