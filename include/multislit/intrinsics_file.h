// A camera calibration made elsewhere: OpenCV's calibrateCamera YAML or a ROS camera_info YAML.
#pragma once

#include "multislit/sensor.h"

#include <string>

namespace multislit {

/// `camera` with the focal length, principal point and distortion of the calibration file at
/// `path`, which is one of
///  - OpenCV's (calibrateCamera's sample writes it): image_width, image_height, camera_matrix and
///    distortion_coefficients as !!opencv-matrix (4, 5 or 8 coefficients; the thin prism and
///    tilt terms of 12 or 14 must be zero);
///  - ROS camera_info: image_width, image_height, camera_matrix {rows, cols, data},
///    distortion_model plumb_bob or rational_polynomial and distortion_coefficients {data}.
/// The pixels are square in this sensor's model: fx and fy may differ by at most
/// kMaxFocalMismatch of their mean, which is used. The image size must be the camera's. Throws
/// std::invalid_argument naming the file and the key (std::runtime_error when it cannot be read).
CameraConfig withIntrinsicsFile(const CameraConfig& camera, const std::string& path);

/// The calibration file's intrinsics for a camera whose images are width x height (its focal
/// length in pixels as read; the pixel size is the default camera's).
CameraConfig intrinsicsForImage(int width, int height, const std::string& path);

/// Largest relative difference of fx and fy a calibration may have: more than the scatter of a
/// good calibration of square pixels.
constexpr double kMaxFocalMismatch = 0.01;

}  // namespace multislit
