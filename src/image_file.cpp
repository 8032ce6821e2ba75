// Image file headers (PNG, PNM, BMP, TIFF, JPEG): the size of an image before it is decoded.
#include "multislit/image_file.h"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace multislit {
namespace {

/// Random access to a file's bytes; a read past its end gives false. Reads are served from a
/// block of the file held in memory: a header is read a few bytes at a time (a TIFF directory of
/// 65535 entries, a PNM's digits), and a seek and read of the file for each cost system calls.
class Bytes {
 public:
  explicit Bytes(const std::string& path) : in_(path, std::ios::binary) {}
  bool read(std::uint64_t offset, std::size_t n, std::uint8_t* out) {
    if (offset < start_ || offset + n > start_ + held_) {  // not in the block: read the next one
      in_.clear();
      in_.seekg(static_cast<std::streamoff>(offset));
      in_.read(reinterpret_cast<char*>(block_.data()), static_cast<std::streamsize>(block_.size()));
      start_ = offset;
      held_ = static_cast<std::size_t>(std::max<std::streamsize>(in_.gcount(), 0));
    }
    if (offset + n > start_ + held_) return false;
    std::copy_n(block_.begin() + static_cast<std::ptrdiff_t>(offset - start_), n, out);
    return true;
  }
  /// An unsigned integer of n (<= 4) bytes, big- or little-endian; nullopt past the end.
  std::optional<std::uint32_t> number(std::uint64_t offset, std::size_t n, bool big_endian) {
    std::array<std::uint8_t, 4> b{};
    if (!read(offset, n, b.data())) return std::nullopt;
    std::uint32_t v = 0;
    for (std::size_t k = 0; k < n; ++k)
      v |= std::uint32_t{b[big_endian ? k : n - 1 - k]} << (8 * (n - 1 - k));
    return v;
  }

 private:
  std::ifstream in_;
  std::array<std::uint8_t, 4096> block_{};  ///< the file's bytes from start_, held_ of them
  std::uint64_t start_ = 0;
  std::size_t held_ = 0;
};

std::optional<cv::Size> sizeOf(std::optional<std::uint32_t> w, std::optional<std::uint32_t> h) {
  if (!w || !h) return std::nullopt;
  // Sizes over 2^31 are clamped: they are refused as too large all the same.
  const auto clamp = [](std::uint32_t v) {
    return static_cast<int>(std::min<std::uint32_t>(v, 1u << 30));
  };
  return cv::Size(clamp(*w), clamp(*h));
}

std::optional<cv::Size> pngSize(Bytes& f) {
  return sizeOf(f.number(16, 4, true), f.number(20, 4, true));
}

std::optional<cv::Size> bmpSize(Bytes& f) {
  const auto w = f.number(18, 4, false), h = f.number(22, 4, false);
  if (!w || !h) return std::nullopt;
  const auto magnitude = [](std::uint32_t v) {  // a negative height is a top-down bitmap
    const auto s = static_cast<std::int32_t>(v);
    return static_cast<std::uint32_t>(s < 0 ? -static_cast<std::int64_t>(s) : s);
  };
  return sizeOf(magnitude(*w), magnitude(*h));
}

/// P1-P6: the magic, then width and height in decimal between white space and # comments.
std::optional<cv::Size> pnmSize(Bytes& f) {
  std::array<std::uint32_t, 2> values{};
  std::uint64_t at = 2;
  for (std::uint32_t& value : values) {
    std::uint8_t c = 0;
    for (;;) {  // white space and comments
      if (!f.read(at, 1, &c)) return std::nullopt;
      if (c == '#') {
        while (c != '\n' && f.read(++at, 1, &c)) {
        }
      } else if (!std::isspace(c)) {
        break;
      }
      ++at;
    }
    int digits = 0;
    for (value = 0; std::isdigit(c) && digits < 10; ++digits, ++at) {
      value = std::min<std::uint32_t>(value * 10 + static_cast<std::uint32_t>(c - '0'), 1u << 30);
      if (!f.read(at + 1, 1, &c)) break;
    }
    if (digits == 0) return std::nullopt;
  }
  return sizeOf(values[0], values[1]);
}

/// Classic TIFF: the first directory's ImageWidth (256) and ImageLength (257) tags.
std::optional<cv::Size> tiffSize(Bytes& f, bool big_endian) {
  const auto ifd = f.number(4, 4, big_endian);
  const auto count = ifd ? f.number(*ifd, 2, big_endian) : std::nullopt;
  if (!count) return std::nullopt;
  std::optional<std::uint32_t> width, height;
  for (std::uint32_t k = 0; k < *count; ++k) {
    const std::uint64_t entry = *ifd + 2 + 12ull * k;
    const auto tag = f.number(entry, 2, big_endian), type = f.number(entry + 2, 2, big_endian);
    if (!tag || !type) return std::nullopt;
    if (*tag != 256 && *tag != 257) continue;
    const auto value = f.number(entry + 8, *type == 3 ? 2 : 4, big_endian);
    (*tag == 256 ? width : height) = value;
  }
  return sizeOf(width, height);
}

/// JPEG: the segments up to the first start-of-frame marker, which holds the size.
std::optional<cv::Size> jpegSize(Bytes& f) {
  std::uint64_t at = 2;
  for (int segment = 0; segment < 10000; ++segment) {
    const auto marker = f.number(at, 2, true);
    if (!marker || (*marker >> 8) != 0xFF) return std::nullopt;
    const std::uint32_t m = *marker & 0xFF;
    if (m == 0xD8 || m == 0x01 || (m >= 0xD0 && m <= 0xD7)) {  // no length
      at += 2;
      continue;
    }
    const auto length = f.number(at + 2, 2, true);
    if (!length) return std::nullopt;
    if (m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC)
      return sizeOf(f.number(at + 7, 2, true), f.number(at + 5, 2, true));
    at += 2 + *length;
  }
  return std::nullopt;
}

}  // namespace

std::optional<cv::Size> imageFileSize(const std::string& path) {
  Bytes f(path);
  std::array<std::uint8_t, 8> magic{};
  if (!f.read(0, magic.size(), magic.data())) return std::nullopt;
  constexpr std::array<std::uint8_t, 8> kPng{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (magic == kPng) return pngSize(f);
  if (magic[0] == 'B' && magic[1] == 'M') return bmpSize(f);
  if (magic[0] == 'P' && magic[1] >= '1' && magic[1] <= '6') return pnmSize(f);
  if (magic[0] == 'I' && magic[1] == 'I' && magic[2] == 42 && magic[3] == 0)
    return tiffSize(f, false);
  if (magic[0] == 'M' && magic[1] == 'M' && magic[2] == 0 && magic[3] == 42)
    return tiffSize(f, true);
  if (magic[0] == 0xFF && magic[1] == 0xD8) return jpegSize(f);
  return std::nullopt;
}

namespace {

/// A PNG's colour type (IHDR byte 25: 0 grey, 2 RGB, 3 palette, 4 grey + alpha, 6 RGBA); nullopt
/// for other formats.
std::optional<int> pngColourType(const std::string& path) {
  Bytes f(path);
  std::array<std::uint8_t, 26> head{};
  if (!f.read(0, head.size(), head.data()) || head[1] != 'P' || head[2] != 'N' || head[3] != 'G')
    return std::nullopt;
  return head[25];
}

/// The size in the header of `path`, checked before anything is decoded: a file, of a known
/// format, at most kMaxImageSide a side, `expected` when given, and not a colour PNG.
void checkBeforeDecoding(const std::string& path, std::optional<cv::Size> expected) {
  std::error_code error;
  const std::filesystem::file_status status = std::filesystem::status(path, error);
  if (!std::filesystem::exists(status))
    throw std::runtime_error("image '" + path + "' " +
                             (status.type() == std::filesystem::file_type::not_found
                                  ? std::string("does not exist")
                                  : "cannot be read: " + error.message()));
  if (!std::filesystem::is_regular_file(status))  // a folder, FIFO or device: never opened
    throw std::runtime_error("image '" + path + "' is not a file (a folder, pipe or device)");
  const std::optional<cv::Size> size = imageFileSize(path);
  if (!size)
    throw std::runtime_error("image '" + path +
                             "' is corrupt or not a PNG, PNM, BMP, TIFF or JPEG image");
  const std::string px = std::to_string(size->width) + "x" + std::to_string(size->height) + " px";
  if (size->width > kMaxImageSide || size->height > kMaxImageSide)
    throw std::runtime_error("image '" + path + "' is " + px + ", more than the limit of " +
                             std::to_string(kMaxImageSide) + " px a side");
  if (expected && *size != *expected)
    throw std::runtime_error("image '" + path + "' is " + px + ", not the calibration's " +
                             std::to_string(expected->width) + "x" +
                             std::to_string(expected->height) + " px");
  const std::optional<int> colour = pngColourType(path);
  if (colour && *colour != 0)  // decoding would take 3 or 4 times the memory of grey first
    throw std::runtime_error("image '" + path + "' must be 8- or 16-bit grey (one channel), not " +
                             "a colour PNG (colour type " + std::to_string(*colour) + ")");
}

}  // namespace

cv::Mat readMonoImage(const std::string& path) { return readMonoImage(path, std::nullopt); }

cv::Mat readMonoImage(const std::string& path, std::optional<cv::Size> expected) {
  checkBeforeDecoding(path, expected);
  cv::Mat image;
  try {
    image = cv::imread(path, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw std::runtime_error("image '" + path + "' cannot be decoded: " + e.err);
  }
  if (image.empty()) throw std::runtime_error("image '" + path + "' is corrupt or not an image");
  if (image.channels() != 1 || (image.depth() != CV_8U && image.depth() != CV_16U))
    throw std::runtime_error("image '" + path + "' must be 8- or 16-bit grey (one channel), not " +
                             std::to_string(image.channels()) + " channel(s) of depth " +
                             std::to_string(image.depth()));
  return image;
}

}  // namespace multislit
