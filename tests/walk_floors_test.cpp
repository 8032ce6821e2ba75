// The walk over the floors people have (issue 38): on every named photometry and on random ones,
// a bare floor never becomes an obstacle, because the map judges evidence over the sweep of the
// slits; with the ball and the cable on textured floors the robot still stops for the ball, turns
// away from the cable and touches nothing.
#include "multislit/sim/photometry.h"
#include "multislit/sim/truth.h"
#include "multislit/sim/walk.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <ostream>
#include <string>
#include <vector>

using namespace multislit;

namespace {

/// A photometry: a preset's name, or "random" with its seed.
struct Floor {
  std::string choice;
  std::uint64_t seed = 1;
};

std::vector<Floor> floors() {
  std::vector<Floor> all;
  for (const std::string& name : photometryPresetNames()) all.push_back({name, 1});
  for (std::uint64_t seed = 1001; seed <= 1018; ++seed) all.push_back({"random", seed});
  return all;
}

WalkConfig walkOn(const Floor& floor, bool objects) {
  WalkConfig config;
  config.render_config.seed = floor.seed;
  config.scene.ball = config.scene.cable = objects;
  applyPhotometry(choosePhotometry(floor.choice, floor.seed), config);
  return config;
}

std::string nameOf(const Floor& f) {
  std::string name = f.choice == "random" ? "random" + std::to_string(f.seed) : f.choice;
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

// CTest's test list names the floor, not the bytes of the struct.
void PrintTo(const Floor& f, std::ostream* os) { *os << nameOf(f); }

class BareFloor : public ::testing::TestWithParam<Floor> {};

}  // namespace

TEST_P(BareFloor, NeverBecomesAnObstacle) {
  WalkSimulation walk(walkOn(GetParam(), false));
  const int frames = frameCount(300, 40);
  int walking = 0;
  std::size_t most = 0;
  for (int k = 0; k < frames; ++k) {
    const WalkFrame f = walk.step();
    walking += f.motion == Command::Walk;
    most = std::max(most, walk.map().occupiedCount());  // no object: every voxel is false
  }
  std::printf("%s: %d of %d frames walking, at most %zu occupied voxels, %zu at the end\n",
              nameOf(GetParam()).c_str(), walking, frames, most, walk.map().occupiedCount());
  EXPECT_GE(walking, frames * 95 / 100);
  EXPECT_LE(walk.map().occupiedCount(), 2u);
}

INSTANTIATE_TEST_SUITE_P(Walk, BareFloor, ::testing::ValuesIn(floors()),
                         [](const ::testing::TestParamInfo<Floor>& param) {
                           return nameOf(param.param);
                         });

namespace {

class WithObjects : public ::testing::TestWithParam<Floor> {};

/// Occupied voxels within 3 cm of `at`, seen from above.
std::size_t occupiedNear(const OccupancyMap& map, const Eigen::Vector2d& at) {
  const double m = 0.03;
  return map
      .occupiedInBox(Eigen::Vector3d(at.x() - m, at.y() - m, -1),
                     Eigen::Vector3d(at.x() + m, at.y() + m, 1))
      .size();
}

}  // namespace

TEST_P(WithObjects, StopsForTheBallTurnsFromTheCableTouchesNothing) {
  WalkSimulation walk(walkOn(GetParam(), true));
  const WalkSceneConfig& scene = walk.config().scene;
  // Under the sanitizers: the ball only (its landing, the stop and its clearing).
  const int frames = frameCount(900, scene.ball_roll_frame + 61);
  int stopped = -1, cleared = -1, turned_for_cable = -1, touching = 0;
  Eigen::Vector2d landed = Eigen::Vector2d::Zero();
  for (int k = 0; k < frames; ++k) {
    const WalkFrame f = walk.step();
    if (k == scene.ball_frame) landed = f.body.toWorld(scene.ball_landing);
    if (stopped < 0 && k >= scene.ball_frame && f.walker.reason == Reason::SuddenObstacle)
      stopped = k;
    if (cleared < 0 && k >= scene.ball_roll_frame && occupiedNear(walk.map(), landed) == 0)
      cleared = k;
    if (turned_for_cable < 0 && f.walker.command == Command::Turn &&
        !f.walker.check.cells.empty() &&
        std::abs(f.walker.check.cells.front().centre.x() - scene.cable_start.x()) < 0.03)
      turned_for_cable = k;
    touching += f.footstep && f.footstep_clearance <= 0.0;
  }
  std::printf(
      "%s: stopped at %d (the ball lands at %d), the ball cleared at %d (rolls at %d), "
      "turned for the cable at %d, %d footsteps touching\n",
      nameOf(GetParam()).c_str(), stopped, scene.ball_frame, cleared, scene.ball_roll_frame,
      turned_for_cable, touching);
  EXPECT_GE(stopped, scene.ball_frame);
  EXPECT_LE(stopped, scene.ball_frame + 2);
  EXPECT_GE(cleared, scene.ball_roll_frame);
  EXPECT_LE(cleared, scene.ball_roll_frame + 60);
  EXPECT_EQ(touching, 0);
  if (!kSanitized) {
    EXPECT_GE(turned_for_cable, 0);
  }
}

INSTANTIATE_TEST_SUITE_P(Walk, WithObjects,
                         ::testing::Values(Floor{"default", 1}, Floor{"tiles", 1},
                                           Floor{"carpet", 1}, Floor{"speckle", 1}),
                         [](const ::testing::TestParamInfo<Floor>& param) {
                           return nameOf(param.param);
                         });
