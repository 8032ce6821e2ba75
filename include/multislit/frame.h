// One camera image as it leaves a FrameSource (camera, recorded files or the simulator).
#pragma once

#include <opencv2/core/mat.hpp>

#include <chrono>
#include <cstdint>

namespace multislit {

/// An 8- or 16-bit one-channel image with its time and number. The image owns its pixels.
struct Frame {
  cv::Mat image;               ///< CV_8UC1 or CV_16UC1
  std::uint64_t stamp_us = 0;  ///< when it was taken, microseconds since the epoch [us]
  std::uint64_t seq = 0;       ///< the source's frame number: camera frame id, file index, ...
  std::chrono::steady_clock::time_point arrival{};  ///< when the host received it (latency)
};

}  // namespace multislit
