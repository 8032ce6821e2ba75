// The simulator's row-parallel loops (private to it): cv::parallel_for_, which runs them on TBB's
// threads here, made visible to ThreadSanitizer.
#pragma once

#include <opencv2/core/utility.hpp>

#if defined(__SANITIZE_THREAD__)
#define MULTISLIT_TSAN_ANNOTATE 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define MULTISLIT_TSAN_ANNOTATE 1
#endif
#endif
#ifdef MULTISLIT_TSAN_ANNOTATE
#include <sanitizer/tsan_interface.h>
#endif

namespace multislit {

#ifdef MULTISLIT_TSAN_ANNOTATE
/// TBB, not built with ThreadSanitizer, hands each range to its threads and waits for them
/// through atomics TSan does not see: this body says so. The caller's work before the loop
/// happens before every range (fork), every range before the caller's return (join), so TSan
/// checks the ranges against each other and against the caller and reports nothing else.
template <typename Body>
class TsanVisibleRows final : public cv::ParallelLoopBody {
 public:
  explicit TsanVisibleRows(const Body& body) : body_(body) { __tsan_release(&fork_); }
  void operator()(const cv::Range& rows) const override {
    __tsan_acquire(&fork_);
    body_(rows);
    __tsan_release(&join_);
  }
  void joined() const { __tsan_acquire(&join_); }

 private:
  const Body& body_;
  mutable char fork_ = 0, join_ = 0;  // only their addresses: TSan's synchronization objects
};
#endif

/// body(rows) for disjoint ranges of rows that cover [0, rows), on OpenCV's threads; returns when
/// all are done.
template <typename Body>
void parallelRows(int rows, const Body& body) {
#ifdef MULTISLIT_TSAN_ANNOTATE
  const TsanVisibleRows<Body> visible(body);
  cv::parallel_for_(cv::Range(0, rows), visible);
  visible.joined();
#else
  cv::parallel_for_(cv::Range(0, rows), body);
#endif
}

}  // namespace multislit
