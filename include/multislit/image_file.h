// Reading a camera image from a file: its size checked in the file's header before it is decoded
// (a 1.7 MB PNG may hold 30000 x 30000 pixels), its type checked after.
#pragma once

#include <opencv2/core/mat.hpp>

#include <optional>
#include <string>

namespace multislit {

/// Largest image side the library takes [px]: 4x the paper's camera, a 16k sensor. Sensor files,
/// calibrations and image files are all held to it.
constexpr int kMaxImageSide = 16384;

/// Width and height from the header of a PNG, PNM (P1-P6), BMP, TIFF or JPEG file, without
/// decoding it; std::nullopt when the file is none of these or its header is cut.
std::optional<cv::Size> imageFileSize(const std::string& path);

/// Reads an 8- or 16-bit one-channel image. Throws std::runtime_error naming the file when it is
/// missing, not one of the formats above, larger than kMaxImageSide on a side (read from the
/// header: nothing is decoded), a colour PNG (from the header too), corrupt, or of another type.
cv::Mat readMonoImage(const std::string& path);
/// The same, also refused before decoding when the header's size is not `expected` (the
/// calibration's camera: a frame of another size could not be used, and decoding it first took
/// its whole memory).
cv::Mat readMonoImage(const std::string& path, std::optional<cv::Size> expected);

}  // namespace multislit
