#include "bench_render.h"

#include "cli.h"
#include "output_file.h"

#include "multislit/sim/simulator.h"
#include "multislit/sim/walk.h"

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <memory>
#include <vector>

namespace multislit::apps {
namespace {

// One frame of the walk: what the camera sees and from where.
struct View {
  Scene scene;
  Eigen::Isometry3d world_from_camera;
  std::uint64_t frame = 0;
};

// `frames` views spread over the demo walk's 900 frames (synthesized: only the poses and scenes
// are needed).
std::vector<View> walkViews(long frames) {
  WalkConfig config;
  config.render = false;
  WalkSimulation walk(config);
  const SensorGeometry geometry(config.pipeline.sensor);
  const long walk_frames = 900, every = std::max(1L, walk_frames / frames);
  std::vector<View> views;
  cli::Progress progress(static_cast<std::size_t>(walk_frames), "walk");
  for (long k = 0; k < walk_frames && static_cast<long>(views.size()) < frames; ++k) {
    const WalkFrame f = walk.step();
    progress.update(static_cast<std::size_t>(k + 1));
    if (k % every != 0) continue;
    View v;
    for (const ObjectView& o : f.objects) v.scene.objects.push_back(o.object);
    v.world_from_camera = f.world_from_torso * geometry.robotFromCamera(f.mount);
    v.frame = f.frame;
    views.push_back(std::move(v));
  }
  progress.finish();
  return views;
}

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5)];
}

struct MethodTimes {
  const char* name;
  std::vector<double> total, centres, laser, noise, truth;
  std::vector<double> cpu;  ///< CPU time of every thread of the process: what other load leaves
};

// CPU time of the whole process, every thread [s].
double processCpuSeconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

MethodTimes timeMethod(const char* name, RenderMethod method, const std::vector<View>& views,
                       int passes) {
  RenderConfig render;
  render.method = method;
  const Simulator sim(SensorConfig{}, render);
  MethodTimes t{name, {}, {}, {}, {}, {}, {}};
  if (!views.empty())  // not timed: the first render builds tables and buffers
    sim.render(views.front().scene, views.front().world_from_camera, views.front().frame);
  cli::Progress progress(views.size() * static_cast<std::size_t>(passes), name);
  for (int pass = 0; pass < passes && !StopSignal::requested(); ++pass) {
    for (const View& v : views) {
      RenderTimes spent;
      const double cpu_start = processCpuSeconds();
      sim.render(v.scene, v.world_from_camera, v.frame, &spent);
      t.cpu.push_back(1e3 * (processCpuSeconds() - cpu_start));
      t.total.push_back(1e3 * spent.total());
      t.centres.push_back(1e3 * spent.centres);
      t.laser.push_back(1e3 * spent.laser);
      t.noise.push_back(1e3 * spent.noise);
      t.truth.push_back(1e3 * spent.truth);
      progress.update(t.total.size());
    }
  }
  progress.finish();
  return t;
}

}  // namespace

int benchRender(long frames, int passes, const std::string& csv) {
  const std::vector<View> views = walkViews(frames);
  const MethodTimes before = timeMethod("exhaustive", RenderMethod::Exhaustive, views, passes);
  const MethodTimes after = timeMethod("culled", RenderMethod::Culled, views, passes);
  if (StopSignal::requested()) return interruptedNothingWritten("bench --render");
  std::printf(
      "multislit bench --render: %zu frames of the walk (floor, ball, cable), 1296x964, %d "
      "passes, %d threads\n",
      views.size(), passes, cv::getNumThreads());
  std::printf("%-12s %10s %10s %10s   median per stage [ms]: %8s %8s %8s %8s\n", "method",
              "median ms", "p99 ms", "cpu ms", "centres", "laser", "noise", "truth");
  std::unique_ptr<OutputFile> out;  // whole or absent
  if (!csv.empty()) {
    out = std::make_unique<OutputFile>(csv);
    out->stream() << "method,median_ms,p99_ms,cpu_ms,centres_ms,laser_ms,noise_ms,truth_ms\n";
  }
  for (const MethodTimes* t : {&before, &after}) {
    const double row[] = {quantile(t->total, 0.5), quantile(t->total, 0.99),
                          quantile(t->cpu, 0.5),   quantile(t->centres, 0.5),
                          quantile(t->laser, 0.5), quantile(t->noise, 0.5),
                          quantile(t->truth, 0.5)};
    std::printf("%-12s %10.1f %10.1f %10.1f   %31.1f %8.1f %8.1f %8.1f\n", t->name, row[0], row[1],
                row[2], row[3], row[4], row[5], row[6]);
    if (out) {
      out->stream() << t->name;
      for (double x : row) out->stream() << ',' << x;
      out->stream() << '\n';
    }
  }
  if (out) out->commit();
  std::printf("ratio (median): %.1fx faster; at 30 Hz a frame has 33.3 ms\n",
              quantile(before.total, 0.5) / quantile(after.total, 0.5));
  return 0;
}

}  // namespace multislit::apps
