// What one path of `multislit bench` measures over the passes: the CPU time of each stage per
// frame, and what it detected, for the agreement of the two paths.
#pragma once

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace multislit::apps {

/// CPU time of the calling thread [s]: every stage runs on this thread (PCL's RANSAC and
/// OctoMap run serially here), and CPU time leaves out the time other processes take the core.
inline double threadSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// The times of one stage: per frame, one sample per pass [s].
class StageTimes {
 public:
  explicit StageTimes(std::size_t frames = 0) : samples_(frames) {}
  void add(std::size_t frame, double seconds) { samples_[frame].push_back(seconds); }
  bool empty() const { return samples_.empty() || samples_[0].empty(); }

  /// The q-quantile over frames (nearest rank) of each frame's median over the passes: the
  /// spread between frames is the pipeline's, while the median of a frame's passes drops the
  /// cache misses other engineers' builds cause on the shared cores [s].
  double quantile(double q) const {
    std::vector<double> medians = frameMedians();
    if (medians.empty()) return std::nan("");
    std::sort(medians.begin(), medians.end());
    const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(medians.size())));
    return medians[std::min(medians.size() - 1, rank > 0 ? rank - 1 : 0)];
  }
  /// The mean of the frames' medians [s].
  double mean() const {
    const std::vector<double> medians = frameMedians();
    double sum = 0;
    for (const double m : medians) sum += m;
    return medians.empty() ? std::nan("") : sum / static_cast<double>(medians.size());
  }
  /// Stages run one after the other: per frame, the sum of their medians. Empty when one is.
  static StageTimes sumOf(const std::vector<const StageTimes*>& stages) {
    StageTimes out(stages.front()->samples_.size());
    for (const StageTimes* stage : stages)
      if (stage->empty()) return StageTimes();
    for (const StageTimes* stage : stages) {
      const std::vector<double> medians = stage->frameMedians();
      for (std::size_t k = 0; k < medians.size(); ++k) {
        if (out.samples_[k].empty()) out.samples_[k].push_back(0.0);
        out.samples_[k][0] += medians[k];
      }
    }
    return out;
  }

 private:
  std::vector<double> frameMedians() const {
    std::vector<double> out;
    for (std::vector<double> s : samples_) {
      if (s.empty()) continue;
      std::nth_element(s.begin(), s.begin() + static_cast<long>(s.size() / 2), s.end());
      out.push_back(s[s.size() / 2]);
    }
    return out;
  }
  std::vector<std::vector<double>> samples_;
};

/// What a path detected in one frame, for the agreement of the two paths.
struct Detection {
  bool found = false;                ///< a floor was found
  std::vector<int> obstacle_points;  ///< cloud indices off the floor (points with x, y, z), sorted
  std::size_t clusters = 0;          ///< obstacle groups of at least 3 points
};

/// Stage times of a path over every pass, and what it detected in the first pass.
struct PathRun {
  StageTimes extract, floor, clusters, map;
  StageTimes walker;  ///< footsteps and decision (ours only)
  std::vector<Detection> detections;
  double valid_points = 0;  ///< per frame, mean
};

}  // namespace multislit::apps
