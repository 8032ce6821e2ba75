// The multi-slit sensor in a PCL program, used like any pcl::Grabber. The same program reads a
// GigE Vision camera, recorded images, or the simulator:
//
//   multislit_grabber_example --simulate ball --seconds 10
//   multislit emulate &   multislit_grabber_example --camera 127.0.0.1 --calibration calib.yaml
//   multislit_grabber_example --sequence out/simulate --calibration calib.yaml --save clouds
#include <multislit/grabber.h>
#include <multislit/pipeline.h>
#include <multislit/sim/simulated_source.h>
#include <multislit/sources.h>

#include <pcl/console/parse.h>
#include <pcl/io/pcd_io.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>

namespace {

void usage(const char* program) {
  std::printf(
      "usage: %s (--camera ADDRESS | --sequence DIR | --simulate SCENARIO) [options]\n"
      "  --camera ADDRESS      GigE Vision camera address (e.g. 127.0.0.1 of multislit emulate)\n"
      "  --sequence DIR        recorded PNG images (frames.csv of multislit simulate is used)\n"
      "  --simulate SCENARIO   the simulator filming a scenario (ball, cable, fig8, ...)\n"
      "  --calibration FILE    reference from multislit calibrate (built for --simulate)\n"
      "  --fps HZ              camera / replay / simulator rate (default: camera 30, else max)\n"
      "  --packet-size BYTES   GigE Vision packet size (default: the camera's)\n"
      "  --seconds S           run this long (default 10)\n"
      "  --frames N            stop after N clouds (default: no limit)\n"
      "  --save DIR            write every cloud as binary PCD\n",
      program);
}

struct Options {
  std::string camera, sequence, scenario, calibration, save_dir;
  double fps = 0.0, seconds = 10.0;
  int frames = 0, packet_size = 0;
};

Options parseOptions(int argc, char** argv) {
  Options o;
  pcl::console::parse_argument(argc, argv, "--camera", o.camera);
  pcl::console::parse_argument(argc, argv, "--sequence", o.sequence);
  pcl::console::parse_argument(argc, argv, "--simulate", o.scenario);
  pcl::console::parse_argument(argc, argv, "--calibration", o.calibration);
  pcl::console::parse_argument(argc, argv, "--fps", o.fps);
  pcl::console::parse_argument(argc, argv, "--packet-size", o.packet_size);
  pcl::console::parse_argument(argc, argv, "--seconds", o.seconds);
  pcl::console::parse_argument(argc, argv, "--frames", o.frames);
  pcl::console::parse_argument(argc, argv, "--save", o.save_dir);
  return o;
}

// A frame source, the reference that goes with it and the sensor's mount for the pipeline.
struct Input {
  std::shared_ptr<multislit::FrameSource> source;
  multislit::Reference reference;
  multislit::PipelineConfig pipeline_config;  // the paper's sensor on its nominal mount
};

Input openInput(const Options& o) {
  Input in;
  if (!o.calibration.empty()) in.reference = multislit::Reference::load(o.calibration);
  if (!o.camera.empty()) {
    multislit::AravisConfig config;
    config.camera = o.camera;
    config.frame_rate = o.fps > 0 ? o.fps : 30.0;
    config.roi_width = in.reference.image_width;
    config.roi_height = in.reference.image_height;
    config.packet_size = o.packet_size;
    in.source = std::make_shared<multislit::AravisSource>(config);
  } else if (!o.sequence.empty()) {
    multislit::ImageSequenceConfig config;
    config.folder = o.sequence;
    config.fps = o.fps;
    in.source = std::make_shared<multislit::ImageSequenceSource>(config);
  } else {
    multislit::SimulatorSourceConfig config;
    config.scenario = o.scenario;
    config.fps = o.fps;
    auto simulator = std::make_shared<multislit::SimulatorSource>(config);
    if (o.calibration.empty()) in.reference = simulator->makeReference();
    in.pipeline_config.sensor.mount = simulator->scenario().mount;
    in.source = simulator;
  }
  return in;
}

// What the callback saw, read by the main thread.
struct LastCloud {
  std::atomic<int> clouds{0};
  std::atomic<std::size_t> points{0}, groups{0};
  std::atomic<multislit::Command> decision{multislit::Command::Stop};
};

// Waits while the grabber runs, until o.seconds from `begin` or o.frames clouds, with a line of
// news every second.
void waitForClouds(const multislit::MultiSlitGrabber& grabber, const Options& o,
                   const LastCloud& last, std::size_t reference_points,
                   std::chrono::steady_clock::time_point begin) {
  auto report = begin;
  while (grabber.isRunning() &&
         std::chrono::steady_clock::now() - begin < std::chrono::duration<double>(o.seconds) &&
         (o.frames == 0 || last.clouds < o.frames)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (std::chrono::steady_clock::now() - report >= std::chrono::seconds(1)) {
      report = std::chrono::steady_clock::now();
      std::printf(
          "%d clouds, %.1f fps, %zu of %zu points in the last cloud, %zu obstacle "
          "group(s), decision: %s\n",
          last.clouds.load(), grabber.getFramesPerSecond(), last.points.load(), reference_points,
          last.groups.load(), multislit::commandName(last.decision));
    }
  }
}

void printStats(const multislit::GrabberStats& s, int clouds, double stop_ms) {
  std::printf(
      "%d clouds; received %llu, processed %llu, dropped %llu (busy), bad buffers %llu, "
      "reconnects %llu, read errors %llu\nlatency from arrival to callback: median %.2f ms, "
      "99th %.2f ms; stop() took %.1f ms\n",
      clouds, static_cast<unsigned long long>(s.frames_received),
      static_cast<unsigned long long>(s.frames_processed),
      static_cast<unsigned long long>(s.frames_dropped),
      static_cast<unsigned long long>(s.source.bad_buffers),
      static_cast<unsigned long long>(s.source.reconnects),
      static_cast<unsigned long long>(s.source.read_errors), s.latency_median_ms, s.latency_p99_ms,
      stop_ms);
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parseOptions(argc, argv);
  const int sources = !o.camera.empty() + !o.sequence.empty() + !o.scenario.empty();
  if (pcl::console::find_switch(argc, argv, "--help") || sources != 1 ||
      (o.scenario.empty() && o.calibration.empty())) {
    usage(argv[0]);
    return sources == 1 ? 0 : 2;
  }

  try {
    // 1. A frame source and the reference that goes with it.
    const Input in = openInput(o);

    // 2. The grabber and a callback, as with any pcl::Grabber. The callback runs the whole chain
    //    (floor, obstacle groups, map, footsteps, decision) on each cloud, the robot standing
    //    still at the origin; a robot would give its odometry as input.world_from_robot.
    multislit::MultiSlitGrabber grabber(in.source, in.reference);
    multislit::Pipeline pipeline(in.pipeline_config);
    LastCloud last;
    std::function<void(const pcl::PointCloud<multislit::PointRDM>::ConstPtr&)> on_cloud =
        [&](const pcl::PointCloud<multislit::PointRDM>::ConstPtr& cloud) {
          multislit::PipelineInput input;
          input.cloud = cloud;
          const multislit::PipelineResult r = pipeline.process(input);
          last.points = r.floor.valid_points;
          last.groups = r.obstacles.obstacles.size();
          last.decision = r.walker.command;
          if (!o.save_dir.empty()) {
            char name[64];
            std::snprintf(name, sizeof name, "cloud_%010u.pcd", cloud->header.seq);
            pcl::io::savePCDFileBinary((std::filesystem::path(o.save_dir) / name).string(), *cloud);
          }
          ++last.clouds;
        };
    grabber.registerCallback(on_cloud);
    if (!o.save_dir.empty()) std::filesystem::create_directories(o.save_dir);

    // 3. Run for a while, then stop.
    const auto begin = std::chrono::steady_clock::now();
    grabber.start();
    std::printf("%s: %s\n", grabber.getName().c_str(), in.source->name().c_str());
    waitForClouds(grabber, o, last, in.reference.pointCount(), begin);
    const auto stopping = std::chrono::steady_clock::now();
    grabber.stop();
    const double stop_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - stopping)
            .count();
    printStats(grabber.getStats(), last.clouds.load(), stop_ms);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
