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

}  // namespace

int main(int argc, char** argv) {
  std::string camera, sequence, scenario, calibration, save_dir;
  double fps = 0.0, seconds = 10.0;
  int frames = 0, packet_size = 0;
  pcl::console::parse_argument(argc, argv, "--camera", camera);
  pcl::console::parse_argument(argc, argv, "--sequence", sequence);
  pcl::console::parse_argument(argc, argv, "--simulate", scenario);
  pcl::console::parse_argument(argc, argv, "--calibration", calibration);
  pcl::console::parse_argument(argc, argv, "--fps", fps);
  pcl::console::parse_argument(argc, argv, "--packet-size", packet_size);
  pcl::console::parse_argument(argc, argv, "--seconds", seconds);
  pcl::console::parse_argument(argc, argv, "--frames", frames);
  pcl::console::parse_argument(argc, argv, "--save", save_dir);
  const int sources = !camera.empty() + !sequence.empty() + !scenario.empty();
  if (pcl::console::find_switch(argc, argv, "--help") || sources != 1 ||
      (scenario.empty() && calibration.empty())) {
    usage(argv[0]);
    return sources == 1 ? 0 : 2;
  }

  try {
    // 1. A frame source and the reference that goes with it.
    std::shared_ptr<multislit::FrameSource> source;
    multislit::Reference reference;
    multislit::PipelineConfig pipeline_config;  // the paper's sensor on its nominal mount
    if (!calibration.empty()) reference = multislit::Reference::load(calibration);
    if (!camera.empty()) {
      multislit::AravisConfig config;
      config.camera = camera;
      config.frame_rate = fps > 0 ? fps : 30.0;
      config.roi_width = reference.image_width;
      config.roi_height = reference.image_height;
      config.packet_size = packet_size;
      source = std::make_shared<multislit::AravisSource>(config);
    } else if (!sequence.empty()) {
      multislit::ImageSequenceConfig config;
      config.folder = sequence;
      config.fps = fps;
      source = std::make_shared<multislit::ImageSequenceSource>(config);
    } else {
      multislit::SimulatorSourceConfig config;
      config.scenario = scenario;
      config.fps = fps;
      auto simulator = std::make_shared<multislit::SimulatorSource>(config);
      if (calibration.empty()) reference = simulator->makeReference();
      pipeline_config.sensor.mount = simulator->scenario().mount;
      source = simulator;
    }

    // 2. The grabber and a callback, as with any pcl::Grabber. The callback runs the whole chain
    //    (floor, obstacle groups, map, footsteps, decision) on each cloud, the robot standing
    //    still at the origin; a robot would give its odometry as input.world_from_robot.
    multislit::MultiSlitGrabber grabber(source, reference);
    multislit::Pipeline pipeline(pipeline_config);
    std::atomic<int> clouds{0};
    std::atomic<std::size_t> points{0}, groups{0};
    std::atomic<multislit::Command> decision{multislit::Command::Stop};
    std::function<void(const pcl::PointCloud<multislit::PointRDM>::ConstPtr&)> on_cloud =
        [&](const pcl::PointCloud<multislit::PointRDM>::ConstPtr& cloud) {
          multislit::PipelineInput input;
          input.cloud = cloud;
          const multislit::PipelineResult r = pipeline.process(input);
          points = r.floor.valid_points;
          groups = r.obstacles.obstacles.size();
          decision = r.walker.command;
          if (!save_dir.empty()) {
            char name[64];
            std::snprintf(name, sizeof name, "cloud_%010u.pcd", cloud->header.seq);
            pcl::io::savePCDFileBinary((std::filesystem::path(save_dir) / name).string(), *cloud);
          }
          ++clouds;
        };
    grabber.registerCallback(on_cloud);
    if (!save_dir.empty()) std::filesystem::create_directories(save_dir);

    // 3. Run for a while, then stop.
    const auto begin = std::chrono::steady_clock::now();
    grabber.start();
    std::printf("%s: %s\n", grabber.getName().c_str(), source->name().c_str());
    auto report = begin;
    while (grabber.isRunning() &&
           std::chrono::steady_clock::now() - begin < std::chrono::duration<double>(seconds) &&
           (frames == 0 || clouds < frames)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      if (std::chrono::steady_clock::now() - report >= std::chrono::seconds(1)) {
        report = std::chrono::steady_clock::now();
        std::printf(
            "%d clouds, %.1f fps, %zu of %zu points in the last cloud, %zu obstacle "
            "group(s), decision: %s\n",
            clouds.load(), grabber.getFramesPerSecond(), points.load(), reference.pointCount(),
            groups.load(), multislit::commandName(decision));
      }
    }
    const auto stopping = std::chrono::steady_clock::now();
    grabber.stop();
    const double stop_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - stopping)
            .count();

    const multislit::GrabberStats s = grabber.getStats();
    std::printf(
        "%d clouds; received %llu, processed %llu, dropped %llu (busy), bad buffers %llu, "
        "reconnects %llu, read errors %llu\nlatency from arrival to callback: median %.2f ms, "
        "99th %.2f ms; stop() took %.1f ms\n",
        clouds.load(), static_cast<unsigned long long>(s.frames_received),
        static_cast<unsigned long long>(s.frames_processed),
        static_cast<unsigned long long>(s.frames_dropped),
        static_cast<unsigned long long>(s.source.bad_buffers),
        static_cast<unsigned long long>(s.source.reconnects),
        static_cast<unsigned long long>(s.source.read_errors), s.latency_median_ms,
        s.latency_p99_ms, stop_ms);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
