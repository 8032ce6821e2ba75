// Fuzz target: a calibration file (Reference::load, which validates), then one extraction with it,
// of an image in which its own slits are drawn 1.5 px to the right.
#include "fuzz_support.h"

#include <optional>

#include "multislit/extractor.h"
#include "multislit/reference.h"

#include <opencv2/core.hpp>

#include <cmath>
#include <stdexcept>

using namespace multislit;

namespace {

/// Largest image extracted [px]: larger references are loaded and validated only (an image of
/// 16384 x 16384 px takes 256 MB and a second per input).
constexpr long long kMaxExtractedPixels = 2048LL * 2048;

/// The reference's slits as 3-px-wide stripes 1.5 px right of their reference columns.
cv::Mat imageOfSlits(const Reference& ref) {
  cv::Mat image(ref.image_height, ref.image_width, CV_8UC1, cv::Scalar(10));
  for (const ReferenceSlit& s : ref.slits)
    for (std::size_t k = 0; k < s.u.size(); ++k) {
      if (!std::isfinite(s.u[k])) continue;
      const int row = s.first_row + static_cast<int>(k);
      const int col = static_cast<int>(std::lround(s.u[k] + 1.5));
      for (int dc = -1; dc <= 1; ++dc)
        if (col + dc >= 0 && col + dc < ref.image_width)
          image.at<std::uint8_t>(row, col + dc) = dc == 0 ? 250 : 130;
    }
  return image;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::optional<Reference> loaded =
      fuzz::loadInput("calibration.yaml", data, size,
                      [](const std::string& path) { return Reference::load(path); });
  if (!loaded) return 0;  // refused, naming the value or the file
  const Reference& ref = *loaded;
  ref.validate();  // load() validated: must not throw
  if (static_cast<long long>(ref.image_width) * ref.image_height > kMaxExtractedPixels) return 0;
  const Extractor extractor(ref);
  pcl::PointCloud<PointRDM> cloud;
  const ExtractionStats stats = extractor.extract(imageOfSlits(ref), cloud);
  fuzz::expect(cloud.size() == ref.slits.size() * static_cast<std::size_t>(ref.maxSlitLength()),
               "one cloud column per reference row of the longest slit");
  fuzz::expect(stats.reference_points == ref.pointCount() && stats.valid <= stats.reference_points,
               "counts of the extraction");
  for (const PointRDM& p : cloud)
    if (std::isfinite(p.dk))
      fuzz::expect(p.u + p.dk > -1 && p.u + p.dk < ref.image_width, "measured inside the image");
  return 0;
}
