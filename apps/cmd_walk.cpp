// multislit walk: the paper's walking experiment (Sec. V, Fig. 13-15) on the simulator. A HOAP-2
// with the multi-slit sensor walks; a ping-pong ball is thrown in just in front of its foot, a LAN
// cable lies across its path. Every frame: image -> RDMap -> floor -> obstacles -> map -> walker.
#include "cli.h"
#include "commands.h"
#include "common.h"
#include "config_options.h"
#include "multislit/units.h"
#include "object_outline.h"
#include "output_file.h"
#include "photometry_input.h"
#include "plot.h"
#include "recording.h"
#include "walk_csv.h"
#include "walk_figures.h"
#include "walk_sweep.h"

#include "multislit/sim/photometry.h"
#include "multislit/sim/walk.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>

namespace multislit::apps {
namespace {

void declareWalkOptions(cli::ArgParser& args) {
  const WalkConfig defaults;
  args.option("out", "out/walk", "output folder");
  args.option("frames", std::to_string(kWalkFrames),
              "frames to walk (30 Hz; the paper's run is about 900)");
  args.option("seed", std::to_string(defaults.render_config.seed),
              "noise seed of the images (or of the synthesized RDMaps)");
  args.option("ball-frame", defaultText(defaults.scene.ball_frame),
              "frame the ping-pong ball lands in front of the foot");
  args.option("step-length", defaultText(defaults.pipeline.foot.step_length),
              "the body's advance per step [m]");
  args.option("step-frames", defaultText(defaults.gait.step_frames), "frames per step");
  args.option("cluster", "grid", "obstacle grouping: grid (RDMap neighbours) or euclidean");
  args.option("screw", "", "X,Y: add a screw head 6 mm across, 2 mm high, at world (X, Y) [m]");
  args.option("sensor", "", "sensor YAML (default: the paper's sensor)");
  args.option("photometry", "",
              "the images' light, speckle, stripes, floor and objects: a preset, random (drawn "
              "from --seed) or a photometry YAML, as multislit simulate takes");
  args.option("record", "",
              "DIR: also write the walk as a recording (frames, odometry.csv, calibration.yaml) "
              "that multislit map --sequence DIR replays");
  args.flag("measure-sweep",
            "walk straight whatever the map holds and write each pass of the slits over a place "
            "with evidence to sweep_passes.csv, and their histograms to sweep_runs.png, "
            "sweep_balance.png, sweep_extent.png and sweep_histograms.csv (docs/walk.md)");
  args.flag("no-ball", "no ball is thrown in");
  args.flag("no-cable", "no LAN cable on the floor");
  args.flag("synthesize",
            "RDMaps from the simulator's ground truth plus noise, not images "
            "(about 50 times faster)");
}

WalkConfig configFromArgs(const cli::ArgParser& args) {
  WalkConfig c;
  if (args.has("sensor")) c.pipeline.sensor = SensorConfig::load(args.str("sensor"));
  c.reference_mount = c.pipeline.sensor.mount;
  c.render = !args.has("synthesize");
  c.render_config.seed = static_cast<std::uint64_t>(args.integer("seed", 0, 1L << 62));
  c.synth.seed = c.render_config.seed;
  c.scene.ball = !args.has("no-ball");
  c.scene.cable = !args.has("no-cable");
  c.scene.ball_frame = intOption(args, "ball-frame");
  // The ball rolls away as long after it lands as by default.
  c.scene.ball_roll_frame += c.scene.ball_frame - WalkSceneConfig{}.ball_frame;
  c.pipeline.foot.step_length = args.number("step-length");
  c.gait.step_frames = intOption(args, "step-frames");
  const std::string cluster = args.str("cluster");
  if (cluster != "grid" && cluster != "euclidean")
    throw cli::UsageError("--cluster must be grid or euclidean");
  c.pipeline.obstacles.method = cluster == "grid" ? ClusterMethod::Grid : ClusterMethod::Euclidean;
  if (args.has("screw")) {
    double x = 0, y = 0;
    char end = 0;
    if (std::sscanf(args.str("screw").c_str(), "%lf,%lf%c", &x, &y, &end) != 2 ||
        !(std::abs(x) <= 100 && std::abs(y) <= 100))
      throw cli::UsageError("--screw needs X,Y in metres, each within +-100, not '" +
                            args.str("screw") + "'");
    c.scene.extra.push_back(SceneObject::cylinder("screw", Eigen::Vector3d(x, y, 0),
                                                  Eigen::Vector3d(x, y, 0.002), 0.003));
  }
  try {
    if (args.has("photometry") && !c.render)
      throw std::invalid_argument("--photometry needs rendered images, not --synthesize");
    if (args.has("photometry"))
      applyPhotometry(choosePhotometry(args.str("photometry"), c.render_config.seed), c);
    if (args.has("measure-sweep")) measureSweep(c);
    c.validate();
  } catch (const std::invalid_argument& e) {
    throw cli::UsageError(optionMessage(e.what(), args));
  }
  return c;
}

/// One object over the walk, against the ground truth.
struct ObjectRecord {
  SceneObject object;       ///< where it was first seen
  int first_lit = -1;       ///< first frame the slits touch it at least 3.5 mm high
  int first_detected = -1;  ///< first frame obstacle points lie on it
  int last_detected = -1;
  int first_mapped = -1;  ///< first frame the map holds an occupied voxel on it
  std::size_t most_points = 0;
  WalkFrame best;  ///< the frame with most obstacle points on it (for Fig. 14)
};

/// Everything the outputs need, gathered frame by frame.
struct Recorder {
  std::ostream* csv = nullptr;  ///< obstacles.csv, one row per frame
  std::map<std::string, ObjectRecord> objects;
  std::vector<std::string> events;
  TopViewContent top;
  std::vector<double> obstacle_points;  ///< per frame (Fig. 15)
  Command motion = Command::Stop;
  int motion_since = 0;
  double measure_s = 0, process_s = 0;
  int ball_cleared = -1;  ///< first frame the map is free where the ball landed, after it left
  Eigen::Vector2d ball_spot = Eigen::Vector2d::Constant(NAN);
  std::string photometry = "default";  ///< --photometry, as given
  std::size_t false_voxels = 0;        ///< occupied voxels where no object lies, now
  std::size_t false_voxels_most = 0;   ///< ... at most
  int walking = 0;                     ///< frames walking straight
};

/// The true object that explains a place best (nearest seen from above, within 5 cm), as "the
/// <name>"; `if_none` where no object lies (a false obstacle).
std::string theObjectAt(const std::vector<SceneObject>& objects, const Eigen::Vector2d& at,
                        const std::string& if_none) {
  const SceneObject* o = objectNear(objects, at, 0.0, 0.05);
  return o ? "the " + o->name : if_none;
}

std::string describeMotion(const WalkFrame& f, const std::vector<SceneObject>& objects,
                           int turn_direction, double stop_seconds) {
  char s[256];
  const WalkerResult& w = f.walker;
  if (f.motion == Command::Walk) return "walks straight (the next footsteps are free)";
  if (f.motion == Command::Turn) {
    const std::string what = w.check.cells.empty()
                                 ? "an obstacle"
                                 : theObjectAt(objects, w.check.cells.front().centre.head<2>(),
                                               "a voxel where no object lies: a false obstacle");
    std::snprintf(s, sizeof s, "turns %s in place (footstep %d ahead touches %s in the map)",
                  turn_direction > 0 ? "left" : "right", w.check.first_blocked + 1, what.c_str());
    return s;
  }
  if (w.reason == Reason::NoFloor) return "stops: no floor in the frame (fail safe)";
  if (w.obstacle) {
    const std::string what = theObjectAt(objects, f.body.toWorld(w.obstacle->centroid.head<2>()),
                                         "an obstacle where no object lies (false)");
    std::snprintf(s, sizeof s,
                  "stops for %.0f s: %s appeared suddenly %.0f mm in front of the feet (%zu "
                  "points, %.0f mm high)",
                  stop_seconds, what.c_str(), 1e3 * w.obstacle->distance, w.obstacle->pointCount(),
                  1e3 * w.obstacle->height);
    return s;
  }
  return "stops";
}

void record(Recorder& r, const WalkFrame& f, const WalkSimulation& walk) {
  const int k = static_cast<int>(f.frame);
  writeWalkCsvLine(*r.csv, f, walk.map(), walk.config().gait.frame_rate);
  r.obstacle_points.push_back(static_cast<double>(f.obstacles.pointCount()));
  r.measure_s += f.measure_seconds;
  r.process_s += f.process_seconds;
  r.top.path.push_back(f.body);
  std::vector<SceneObject> objects;
  for (const ObjectView& o : f.objects) objects.push_back(o.object);
  r.false_voxels = falseVoxels(walk.map(), objects);
  r.false_voxels_most = std::max(r.false_voxels_most, r.false_voxels);
  r.walking += f.motion == Command::Walk;
  if (f.footstep) {
    r.top.footsteps.push_back(*f.footstep);
    r.top.clearances.push_back(f.footstep_clearance);
  }
  for (const ObjectView& o : f.objects) {
    ObjectRecord& rec = r.objects[o.object.name];
    if (o.lit_any > 0 && rec.first_lit < 0) {
      rec.first_lit = k;
      rec.object = o.object;
    }
    if (rec.first_mapped < 0 && mapped(walk.map(), o.object)) rec.first_mapped = k;
    if (o.detected == 0) continue;
    if (rec.first_detected < 0) rec.first_detected = k;
    rec.last_detected = k;
    if (o.detected > rec.most_points) {
      rec.most_points = o.detected;
      rec.best = f;
    }
  }
  if (f.motion != r.motion || k == 0) {
    char head[64];
    std::snprintf(head, sizeof head, "frame %4d (%5.1f s): ", k, k / walk.config().gait.frame_rate);
    const WalkConfig& c = walk.config();
    r.events.push_back(head + describeMotion(f, objects, walk.gait().turnDirection(),
                                             c.pipeline.walker.stop_frames / c.gait.frame_rate));
    r.motion = f.motion;
  }
}

void trackBall(Recorder& r, const WalkFrame& f, const WalkSimulation& walk) {
  const WalkSceneConfig& s = walk.config().scene;
  const int k = static_cast<int>(f.frame);
  if (!s.ball || k < s.ball_frame) return;
  if (k == s.ball_frame) r.ball_spot = f.body.toWorld(s.ball_landing);
  if (r.ball_cleared >= 0 || k < s.ball_roll_frame) return;
  const double m = 0.03;
  if (walk.map()
          .occupiedInBox(Eigen::Vector3d(r.ball_spot.x() - m, r.ball_spot.y() - m, -1),
                         Eigen::Vector3d(r.ball_spot.x() + m, r.ball_spot.y() + m, 1))
          .empty())
    r.ball_cleared = k;
}

// What appeared, and when it was detected and mapped (frame numbers; +n: frames later).
void describeDetections(std::ostream& o, const Recorder& r, const WalkConfig& c) {
  o << "what appeared, and when it was detected (frame numbers; +n: frames later):\n";
  const auto frameAfter = [](int frame, int since) {
    if (frame < 0) return std::string("never");
    return "at frame " + std::to_string(frame) + " (+" + std::to_string(frame - since) + ")";
  };
  for (const auto& [name, rec] : r.objects) {
    if (rec.first_lit < 0) continue;
    o << "  " << name << ": in sight of the slits from frame " << rec.first_lit
      << "; obstacle points on it " << frameAfter(rec.first_detected, rec.first_lit)
      << (rec.last_detected >= 0 ? " to frame " + std::to_string(rec.last_detected) : "")
      << "; occupied in the map " << frameAfter(rec.first_mapped, rec.first_lit) << "\n";
  }
  if (r.ball_cleared >= 0)
    o << "  the ball rolled away from frame " << c.scene.ball_roll_frame
      << "; the map was free where it had landed at frame " << r.ball_cleared << "\n";
}

std::string summary(const Recorder& r, const WalkSimulation& walk, double seconds,
                    const std::string& out) {
  const WalkConfig& c = walk.config();
  std::ostringstream o;
  char s[512];
  const int frames = static_cast<int>(walk.frame());
  std::snprintf(s, sizeof s,
                "multislit walk: the paper's walking experiment (Sec. V) on the simulator\n"
                "  %d frames at %.0f Hz of %s (seed %llu, photometry %s)\n"
                "  HOAP-2: soles %.0f x %.0f mm, feet %.0f mm apart, %.0f mm steps of %.2f s "
                "(%.0f mm/s), turns %.0f deg per step\n",
                frames, c.gait.frame_rate,
                c.render ? "rendered images" : "RDMaps synthesized from the ground truth",
                static_cast<unsigned long long>(c.render_config.seed), r.photometry.c_str(),
                1e3 * c.pipeline.foot.foot_length, 1e3 * c.pipeline.foot.foot_width,
                1e3 * c.pipeline.foot.foot_separation, 1e3 * c.pipeline.foot.step_length,
                c.gait.step_frames / c.gait.frame_rate, 1e3 * c.gait.speed(c.pipeline.foot),
                c.pipeline.foot.turn_step);
  o << s;
  describeDetections(o, r, c);
  o << "what the robot did:\n";
  for (const std::string& e : r.events) o << "  " << e << "\n";
  int touched = 0;
  double closest = INFINITY;
  for (const double d : r.top.clearances) {
    touched += d <= 0.0;
    closest = std::min(closest, d);
  }
  const Pose2D& end = walk.gait().pose();
  double walked = 0;
  for (std::size_t k = 1; k < r.top.path.size(); ++k)
    walked += (r.top.path[k].position() - r.top.path[k - 1].position()).norm();
  std::snprintf(s, sizeof s,
                "footsteps: %zu, touching an object: %d (closest %.1f mm)\n"
                "path: %.2f m walked, ends at (%.2f, %.2f) m heading %.0f deg\n"
                "frames walking straight: %d of %d\n"
                "map: %zu occupied voxels of %.0f mm (%zu where no object lies; %zu at most), %zu "
                "voxels, %.0f kB (a window of +-%.1f m around the robot)\n"
                "time: %.0f s in all; per frame %.1f ms %s, %.2f ms floor + obstacles + map + "
                "walker\n",
                r.top.footsteps.size(), touched, 1e3 * closest, walked, end.x, end.y,
                end.yaw / kDeg, r.walking, frames, walk.map().occupiedCount(),
                1e3 * c.pipeline.map.resolution, r.false_voxels, r.false_voxels_most,
                walk.map().leafCount(), walk.map().memoryUsage() / 1e3,
                c.pipeline.map.window_half_size, seconds, 1e3 * r.measure_s / frames,
                c.render ? "rendering and extracting" : "synthesizing", 1e3 * r.process_s / frames);
  o << s << "outputs in " << out
    << ": obstacles.csv, fig15_obstacle_points.png, rdmap_*.png (Fig. 14), map.bt, "
       "map_top.png, summary.txt\n";
  return o.str();
}

void writeFigures(Recorder& r, const WalkSimulation& walk, const std::filesystem::path& out) {
  drawLinePlot((out / "fig15_obstacle_points.png").string(),
               "Fig. 15: points detected as obstacles in each frame", "frame", "points",
               {Series{"obstacle points", r.obstacle_points, 0xd03030}});
  for (const auto& [name, rec] : r.objects) {
    if (rec.most_points == 0) continue;
    char title[160];
    std::snprintf(title, sizeof title, "Fig. 14: RDMap of frame %llu, the floor plane and the %s",
                  static_cast<unsigned long long>(rec.best.frame), name.c_str());
    drawRDMapFigure((out / ("rdmap_" + name + ".png")).string(), title, *rec.best.cloud,
                    rec.best.floor);
    char note[96];
    std::snprintf(note, sizeof note, "%s (frames %d-%d)", name.c_str(), rec.first_detected,
                  rec.last_detected);
    r.top.objects.push_back(outlineOf(rec.object));
    r.top.object_notes.push_back(note);
  }
  writeWhole(out / "map.bt", [&walk](const std::string& p) { walk.map().save(p); });
  drawTopView((out / "map_top.png").string(), walk.map(), r.top);
}

/// The files the walk reads (the sensor, a photometry YAML), once --out is known to hold none of
/// them where it writes.
std::vector<NamedInput> checkedInputs(const cli::ArgParser& args,
                                      const std::filesystem::path& out) {
  std::vector<NamedInput> inputs = inputsWithPhotometry(args, {"sensor"});
  refuseOutputFolder(out, "--out",
                     {"obstacles.csv", "summary.txt", "map.bt", "map_top.png",
                      "fig15_obstacle_points.png", "sweep_passes.csv", "sweep_histograms.csv"},
                     inputs);
  return inputs;
}

}  // namespace

int runWalk(int argc, char** argv) {
  cli::ArgParser args(
      "walk",
      "The paper's walking experiment (Sec. V, Fig. 13-15) on the simulator: a HOAP-2 with the\n"
      "multi-slit sensor walks; a 40 mm ping-pong ball is thrown in just in front of its foot\n"
      "(it stops for 5 s), a 7 mm LAN cable lies across its path (it turns away). Each frame:\n"
      "image -> RDMap -> floor (RANSAC) -> obstacles -> OctoMap -> footsteps -> walk/turn/stop.");
  declareWalkOptions(args);
  if (!args.parse(argc, argv)) return 0;
  const StopSignal stop;  // Ctrl-C: the walk ends at a frame boundary, every output written
  const WalkConfig config = configFromArgs(args);
  const long frames = args.integer("frames", 1, 100000000);
  const std::filesystem::path out = args.str("out");
  const std::vector<NamedInput> inputs = checkedInputs(args, out);
  std::filesystem::create_directories(out);

  const auto t0 = std::chrono::steady_clock::now();
  WalkSimulation walk(config);
  Recorder r;
  if (args.has("photometry")) r.photometry = args.str("photometry");
  OutputFile csv(out / "obstacles.csv");  // whole or absent, as every output
  r.csv = &csv.stream();
  writeWalkCsvHeader(*r.csv);
  std::optional<OutputFile> passes;
  SweepHistograms histograms;
  if (args.has("measure-sweep")) {
    passes.emplace(out / "sweep_passes.csv");
    writeSweepPassHeader(passes->stream());
  }
  std::optional<SequenceRecorder> recording;
  if (args.has("record")) {
    if (!config.render) throw cli::UsageError("--record needs rendered images, not --synthesize");
    recording.emplace(args.str("record"), "--record", &walk.reference(), config.pipeline.sensor,
                      inputs);
  }
  cli::Progress progress(static_cast<std::size_t>(frames), "walk");
  for (long k = 0; k < frames && !StopSignal::requested(); ++k) {
    const WalkFrame f = walk.step();
    if (recording) recording->add(f.image, f.stamp_us, "simulated", f.world_from_torso);
    record(r, f, walk);
    if (passes) writeSweepPasses(passes->stream(), f, walk.map(), histograms);
    trackBall(r, f, walk);
    progress.update(static_cast<std::size_t>(k + 1));
  }
  progress.finish();
  if (recording) recording->finish();
  csv.commit();
  if (passes) {
    passes->commit();
    writeSweepHistograms(out.string(), histograms);
  }
  writeFigures(r, walk, out);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::string text =
      summary(r, walk, seconds, out.string()) +
      (StopSignal::requested() ? "interrupted (Ctrl-C) at frame " + std::to_string(walk.frame()) +
                                     " of " + std::to_string(frames) + "\n"
                               : "");
  OutputFile summary_file(out / "summary.txt");
  summary_file.stream() << text;
  summary_file.commit();
  std::cout << text;
  return StopSignal::requested() ? kInterruptedExit : 0;
}

}  // namespace multislit::apps
