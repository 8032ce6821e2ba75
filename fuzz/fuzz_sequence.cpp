// Fuzz target: the frames.csv of a recorded sequence (ImageSequenceSource: the file list, the
// stamps of frames.csv and of the file names), in a folder that also holds two small PNG frames,
// then the first frames played twice over (repeat on).
#include "fuzz_support.h"

#include "multislit/sources.h"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <stdexcept>

using namespace multislit;

namespace {

/// At most this many next() calls per input: frames.csv may list thousands of files.
constexpr std::uint64_t kMaxReads = 6;

const std::filesystem::path& sequenceDir() {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path d = fuzz::scratchDir() / "sequence";
    std::filesystem::create_directories(d);
    const cv::Mat frame(24, 32, CV_8UC1, cv::Scalar(40));
    cv::imwrite((d / "frame_000000.png").string(), frame);
    cv::imwrite((d / "frame_20261123T120000.123456.png").string(), frame);
    return d;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path& dir = sequenceDir();
  fuzz::writeInput("sequence/frames.csv", data, size);
  ImageSequenceConfig config;
  config.folder = dir.string();
  config.repeat = true;
  ImageSequenceSource source(config);
  try {
    source.start();
  } catch (const std::runtime_error&) {
    return 0;  // no files listed (frames.csv names none and there are PNGs: never)
  }
  const std::uint64_t n = source.files().size();
  fuzz::expect(n > 0 && source.stamps().size() == n, "one stamp per file");
  const std::uint64_t reads = std::min<std::uint64_t>(kMaxReads, 2 * n);
  for (std::uint64_t k = 0; k < reads; ++k) {
    const auto frame = source.next(std::chrono::milliseconds(0));
    if (frame) fuzz::expect(frame->seq == k, "seq is the position in the sequence");
  }
  const SourceStats stats = source.stats();
  fuzz::expect(stats.frames + stats.read_errors == reads, "every read a frame or an error");
  return 0;
}
