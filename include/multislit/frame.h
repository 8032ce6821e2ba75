// One camera image as it leaves a FrameSource (camera, recorded files or the simulator).
#pragma once

#include <opencv2/core/mat.hpp>

#include <chrono>
#include <cstdint>

namespace multislit {

/// Which clock a frame's stamp_us comes from.
enum class StampSource {
  Host,   ///< the host's clock when the frame arrived (or a file's, or a synthetic, stamp)
  Camera  ///< the camera's own clock at exposure, synchronized to the epoch by PTP (IEEE 1588)
};
const char* stampSourceName(StampSource source);

/// A frame's time stamp from the camera's timestamp (`camera_ns`, 0: none) and the host's
/// arrival time (`host_ns`), both [ns]: the camera's when its clock is PTP-synchronized (it then
/// counts from the epoch; else it counts from the camera's power-up), the host's otherwise.
struct FrameStamp {
  std::uint64_t stamp_us = 0;  ///< [us since the epoch]
  StampSource source = StampSource::Host;
};
FrameStamp chooseFrameStamp(bool camera_clock_synchronized, std::uint64_t camera_ns,
                            std::uint64_t host_ns);

/// An 8- or 16-bit one-channel image with its time and number. The image owns its pixels.
struct Frame {
  cv::Mat image;               ///< CV_8UC1 or CV_16UC1
  std::uint64_t stamp_us = 0;  ///< when it was taken, microseconds since the epoch [us]
  std::uint64_t seq = 0;       ///< the source's frame number: camera frame id, file index, ...
  std::chrono::steady_clock::time_point arrival{};  ///< when the host received it (latency)
  StampSource stamp_source = StampSource::Host;     ///< the clock of stamp_us
  /// The camera's own timestamp of the exposure on its own clock (GigE Vision / USB3 Vision
  /// leader, the clock of ChunkTimestamp); 0: none (files, the simulator). [ns]
  std::uint64_t camera_stamp_ns = 0;
};

}  // namespace multislit
