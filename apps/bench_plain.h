// The two anchors of extraction in `multislit bench`: the paper's plain method on the same frames
// (the price of our robustness in one number), and the time to read every assigned pixel once
// (what no extractor can beat).
#pragma once

#include "bench_input.h"
#include "bench_run.h"

namespace multislit::apps {

struct PlainRun {
  StageTimes plain;  ///< the paper's method (apps/paper_method.h) on every reference point
  StageTimes read;   ///< every pixel of every assigned region read once
};

/// Both timed per frame on this thread over `passes` passes of the frames (after a warm-up pass),
/// each pass over the frames in order like our extraction's, so each frame comes from memory.
PlainRun runPlain(const BenchInput& in, int passes);

}  // namespace multislit::apps
