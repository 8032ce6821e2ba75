// Ray casting against the scene primitives, and scene files.
#include "multislit/sim/scene.h"
#include "multislit/sim/scenarios.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <utility>
#include <vector>

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

// Found by fuzz/fuzz_scene: a texture of 1e-20 m put the noise lattice out of the range of an
// int64 (undefined behaviour, reported by the sanitizer build); so does a floor point far away.
TEST(Scene, FloorTextureStaysInRangeForAnyScaleAndDistance) {
  for (const FloorTexture texture : {FloorTexture::Wood, FloorTexture::Tiles, FloorTexture::Carpet})
    for (const double scale : {1.2e-20, 0.012, 1e20}) {
      Scene scene;
      scene.floor.texture = texture;
      scene.floor.texture_scale = scale;
      scene.floor.grout_width = 0;
      for (const double x : {0.3, -4e3, 1e15}) {
        const double a = scene.albedo(0, Eigen::Vector3d(x, 0.25 * x, 0));
        EXPECT_GE(a, 0.0) << floorTextureName(texture) << " scale " << scale << " at " << x;
        EXPECT_LE(a, 1.0) << floorTextureName(texture) << " scale " << scale << " at " << x;
      }
    }
}

TEST(Scene, YamlRoundTripAndBadFieldsNamed) {
  const Scenario s = makeScenario("fig8");
  const std::string path = tempPath("multislit_scene.yaml");
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

TEST(Scene, TilesHaveGroutLinesOfTheGivenWidthAndCarpetHasFineContrast) {
  Scene scene;
  scene.floor.texture = FloorTexture::Tiles;
  scene.floor.texture_scale = 0.2;
  scene.floor.grout_width = 0.004;
  scene.floor.grout_albedo = 0.08;
  scene.floor.texture_amplitude = 0.1;
  // Along a line across the tiles (1 mm steps over 2 m): grout on 4 of every 200 mm.
  int grout = 0, tile = 0;
  for (int i = 0; i < 2000; ++i) {
    const double a = scene.albedo(0, Eigen::Vector3d(i * 0.001, 0.1234, 0));
    if (a == 0.08)
      ++grout;
    else if (a >= 0.55 * (1 - 0.1 - 0.03) && a <= 0.55 * (1 + 0.1 + 0.03))
      ++tile;
  }
  EXPECT_NEAR(grout, 40, 10);  // 10 crossings x 4 samples (+ one line along the row, if hit)
  EXPECT_EQ(grout + tile, 2000);
  // Carpet: neighbouring millimetres differ by tens of percent.
  scene.floor = FloorConfig{};
  scene.floor.texture = FloorTexture::Carpet;
  scene.floor.texture_scale = 0.0015;
  scene.floor.texture_amplitude = 0.6;
  double sum = 0, sum2 = 0;
  for (int i = 0; i < 4000; ++i) {
    const double a = scene.albedo(0, Eigen::Vector3d(i * 0.001, 0.5, 0));
    sum += a;
    sum2 += a * a;
  }
  const double mean = sum / 4000, contrast = std::sqrt(sum2 / 4000 - mean * mean) / mean;
  EXPECT_NEAR(mean, 0.55, 0.03);
  EXPECT_GT(contrast, 0.15);
}

TEST(Scene, SurfacePhotometryRoundTripsThroughYaml) {
  Scenario s = makeScenario("ball");
  s.scene.floor.texture = FloorTexture::Tiles;
  s.scene.floor.texture_scale = 0.25;
  s.scene.floor.gloss = 1.5;
  s.scene.floor.laser_albedo = 0.4;
  s.scene.floor.stripe_width = 1.3;
  s.scene.objects[0].stripe_width = 2.0;
  const std::string path = tempPath("multislit_scene_photometry.yaml");
  s.scene.save(path);
  const Scene back = Scene::load(path);
  EXPECT_EQ(back.floor.texture, FloorTexture::Tiles);
  EXPECT_DOUBLE_EQ(back.floor.texture_scale, 0.25);
  EXPECT_DOUBLE_EQ(back.floor.gloss, 1.5);
  EXPECT_DOUBLE_EQ(back.laserAlbedo(0), 0.4);
  EXPECT_DOUBLE_EQ(back.stripeWidth(0), 1.3);
  EXPECT_DOUBLE_EQ(back.stripeWidth(1), 2.0);
  EXPECT_DOUBLE_EQ(back.laserAlbedo(1), 1.0);
  // The glare: a bright spot on the floor where the lamp is mirrored, nothing elsewhere.
  const Eigen::Vector3d camera(0.03, 0, 0.445);
  double brightest = 0;
  for (double x = 0.0; x < 1.5; x += 0.01) {
    const Eigen::Vector3d p(x, 0.05, 0);
    brightest = std::max(brightest, back.floorGlare(p, (p - camera).normalized()));
  }
  EXPECT_GT(brightest, 0.5 * 1.5);
  EXPECT_EQ(back.floorGlare(Eigen::Vector3d(-2, 3, 0), Eigen::Vector3d(-0.6, 0.8, 0)), 0.0);
  s.scene.objects[0].stripe_width = 9;
  EXPECT_THROW(s.scene.validate(), std::invalid_argument);
  std::filesystem::remove(path);
}

// The renderer keeps the glare as a float, computed mostly without std::pow: it must be the same
// float as floorGlare()'s, everywhere, also where the lamp's image is faint (c^40 tiny) or nearly
// on a float's rounding boundary.
TEST(Scene, GlareAsFloatIsTheGlareConverted) {
  Scene scene;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> x(-1.0, 2.5), y(-1.5, 1.5), height(0.05, 1.0);
  std::size_t lit = 0, faint = 0;
  for (const double gloss : {0.3, 1.0, 1.7, 2.0}) {
    scene.floor.gloss = gloss;
    for (int k = 0; k < 250000; ++k) {
      const Eigen::Vector3d point(x(rng), y(rng), 0), camera(x(rng), y(rng), height(rng));
      const Eigen::Vector3d ray = (point - camera).normalized();
      const double glare = scene.floorGlare(point, ray);
      ASSERT_EQ(scene.floorGlareAsFloat(point, ray), static_cast<float>(glare))
          << "gloss " << gloss << " point " << point.transpose() << " ray " << ray.transpose();
      lit += glare > 0;
      faint += glare > 0 && glare < 1e-30;
    }
  }
  EXPECT_GT(lit, 100000u);
  EXPECT_GT(faint, 100u);
}

namespace {

// What Scene::load says of a file whose body (after the YAML header) is `body`: its message, or
// "loaded".
std::string loadMessage(const std::string& body) {
  const std::string path = tempPath("multislit_scene_bad.yaml");
  std::ofstream(path) << "%YAML:1.0\n---\n" << body;
  try {
    Scene::load(path);
  } catch (const std::invalid_argument& e) {
    std::filesystem::remove(path);
    return e.what();
  }
  std::filesystem::remove(path);
  return "loaded";
}

}  // namespace

TEST(Scene, BadValuesUnknownKeysAndHugeScenesAreRefusedNamingTheField) {
  const std::string sphere = "objects:\n  - { type: sphere, name: b, radius: 0.02, ";
  EXPECT_EQ(loadMessage(sphere + "centre: [0.3, 0, 0.02] }\n"), "loaded");
  // (message part, file body): each refused, the field named.
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"'centre' must be a list of 3 numbers", sphere + "centre: [a, b, c] }\n"},
      {"centre must be finite", sphere + "centre: [.nan, 0, 0] }\n"},
      {"centre must be finite", sphere + "centre: [1e300, 0, 0] }\n"},
      {"size must be finite",
       "objects:\n  - { type: box, name: x, centre: [0.3, 0, 0], size: [.inf, 1, 1] }\n"},
      {"radius must be <= 100 m",
       sphere.substr(0, sphere.size() - 14) + "radius: .inf, centre: [0.3, 0, 0] }\n"},
      {"unknown key 'objects[0].size'", sphere + "centre: [0.3, 0, 0], size: [1, 1, 1] }\n"},
      {"unknown key 'floor.albdo'", "floor: { albdo: 0.3 }\n"},
      {"key 'floor.albedo' is given twice", "floor: { albedo: 0.3, albedo: 0.9 }\n"},
      {"unknown key 'lights'", "lights: 3\n"},
      {"'texture_seed' must be an integer", "floor: { texture_seed: -1 }\n"},
      {"'texture_seed' must be an integer", "floor: { texture_seed: 2.5 }\n"},
      {"texture_scale must be in (0, 100] m", "floor: { texture_scale: .inf }\n"},
      {"'objects[0]' must be a map", "objects: [ 3 ]\n"},
  };
  for (const auto& [expected, body] : cases) {
    const std::string message = loadMessage(body);
    EXPECT_NE(message.find(expected), std::string::npos) << body << " -> " << message;
    EXPECT_NE(message.find("multislit_scene_bad.yaml"), std::string::npos) << message;
  }
  std::string many = "objects:\n";
  for (std::size_t k = 0; k <= Scene::kMaxObjects; ++k)
    many += "  - { type: sphere, radius: 0.01, centre: [0.3, 0, 0.01] }\n";
  EXPECT_NE(loadMessage(many).find("1001 objects, more than the limit of 1000"), std::string::npos)
      << loadMessage(many);
}
