// A GigE Vision camera on 127.0.0.1 that serves our own images (Aravis's fake camera): what the
// tests, the demos and `multislit emulate` open exactly as they would open the real sensor.
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace multislit {

/// Aravis's GigE Vision fake camera on 127.0.0.1 (GVCP port 3956) serving images in turn: the
/// frame with camera frame id k carries image imageIndex(k). For tests, demos and
/// `multislit emulate`; it answers on the loopback interface only. Its PixelFormat takes Mono8,
/// Mono12 (the images scaled to 0..4095 in 16 bits) and Mono16.
struct EmulatorConfig {
  std::string serial = "MULTISLIT";  ///< device serial number (at most 15 characters)
  double fps = 30.0;                 ///< frame rate until a client sets its own [Hz]
  double lost_packet_ratio = 0.0;    ///< fraction of stream packets not sent [-]
  /// Send the images' own pixel format whatever the client sets, as a camera whose PixelFormat
  /// does not take: the client reads back its own setting, but the frames come in the images'
  /// format (a frame made in another is not sent). Only a format no larger than the client's
  /// can come: Mono8 images to a client asking Mono16.
  bool keep_pixel_format = false;
  /// Announce a clock that PTP synchronizes (PtpEnable on, PtpStatus Slave), as a camera a
  /// grandmaster sets: clients take its frames' timestamps as time since the epoch.
  bool ptp = false;
  /// How far the camera's clock runs ahead of the host's (UTC) clock, added to every frame's
  /// timestamp [s]: 37 is a PTP clock on TAI. In [-86400, 86400].
  double clock_offset_s = 0.0;

  void validate() const;  ///< throws std::invalid_argument naming the field
};

class CameraEmulator {
 public:
  static constexpr const char* kAddress = "127.0.0.1";
  /// Live images kept ready unless told otherwise: enough for a maker that keeps up.
  static constexpr std::size_t kDefaultAhead = 3;

  /// `images`: one or more images of the same size and type (CV_8UC1 or CV_16UC1). Throws
  /// std::invalid_argument for bad images, std::runtime_error when 127.0.0.1:3956 is taken.
  explicit CameraEmulator(std::vector<cv::Mat> images, const EmulatorConfig& config = {});
  /// Makes the next image of an endless sequence (on the emulator's own thread).
  using ImageMaker = std::function<cv::Mat()>;
  /// Live: the images are made on the fly by `make`, each of `size` and `type`, on a thread of
  /// the emulator's that keeps up to `ahead` of them ready; every frame sent takes the next one,
  /// or, when none is ready in time, the last one again (counted by framesLate()). An image of
  /// another size or type ends the making (lastError()).
  CameraEmulator(ImageMaker make, cv::Size size, int type, const EmulatorConfig& config = {},
                 std::size_t ahead = kDefaultAhead);
  ~CameraEmulator();
  CameraEmulator(const CameraEmulator&) = delete;
  CameraEmulator& operator=(const CameraEmulator&) = delete;

  std::size_t imageIndex(std::uint64_t frame_id) const;
  /// The same for any emulator serving `image_count` images (one that is gone, or not yet made).
  static std::size_t imageIndex(std::uint64_t frame_id, std::size_t image_count);
  std::uint64_t framesServed() const;
  /// Live: the frames sent with the last image again because the next was not made in time.
  std::uint64_t framesLate() const;
  /// Live: the images made so far, and why the making stopped ("" while it goes on).
  std::uint64_t imagesMade() const;
  /// Live: the images made and not yet sent (a camera no client streams from sends none, so they
  /// pile up to `ahead`); else every image.
  std::size_t imagesReady() const;
  /// Live: keep up to `ahead` images ready from now on (at least 1); else nothing.
  void setImagesAhead(std::size_t ahead);
  std::string lastError() const;
  /// 1 makes a camera that answers control requests but sends no image; from the next frame.
  void setLostPacketRatio(double ratio);

 private:
  void start(cv::Size size, int type, const EmulatorConfig& config);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace multislit
