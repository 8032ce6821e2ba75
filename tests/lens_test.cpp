// The lens model (OpenCV's distortion), the sensor file's coefficients, the camera calibration
// files of OpenCV and ROS, and a calibration's lens.
#include "multislit/lens.h"
#include "multislit/intrinsics_file.h"
#include "multislit/reference.h"
#include "multislit/sensor.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

using namespace multislit;

namespace {

// A strong barrel lens with tangential terms: the paper's camera's f and image.
LensDistortion barrel() {
  LensDistortion d;
  d.k1 = -0.12, d.k2 = 0.05, d.p1 = 4e-4, d.p2 = -3e-4, d.k3 = -0.01;
  return d;
}

void writeFile(const std::string& path, const std::string& text) { std::ofstream(path) << text; }
// A sensor file's text: OpenCV's YAML directive, then `body`.
std::string sensorText(const std::string& body) { return "%YAML:1.0\n---\n" + body; }

std::string errorOf(const CameraConfig& camera, const std::string& path) {
  try {
    withIntrinsicsFile(camera, path);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

const char* const kOpenCvFile = R"(%YAML:1.0
---
calibration_time: "Sun Dec  6 10:00:00 2026"
image_width: 1296
image_height: 964
flags: 0
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 1070., 0., 650.5, 0., 1064., 480.25, 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 5
   cols: 1
   dt: d
   data: [ -0.12, 0.05, 4.0e-4, -3.0e-4, -0.01 ]
avg_reprojection_error: 0.21
)";

const char* const kRosFile = R"(image_width: 1296
image_height: 964
camera_name: multislit
camera_matrix:
  rows: 3
  cols: 3
  data: [1067, 0, 650.5, 0, 1067, 480.25, 0, 0, 1]
distortion_model: rational_polynomial
distortion_coefficients:
  rows: 1
  cols: 8
  data: [-0.12, 0.05, 0.0004, -0.0003, -0.01, 0.02, 0, 0]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]
projection_matrix:
  rows: 3
  cols: 4
  data: [1067, 0, 650.5, 0, 0, 1067, 480.25, 0, 0, 0, 1, 0]
)";

}  // namespace

TEST(Lens, UndistortInvertsDistortOverTheImage) {
  const Lens lens(1066.7, 647.5, 481.5, barrel());
  EXPECT_TRUE(lens.monotonicOver(1296, 964));
  for (double u = 0; u <= 1295; u += 161.875)
    for (double v = 0; v <= 963; v += 120.375) {
      const Eigen::Vector2d recorded(u, v);
      const Eigen::Vector2d ideal = lens.undistort(recorded);
      EXPECT_LT((lens.distort(ideal) - recorded).norm(), 1e-8);
    }
  // The Jacobian against central differences.
  Eigen::Matrix2d j;
  const Eigen::Vector2d p(1100, 120);
  lens.distort(p, &j);
  for (int axis = 0; axis < 2; ++axis) {
    const Eigen::Vector2d h = 1e-4 * Eigen::Vector2d::Unit(axis);
    const Eigen::Vector2d numeric = (lens.distort(p + h) - lens.distort(p - h)) / 2e-4;
    EXPECT_LT((numeric - j.col(axis)).norm(), 1e-6);
  }
  // A barrel lens pulls the corners in: their ideal points lie farther out, by > 5 px.
  EXPECT_GT(lens.largestShift(1296, 964), 5.0);
  EXPECT_EQ(Lens(1066.7, 647.5, 481.5, LensDistortion{}).largestShift(1296, 964), 0.0);
}

TEST(Lens, OpenCvCoefficientOrder) {
  const LensDistortion d = LensDistortion::fromOpenCV({1, 2, 0.3, 0.4, 5, 6, 7, 8, 0, 0, 0, 0});
  const double got[] = {d.k1, d.k2, d.p1, d.p2, d.k3, d.k4, d.k5, d.k6};
  const double want[] = {1, 2, 0.3, 0.4, 5, 6, 7, 8};
  for (int i = 0; i < 8; ++i) EXPECT_EQ(got[i], want[i]) << i;
  EXPECT_THROW(LensDistortion::fromOpenCV({1, 2, 3}), std::invalid_argument);
  EXPECT_THROW(LensDistortion::fromOpenCV({0, 0, 0, 0, 0, 0, 0, 0, 0.1, 0, 0, 0}),
               std::invalid_argument);
}

TEST(SensorConfig, DistortionRoundTripsAndIsChecked) {
  SensorConfig s;
  s.camera.distortion = barrel();
  const std::string path = tempPath("distorted_sensor.yaml");
  s.save(path);
  const SensorConfig back = SensorConfig::load(path);
  EXPECT_EQ(back.camera.distortion.k1, s.camera.distortion.k1);
  EXPECT_EQ(back.camera.distortion.p2, s.camera.distortion.p2);
  EXPECT_EQ(back.camera.distortion.k3, s.camera.distortion.k3);
  // A pinhole's file has no coefficients; a misspelt one is named.
  SensorConfig{}.save(path);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(std::ifstream(path).rdbuf()), {}).find("k1"),
            std::string::npos);
  writeFile(path, sensorText("camera: {k1: .nan}\n"));
  EXPECT_THROW(SensorConfig::load(path), std::invalid_argument);
  writeFile(path, sensorText("camera: {kk1: 0.1}\n"));
  try {
    SensorConfig::load(path);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("kk1"), std::string::npos) << e.what();
  }
  // A lens whose radial map folds back inside the image is refused, naming the key.
  writeFile(path, sensorText("camera: {k1: -0.9}\n"));
  try {
    SensorConfig::load(path);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("camera.k1"), std::string::npos) << e.what();
  }
}

TEST(IntrinsicsFile, ReadsOpenCvAndRosCalibrations) {
  const std::string opencv = tempPath("opencv.yaml"), ros = tempPath("ros.yaml");
  writeFile(opencv, kOpenCvFile);
  writeFile(ros, kRosFile);
  const CameraConfig a = withIntrinsicsFile(CameraConfig{}, opencv);
  EXPECT_NEAR(a.f(), 1067.0, 1e-9);  // the mean of fx and fy
  EXPECT_EQ(a.cx(), 650.5);
  EXPECT_EQ(a.cy(), 480.25);
  EXPECT_EQ(a.distortion.k1, -0.12);
  EXPECT_EQ(a.distortion.p1, 4e-4);
  EXPECT_EQ(a.distortion.k3, -0.01);
  const CameraConfig b = withIntrinsicsFile(CameraConfig{}, ros);
  EXPECT_NEAR(b.f(), 1067.0, 1e-9);
  EXPECT_EQ(b.distortion.k2, 0.05);
  EXPECT_EQ(b.distortion.k4, 0.02);
}

TEST(IntrinsicsFile, BadFilesNameTheFileAndTheKey) {
  const std::string path = tempPath("bad_intrinsics.yaml");
  const auto errorFor = [&](const std::string& text) {
    writeFile(path, text);
    return errorOf(CameraConfig{}, path);
  };
  std::string ros = kRosFile;
  const auto replaced = [](std::string text, const std::string& from, const std::string& to) {
    return text.replace(text.find(from), from.size(), to);
  };
  const struct {
    std::string text, key;
  } cases[] = {
      {replaced(ros, "image_width: 1296", "image_width: 640"), "image_width"},
      {replaced(ros, "camera_matrix:", "camera_matrixx:"), "camera_matrix"},
      {replaced(ros, "data: [1067, 0, 650.5, 0, 1067,", "data: [1067, 0, 650.5, 0, 1100,"), "fy"},
      {replaced(ros, "rational_polynomial", "equidistant"), "distortion_model"},
      {replaced(ros, "0.02, 0, 0]", "0.02]"), "distortion_coefficients"},
      {replaced(ros, "[-0.12, 0.05", "[-0.12, x"), "distortion_coefficients"},
      {replaced(ros, "image_height: 964\n", ""), "image_height"},
  };
  for (const auto& c : cases) {
    const std::string error = errorFor(c.text);
    EXPECT_NE(error.find(path), std::string::npos) << error;
    EXPECT_NE(error.find(c.key), std::string::npos) << error;
  }
  EXPECT_NE(errorOf(CameraConfig{}, tempPath("absent.yaml")).find("absent.yaml"),
            std::string::npos);
}

TEST(Reference, KeepsItsLensAndRefusesAnother) {
  Reference ref;
  ref.image_width = 1296, ref.image_height = 964, ref.region_width = 20;
  ref.max_region_width = 30, ref.profile_width = 3;
  ReferenceSlit slit;
  slit.first_row = 100;
  slit.u.assign(300, 500.0f);
  ref.slits.push_back(slit);
  CameraConfig camera;
  camera.distortion = barrel();
  ref.setLens(camera);
  const std::string path = tempPath("lens_calibration.yaml");
  ref.save(path);
  const Reference back = Reference::load(path);
  EXPECT_TRUE(back.lens.distorted());
  EXPECT_EQ(back.lens.distortion().k1, camera.distortion.k1);
  EXPECT_NO_THROW(back.checkLens(camera, "calibration"));
  EXPECT_THROW(back.checkLens(CameraConfig{}, "calibration"), std::invalid_argument);
  EXPECT_THROW(Reference{}.checkLens(camera, "calibration"), std::invalid_argument);
  // The ideal points are the recorded ones through the lens.
  const Eigen::Vector2d ideal = back.idealPoint(back.slits[0], 0);
  EXPECT_LT((camera.lens().distort(ideal) - Eigen::Vector2d(500, 100)).norm(), 1e-6);
}
