#include "stray_runs.h"

#include "slit_run.h"

#include <cmath>
#include <cstdlib>
#include <limits>

namespace multislit::detail {

std::size_t dropStrayRuns(std::vector<SlitSample>& samples, int longest, double step) {
  if (longest <= 0) return 0;
  const std::size_t n = samples.size();
  const auto next = [&](std::size_t i) {  // the next measured point after i, or n
    while (++i < n && !std::isfinite(samples[i].dk)) {
    }
    return i;
  };
  const auto near = [&](std::size_t a, std::size_t b) {
    return std::abs(samples[b].row - samples[a].row) <= kRunReach;
  };
  std::size_t dropped = 0;
  std::size_t before = n;  // the last measured point before the run, or n
  std::size_t first = n > 0 && std::isfinite(samples[0].dk) ? 0 : next(0);
  while (first < n) {
    std::size_t last = first, count = 1, after = next(first);
    while (after < n && near(last, after) &&
           std::abs(samples[after].dk - samples[last].dk) <= step) {
      last = after;
      after = next(after);
      ++count;
    }
    const bool jumps = (before < n && near(before, first)) || (after < n && near(last, after));
    if (jumps && count <= static_cast<std::size_t>(longest)) {
      for (std::size_t i = first; i <= last; ++i)
        samples[i].dk = std::numeric_limits<double>::quiet_NaN();
      dropped += count;
    }
    before = last;
    first = after;
  }
  return dropped;
}

}  // namespace multislit::detail
