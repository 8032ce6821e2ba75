// Footsteps, gait and walker, and the paper's walking experiment (Sec. V) on the simulator: the
// robot stops for the ball thrown in front of its foot, turns away from the LAN cable, and no
// footstep ever touches an object.
#include "multislit/walker.h"
#include "default_reference.h"
#include "multislit/footsteps.h"
#include "multislit/gait.h"
#include "multislit/sim/rdmap_synth.h"
#include "multislit/sim/walk.h"
#include "multislit/units.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

using namespace multislit;

namespace {

const Reference& reference() { return test::defaultReference(); }

/// What a walk did, frame by frame, summed up.
struct WalkLog {
  int ball_lit = -1;         // first frame the slits touch the ball
  int first_stop = -1;       // first frame of a stop for a sudden obstacle
  int stop_frames = 0;       // frames stopped for a sudden obstacle
  int sudden_stops = 0;      // stops started
  int cable_lit = -1;        // first frame the slits touch the cable
  int first_turn = -1;       // first frame the walker turns for a blocked path
  int turn_direction = 0;    // of that turn
  int turn_frames = 0;       // frames turning
  int walk_after_turn = -1;  // first frame walking after the first turn
  int footsteps = 0;
  double min_clearance = 1e9;  // of all footsteps from the true objects [m]
  Pose2D end;
};

WalkLog walk(WalkSimulation& sim, int frames) {
  WalkLog log;
  for (int k = 0; k < frames; ++k) {
    const WalkFrame f = sim.step();
    for (const ObjectView& o : f.objects) {
      if (o.object.name == "pingpong_ball" && o.lit > 0 && log.ball_lit < 0) log.ball_lit = k;
      if (o.object.name == "lan_cable" && o.lit > 0 && log.cable_lit < 0) log.cable_lit = k;
    }
    const WalkerResult& w = f.walker;
    if (w.reason == Reason::SuddenObstacle) {
      ++log.stop_frames;
      if (log.first_stop < 0) log.first_stop = k;
      log.sudden_stops += w.obstacle.has_value();
    }
    if (f.motion == Command::Turn) {
      ++log.turn_frames;
      if (log.first_turn < 0) {
        log.first_turn = k;
        log.turn_direction = sim.gait().turnDirection();
      }
    }
    if (log.first_turn >= 0 && log.walk_after_turn < 0 && f.motion == Command::Walk)
      log.walk_after_turn = k;
    if (f.footstep) {
      ++log.footsteps;
      log.min_clearance = std::min(log.min_clearance, f.footstep_clearance);
    }
  }
  log.end = sim.gait().pose();
  return log;
}

WalkConfig synthesized() {
  WalkConfig config;
  config.render = false;
  return config;
}

}  // namespace

TEST(Walk, PaperExperimentStopsForTheBallAndTurnsAwayFromTheCable) {
  WalkSimulation sim(synthesized(), reference());
  const WalkLog log = walk(sim, 900);
  const WalkSceneConfig& scene = sim.config().scene;
  // The ball lands in front of the foot at frame 200: seen at once, the robot stops for 5 s.
  EXPECT_EQ(log.ball_lit, scene.ball_frame);
  EXPECT_GE(log.first_stop, scene.ball_frame);
  EXPECT_LE(log.first_stop, scene.ball_frame + 3);
  EXPECT_EQ(log.sudden_stops, 1);  // the cable, seen far ahead first, never stops it
  EXPECT_EQ(log.stop_frames, sim.config().pipeline.walker.stop_frames);
  // The cable, first seen far ahead, blocks the footsteps: the robot turns left and walks on.
  ASSERT_GE(log.cable_lit, 0);
  EXPECT_GT(log.first_turn, log.cable_lit);
  EXPECT_EQ(log.turn_direction, 1);
  EXPECT_GT(log.walk_after_turn, log.first_turn);
  EXPECT_GT(log.end.yaw, 15 * kDeg);
  EXPECT_GT(log.end.x, 0.8);
  // No footstep touched the ball or the cable.
  EXPECT_GT(log.footsteps, 20);
  EXPECT_GT(log.min_clearance, 0.0);
  std::printf(
      "ball lit at %d, stop at %d for %d frames; cable lit at %d, turn at %d (%d frames), "
      "walking again at %d; %d footsteps, closest %.1f mm from an object; end (%.2f, "
      "%.2f) m, %.0f deg\n",
      log.ball_lit, log.first_stop, log.stop_frames, log.cable_lit, log.first_turn, log.turn_frames,
      log.walk_after_turn, log.footsteps, 1e3 * log.min_clearance, log.end.x, log.end.y,
      log.end.yaw / kDeg);
}

TEST(Walk, EmptyFloorFor1000FramesNeverStopsOrTurns) {
  WalkConfig config = synthesized();
  config.scene.ball = false;
  config.scene.cable = false;
  WalkSimulation sim(config, reference());
  int not_walking = 0;
  const int frames = frameCount(1000, 300);
  for (int k = 0; k < frames; ++k) not_walking += sim.step().walker.command != Command::Walk;
  EXPECT_EQ(not_walking, 0);
  const double walked = sim.gait().pose().x;
  EXPECT_NEAR(walked, frames * config.gait.speed(config.pipeline.foot) / config.gait.frame_rate,
              1e-6);
  EXPECT_DOUBLE_EQ(sim.gait().pose().yaw, 0.0);
}

TEST(Walk, RenderedImagesStopForTheBall) {
  // The full pipeline on rendered images: the ball lands at frame 4 of a 10-frame walk.
  WalkConfig config;
  config.scene.cable = false;
  config.scene.ball_frame = 4;
  config.scene.ball_roll_frame = 100;
  WalkSimulation sim(config, reference());
  int stopped = -1;
  for (int k = 0; k < 10; ++k) {
    const WalkFrame f = sim.step();
    if (stopped < 0 && f.walker.reason == Reason::SuddenObstacle) stopped = k;
    if (k < 4) {
      EXPECT_EQ(f.walker.command, Command::Walk) << k;
    }
    ASSERT_TRUE(f.floor.found) << k;
  }
  EXPECT_GE(stopped, 4);
  EXPECT_LE(stopped, 6);
  EXPECT_EQ(sim.gait().command(), Command::Stop);
}

TEST(Gait, StepsTurnsStopsAndSways) {
  const GaitConfig config;
  const FootConfig foot;
  Gait gait(config, foot, MountConfig{});
  EXPECT_EQ(gait.nextFoot(), Foot::Left);
  double max_roll = 0, max_dh = 0;
  std::optional<Footstep> landed;
  for (int k = 0; k < config.step_frames; ++k) {
    landed = gait.advance(Command::Walk);
    max_roll = std::max(max_roll, std::abs(gait.mount().roll));
    max_dh = std::max(max_dh, std::abs(gait.mount().height - MountConfig{}.height));
    if (k + 1 < config.step_frames) {
      EXPECT_FALSE(landed) << k;
    }
  }
  // One step: the body 40 mm ahead, the left foot down half a step ahead of it.
  ASSERT_TRUE(landed);
  EXPECT_EQ(landed->foot, Foot::Left);
  EXPECT_NEAR(gait.pose().x, foot.step_length, 1e-12);
  EXPECT_NEAR(landed->sole.centre.x(), 1.5 * foot.step_length, 1e-12);
  EXPECT_NEAR(landed->sole.centre.y(), 0.5 * foot.foot_separation, 1e-12);
  EXPECT_NEAR(max_roll, config.roll_amplitude, 0.05);
  EXPECT_NEAR(max_dh, config.height_amplitude, 1e-4);
  // A turn asked for mid-step waits for the step to end; a turn step is 10 deg.
  for (int k = 0; k < config.step_frames / 2; ++k) gait.advance(Command::Walk);
  for (int k = 0; k < config.step_frames / 2; ++k) gait.advance(Command::Turn, -1);
  EXPECT_NEAR(gait.pose().x, 2 * foot.step_length, 1e-12);
  for (int k = 0; k < config.step_frames; ++k) landed = gait.advance(Command::Turn, -1);
  EXPECT_NEAR(gait.pose().yaw, -foot.turn_step * kDeg, 1e-12);
  ASSERT_TRUE(landed);
  EXPECT_EQ(landed->foot, Foot::Left);
  // Stop acts at once: the swing foot is put down, the sensor stands still.
  gait.advance(Command::Walk);
  landed = gait.advance(Command::Stop);
  ASSERT_TRUE(landed);
  EXPECT_EQ(landed->foot, Foot::Right);
  EXPECT_EQ(gait.mount().roll, 0.0);
  EXPECT_FALSE(gait.advance(Command::Stop));
}

TEST(Footsteps, PlanAlternatesAndClearanceMeasuresObjects) {
  const FootConfig foot;
  const std::vector<Footstep> plan = planStraight(Pose2D{1, 2, M_PI / 2}, Foot::Right, 4, foot);
  ASSERT_EQ(plan.size(), 4u);
  EXPECT_EQ(plan[0].foot, Foot::Right);
  EXPECT_EQ(plan[1].foot, Foot::Left);
  // Facing +y: the right foot is at +x, 1.5 steps ahead.
  EXPECT_NEAR(plan[0].sole.centre.x(), 1 + 0.5 * foot.foot_separation, 1e-12);
  EXPECT_NEAR(plan[0].sole.centre.y(), 2 + 1.5 * foot.step_length, 1e-12);
  EXPECT_NEAR(plan[3].body.y, 2 + 4 * foot.step_length, 1e-12);

  Footprint sole;  // 95 x 65 mm at the origin, facing x
  sole.length = foot.foot_length;
  sole.width = foot.foot_width;
  const double front = 0.5 * foot.foot_length;
  EXPECT_NEAR(
      clearance(sole, SceneObject::sphere("b", Eigen::Vector3d(front + 0.03, 0, 0.02), 0.02)), 0.01,
      1e-9);
  EXPECT_EQ(clearance(sole, SceneObject::sphere("b", Eigen::Vector3d(front, 0.01, 0.02), 0.02)),
            0.0);
  // A cable across, 7 mm thick, 5 mm in front of the toes; and one under the sole.
  const auto cable = [](double x) {
    return SceneObject::cylinder("c", Eigen::Vector3d(x, -1, 0.0035), Eigen::Vector3d(x, 1, 0.0035),
                                 0.0035);
  };
  EXPECT_NEAR(clearance(sole, cable(front + 0.0085)), 0.005, 1e-9);
  EXPECT_EQ(clearance(sole, cable(0.0)), 0.0);
  // A box beside the sole, turned 45 deg: its corner 10 mm from the sole's side.
  const double half_diagonal = 0.05 * std::sqrt(2.0);
  const SceneObject box = SceneObject::box(
      "box", Eigen::Vector3d(0, 0.5 * foot.foot_width + 0.01 + half_diagonal, 0.02),
      Eigen::Vector3d(0.1, 0.1, 0.04), 45.0);
  EXPECT_NEAR(clearance(sole, box), 0.01, 1e-9);
}

TEST(Walker, StopsForASuddenObstacleThenWalks) {
  WalkerConfig config;
  config.stop_frames = 5;
  const FootConfig foot;
  Walker walker(config, foot);
  const OccupancyMap map;  // empty: nothing known
  ObstacleResult seen;
  Obstacle ball;
  ball.min = Eigen::Vector3d(0.09, 0.0, 0.0);
  ball.max = Eigen::Vector3d(0.13, 0.04, 0.04);
  ball.distance = 0.09 - foot.toe();
  ball.height = 0.04;
  ball.indices.assign(37, 0);  // the points the ball gives where it lands
  ball.surface.assign(37, 0);
  ball.surface_heights.assign(37, 0.035f);
  seen.obstacles.push_back(ball);
  // Seen in one frame only: a floor's texture lobe lasts one or two.
  EXPECT_FALSE(walker.findSudden(seen, map, Pose2D{}));
  const std::optional<Obstacle> sudden = walker.findSudden(seen, map, Pose2D{});
  ASSERT_TRUE(sudden);
  // Its surface no higher than a texture lobe reaches: never sudden, however long it is seen,
  // even with speckle where a stripe was lost (no surface) reaching any height.
  seen.obstacles[0].surface_heights.assign(37,
                                           static_cast<float>(config.sudden_min_height) - 0.001f);
  seen.obstacles[0].height = 0.12;
  EXPECT_FALSE(walker.findSudden(seen, map, Pose2D{}));
  EXPECT_FALSE(walker.findSudden(seen, map, Pose2D{}));
  // Fewer tall surface points than a ball gives (a stray run): never sudden either.
  seen.obstacles[0] = ball;
  seen.obstacles[0].surface_heights.resize(static_cast<std::size_t>(config.sudden_min_points) - 1);
  EXPECT_FALSE(walker.findSudden(seen, map, Pose2D{}));
  EXPECT_FALSE(walker.findSudden(seen, map, Pose2D{}));
  // Beside a line below the floor, in this frame or the last (a dark line's lobes): not sudden.
  Obstacle line = ball;
  line.min.x() = line.max.x() + 0.01;
  line.max.x() = line.min.x() + 0.005;
  line.height = -0.02;
  line.surface_heights.assign(37, -0.02f);
  seen.obstacles[0] = ball;
  seen.obstacles.push_back(line);
  EXPECT_FALSE(walker.findSudden(seen, map, Pose2D{}));
  seen.obstacles.pop_back();
  EXPECT_FALSE(walker.findSudden(seen, map, Pose2D{}));  // the line was there a frame ago
  EXPECT_FALSE(walker.findSudden(seen, map, Pose2D{}));  // seen once since: one frame
  ASSERT_TRUE(walker.findSudden(seen, map, Pose2D{}));
  seen.obstacles[0].surface_heights.clear();  // a frame without it
  EXPECT_FALSE(walker.findSudden(seen, map, Pose2D{}));
  seen.obstacles[0] = ball;
  EXPECT_FALSE(walker.findSudden(seen, map, Pose2D{}));  // the run starts again
  ASSERT_TRUE(walker.findSudden(seen, map, Pose2D{}));
  // A line below the floor in one group with a lobe above it (the group's highest point is above
  // the floor, as on random floor 1006): still a line, whatever the group's height.
  {
    Walker fresh(config, foot);
    Obstacle mixed = line;
    mixed.height = 0.045;
    mixed.surface_heights.assign(36, -0.01f);
    mixed.surface_heights.resize(39, 0.045f);
    ObstacleResult both;
    both.obstacles = {ball, mixed};
    EXPECT_FALSE(fresh.findSudden(both, map, Pose2D{}));
    EXPECT_FALSE(fresh.findSudden(both, map, Pose2D{}));
  }
  // Beside the path (not in front of the soles) or far: not sudden.
  seen.obstacles[0].min.y() = 0.12;
  seen.obstacles[0].max.y() = 0.16;
  EXPECT_FALSE(walker.findSudden(seen, map, Pose2D{}));
  seen.obstacles[0] = ball;
  seen.obstacles[0].distance = 0.2;
  EXPECT_FALSE(walker.findSudden(seen, map, Pose2D{}));

  WalkerResult r = walker.step(map, Pose2D{}, Foot::Left, {true, sudden});
  EXPECT_EQ(r.command, Command::Stop);
  EXPECT_EQ(r.reason, Reason::SuddenObstacle);
  EXPECT_TRUE(r.obstacle);
  EXPECT_EQ(r.stop_frames_left, 4);
  for (int k = 0; k < 4; ++k) {
    r = walker.step(map, Pose2D{}, Foot::Left, {true, std::nullopt});
    EXPECT_EQ(r.command, Command::Stop) << k;
  }
  r = walker.step(map, Pose2D{}, Foot::Left, {true, std::nullopt});
  EXPECT_EQ(r.command, Command::Walk);
  EXPECT_EQ(r.reason, Reason::PathClear);
  EXPECT_EQ(r.planned.size(), static_cast<std::size_t>(config.lookahead_steps));
  // Fail safe: no floor, no step.
  r = walker.step(map, Pose2D{}, Foot::Left, {false, std::nullopt});
  EXPECT_EQ(r.command, Command::Stop);
  EXPECT_EQ(r.reason, Reason::NoFloor);
}

TEST(Walker, ConfigErrorsNameTheField) {
  WalkerConfig config;
  config.stop_frames = 0;
  try {
    config.validate();
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("stop_frames"), std::string::npos);
  }
  FootConfig foot;
  foot.turn_step = 0;
  EXPECT_THROW(Walker(WalkerConfig{}, foot), std::invalid_argument);
  GaitConfig gait;
  gait.step_frames = 1;
  EXPECT_THROW(gait.validate(), std::invalid_argument);
}

// A walk under a photometry: its floor and object surfaces reach the scene every frame, its light
// reaches the renderer, and the walk's own noise seed stays.
TEST(Walk, PhotometrySetsTheFloorTheObjectsAndTheLightButNotTheSeed) {
  const Photometry translucent = photometryPreset("translucent-objects");
  const Photometry tiles = photometryPreset("tiles");
  WalkConfig config;
  config.render_config.seed = 77;
  applyPhotometry(tiles, config);
  EXPECT_EQ(config.render_config.seed, 77u);
  EXPECT_EQ(config.render_config.laser_peak, tiles.render.laser_peak);
  EXPECT_EQ(config.scene.floor.texture, FloorTexture::Tiles);
  applyPhotometry(translucent, config);
  config.scene.extra.push_back(
      SceneObject::cylinder("screw", {0.3, 0.0, 0.0}, {0.3, 0.0, 0.002}, 0.003));
  WalkWorld world(config.scene);
  Pose2D body;
  for (const int frame : {0, config.scene.ball_frame}) {
    const Scene& scene = world.sceneAt(static_cast<std::uint64_t>(frame), body);
    EXPECT_EQ(scene.floor.texture, translucent.floor.texture);
    EXPECT_EQ(scene.floor.albedo, translucent.floor.albedo);
    ASSERT_EQ(scene.objects.size(), frame == 0 ? 2u : 3u);  // screw, cable (and the ball)
    for (const SceneObject& o : scene.objects) {
      EXPECT_EQ(o.albedo, translucent.object_albedo) << o.name;
      EXPECT_EQ(o.stripe_width, translucent.object_stripe_width) << o.name;
    }
  }
  // Without a photometry each object keeps its own surface: the ball 0.85, the cable 0.35.
  WalkWorld plain{WalkSceneConfig{}};
  for (const SceneObject& o : plain.sceneAt(300, body).objects) {
    EXPECT_EQ(o.albedo, o.name == "pingpong_ball" ? 0.85 : 0.35) << o.name;
    EXPECT_EQ(o.stripe_width, 1.0) << o.name;
  }
}

TEST(Walk, SurfaceErrorsNameTheField) {
  const auto message = [](auto change) { return validationMessage<WalkSceneConfig>(change); };
  EXPECT_NE(message([](WalkSceneConfig& c) {
              c.object_stripe_width = 5;
            }).find("WalkSceneConfig.object_stripe_width"),
            std::string::npos);
  EXPECT_NE(message([](WalkSceneConfig& c) {
              c.object_albedo = 1.5;
            }).find("WalkSceneConfig.object_albedo"),
            std::string::npos);
  EXPECT_NE(message([](WalkSceneConfig& c) { c.floor.albedo = -0.1; }).find("albedo"),
            std::string::npos);
  EXPECT_EQ(message([](WalkSceneConfig& c) { c.object_stripe_width = 0.5; }), "valid");
}
