#include "bench_plain.h"

#include "output_file.h"
#include "paper_method.h"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace multislit::apps {

namespace {

/// One reference point and its assigned region on its row, in the order of the image's rows.
struct Region {
  int row = 0, first = 0, last = 0;  ///< columns first .. last, inside the image
  double u = 0;
};

std::vector<Region> regionsOf(const Reference& ref, int columns) {
  const double half = 0.5 * ref.region_width;
  std::vector<Region> out;
  for (const ReferenceSlit& slit : ref.slits)
    for (std::size_t k = 0; k < slit.u.size(); ++k) {
      const double u = slit.u[k];
      if (!std::isfinite(u)) continue;
      Region r;
      r.row = slit.first_row + static_cast<int>(k);
      r.first = std::max(0, static_cast<int>(std::ceil(u - half)));
      r.last = std::min(columns - 1, static_cast<int>(std::floor(u + half)));
      r.u = u;
      if (r.first <= r.last) out.push_back(r);
    }
  std::sort(out.begin(), out.end(), [](const Region& a, const Region& b) {
    return a.row != b.row ? a.row < b.row : a.first < b.first;
  });
  return out;
}

template <typename T>
void measurePlain(const cv::Mat& image, const std::vector<Region>& regions, double half,
                  double min_contrast, std::vector<paper::PaperPoint>& out) {
  for (std::size_t i = 0; i < regions.size(); ++i) {
    paper::PaperPoint& p = out[i];
    p.dk = std::nan("");
    paper::paperMeasureRow(image.ptr<T>(regions[i].row), image.cols, regions[i].u, half,
                           min_contrast, &p);
  }
}

template <typename T>
std::uint64_t readRegions(const cv::Mat& image, const std::vector<Region>& regions) {
  std::uint64_t sum = 0;
  for (const Region& r : regions) {
    const T* row = image.ptr<T>(r.row);
    std::uint32_t region = 0;  // at most 65535 x the image's width
    for (int x = r.first; x <= r.last; ++x) region += row[x];
    sum += region;
  }
  return sum;
}

double fullScale(const Reference& ref, const cv::Mat& image) {
  if (ref.full_scale > 0) return ref.full_scale;
  return image.depth() == CV_8U ? 255.0 : 65535.0;
}

}  // namespace

PlainRun runPlain(const BenchInput& in, int passes) {
  const std::size_t n = in.images.size();
  PlainRun run{StageTimes(n), StageTimes(n)};
  if (n == 0) return run;
  const std::vector<Region> regions = regionsOf(in.reference, in.images.front().cols);
  std::vector<paper::PaperPoint> points(regions.size());
  const double half = 0.5 * in.reference.region_width;
  volatile std::uint64_t sink = 0;  // the sums are used: the reads are not optimized away
  // Each in passes of its own over the frames, so that each frame comes from memory as in ours.
  for (int pass = -1; pass < passes && !StopSignal::requested(); ++pass) {  // -1: warm-up
    for (std::size_t k = 0; k < n; ++k) {
      const cv::Mat& image = in.images[k];
      const double min_contrast = 0.06 * fullScale(in.reference, image);  // the paper's limit
      const double t0 = threadSeconds();
      if (image.depth() == CV_8U)
        measurePlain<std::uint8_t>(image, regions, half, min_contrast, points);
      else
        measurePlain<std::uint16_t>(image, regions, half, min_contrast, points);
      if (pass >= 0) run.plain.add(k, threadSeconds() - t0);
    }
    for (std::size_t k = 0; k < n; ++k) {
      const cv::Mat& image = in.images[k];
      const double t0 = threadSeconds();
      sink = sink + (image.depth() == CV_8U ? readRegions<std::uint8_t>(image, regions)
                                            : readRegions<std::uint16_t>(image, regions));
      if (pass >= 0) run.read.add(k, threadSeconds() - t0);
    }
  }
  return run;
}

}  // namespace multislit::apps
