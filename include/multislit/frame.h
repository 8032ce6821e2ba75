// One camera image as it leaves a FrameSource (camera, recorded files or the simulator).
#pragma once

#include <opencv2/core/mat.hpp>

#include <chrono>
#include <cstdint>
#include <string>

namespace multislit {

/// Which clock a frame's stamp_us comes from.
enum class StampSource {
  Host,   ///< the host's clock when the frame arrived (or a file's, or a synthetic, stamp)
  Camera  ///< the camera's own clock at exposure, synchronized to the epoch by PTP (IEEE 1588)
};
const char* stampSourceName(StampSource source);

/// A frame's time stamp from the camera's timestamp (`camera_ns`, 0: none) and the host's
/// arrival time (`host_ns`), both [ns]: the camera's when its clock is PTP-synchronized (it then
/// counts from the epoch; else it counts from the camera's power-up), less `camera_lead_ns`, the
/// camera clock's lead over UTC (37 s on a PTP clock on TAI); the host's otherwise.
struct FrameStamp {
  std::uint64_t stamp_us = 0;  ///< [us since the epoch, UTC]
  StampSource source = StampSource::Host;
};
FrameStamp chooseFrameStamp(bool camera_clock_synchronized, std::uint64_t camera_ns,
                            std::uint64_t host_ns, std::int64_t camera_lead_ns);

/// TAI - UTC since 1 January 2017 (no leap second announced since) [s]: how far a PTP clock on
/// its default time scale, TAI, runs ahead of the Unix epoch's UTC.
inline constexpr double kTaiUtcOffsetS = 37.0;

/// The stamps' time base in words, for summaries: "camera PTP clock, TAI-UTC offset 37 s
/// applied" (the camera's clock, `camera_lead_s` [s] subtracted) or "host clock".
std::string timeBaseText(StampSource source, double camera_lead_s);

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
