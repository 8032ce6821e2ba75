// `multislit bench --soak N`: the whole chain (extraction, floor, obstacles, map, footsteps and
// decision) over N frames, sampling the process's resident memory: a leak shows as growth.
#pragma once

#include "bench_input.h"

#include <cstddef>
#include <string>
#include <vector>

namespace multislit::apps {

/// The resident set size now (not the peak) [MB], from /proc/self/statm.
double residentMb();

struct SoakResult {
  std::vector<std::size_t> frames;  ///< frames done at each sample
  std::vector<double> rss_mb;       ///< resident memory at each sample [MB]
  double seconds = 0;               ///< wall time of the whole run [s]
  /// (max - min) / min of the samples after the warm-up (the first `warmup` share) [-].
  double growth(double warmup) const;
};

/// Runs `frames` frames of `in` in turn (its poses repeat, so the map stops growing after the
/// first loop) through Extractor and Pipeline, `samples` RSS samples spread over the run.
/// Stops early at Ctrl-C (StopSignal).
SoakResult soak(const BenchInput& in, std::size_t frames, std::size_t samples);

/// Prints the curve and the verdict, writes `out_png` (when not empty) and returns 0 when the
/// growth after warm-up stays within `limit` (0.05), else 1.
int reportSoak(const SoakResult& r, double warmup, double limit, const std::string& out_png);

}  // namespace multislit::apps
