// The frame-sized buffers of one render (private to the simulator), kept from render to render:
// fresh pages cost more than filling them (page faults took 9 % of a render).
#pragma once

#include "pixel_centres.h"

#include <opencv2/core/mat.hpp>

#include <memory>
#include <mutex>
#include <vector>

namespace multislit {

/// What one render writes before its image: the pixel centres (40 MB), the laser's light, the
/// speckle's field and a filter's output (CV_32F, made by create(): reused at the same size).
struct RenderBuffers {
  CentreSamples centre;
  cv::Mat laser, field, blurred;
};

/// RenderBuffers for renders in turn or at once. Thread-safe; a render takes one and gives it back.
class RenderPool {
 public:
  std::unique_ptr<RenderBuffers> take();
  void give(std::unique_ptr<RenderBuffers> buffers);

 private:
  std::mutex mutex_;
  std::vector<std::unique_ptr<RenderBuffers>> free_;
};

}  // namespace multislit
