// Sensor geometry: projections, slit surfaces, mount, configuration files.
#include "multislit/sensor.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <vector>

using multislit::SensorConfig;
using multislit::SensorGeometry;

namespace {

std::string validationMessage(const SensorConfig& c) {
  try {
    c.validate();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(SensorConfig, DefaultsAreThePapers) {
  const SensorConfig c;
  EXPECT_EQ(c.camera.width, 1296);
  EXPECT_EQ(c.camera.height, 964);
  EXPECT_NEAR(c.camera.f(), 4.0e-3 / 3.75e-6, 1e-9);
  EXPECT_EQ(c.projector.slit_count, 15);
  EXPECT_DOUBLE_EQ(c.projector.slit_spacing, 2.3);
  EXPECT_DOUBLE_EQ(c.projector.baseline, 0.060);
  EXPECT_DOUBLE_EQ(c.projector.rotation, 70.0);
  EXPECT_DOUBLE_EQ(c.mount.tilt, 66.0);
  EXPECT_DOUBLE_EQ(c.mount.height, 0.445);
  EXPECT_NO_THROW(c.validate());
}

TEST(SensorConfig, BadFieldIsNamed) {
  SensorConfig c;
  c.camera.width = -3;
  EXPECT_NE(validationMessage(c).find("camera.width"), std::string::npos);
  c = SensorConfig{};
  c.projector.baseline = 0.0;
  EXPECT_NE(validationMessage(c).find("projector.baseline"), std::string::npos);
  c = SensorConfig{};
  c.projector.curvature = 2.0;  // a slit would cross some rows twice
  EXPECT_NE(validationMessage(c).find("projector.curvature"), std::string::npos);
  c = SensorConfig{};
  c.mount.tilt = 120;
  EXPECT_NE(validationMessage(c).find("mount.tilt"), std::string::npos);
  // Found by fuzz/fuzz_sensor: f = 1e29 px put slit rows out of an int's range (undefined).
  c = SensorConfig{};
  c.camera.pixel_size = 3.75e-32;
  EXPECT_NE(validationMessage(c).find("camera.focal_length over pixel_size"), std::string::npos);
  c.camera.pixel_size = 1e-3 * (1 - 1e-9);  // f = 4 px: a wide lens, still valid
  EXPECT_EQ(validationMessage(c), "");
}

TEST(SensorConfig, YamlRoundTripAndErrorsNameTheFile) {
  SensorConfig c;
  c.projector.baseline = 0.07;
  c.mount.roll = -5;
  const std::string path = tempPath("roundtrip.yaml");
  c.save(path);
  const SensorConfig back = SensorConfig::load(path);
  EXPECT_DOUBLE_EQ(back.projector.baseline, 0.07);
  EXPECT_DOUBLE_EQ(back.mount.roll, -5);
  EXPECT_EQ(back.camera.width, c.camera.width);

  const std::string bad = tempPath("bad.yaml");
  std::ofstream(bad) << "%YAML:1.0\n---\ncamera:\n  width: -5\n";
  try {
    SensorConfig::load(bad);
    FAIL() << "a negative width must be rejected";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("camera.width"), std::string::npos) << e.what();
  }
  std::ofstream(bad) << "%YAML:1.0\n---\ncamera:\n  width: wide\n";
  EXPECT_THROW(SensorConfig::load(bad), std::invalid_argument);
  EXPECT_THROW(SensorConfig::load(tempPath("missing.yaml")), std::runtime_error);
  std::remove(path.c_str());
  std::remove(bad.c_str());
}

// A misspelt key, a key given twice or a section of the wrong shape is an error naming it, not a
// default silently used (OpenCV's parser keeps both entries of a repeated key; load() sees them).
TEST(SensorConfig, UnknownRepeatedAndMisshapenKeysAreErrors) {
  const std::string path = tempPath("keys.yaml");
  const auto error = [&](const std::string& body) {
    std::ofstream(path) << "%YAML:1.0\n---\n" << body;
    try {
      SensorConfig::load(path);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error("camera:\n  heigth: 900\n").find("unknown key 'camera.heigth'"),
            std::string::npos);
  EXPECT_NE(error("camera:\n  width: 1296\n  width: 640\n").find("'camera.width' is given twice"),
            std::string::npos);
  EXPECT_NE(error("mount: [66, 0, 0.445]\n").find("'mount' must be a map"), std::string::npos);
  EXPECT_NE(error("lens:\n  f: 4\n").find("unknown key 'lens'"), std::string::npos);
  EXPECT_NE(error("camera:\n  width: 1296\ncamera:\n  width: 640\n").find("'camera' is given"),
            std::string::npos);
  EXPECT_NE(error("mount:\n  tilte: 60\n").find(path), std::string::npos);  // the file, too
  EXPECT_EQ(error("mount:\n  tilt: 60\n"), "");
  std::remove(path.c_str());
}

// OpenCV's YAML parser recurses per level: 200 000 nested brackets overflowed the stack. The
// loaders refuse a file nested deeper than 64 brackets (or 1024 spaces) before parsing it.
TEST(SensorConfig, DeeplyNestedFilesAreRefusedBeforeParsing) {
  const std::string path = tempPath("nested.yaml");
  std::ofstream(path) << "%YAML:1.0\n---\ncamera: " << std::string(200000, '[')
                      << std::string(200000, ']') << "\n";
  try {
    SensorConfig::load(path);
    FAIL() << "a file nested 200000 deep was parsed";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nested 200000 brackets deep"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  std::ofstream(path) << "%YAML:1.0\n---\n# a comment [[[[ is no nesting\nmount:\n  tilt: 60\n";
  EXPECT_DOUBLE_EQ(SensorConfig::load(path).mount.tilt, 60.0);
  std::remove(path.c_str());
}

// Found by fuzz/fuzz_sensor: on an empty key in a flow map OpenCV's parser throws
// std::length_error, which escaped the loaders (they promise std::runtime_error naming the file).
TEST(SensorConfig, AFileTheParserFailsOnIsARuntimeErrorNamingIt) {
  const std::string path = tempPath("length_error.yaml");
  std::ofstream(path) << "%YAML:1.0\n---\ncamera: {width: 1296, : 2}\n";
  try {
    SensorConfig::load(path);
    FAIL() << "a malformed file was loaded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'" + path + "' is not valid YAML"), std::string::npos)
        << e.what();
  }
  std::remove(path.c_str());
}

// Found by fuzz/fuzz_sensor: OpenCV's parser loops forever when the first map ends before the
// file and a line starting with '-' follows, and reads before its buffer on a line starting with
// ':'. Such files are refused before parsing, naming the line.
TEST(SensorConfig, FilesTheParserHangsOnAreRefusedBeforeParsing) {
  const std::string path = tempPath("layout.yaml");
  const auto error = [&path](const std::string& text) {
    std::ofstream(path) << text;
    try {
      SensorConfig::load(path);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("loaded");
  };
  const std::string first_key = "line 2 must be the first key of a map, at the start of the line";
  EXPECT_NE(error("%YAML:1.\n---s:0\n-#\n-").find(first_key), std::string::npos);  // the hang
  EXPECT_NE(error("%YAML:1.0\n   mount:\n     tilt: 60\n-x\n").find(first_key), std::string::npos);
  EXPECT_NE(error("%YAML:1.0\n{mount: {tilt: 60}}\n").find(first_key), std::string::npos);
  EXPECT_NE(error("%YAML:1.0\n...\n-M---\n").find(first_key), std::string::npos);
  EXPECT_NE(error(std::string("%YAML:1.\0\ns\n -s\ns\n-", 19)).find("line 1 holds a NUL byte"),
            std::string::npos);  // found by fuzz/fuzz_scene: another way to the endless loop
  EXPECT_NE(error("%YAML:1.0\n---\n---\nmount:\n").find("line 3 starts a second document"),
            std::string::npos);  // (its top level a list, on which Scene::load threw cv::Exception)
  EXPECT_NE(error("%YAML:1.0\nmount:\n  tilt: 60\n...\n-x\n").find("line 4 ends the document"),
            std::string::npos);
  EXPECT_NE(error("%YAML:1.0\nmount:\n  tilt: 60\n  : 2\n").find("line 4 starts with ':'"),
            std::string::npos);
  EXPECT_NE(error("%YAML:1.0\nmount:\n  : 2\n").find(path), std::string::npos);
  EXPECT_EQ(error("%YAML:1.0\n--- # a comment\n\n# a comment\nmount:\n  tilt: 60\n"), "loaded");
  std::remove(path.c_str());
}

TEST(SensorConfig, CommittedDefaultFileIsTheDefault) {
  const SensorConfig c = SensorConfig::load(std::string(MULTISLIT_DATA_DIR) + "/sensor.yaml");
  const SensorConfig d;
  EXPECT_EQ(c.camera.width, d.camera.width);
  EXPECT_DOUBLE_EQ(c.projector.curvature, d.projector.curvature);
  EXPECT_DOUBLE_EQ(c.projector.sheet_sigma, d.projector.sheet_sigma);
  EXPECT_DOUBLE_EQ(c.mount.forward, d.mount.forward);
}

TEST(SensorGeometry, ProjectInvertsPixelRay) {
  const SensorGeometry g{SensorConfig{}};
  for (double u : {0.0, 100.25, 647.5, 1295.0})
    for (double v : {0.0, 481.5, 900.75}) {
      const Eigen::Vector2d uv = g.project(0.37 * g.pixelRay(u, v));
      EXPECT_NEAR(uv.x(), u, 1e-9);
      EXPECT_NEAR(uv.y(), v, 1e-9);
    }
}

TEST(SensorGeometry, SlitRaysLieOnTheirSheetAndKeepTheirRowAtAnyDepth) {
  const SensorGeometry g{SensorConfig{}};
  for (int slit : {0, 7, 14})
    for (double t : {-0.4, 0.0, 0.3}) {
      const Eigen::Vector3d dir = g.slitRay(slit, t);
      for (double s : {0.2, 0.5, 2.0}) {
        const Eigen::Vector3d p = g.projectorCentre() + s * dir;
        EXPECT_NEAR(g.sheetOffset(slit, g.toProjector(p)), 0.0, 1e-12);
        EXPECT_EQ(g.nearestSlit(g.toProjector(p)), slit);
        // Parallel stereo: a projector ray is seen on one image row, whatever the depth.
        EXPECT_NEAR(g.project(p).y(), g.rowOf(slit, t), 1e-9);
      }
      const std::optional<double> back = g.slitParamForRow(slit, g.rowOf(slit, t));
      ASSERT_TRUE(back.has_value());
      EXPECT_NEAR(*back, t, 1e-12);
    }
}

// The batch of a row (the simulator's) gives what the point-wise search gives, bit for bit:
// inside the fan, beyond it (where atan takes over from the series), on the boundaries between
// sheets, back and forth along a row, and NaN.
TEST(SensorGeometry, NearestSheetOffsetsOfARowAreThoseOfEachPoint) {
  SensorConfig config;
  for (const double curvature : {0.0, 0.08}) {
    config.projector.curvature = curvature;
    const SensorGeometry g{config};
    std::vector<double> x, y;
    for (int i = 0; i < 4000; ++i) {  // a row across the whole fan and far beyond it
      x.push_back(-1.2 + 0.0006 * i);
      y.push_back(0.3 - 0.0001 * i);
    }
    for (int i = 0; i < 400; ++i) {  // back and forth, and jumps
      x.push_back(std::sin(0.37 * i) * 0.5);
      y.push_back(std::cos(0.11 * i) * 0.4);
    }
    for (int slit = 0; slit + 1 < g.slitCount(); ++slit) {  // midway between two sheets
      const double mid =
          std::tan(0.5 * (std::atan(g.slitTan(slit)) + std::atan(g.slitTan(slit + 1))));
      for (const double yy : {0.0, 0.2})
        for (const double dx : {-1e-17, 0.0, 1e-17})
          x.push_back(mid + dx + curvature * yy * yy), y.push_back(yy);
    }
    x.push_back(std::numeric_limits<double>::quiet_NaN()), y.push_back(0.0);
    x.push_back(0.1), y.push_back(std::numeric_limits<double>::quiet_NaN());
    x.push_back(std::numeric_limits<double>::infinity()), y.push_back(0.0);
    const int n = static_cast<int>(x.size());
    std::vector<double> offsets(x.size());
    std::vector<int> slits(x.size());
    std::vector<double> near_offsets(x.size());  // exact_far false: exact within kFarOffset
    std::vector<int> near_slits(x.size());
    g.nearestSheetOffsets(x.data(), y.data(), n, offsets.data(), slits.data());
    g.nearestSheetOffsets(x.data(), y.data(), n, near_offsets.data(), near_slits.data(), false);
    int far = 0;
    for (int i = 0; i < n; ++i) {
      int slit = -1;
      const double offset = g.nearestSheetOffset(Eigen::Vector2d(x[i], y[i]), &slit);
      EXPECT_EQ(slits[i], slit) << "point " << i << " (" << x[i] << ", " << y[i] << ")";
      EXPECT_EQ(near_slits[i], slit) << "point " << i;
      if (std::isnan(offset)) {
        EXPECT_TRUE(std::isnan(offsets[i])) << "point " << i;
        EXPECT_TRUE(std::isnan(near_offsets[i])) << "point " << i;
        continue;
      }
      EXPECT_EQ(offsets[i], offset) << "point " << i << " (" << x[i] << ", " << y[i] << ")";
      if (std::abs(offset) <= SensorGeometry::kFarOffset) {
        EXPECT_EQ(near_offsets[i], offset) << "point " << i;
      } else {  // the same side of the sheet, and as far as it needs to be seen to be
        ++far;
        EXPECT_EQ(std::signbit(near_offsets[i]), std::signbit(offset)) << "point " << i;
        EXPECT_GT(std::abs(near_offsets[i]), SensorGeometry::kFarOffset) << "point " << i;
      }
    }
    EXPECT_GT(far, 2000);  // most of the row lies outside the fan
  }
}

TEST(SensorGeometry, RotationShrinksRowsPerSlitByCosTheta) {
  // v(t) = cy + f (sin(rho) (a + k t^2) + cos(rho) t): the curvature term is even in t, so a slit
  // spans 2 f tan(half length) cos(rho) rows (paper Sec. II-A: "cos(theta) times").
  const SensorGeometry g{SensorConfig{}};
  const double expected = 2.0 * g.config().camera.f() * g.slitTMax() * std::cos(70.0 * M_PI / 180);
  for (int slit = 0; slit < g.slitCount(); ++slit) {
    const auto [first, last] = g.slitRows(slit);
    EXPECT_NEAR(last - first + 1, expected, 1.0) << "slit " << slit;
  }
}

TEST(SensorGeometry, MountLooksDownAtTheFloorInFrontOfTheFeet) {
  const SensorGeometry g{SensorConfig{}};
  const Eigen::Isometry3d robot_from_camera = g.robotFromCamera();
  EXPECT_NEAR(robot_from_camera.translation().z(), 0.445, 1e-12);
  const Eigen::Vector3d axis = robot_from_camera.linear() * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(std::asin(-axis.z()) * 180 / M_PI, 66.0, 1e-9);  // theta below the horizontal
  EXPECT_NEAR(axis.y(), 0.0, 1e-12);
  // The optical axis meets the floor h / tan(theta) ahead of the camera.
  const double s = 0.445 / -axis.z();
  EXPECT_NEAR((robot_from_camera.translation() + s * axis).x(),
              0.03 + 0.445 / std::tan(66 * M_PI / 180), 1e-9);
  // The slits lie across the walking direction: the middle slit's ends on the floor differ in y.
  const Eigen::Vector3d origin = robot_from_camera * g.projectorCentre();
  auto onFloor = [&](double t) {
    const Eigen::Vector3d d = robot_from_camera.linear() * g.slitRay(7, t);
    return Eigen::Vector3d(origin - origin.z() / d.z() * d);
  };
  const Eigen::Vector3d across = onFloor(0.3) - onFloor(-0.3);
  EXPECT_GT(std::abs(across.y()), 10 * std::abs(across.x()));
}
