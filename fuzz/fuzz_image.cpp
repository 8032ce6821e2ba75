// Fuzz target: an image file as the commands read it (readMonoImage: the size from its header,
// OpenCV's decoders, then the checks of a one-channel 8- or 16-bit image), extracted against a
// fixed reference: the calibration of the quarter-size sensor in corpus/calibration/small.yaml
// (corpus/README.md).
#include "fuzz_support.h"

#include "multislit/extractor.h"
#include "multislit/image_file.h"

#include <cmath>
#include <stdexcept>

using namespace multislit;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const Extractor extractor(
      Reference::load(MULTISLIT_FUZZ_DIR "/corpus/calibration/small.yaml"));
  const std::string path = fuzz::writeInput("image", data, size);
  cv::Mat image;
  try {
    image = readMonoImage(path);
  } catch (const std::runtime_error&) {
    return 0;  // not an image, too large, corrupt, or not one-channel 8- or 16-bit
  }
  pcl::PointCloud<PointRDM> cloud;
  try {
    extractor.extract(image, cloud);
  } catch (const std::invalid_argument&) {
    const Reference& ref = extractor.reference();
    fuzz::expect(image.cols != ref.image_width || image.rows != ref.image_height,
                 "an image of the reference's size is extracted");
    return 0;
  }
  for (const PointRDM& p : cloud)
    if (std::isfinite(p.dk))
      fuzz::expect(p.u + p.dk > -1 && p.u + p.dk < image.cols, "measured inside the image");
  return 0;
}
