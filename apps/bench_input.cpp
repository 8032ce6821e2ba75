// The frames of `multislit bench`: the simulator's, rendered once, or a recorded folder's.
#include "bench_input.h"

#include "common.h"
#include "output_file.h"

#include "multislit/odometry.h"
#include "multislit/sim/scenarios.h"
#include "multislit/sim/simulator.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace multislit::apps {
namespace {

/// The paper's sensor with `scale` times its points: 2x the slits over the same fan (scale 2),
/// and also 2x the pixels over the same field of view (scale 4: twice the rows per slit).
SensorConfig scaledSensor(int scale) {
  SensorConfig s;
  if (scale >= 2) {
    s.projector.slit_count *= 2;
    s.projector.slit_spacing /= 2;
  }
  if (scale >= 4) {
    s.camera.width *= 2;
    s.camera.height *= 2;
    s.camera.pixel_size /= 2;
  }
  s.validate();
  return s;
}

/// robot_x of each frame from the frames.csv `multislit simulate` writes; 0 without it (or when
/// it is not a regular file: a FIFO is never opened). Throws naming the line of a robot_x that is
/// not a finite position within kMaxOdometryDistance.
std::vector<double> robotPositions(const std::filesystem::path& dir, std::size_t frames) {
  std::vector<double> x(frames, 0.0);
  const std::filesystem::path path = dir / "frames.csv";
  if (!std::filesystem::is_regular_file(path)) return x;
  std::ifstream csv(path);
  std::string line;
  std::getline(csv, line);  // header: frame,file,stamp_us,robot_x,...
  for (std::size_t k = 0; k < frames && std::getline(csv, line); ++k) {
    std::stringstream fields(line);
    std::string field;
    for (int column = 0; column < 4 && std::getline(fields, field, ','); ++column) {
      if (column != 3) continue;
      char* end = nullptr;
      x[k] = std::strtod(field.c_str(), &end);
      if (field.empty() || *end != '\0' || !(std::abs(x[k]) <= kMaxOdometryDistance))
        throw std::runtime_error(path.string() + ":" + std::to_string(k + 2) + ": robot_x '" +
                                 field + "' is not a position within " +
                                 std::to_string(static_cast<long>(kMaxOdometryDistance)) + " m");
    }
  }
  return x;
}

}  // namespace

BenchInput renderBenchInput(const std::string& scenario, long frames, double step, int scale) {
  BenchInput in;
  in.scale = scale;
  const SensorConfig sensor = scaledSensor(scale);
  const Simulator sim(sensor);
  Scenario s = makeScenario(scenario);
  if (step >= 0) s.step = step;
  in.label = s.name;
  ReferenceConfig rc;
  rc.expected_slits = sensor.projector.slit_count;
  const Scene floor = makeScenario("reference").scene;
  in.reference = Reference::fromImage(sim.renderReference(floor, s.reference_mount).image, rc);
  in.reference.setNominalScale(sensor, s.reference_mount);
  in.robot_from_camera = sim.geometry().robotFromCamera(s.mount);
  in.light_origin = sim.geometry().projectorCentre();
  in.sensor = sensor;
  in.sensor.mount = s.mount;
  cli::Progress progress(static_cast<std::size_t>(frames),
                         "render x" + std::to_string(scale) + " " + s.name);
  for (long k = 0; k < frames && !StopSignal::requested(); ++k) {
    const auto frame = static_cast<std::uint64_t>(k);
    in.world_from_camera.push_back(s.worldFromRobot(frame) * in.robot_from_camera);
    in.images.push_back(sim.render(s.scene, in.world_from_camera.back(), frame).image);
    progress.update(static_cast<std::size_t>(k + 1));
  }
  progress.finish();
  return in;
}

BenchInput readBenchInput(const cli::ArgParser& args) {
  BenchInput in;
  const std::filesystem::path dir = args.str("sequence");
  in.label = dir.filename().string();
  in.reference = referenceFromArgs(args);
  if (!in.reference.scale.valid())
    throw std::runtime_error("the reference has no metric scale: the stock path needs x, y, z");
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (entry.path().extension() == ".png" && entry.path().filename() != "reference.png")
      files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  if (files.empty()) throw std::runtime_error("no PNG frames in '" + dir.string() + "'");
  const SensorConfig sensor = sensorFromArgs(args);
  const SensorGeometry geometry(sensor);
  in.robot_from_camera = geometry.robotFromCamera(sensor.mount);
  in.light_origin = geometry.projectorCentre();
  in.sensor = sensor;
  const std::vector<double> x = robotPositions(dir, files.size());
  for (std::size_t k = 0; k < files.size(); ++k) {
    in.images.push_back(readMonoImage(files[k]));
    Eigen::Isometry3d world_from_robot = Eigen::Isometry3d::Identity();
    world_from_robot.translation().x() = x[k];
    in.world_from_camera.push_back(world_from_robot * in.robot_from_camera);
  }
  return in;
}

}  // namespace multislit::apps
