// Opening and setting up a camera for AravisSource (private to the library): the device by
// address or USB identity, never by discovery; its identity, region and pixel format checked
// against what was asked, with errors that name both.
#pragma once

#include "aravis_util.h"
#include "multislit/sources.h"

#include <string>

namespace multislit::aravis {

/// The frames an opened camera was set to send; buffers of another shape are refused.
struct FrameShape {
  int width = 0, height = 0;  ///< [px]
  ArvPixelFormat format = 0;
};
/// "1296x964 Mono8".
std::string describe(const FrameShape& shape);

bool isUsb(const std::string& camera);
/// The device at `camera` (an IPv4 address or usb3:VENDOR:MODEL:SERIAL); throws
/// std::runtime_error when it does not answer, std::invalid_argument for a bad address.
GPtr<ArvDevice> openDevice(const std::string& camera);
/// Whether the camera's clock is synchronized by PTP (IEEE 1588).
bool ptpSynchronized(ArvDevice* device);
/// Throws std::runtime_error naming both unless the camera is config.camera_id (when set).
void checkCameraId(ArvCamera* camera, const AravisConfig& config);
/// Acquisition mode, pixel format, region, exposure, gain, rate or trigger and packet size, as
/// the config asks; returns the frames' shape. Throws std::runtime_error naming the feature the
/// camera refused, or what was asked and what the camera took when it took something else.
FrameShape configureCamera(ArvCamera* camera, const AravisConfig& config);

}  // namespace multislit::aravis
