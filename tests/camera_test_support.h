// Shared by the tests that wait for frames and open the emulated GigE Vision camera on 127.0.0.1
// (grabber_test, sources_test): clocks, generous deadlines, and an emulator that waits its turn
// for port 3956.
#pragma once

#include "multislit/sim/camera_emulator.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <thread>
#include <vector>

namespace multislit::test {

using Clock = std::chrono::steady_clock;

// Deadline of the waits for something to happen: generous for a loaded 2-core machine with
// sanitizers; the waits end as soon as it happened, so it costs nothing when all is well.
constexpr double kDeadlineMs = 20000;

inline double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

inline std::uint64_t nowMicros() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}

/// Polls `done` until it holds or `ms` passed.
inline bool waitFor(const std::function<bool()>& done, double ms = kDeadlineMs) {
  const auto t0 = Clock::now();
  while (!done() && msSince(t0) < ms) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  return done();
}

/// The emulator binds 127.0.0.1:3956; another test process may hold it for a while: `make` is
/// tried for 30 s, then nullptr (see REQUIRE_EMULATOR).
template <typename Make>
std::unique_ptr<CameraEmulator> whenPortIsFree(const Make& make) {
  const auto deadline = Clock::now() + std::chrono::seconds(30);
  for (;;) {
    try {
      return make();
    } catch (const std::runtime_error&) {
      if (Clock::now() > deadline) return nullptr;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  }
}

/// An emulator serving `images` in turn, once the port is free.
inline std::unique_ptr<CameraEmulator> makeEmulator(const std::vector<cv::Mat>& images,
                                                    const EmulatorConfig& config = {}) {
  return whenPortIsFree([&] { return std::make_unique<CameraEmulator>(images, config); });
}

/// The same with live images (CameraEmulator's ImageMaker), up to `ahead` of them kept ready.
inline std::unique_ptr<CameraEmulator> makeLiveEmulator(
    const CameraEmulator::ImageMaker& make, cv::Size size,
    std::size_t ahead = CameraEmulator::kDefaultAhead) {
  return whenPortIsFree([&] {
    return std::make_unique<CameraEmulator>(make, size, CV_8UC1, EmulatorConfig{}, ahead);
  });
}

}  // namespace multislit::test

#define REQUIRE_EMULATOR(emulator)                                                       \
  if (!(emulator))                                                                       \
  GTEST_SKIP() << "127.0.0.1:3956 stayed taken by another GigE Vision camera for 30 s, " \
                  "so the fake camera could not start"
