// Odometry files: read back to the same bits, interpolated between samples, and every malformed
// file (gaps, reversed or repeated stamps, NaN, short rows, a wrong header) refused with the file,
// line and field named.
#include "multislit/odometry.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

using namespace multislit;

namespace {

std::filesystem::path writeFile(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::path(tempPath("multislit_odometry_" + name));
  std::ofstream(path) << text;
  return path;
}

/// The message of the error that loading `text` throws, or "" when it loads.
std::string loadError(const std::string& name, const std::string& text) {
  try {
    Odometry::load(writeFile(name, text).string());
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

Eigen::Isometry3d pose(double x, double y, double yaw) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = fromRollPitchYaw(0.01, -0.02, yaw);
  t.translation() = Eigen::Vector3d(x, y, 0.3);
  return t;
}

}  // namespace

TEST(Odometry, SavedFileReadsBackTheSamePoses) {
  std::vector<OdometrySample> samples;
  for (int k = 0; k < 50; ++k)
    samples.push_back({static_cast<std::uint64_t>(1700000000000000 + 33333 * k),
                       pose(0.01 * k, -0.002 * k, 0.03 * k - 0.7)});
  const auto path = std::filesystem::path(tempPath("multislit_odometry_roundtrip.csv"));
  saveOdometry(path.string(), samples);
  const Odometry odometry = Odometry::load(path.string());
  ASSERT_EQ(odometry.samples().size(), samples.size());
  for (const OdometrySample& s : samples) {
    const auto got = odometry.at(s.stamp_us);
    ASSERT_TRUE(got);
    EXPECT_LT((got->matrix() - s.world_from_robot.matrix()).cwiseAbs().maxCoeff(), 1e-15);
  }
}

// Found by fuzz/fuzz_odometry: pitched 90 deg, roll and yaw were taken from rounding noise, and
// the file written back held another rotation (0.1 apart in the matrix).
TEST(Odometry, APoseAtGimbalLockIsWrittenAndReadBackTheSame) {
  for (const double pitch : {M_PI / 2, -M_PI / 2, M_PI / 2 - 1e-9, M_PI / 2 - 1e-7}) {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = fromRollPitchYaw(0.3, pitch, -3.1);
    const auto path = writeFile("gimbal.csv", "");
    saveOdometry(path.string(), {{1000, t}});
    const Odometry back = Odometry::load(path.string());
    EXPECT_LT((back.samples()[0].world_from_robot.linear() - t.linear()).cwiseAbs().maxCoeff(),
              1e-8)
        << "pitch " << pitch;
  }
}

// Read while writing fuzz/fuzz_odometry: a stamp such as 1e5 passed the whole-number check as a
// double and was then read as an integer up to the 'e': 1 us instead of 100000.
TEST(Odometry, AStampInExponentFormIsReadWhole) {
  const std::string header = "stamp_us,x,y,z,roll,pitch,yaw\n";
  const Odometry odometry =
      Odometry::load(writeFile("exponent.csv", header + "1e5,0,0,0,0,0,0\n100001.0,0,0,0,0,0,0\n"
                                                        "1796209002323686,0,0,0,0,0,0\n")
                         .string());
  ASSERT_EQ(odometry.samples().size(), 3u);
  EXPECT_EQ(odometry.samples()[0].stamp_us, 100000u);
  EXPECT_EQ(odometry.samples()[1].stamp_us, 100001u);
  EXPECT_EQ(odometry.samples()[2].stamp_us, 1796209002323686u);
}

TEST(Odometry, InterpolatesPositionLinearlyAndYawOnTheShorterArc) {
  const Odometry odometry({{1000, pose(0.0, 0.0, 3.0)}, {2000, pose(1.0, 2.0, -3.0)}});
  const auto mid = odometry.at(1250);
  ASSERT_TRUE(mid);
  EXPECT_NEAR(mid->translation().x(), 0.25, 1e-12);
  EXPECT_NEAR(mid->translation().y(), 0.5, 1e-12);
  // From 3 rad to -3 rad the short way is through pi: a quarter of the 0.283 rad between them.
  const double yaw = rollPitchYaw(mid->linear())[2];
  EXPECT_NEAR(std::remainder(yaw - (3.0 + 0.25 * (2 * M_PI - 6.0)), 2 * M_PI), 0.0, 2e-3);
}

TEST(Odometry, FramesOutsideTheSpanOrInAGapGetNoPose) {
  const Odometry odometry({{1000, pose(0, 0, 0)}, {2000, pose(1, 0, 0)}, {900000, pose(2, 0, 0)}},
                          500000);
  PoseMiss miss = PoseMiss::None;
  EXPECT_FALSE(odometry.at(999, &miss));
  EXPECT_EQ(miss, PoseMiss::BeforeStart);
  EXPECT_FALSE(odometry.at(900001, &miss));
  EXPECT_EQ(miss, PoseMiss::AfterEnd);
  EXPECT_FALSE(odometry.at(400000, &miss));  // 0.898 s between the samples around it
  EXPECT_EQ(miss, PoseMiss::InGap);
  EXPECT_TRUE(odometry.at(1500, &miss));
  EXPECT_EQ(miss, PoseMiss::None);
  EXPECT_TRUE(odometry.at(900000, &miss));  // a sample's own stamp, even after a gap
}

TEST(Odometry, MalformedFilesAreRefusedNamingFileLineAndField) {
  const std::string header = "stamp_us,x,y,z,roll,pitch,yaw\n";
  const std::string row1 = "1000,0,0,0,0,0,0\n";
  EXPECT_NE(loadError("nan.csv", header + row1 + "2000,0.1,0,0,nan,0,0\n")
                .find("nan.csv:3: roll 'nan' is not a finite number"),
            std::string::npos);
  EXPECT_NE(loadError("reversed.csv", header + row1 + "900,0,0,0,0,0,0\n")
                .find("reversed.csv:3: stamp_us 900 goes back from 1000"),
            std::string::npos);
  EXPECT_NE(loadError("duplicate.csv", header + row1 + row1)
                .find("duplicate.csv:3: stamp_us 1000 repeats the row before"),
            std::string::npos);
  EXPECT_NE(loadError("short.csv", header + "1000,0,0,0\n").find("short.csv:2: 4 values"),
            std::string::npos);
  EXPECT_NE(loadError("header.csv", "t,x,y\n" + row1).find("header.csv:1: the header must be"),
            std::string::npos);
  EXPECT_NE(loadError("stamp.csv", header + "-5,0,0,0,0,0,0\n").find("stamp.csv:2: stamp_us '-5'"),
            std::string::npos);
  EXPECT_NE(loadError("empty.csv", header).find("no poses"), std::string::npos);
  EXPECT_NE(loadError("inf.csv", header + "1000,inf,0,0,0,0,0\n").find("x 'inf'"),
            std::string::npos);
  EXPECT_EQ(loadError("good.csv", header + row1 + "2000,0.1,0,0,0,0,0.5\n"), "");
  EXPECT_THROW(Odometry::load("/nonexistent/odometry.csv"), std::runtime_error);
}
