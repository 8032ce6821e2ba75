// Fuzz target: the image loader alone (readMonoImage: the size from the header, OpenCV's
// decoders, then the checks of a one-channel 8- or 16-bit image), with and without an expected
// size. fuzz_image runs the same files on through the extractor, a hundred times slower; this one
// gives the loader its million executions. Seeded from corpus/image (corpus/image_file links it).
#include "fuzz_support.h"

#include "multislit/image_file.h"

#include <stdexcept>

using namespace multislit;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = fuzz::writeInput("image_file", data, size);
  for (const std::optional<cv::Size> expected :
       {std::optional<cv::Size>{}, std::optional<cv::Size>{cv::Size(324, 241)}}) {
    cv::Mat image;
    try {
      image = readMonoImage(path, expected);
    } catch (const std::runtime_error&) {
      continue;  // not an image, too large, corrupt, not one-channel 8- or 16-bit, another size
    }
    fuzz::expect(!image.empty() && image.channels() == 1 &&
                     (image.depth() == CV_8U || image.depth() == CV_16U),
                 "a loaded image is one-channel 8- or 16-bit");
    fuzz::expect(!expected || image.size() == *expected, "a loaded image has the expected size");
  }
  return 0;
}
