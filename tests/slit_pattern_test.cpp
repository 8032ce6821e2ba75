// The slits as one pattern (src/slit_pattern.h) on the exact slits the simulator gives at the
// poses of Table I: the surface holds every centre of a clean reference, and a stretch of one
// slit pulled sideways, as a grout line running along its stripe pulls it, is found off the
// pattern while the rest of that slit and its neighbours stay on it.
#include "slit_pattern.h"

#include "multislit/sim/scenarios.h"
#include "multislit/sim/simulator.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <vector>

using namespace multislit;

namespace {

// The exact crossings of the bare floor at Table I pose `pose` as 15 tracks, with white noise of
// std `noise` [px] on each centre.
std::vector<Track> exactSlits(int pose, double noise) {
  const Simulator sim(SensorConfig{}, RenderConfig{});
  const Eigen::Isometry3d camera = sim.geometry().robotFromCamera(tableIPose(pose));
  std::vector<Track> slits(15);
  std::mt19937 rng(7u + static_cast<unsigned>(pose));
  std::normal_distribution<double> gauss(0.0, noise);
  for (const SlitCrossing& t : sim.groundTruth(Scene{}, camera))
    slits[static_cast<std::size_t>(t.slit)].points.push_back({t.row, t.u + gauss(rng), 5.0});
  return slits;
}

std::vector<std::vector<bool>> allOf(const std::vector<Track>& slits) {
  std::vector<std::vector<bool>> all;
  for (const Track& t : slits) all.emplace_back(t.points.size(), true);
  return all;
}

std::size_t countOff(const std::vector<std::vector<bool>>& on) {
  std::size_t off = 0;
  for (const auto& slit : on)
    for (const bool b : slit) off += !b;
  return off;
}

}  // namespace

TEST(SlitPattern, HoldsEveryCentreOfTheExactSlitsAtTheTableIPoses) {
  for (int pose = 0; pose < 7; ++pose) {
    const std::vector<Track> slits = exactSlits(pose, 0.0);
    const auto on = onPattern(slits, allOf(slits));
    EXPECT_EQ(countOff(on), 0u) << "pose " << pose;
  }
}

// Slit 7, rows 120 to 219 of its track moved by +1 px (a smooth bump rising over 10 rows at each
// end), on centres with 0.08 px of noise (a clean reference's): the bump is off the pattern, the
// rest of slit 7 and slits 6 and 8 on it.
TEST(SlitPattern, FindsAStretchPulledSideways) {
  std::vector<Track> slits = exactSlits(0, 0.08);
  std::vector<Centre>& seven = slits[7].points;
  ASSERT_GT(seven.size(), 250u);
  for (std::size_t k = 110; k < 230; ++k) {
    const double in = std::min({1.0, (static_cast<double>(k) - 110) / 10, (230.0 - k) / 10});
    seven[k].u += in;
  }
  const auto on = onPattern(slits, allOf(slits));
  std::size_t bump_off = 0, rest_off = 0;
  for (std::size_t k = 0; k < seven.size(); ++k) {
    if (k >= 120 && k < 220) bump_off += !on[7][k];
    if (k < 100 || k >= 240) rest_off += !on[7][k];
  }
  std::size_t neighbours_off = 0;
  for (const std::size_t s : {6u, 8u})
    for (const bool b : on[s]) neighbours_off += !b;
  std::printf("bump: %zu of 100 off the pattern; rest of slit 7: %zu off; slits 6 and 8: %zu off\n",
              bump_off, rest_off, neighbours_off);
  EXPECT_EQ(bump_off, 100u);
  EXPECT_LE(rest_off, 2u);
  EXPECT_LE(neighbours_off, 4u);
}

// A pattern that is no smooth surface (every other slit moved by 5 px): nothing is judged.
// The 60 % share on its own: the first fit starts from the unmoved slits only (as if each moved
// slit's own fit had refused its centres), so the surface fits them to the noise and every moved
// centre lies 5 px off it. With 8 slits of 15 unmoved (about 53 % of the centres) nothing is
// judged; with 11 (about 73 %) every centre of the 4 moved slits is off and none other.
TEST(SlitPattern, JudgesOnlyWhenMostCentresFitTheSurface) {
  for (const std::size_t step : {2u, 4u}) {
    std::vector<Track> slits = exactSlits(0, 0.05);
    std::vector<std::vector<bool>> start = allOf(slits);
    std::size_t moved = 0, all = 0;
    for (std::size_t s = 0; s < slits.size(); ++s) {
      all += slits[s].points.size();
      if (s % step != 1) continue;
      for (Centre& c : slits[s].points) c.u += 5.0;
      start[s].assign(slits[s].points.size(), false);
      moved += slits[s].points.size();
    }
    const double share = 1.0 - static_cast<double>(moved) / static_cast<double>(all);
    const std::size_t off = countOff(onPattern(slits, start));
    if (step == 2) {
      EXPECT_LT(share, 0.6);
      EXPECT_EQ(off, 0u) << "fitting share " << share;
    } else {
      EXPECT_GT(share, 0.6);
      EXPECT_EQ(off, moved) << "fitting share " << share;
    }
  }
}

TEST(SlitPattern, JudgesNothingWhereTheSlitsMakeNoSmoothPattern) {
  std::vector<Track> slits = exactSlits(0, 0.05);
  for (std::size_t s = 1; s < slits.size(); s += 2)
    for (Centre& c : slits[s].points) c.u += 5.0;
  EXPECT_EQ(countOff(onPattern(slits, allOf(slits))), 0u);
}
