// The occupancy map: evidence over frames (a screw too small for one frame), free space clearing a
// ball that rolled away, no cells from noise, .bt files, bounded memory, footprint queries.
#include "multislit/occupancy_map.h"
#include "default_reference.h"
#include "multislit/sim/walk.h"
#include "multislit/sweep_evidence.h"
#include "test_support.h"

#include <octomap/OcTree.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>

using namespace multislit;

namespace {

const Reference& reference() { return test::defaultReference(); }

/// The walk on synthesized RDMaps (Simulator::groundTruth plus the extractor's noise).
WalkConfig walkConfig(bool ball, bool cable) {
  WalkConfig config;
  config.render = false;
  config.scene.ball = ball;
  config.scene.cable = cable;
  return config;
}

/// Occupied voxels within `radius` of (x, y) seen from above.
std::size_t occupiedNear(const OccupancyMap& map, double x, double y, double radius) {
  return map
      .occupiedInBox(Eigen::Vector3d(x - radius, y - radius, -1.0),
                     Eigen::Vector3d(x + radius, y + radius, 1.0))
      .size();
}

using KeySet = std::set<std::tuple<unsigned, unsigned, unsigned>>;

/// The occupied voxels of a tree at its finest level.
KeySet occupiedKeys(const octomap::OcTree& tree) {
  KeySet keys;
  const unsigned depth = tree.getTreeDepth();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const octomap::OcTreeKey base = it.getIndexKey();
    const unsigned n = 1u << (depth - it.getDepth());
    for (unsigned i = 0; i < n * n * n; ++i)
      keys.emplace(base[0] + i % n, base[1] + i / n % n, base[2] + i / (n * n));
  }
  return keys;
}

}  // namespace

TEST(OccupancyMap, ScrewTooSmallForAnyFrameIsFoundFromSequentialData) {
  // A screw head 6 mm across and 2 mm high gives about 0.5 px: below the 0.9 px threshold of
  // every frame, while the extractor's noise is 0.12 px. Three places: inside one voxel, across
  // two, across four.
  for (const Eigen::Vector2d& at : {Eigen::Vector2d(0.655, -0.027), Eigen::Vector2d(0.600, 0.013),
                                    Eigen::Vector2d(0.700, 0.000)}) {
    WalkConfig config = walkConfig(false, false);
    config.scene.extra.push_back(SceneObject::cylinder("screw", Eigen::Vector3d(at.x(), at.y(), 0),
                                                       Eigen::Vector3d(at.x(), at.y(), 0.002),
                                                       0.003));
    WalkSimulation walk(config, reference());
    int first_lit = -1, found = -1, detected = 0;
    for (int k = 0; k < 320 && found < 0; ++k) {
      const WalkFrame f = walk.step();
      const ObjectView& screw = f.objects.at(0);
      if (screw.lit_any > 0 && first_lit < 0) first_lit = k;
      detected += screw.detected > 0;
      if (occupiedNear(walk.map(), at.x(), at.y(), 0.01) > 0) found = k;
    }
    EXPECT_EQ(detected, 0) << "a single frame detected the screw at " << at.transpose();
    ASSERT_GE(first_lit, 0);
    EXPECT_GE(found, first_lit) << "the screw at " << at.transpose() << " is not in the map";
    std::printf("screw at (%.3f, %.3f): first lit at frame %d, in the map at frame %d\n", at.x(),
                at.y(), first_lit, found);
  }
}

TEST(OccupancyMap, NoiseMakesNoOccupiedVoxels) {
  WalkSimulation walk(walkConfig(false, false), reference());
  std::size_t most = 0;
  for (int k = 0; k < 600; ++k) {
    walk.step();
    if (k % 10 == 0) most = std::max(most, walk.map().occupiedCount());
  }
  EXPECT_EQ(most, 0u);
}

TEST(OccupancyMap, RenderedBareFloorMakesNoOccupiedVoxels) {
  // Rendered images, not synthesized RDMaps: their noise is correlated between adjacent rows
  // (lens blur, speckle grain), the outer slits are noisier, and the floor's texture biases some
  // centres. None of it may become an obstacle in the map, or the robot avoids nothing.
  WalkConfig config = walkConfig(false, false);
  config.render = true;
  WalkSimulation walk(config, reference());
  std::size_t most = 0, weak = 0;
  int not_walking = 0;
  const int frames = frameCount(150, 8);
  for (int k = 0; k < frames; ++k) {
    const WalkFrame f = walk.step();
    weak += f.map.weak_voxels;
    not_walking += f.walker.command != Command::Walk;
    most = std::max(most, walk.map().occupiedCount());
  }
  EXPECT_EQ(most, 0u);
  EXPECT_EQ(not_walking, 0);
  std::printf("rendered bare floor, %d frames: %zu weak voxel updates, no occupied voxel\n", frames,
              weak);
}

TEST(OccupancyMap, BallThatRolledAwayIsClearedAndTheMapReloadsFromBt) {
  WalkSimulation walk(walkConfig(true, false), reference());
  const WalkSceneConfig& scene = walk.config().scene;
  Eigen::Vector2d landed = Eigen::Vector2d::Zero();
  std::size_t while_there = 0;
  const std::string path = tempPath("occupancy_map_test.bt");
  for (int k = 0; k <= scene.ball_roll_frame + 80; ++k) {
    const WalkFrame f = walk.step();
    if (k == scene.ball_frame) landed = f.body.toWorld(scene.ball_landing);
    if (k != scene.ball_roll_frame - 1) continue;
    while_there = occupiedNear(walk.map(), landed.x(), landed.y(), 0.03);
    walk.map().save(path);  // a map with the ball in it
    octomap::OcTree loaded(0.1);
    ASSERT_TRUE(loaded.readBinary(path));
    EXPECT_DOUBLE_EQ(loaded.getResolution(), walk.map().config().resolution);
    const KeySet saved = occupiedKeys(walk.map().tree());
    EXPECT_FALSE(saved.empty());
    EXPECT_EQ(occupiedKeys(loaded), saved);
  }
  EXPECT_GE(while_there, 5u);
  // 80 frames after it started rolling away (2.7 s), the floor seen there has cleared it.
  EXPECT_EQ(occupiedNear(walk.map(), landed.x(), landed.y(), 0.05), 0u);
  EXPECT_EQ(walk.map().occupiedCount(), 0u);
  std::remove(path.c_str());
}

namespace {

/// Memory and places of the map along a walk on a circle.
struct CircleWalk {
  int frames = 0;
  std::size_t most = 0, at_1000 = 0, end = 0;                    ///< map memory [bytes]
  std::size_t places_most = 0, places_1000 = 0, places_end = 0;  ///< places with evidence
  double seconds = 0.0;
};

/// One frame of `scene` inserted along a circle of 5 m radius at 5 mm per frame (50 m in 10 000
/// frames): the objects move with the robot, so their evidence falls on new places every frame.
/// Three of the fifteen slits (0, 7, 14) are kept: as they sweep the floor they touch the same
/// voxels as all fifteen, at a fifth of the cost.
CircleWalk walkCircle(const Scene& scene) {
  const RDMapSynthesizer synth(SensorConfig{}, reference());
  const SensorGeometry& geometry = synth.simulator().geometry();
  const Eigen::Isometry3d robot_from_camera = geometry.robotFromCamera(MountConfig{});
  const auto cloud = synth.synthesize(scene, robot_from_camera, 1);
  for (PointRDM& p : *cloud)
    if (p.slit % 7 != 0) p.dk = std::numeric_limits<float>::quiet_NaN();
  const FloorResult floor = FloorDetector().detect(cloud);
  const ObstacleResult obstacles = ObstacleClusterer().cluster(cloud, floor, robot_from_camera);
  EXPECT_TRUE(floor.found);
  OccupancyMap map;
  CircleWalk w;
  const auto t0 = std::chrono::steady_clock::now();
  w.frames = frameCount(10000, 2500);  // under the sanitizers: 12.5 m, two fifths of the circle
  for (int k = 0; k < w.frames; ++k) {
    const double angle = 0.005 * k / 5.0;
    const Pose2D body{5.0 * std::sin(angle), 5.0 * (1 - std::cos(angle)), angle};
    map.insertFrame(*cloud, floor, obstacles, body.isometry() * robot_from_camera,
                    geometry.projectorCentre());
    w.most = std::max(w.most, map.memoryUsage());
    w.places_most = std::max(w.places_most, map.sweepEvidence().places());
    if (k == 1000) {
      w.at_1000 = map.memoryUsage();
      w.places_1000 = map.sweepEvidence().places();
    }
  }
  w.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  w.end = map.memoryUsage();
  w.places_end = map.sweepEvidence().places();
  std::printf(
      "map memory over %d frames: at most %zu bytes, %zu at frame 1000, %zu at the end "
      "(%zu voxels); places with evidence: at most %zu, %zu at frame 1000, %zu at the end; %.0f "
      "frames per second\n",
      w.frames, w.most, w.at_1000, w.end, map.leafCount(), w.places_most, w.places_1000,
      w.places_end, w.frames / w.seconds);
  return w;
}

}  // namespace

TEST(OccupancyMap, MemoryStaysBoundedOver10000Frames) {
  const CircleWalk w = walkCircle(Scene{});
  EXPECT_LT(w.most, 2u << 20);  // 2 MB
  EXPECT_LT(w.end, 3 * w.at_1000 / 2);
}

TEST(OccupancyMap, SweepEvidenceStaysBoundedOver10000Frames) {
  // A cable along the path that walks with the robot, crossing every slit: new places with
  // evidence every frame, forgotten once the slits have left them 0.15 m behind.
  Scene scene;
  scene.objects.push_back(SceneObject::cylinder("cable", Eigen::Vector3d(0.0, 0.02, 0.0035),
                                                Eigen::Vector3d(0.6, 0.02, 0.0035), 0.0035));
  const CircleWalk w = walkCircle(scene);
  EXPECT_GT(w.places_1000, 0u);
  EXPECT_LT(w.places_most, 2000u);
  EXPECT_LT(w.places_end, 3 * w.places_1000 / 2);
  EXPECT_LT(w.most, 2u << 20);
}

TEST(OccupancyMap, UpdateRateOfFullFrames) {
  const RDMapSynthesizer synth(SensorConfig{}, reference());
  const SensorGeometry& geometry = synth.simulator().geometry();
  const Eigen::Isometry3d robot_from_camera = geometry.robotFromCamera(MountConfig{});
  const auto cloud = synth.synthesize(Scene{}, robot_from_camera, 2);
  const FloorResult floor = FloorDetector().detect(cloud);
  const ObstacleResult obstacles = ObstacleClusterer().cluster(cloud, floor, robot_from_camera);
  OccupancyMap map;
  const auto t0 = std::chrono::steady_clock::now();
  MapUpdateStats stats;
  for (int k = 0; k < 300; ++k)
    stats = map.insertFrame(*cloud, floor, obstacles,
                            Pose2D{0.00167 * k, 0, 0}.isometry() * robot_from_camera,
                            geometry.projectorCentre());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_TRUE(stats.inserted);
  EXPECT_GT(stats.free_voxels, 500u);
  std::printf("%zu points per frame: %.0f map updates per second (%zu voxels updated per frame)\n",
              floor.valid_points, 300 / seconds, stats.free_voxels);
}

// Tall evidence occupies a place after two moving frames, unless a line below the floor lies
// beside it in this frame or the last (a dark line's lobes on neighbouring slits).
TEST(SweepEvidence, TallBesideALineBelowTheFloorIsTheLinesOtherLobe) {
  const auto tall = [](std::int32_t x) {
    return std::vector<SweepPoint>(3, SweepPoint{x, 0, 0.03f, true, true, true});
  };
  const auto below = [](std::int32_t x) {
    return std::vector<SweepPoint>(3, SweepPoint{x, 0, -0.01f, false, true, false});
  };
  const auto walk = [](SweepEvidence& e, const std::vector<SweepPoint>& points) {
    e.beginFrame(0.002);  // the slits moved 2 mm
    e.addEvidence(points);
    return e.verdictAt(0, 0);
  };
  std::vector<SweepPoint> with_line = tall(0);
  for (const SweepPoint& p : below(3)) with_line.push_back(p);
  SweepEvidence alone, beside, beyond, off;
  EXPECT_EQ(walk(alone, tall(0)), SweepVerdict::Pending);
  EXPECT_EQ(walk(alone, tall(0)), SweepVerdict::Above);
  // The line 3 columns away in the first frame: both frames' tall evidence is dropped.
  EXPECT_EQ(walk(beside, with_line), SweepVerdict::Pending);
  EXPECT_EQ(walk(beside, tall(0)), SweepVerdict::Pending);
  EXPECT_EQ(walk(beside, tall(0)), SweepVerdict::Pending);
  EXPECT_EQ(walk(beside, tall(0)), SweepVerdict::Above);
  // 4 columns away: no line beside it.
  std::vector<SweepPoint> far_line = tall(0);
  for (const SweepPoint& p : below(4)) far_line.push_back(p);
  EXPECT_EQ(walk(beyond, far_line), SweepVerdict::Pending);
  EXPECT_EQ(walk(beyond, tall(0)), SweepVerdict::Above);
  // Without the rule.
  SweepEvidenceConfig no_rule;
  no_rule.line_radius = 0;
  off = SweepEvidence(no_rule);
  EXPECT_EQ(walk(off, with_line), SweepVerdict::Pending);
  EXPECT_EQ(walk(off, tall(0)), SweepVerdict::Above);
}

TEST(OccupancyMap, FootprintQueryFindsTheCellsUnderASole) {
  // The ball 0.18 m ahead, seen from the reference pose.
  const RDMapSynthesizer synth(SensorConfig{}, reference());
  const Eigen::Isometry3d robot_from_camera =
      synth.simulator().geometry().robotFromCamera(MountConfig{});
  Scene scene;
  scene.objects.push_back(SceneObject::sphere("ball", Eigen::Vector3d(0.18, 0.02, 0.02), 0.02));
  const auto cloud = synth.synthesize(scene, robot_from_camera, 3);
  const FloorResult floor = FloorDetector().detect(cloud);
  const ObstacleResult obstacles = ObstacleClusterer().cluster(cloud, floor, robot_from_camera);
  // One frame is never enough over the sweep (evidence waits for consistent frames): taken as
  // truth here, where the footprint query is tested.
  OccupancyMapConfig one_frame;
  one_frame.sweep.tall_frames = 1;
  OccupancyMap map(one_frame);
  map.insertFrame(*cloud, floor, obstacles, robot_from_camera,
                  synth.simulator().geometry().projectorCentre());
  Footprint sole;
  sole.length = 0.095;
  sole.width = 0.065;
  sole.centre = Eigen::Vector2d(0.18, 0.02);
  const std::vector<MapCell> under = map.occupiedUnder(sole, 0.0, 0.25);
  EXPECT_GE(under.size(), 5u);
  for (const MapCell& c : under) {
    EXPECT_TRUE(sole.inflated(0.5 * c.size * std::sqrt(2.0)).contains(c.centre.head<2>()));
    EXPECT_GT(c.probability, map.config().occupancy_threshold);
  }
  EXPECT_TRUE(map.occupiedUnder(sole, 0.05, 0.25).empty());  // nothing above the ball
  sole.centre = Eigen::Vector2d(0.18, 0.085);                // beside it, 12 mm away
  EXPECT_TRUE(map.occupiedUnder(sole, 0.0, 0.25).empty());
  sole.yaw = M_PI / 2;  // turned: now 95 mm across, over the ball
  EXPECT_FALSE(map.occupiedUnder(sole, 0.0, 0.25).empty());
  EXPECT_THROW(map.save("/nonexistent/dir/map.bt"), std::runtime_error);
}

TEST(OccupancyMap, ConfigErrorsNameTheField) {
  OccupancyMapConfig config;
  config.prob_miss = 0.6;
  try {
    config.validate();
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("prob_miss"), std::string::npos);
  }
  config = {};
  config.free_height = 0.001;
  EXPECT_THROW(OccupancyMap{config}, std::invalid_argument);
}
