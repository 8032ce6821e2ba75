// The sweep rules of the map: a dark line's two lobes are neither an object nor a hole, the sweep
// is judged per place (a turn in place sweeps the sides, not the middle), and a rendered tiled
// floor stays empty while the robot walks, turns in place and stands.
#include "multislit/occupancy_map.h"
#include "multislit/sim/photometry.h"
#include "multislit/sim/walk.h"
#include "multislit/sweep_evidence.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

using namespace multislit;

namespace {

/// Strong evidence in column (x, 0), above or below the floor.
std::vector<SweepPoint> at(std::int32_t x, bool above) {
  return std::vector<SweepPoint>(3, SweepPoint{x, 0, above ? 0.008f : -0.008f, above, true, false});
}

std::vector<SweepPoint> both(const std::vector<SweepPoint>& a, const std::vector<SweepPoint>& b) {
  std::vector<SweepPoint> all = a;
  all.insert(all.end(), b.begin(), b.end());
  return all;
}

/// Two passes of slits, 2 mm of sweep a frame: 3 frames of `points`, 4 frames without, 3 with.
/// The verdicts of columns (0, 0) and (1, 0) at the end.
std::pair<SweepVerdict, SweepVerdict> twoPasses(const std::vector<SweepPoint>& points) {
  SweepEvidence e;
  for (int k = 0; k < 10; ++k) {
    e.beginFrame(0.002);
    e.addEvidence(k < 3 || k >= 7 ? points : std::vector<SweepPoint>{});
  }
  return {e.verdictAt(0, 0), e.verdictAt(1, 0)};
}

}  // namespace

TEST(SweepEvidence, ALinesTwoLobesAreNeitherAnObjectNorAHole) {
  // Alone, two consistent passes above occupy the place, two below make a hole.
  EXPECT_EQ(twoPasses(at(0, true)).first, SweepVerdict::Above);
  EXPECT_EQ(twoPasses(at(1, false)).second, SweepVerdict::Below);
  // Side by side (a dark line pulls the stripe above on one side, below on the other): neither.
  const auto lobes = twoPasses(both(at(0, true), at(1, false)));
  EXPECT_EQ(lobes.first, SweepVerdict::Pending);
  EXPECT_EQ(lobes.second, SweepVerdict::Pending);
  // Three columns apart they are two things.
  SweepEvidence far;
  for (int k = 0; k < 10; ++k) {
    far.beginFrame(0.002);
    far.addEvidence(k < 3 || k >= 7 ? both(at(0, true), at(3, false)) : std::vector<SweepPoint>{});
  }
  EXPECT_EQ(far.verdictAt(0, 0), SweepVerdict::Above);
  EXPECT_EQ(far.verdictAt(3, 0), SweepVerdict::Below);
}

TEST(SweepEvidence, ATurnInPlaceSweepsTheSidesNotTheMiddle) {
  // Turning about column y = 0 moves the slits in proportion to y: 0 at y = 0, 2 mm a frame at
  // y = 20 columns. The same tall evidence in both places: only the swept one is new evidence.
  SweepStep turn;
  turn.per_y = 0.0001;  // [m per column]
  SweepEvidence e;
  std::vector<SweepPoint> tall;
  for (const std::int32_t y : {0, 20})
    for (int i = 0; i < 3; ++i) tall.push_back(SweepPoint{0, y, 0.03f, true, true, true});
  for (int k = 0; k < 5; ++k) {
    e.beginFrame(turn);
    e.addEvidence(tall);
  }
  EXPECT_EQ(e.verdictAt(0, 0), SweepVerdict::Pending);
  EXPECT_EQ(e.verdictAt(0, 20), SweepVerdict::Above);
  EXPECT_NEAR(e.sweepAt(0, 20), 5 * 0.002, 1e-12);
  EXPECT_NEAR(e.sweepAt(0, 0), 0.0, 1e-12);
}

TEST(Walk, TiledFloorStaysEmptyWalkingTurningInPlaceAndStanding) {
  // Rendered tiles (dark grout 4 mm wide on 20 cm tiles): walk, turn 40 deg in place, stand.
  WalkConfig config;
  config.scene.ball = config.scene.cable = false;
  applyPhotometry(choosePhotometry("tiles", 1), config);
  WalkSimulation walk(config);
  // Whole steps (24 frames each): a step under way is finished before the next command.
  const int walking = frameCount(48, 24), turning = frameCount(96, 24),
            standing = frameCount(48, 6);
  std::size_t most = 0;
  // The slits' move at the middle of the view, summed per what the body did since the last frame
  // (a step under way is finished before a turn or a stop), and the frames of each.
  double moved[3] = {}, sweep = 0.0;
  int frames[3] = {};
  std::size_t motion = 0;
  for (int k = 0; k < walking + turning + standing; ++k) {
    const Command c = k < walking             ? Command::Walk
                      : k < walking + turning ? Command::Turn
                                              : Command::Stop;
    const WalkFrame f = walk.step(c);
    ASSERT_TRUE(f.floor.found) << "frame " << k;
    if (k > 0) {
      moved[motion] += std::abs(f.map.sweep - sweep);
      ++frames[motion];
    }
    motion = static_cast<std::size_t>(f.motion);
    sweep = f.map.sweep;
    most = std::max(most, walk.map().occupiedCount());
  }
  const auto perFrame = [&](Command c) {
    const auto i = static_cast<std::size_t>(c);
    return frames[i] > 0 ? moved[i] / frames[i] : 0.0;
  };
  std::printf(
      "tiles: slits' move at the middle of the view %.2f mm a frame walking, %.2f turning, "
      "%.2f standing (%d, %d, %d frames); occupied voxels at most %zu\n",
      1e3 * perFrame(Command::Walk), 1e3 * perFrame(Command::Turn), 1e3 * perFrame(Command::Stop),
      frames[0], frames[1], frames[2], most);
  EXPECT_EQ(most, 0u);
  EXPECT_GT(perFrame(Command::Walk), 0.001);  // the paper's gait: 1.7 mm a frame
  EXPECT_LT(perFrame(Command::Turn), 0.5 * perFrame(Command::Walk));
  EXPECT_GT(frames[static_cast<std::size_t>(Command::Stop)], 0);
  EXPECT_EQ(perFrame(Command::Stop), 0.0);
}
