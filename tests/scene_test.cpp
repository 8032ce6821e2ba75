// Ray casting against the scene primitives, and scene files.
#include "multislit/scene.h"
#include "multislit/scenarios.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

using namespace multislit;

TEST(Scene, FloorSphereCylinderAndBoxAreHitAtTheRightDistance) {
  Scene scene;
  scene.objects.push_back(SceneObject::sphere("ball", Eigen::Vector3d(1, 0, 0.02), 0.02));
  scene.objects.push_back(SceneObject::cylinder("cable", Eigen::Vector3d(2, -1, 0.0035),
                                                Eigen::Vector3d(2, 1, 0.0035), 0.0035));
  scene.objects.push_back(
      SceneObject::box("box", Eigen::Vector3d(3, 0, 0.015), Eigen::Vector3d(0.2, 0.4, 0.03), 30));
  const Eigen::Vector3d down(0, 0, -1);
  Hit h = scene.intersect(Eigen::Vector3d(0.5, 0, 1), down);
  EXPECT_EQ(h.object, 0);
  EXPECT_NEAR(h.distance, 1.0, 1e-12);
  h = scene.intersect(Eigen::Vector3d(1, 0, 1), down);
  EXPECT_EQ(h.object, 1);
  EXPECT_NEAR(h.distance, 1.0 - 0.04, 1e-12);
  EXPECT_NEAR(h.normal.z(), 1.0, 1e-12);
  h = scene.intersect(Eigen::Vector3d(2, 0.5, 1), down);
  EXPECT_EQ(h.object, 2);
  EXPECT_NEAR(h.distance, 1.0 - 0.007, 1e-12);
  h = scene.intersect(Eigen::Vector3d(2, 1.5, 1), down);  // beyond the cable's end
  EXPECT_EQ(h.object, 0);
  h = scene.intersect(Eigen::Vector3d(3.05, 0.1, 1), down);  // inside the rotated box's top
  EXPECT_EQ(h.object, 3);
  EXPECT_NEAR(h.distance, 1.0 - 0.03, 1e-12);
  // Horizontal ray into the cylinder's side.
  h = scene.intersect(Eigen::Vector3d(1.5, 0, 0.0035), Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(h.object, 2);
  EXPECT_NEAR(h.distance, 0.5 - 0.0035, 1e-12);
  EXPECT_NEAR(h.normal.x(), -1.0, 1e-12);
  // Nothing above the horizon.
  EXPECT_FALSE(scene.intersect(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, 1)).valid());
  EXPECT_NEAR(scene.objects[1].top(), 0.007, 1e-15);
}

TEST(Scene, FloorTextureVariesAroundItsMean) {
  Scene scene;
  double lo = 1, hi = 0, sum = 0;
  const int n = 200;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double a = scene.albedo(0, Eigen::Vector3d(i * 0.003, j * 0.003, 0));
      lo = std::min(lo, a);
      hi = std::max(hi, a);
      sum += a;
    }
  EXPECT_NEAR(sum / (n * n), scene.floor.albedo, 0.03);
  EXPECT_GT(hi - lo, 0.05);
  EXPECT_LE(hi - lo, 2 * scene.floor.texture_amplitude * scene.floor.albedo + 1e-12);
}

TEST(Scene, YamlRoundTripAndBadFieldsNamed) {
  const Scenario s = makeScenario("fig8");
  const std::string path =
      (std::filesystem::temp_directory_path() / "multislit_scene.yaml").string();
  s.scene.save(path);
  const Scene back = Scene::load(path);
  ASSERT_EQ(back.objects.size(), s.scene.objects.size());
  for (std::size_t k = 0; k < back.objects.size(); ++k) {
    EXPECT_EQ(back.objects[k].name, s.scene.objects[k].name);
    EXPECT_EQ(back.objects[k].type, s.scene.objects[k].type);
    EXPECT_NEAR((back.objects[k].centre - s.scene.objects[k].centre).norm(), 0, 1e-12);
    EXPECT_NEAR((back.objects[k].size - s.scene.objects[k].size).norm(), 0, 1e-12);
    EXPECT_DOUBLE_EQ(back.objects[k].radius, s.scene.objects[k].radius);
  }
  std::ofstream(path)
      << "%YAML:1.0\n---\nobjects:\n  - { type: sphere, name: b, centre: [0, 0, 1], radius: -1 }\n";
  try {
    Scene::load(path);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("radius"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  std::ofstream(path) << "%YAML:1.0\n---\nobjects:\n  - { type: cone, name: c }\n";
  EXPECT_THROW(Scene::load(path), std::invalid_argument);
  std::filesystem::remove(path);
}

TEST(Scenarios, TableIPosesAndNames) {
  EXPECT_DOUBLE_EQ(tableIPose(0).tilt, 66);
  EXPECT_DOUBLE_EQ(tableIPose(1).tilt, 61);
  EXPECT_DOUBLE_EQ(tableIPose(2).tilt, 71);
  EXPECT_DOUBLE_EQ(tableIPose(3).roll, -5);
  EXPECT_DOUBLE_EQ(tableIPose(4).roll, 5);
  EXPECT_DOUBLE_EQ(tableIPose(5).height, 0.395);
  EXPECT_DOUBLE_EQ(tableIPose(6).height, 0.495);
  EXPECT_THROW(tableIPose(7), std::out_of_range);
  for (const std::string& n : scenarioNames()) EXPECT_EQ(makeScenario(n).name, n);
  EXPECT_THROW(makeScenario("nothing"), std::invalid_argument);
  EXPECT_DOUBLE_EQ(makeScenario("fig8").mount.height, 0.495);
}
