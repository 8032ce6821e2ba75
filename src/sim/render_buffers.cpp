#include "render_buffers.h"

namespace multislit {

std::unique_ptr<RenderBuffers> RenderPool::take() {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (free_.empty()) return std::make_unique<RenderBuffers>();
  std::unique_ptr<RenderBuffers> buffers = std::move(free_.back());
  free_.pop_back();
  return buffers;
}

void RenderPool::give(std::unique_ptr<RenderBuffers> buffers) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (free_.size() < 2) free_.push_back(std::move(buffers));
}

}  // namespace multislit
