// Stray runs along a slit (src/stray_runs.h): short runs of noise where a stripe is lost are
// dropped; a surface, however steep or tall, and a run nothing contradicts are kept.
#include "stray_runs.h"
#include "multislit/extractor.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

namespace {

using multislit::detail::dropStrayRuns;
using multislit::detail::SlitSample;

constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
constexpr int kLongest = 3;  // the extractor's default
constexpr double kStep = 6.0;

/// A slit of consecutive rows from 100 on, with these dk.
std::vector<SlitSample> slit(const std::vector<double>& dk) {
  std::vector<SlitSample> s;
  for (std::size_t i = 0; i < dk.size(); ++i) s.push_back({100 + static_cast<int>(i), dk[i]});
  return s;
}

/// Which samples are measured after the call.
std::vector<bool> measured(const std::vector<SlitSample>& s) {
  std::vector<bool> m;
  for (const SlitSample& p : s) m.push_back(std::isfinite(p.dk));
  return m;
}

TEST(StrayRuns, NoiseRunsOfALostStripeAreDropped) {
  // The floor with 0.2 px of noise, and runs of one, two and three rows tens of pixels off it, of
  // either sign, as a lost stripe's noise gives them (random floor 1009, frame 17).
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.2);
  std::vector<double> dk(60);
  for (double& d : dk) d = noise(rng);
  dk[10] = 44.8;
  dk[20] = -25.2, dk[21] = -25.1, dk[22] = -23.0;
  dk[23] = 23.7, dk[24] = 25.8;  // two strays side by side, 49 px apart
  dk[40] = 52.7, dk[41] = 52.2;
  auto s = slit(dk);
  EXPECT_EQ(dropStrayRuns(s, kLongest, kStep), 8u);
  for (std::size_t i = 0; i < s.size(); ++i) {
    const bool stray = i == 10 || (i >= 20 && i <= 24) || i == 40 || i == 41;
    EXPECT_EQ(std::isfinite(s[i].dk), !stray) << "row " << s[i].row;
  }
}

TEST(StrayRuns, SurfacesAreKept) {
  // A box 30 mm high (10 px), four rows of it: longer than a stray run.
  auto box = slit({0, 0.1, -0.2, 0, 0, 10.1, 9.8, 10.0, 10.2, 0.1, 0.0, -0.1, 0, 0});
  EXPECT_EQ(dropStrayRuns(box, kLongest, kStep), 0u);
  // A ball: dk climbs and falls by up to 3.5 px a row, the most the truth shows on a surface.
  auto ball = slit({0, 0, 0, 0, 3.5, 7.0, 10.0, 12.5, 13.6, 12.5, 10.0, 7.0, 3.5, 0, 0, 0, 0});
  EXPECT_EQ(dropStrayRuns(ball, kLongest, kStep), 0u);
  // A cable 7 mm high, three rows: its step from the floor is within a surface's.
  auto cable = slit({0.1, 0, 0, 0, 2.3, 2.4, 2.2, 0, -0.1, 0, 0});
  EXPECT_EQ(dropStrayRuns(cable, kLongest, kStep), 0u);
  // The edge of a box seen from its side: the floor, then its top, the stripe hidden between.
  auto edge = slit({0, 0, 0, 0, kNone, kNone, kNone, 15.0, 15.1, 15.0, 14.9, 15.0});
  EXPECT_EQ(dropStrayRuns(edge, kLongest, kStep), 0u);
}

TEST(StrayRuns, ARunNothingContradictsIsKept) {
  // Three rows 20 px off the floor, with no measured point within 2 rows on either side (the
  // stripe hidden around a thin post): nothing says it is not a surface.
  auto post =
      slit({0, 0, 0, 0, kNone, kNone, kNone, 20.0, 20.4, 20.2, kNone, kNone, kNone, 0, 0, 0, 0});
  EXPECT_EQ(dropStrayRuns(post, kLongest, kStep), 0u);
  // One unmeasured row between a run and its neighbour still makes them neighbours.
  auto gap = slit({0, 0, 0, 0, kNone, 20.0, 20.4, 20.2, kNone, 0, 0, 0, 0});
  EXPECT_EQ(dropStrayRuns(gap, kLongest, kStep), 3u);
  EXPECT_EQ(measured(gap), (std::vector<bool>{1, 1, 1, 1, 0, 0, 0, 0, 0, 1, 1, 1, 1}));
}

TEST(StrayRuns, AGapOfOneRowJoinsARunAndTheLongestRunIsAParameter) {
  // The rule has no side: a run of the floor as short as a stray, between two jumps, goes too
  // (a slit's floor runs are hundreds of rows long); so the floors here are 4 rows or more.
  auto joined =
      slit({0, 0, 0, 0, 30.0, kNone, 30.2, 30.1, 29.8, 0, 0, 0, 0});  // four points with the gap
  EXPECT_EQ(dropStrayRuns(joined, kLongest, kStep), 0u);
  auto longer = slit({0, 0, 0, 0, 0, 30.0, 30.2, 30.1, 29.8, 0, 0, 0, 0, 0});
  EXPECT_EQ(dropStrayRuns(longer, 4, kStep), 4u);
  auto off = slit({0, 0, 0, 0, 44.8, 0, 0, 0, 0});
  EXPECT_EQ(dropStrayRuns(off, 0, kStep), 0u);  // 0: nothing is dropped
  auto end = slit({44.8, 0, 0, 0, 0});          // a stray at the slit's end, one neighbour
  EXPECT_EQ(dropStrayRuns(end, kLongest, kStep), 1u);
  std::vector<SlitSample> empty;
  EXPECT_EQ(dropStrayRuns(empty, kLongest, kStep), 0u);
}

TEST(StrayRuns, TheExtractorsFieldsAreValidatedByName) {
  multislit::ExtractorConfig c;
  c.stray_run = -1;
  EXPECT_THROW(
      try { c.validate(); } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("stray_run"), std::string::npos);
        throw;
      },
      std::invalid_argument);
  c = {};
  c.stray_step = 0.0;
  EXPECT_THROW(
      try { c.validate(); } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("stray_step"), std::string::npos);
        throw;
      },
      std::invalid_argument);
}

}  // namespace
