// The fast renderer (RenderMethod::Culled: objects traced only where their bounding spheres fall,
// the floor in closed form, the floor's texture from tables) against the exhaustive one (every
// ray against every object), noise-free: the same image, so the bounds hold every object.
#include "multislit/sim/floor_albedo.h"
#include "multislit/sim/scenarios.h"
#include "multislit/sim/simulator.h"

#include "test_support.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <random>
#include <string>

using namespace multislit;

namespace {

cv::Mat renderWith(RenderMethod method, const Scene& scene, const Eigen::Isometry3d& pose) {
  RenderConfig render;
  render.noise = false;
  render.bit_depth = 16;  // differences down to 1 / 65535 of full scale show
  render.method = method;
  return Simulator(SensorConfig{}, render).render(scene, pose).image;
}

// The largest difference of the two methods' images [DN of 65535].
double largestDifference(const Scene& scene, const Eigen::Isometry3d& pose) {
  const cv::Mat culled = renderWith(RenderMethod::Culled, scene, pose);
  const cv::Mat exhaustive = renderWith(RenderMethod::Exhaustive, scene, pose);
  return cv::norm(culled, exhaustive, cv::NORM_INF);
}

Eigen::Isometry3d poseOf(const Scenario& s, std::uint64_t frame) {
  return s.worldFromRobot(frame) * SensorGeometry(SensorConfig{}).robotFromCamera(s.mount);
}

}  // namespace

TEST(RenderMethods, CulledAndExhaustiveGiveTheSameImageOfEveryScenario) {
  for (const char* name : {"ball", "cable", "fig8", "cond6"}) {
    if (kSanitized && std::string(name) != "cable") continue;  // the exhaustive one is slow there
    const Scenario s = makeScenario(name);
    SCOPED_TRACE(name);
    EXPECT_LE(largestDifference(s.scene, poseOf(s, 3)), 2.0);
  }
}

// Objects of every shape at random places in and around the view, some cut by the image's edge,
// a long thin cable, a tall box, on every floor texture.
TEST(RenderMethods, CulledAndExhaustiveAgreeOnRandomObjects) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> x(0.1, 0.9), y(-0.4, 0.4), size(0.004, 0.08);
  const Scenario view = makeScenario("reference");
  const int scenes = frameCount(9, 1);
  for (int k = 0; k < scenes; ++k) {
    Scene scene;
    scene.floor.texture = static_cast<FloorTexture>(k % 3);
    for (int i = 0; i < 6; ++i) {
      const double r = size(rng);
      const Eigen::Vector3d at(x(rng), y(rng), r);
      switch (i % 3) {
        case 0:
          scene.objects.push_back(SceneObject::sphere("s", at, r));
          break;
        case 1:
          scene.objects.push_back(SceneObject::cylinder("c", Eigen::Vector3d(at.x(), -0.8, 0.1 * r),
                                                        Eigen::Vector3d(at.x() + 0.2, 0.8, 0.1 * r),
                                                        0.1 * r));
          break;
        default:
          scene.objects.push_back(
              SceneObject::box("b", at, Eigen::Vector3d(r, 2 * r, 4 * r), 30.0 * i));
      }
    }
    SCOPED_TRACE("scene " + std::to_string(k));
    EXPECT_LE(largestDifference(scene, poseOf(view, 0)), 2.0);
  }
}

// The tables hold the very hashes: a texture from them equals one hashed point by point.
TEST(RenderMethods, TabulatedFloorTextureEqualsTheHashedOne) {
  for (const FloorTexture texture :
       {FloorTexture::Wood, FloorTexture::Tiles, FloorTexture::Carpet}) {
    FloorConfig floor;
    floor.texture = texture;
    const FloorAlbedo hashed(floor);
    const FloorAlbedo tabulated(
        floor, Eigen::AlignedBox2d(Eigen::Vector2d(-1, -1), Eigen::Vector2d(2, 1)));
    std::vector<double> xs, ys, row(400);
    for (int i = 0; i < 400; ++i) {
      xs.push_back(-1.5 + 0.009 * i);  // the row leaves the table: hashed there
      ys.push_back(0.3 - 0.002 * i);
    }
    tabulated.row(xs.data(), ys.data(), row.data(), 400);
    for (int i = 0; i < 400; ++i) {
      EXPECT_NEAR(tabulated.at(xs[i], ys[i]), hashed.at(xs[i], ys[i]), 1e-12);
      EXPECT_NEAR(row[i], hashed.at(xs[i], ys[i]), 1e-12);
    }
    std::vector<double> inside_x(400, 0.25), inside_y(400);
    for (int i = 0; i < 400; ++i) inside_y[i] = -0.9 + 0.0045 * i;  // all within the tables
    tabulated.row(inside_x.data(), inside_y.data(), row.data(), 400);
    for (int i = 0; i < 400; ++i) EXPECT_NEAR(row[i], hashed.at(0.25, inside_y[i]), 1e-12);
  }
}
