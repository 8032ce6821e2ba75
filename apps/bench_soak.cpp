// The soak of `multislit bench --soak N`: memory over a long run of the whole chain.
#include "bench_soak.h"

#include "cli.h"
#include "output_file.h"
#include "plot.h"

#include "multislit/extractor.h"
#include "multislit/pipeline.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>

namespace multislit::apps {

double residentMb() {
  std::ifstream statm("/proc/self/statm");
  long pages = 0, resident = 0;
  statm >> pages >> resident;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / 1048576.0;
}

double SoakResult::growth(double warmup) const {
  const auto first = static_cast<std::size_t>(warmup * static_cast<double>(rss_mb.size()));
  if (first >= rss_mb.size()) return 0;
  const auto [lo, hi] =
      std::minmax_element(rss_mb.begin() + static_cast<long>(first), rss_mb.end());
  return (*hi - *lo) / *lo;
}

SoakResult soak(const BenchInput& in, std::size_t frames, std::size_t samples) {
  SoakResult r;
  const Extractor extractor(in.reference);
  PipelineConfig config;
  config.sensor = in.sensor;
  Pipeline pipeline(config);
  const Eigen::Isometry3d camera_from_robot = in.robot_from_camera.inverse();
  auto cloud = pcl::make_shared<pcl::PointCloud<PointRDM>>();
  const std::size_t every = std::max<std::size_t>(1, frames / std::max<std::size_t>(1, samples));
  cli::Progress progress(frames, "soak");
  const auto t0 = std::chrono::steady_clock::now();
  for (std::size_t k = 0; k < frames && !StopSignal::requested(); ++k) {
    const std::size_t i = k % in.images.size();
    extractor.extract(in.images[i], *cloud);
    pipeline.process({cloud, in.world_from_camera[i] * camera_from_robot, in.robot_from_camera});
    if ((k + 1) % every == 0 || k + 1 == frames) {
      r.frames.push_back(k + 1);
      r.rss_mb.push_back(residentMb());
      progress.update(k + 1);
    }
  }
  progress.finish();
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

int reportSoak(const SoakResult& r, double warmup, double limit, const std::string& out_png) {
  if (r.rss_mb.empty()) throw std::runtime_error("soak: no frame was run");
  const std::size_t done = r.frames.back();
  std::printf("soak: %zu frames in %.1f s (%.0f frames/s), resident memory [MB] at frame:\n", done,
              r.seconds, static_cast<double>(done) / std::max(r.seconds, 1e-9));
  const std::size_t step = std::max<std::size_t>(1, r.rss_mb.size() / 10);
  for (std::size_t k = 0; k < r.rss_mb.size(); k += step)
    std::printf("  %10zu  %8.1f\n", r.frames[k], r.rss_mb[k]);
  std::printf("  %10zu  %8.1f\n", done, r.rss_mb.back());
  const double growth = r.growth(warmup);
  const bool ok = growth <= limit;
  std::printf(
      "after the first %.0f %% of the samples: max - min = %.2f %% of min (limit %.0f %%): %s\n",
      100 * warmup, 100 * growth, 100 * limit, ok ? "flat" : "GROWS");
  if (!out_png.empty()) {
    drawLinePlot(out_png,
                 "bench --soak: resident memory, one sample per " +
                     std::to_string(r.frames.front()) + " frames",
                 "sample", "MB", {{"RSS", r.rss_mb}});
    std::printf("wrote %s\n", out_png.c_str());
  }
  return ok ? 0 : 1;
}

}  // namespace multislit::apps
