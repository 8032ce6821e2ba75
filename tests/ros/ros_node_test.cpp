// The ROS node on a simulated sequence, as a subscriber sees it (tests/ros/ros_node.sh starts
// roscore on 127.0.0.1 and the node; this program plays the robot's odometry, takes every message
// of one run, then checks them against the scenario's objects, the simulator's reference and,
// when given, what `multislit map` wrote for the same frames).
//   ros_node_test --scenario ball --frames 30 --poses tf|odom [--robot X,Y,YAW_DEG]
//       [--node-out DIR] [--map-out DIR] [--figure PNG] [gtest flags]
#include "ros_capture.h"
#include "ros_checks.h"
#include "ros_view.h"

#include "multislit/sim/scenarios.h"

#include <gtest/gtest.h>
#include <pcl_conversions/pcl_conversions.h>
#include <tf2_msgs/TFMessage.h>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <set>

namespace multislit::ros_test {
namespace {

const char* const kOctomapMd5 = "9a45536b45c5e409cd49f04bb2d9999f";  // octomap_msgs upstream

TEST(RosNode, PublishesTheOrganizedRdmapWithEveryField) {
  const Expected& e = expected();
  for (const auto& item : capture().rdmap.items) {
    const sensor_msgs::PointCloud2& m = *item.message;
    EXPECT_EQ(m.header.frame_id, "multislit_optical");
    EXPECT_EQ(m.width, e.rdmap_width);
    EXPECT_EQ(m.height, e.rdmap_height);
    EXPECT_EQ(m.point_step, 32u);
    EXPECT_EQ(m.row_step, m.width * m.point_step);
    EXPECT_EQ(m.data.size(), static_cast<std::size_t>(m.row_step) * m.height);
    EXPECT_FALSE(m.is_dense);
  }
  const sensor_msgs::PointCloud2& m = *capture().rdmap.items.front().message;
  const std::vector<std::tuple<std::string, std::uint32_t, std::uint8_t>> fields = {
      {"x", 0, sensor_msgs::PointField::FLOAT32},  {"y", 4, sensor_msgs::PointField::FLOAT32},
      {"z", 8, sensor_msgs::PointField::FLOAT32},  {"u", 16, sensor_msgs::PointField::FLOAT32},
      {"v", 20, sensor_msgs::PointField::FLOAT32}, {"dk", 24, sensor_msgs::PointField::FLOAT32},
      {"slit", 28, sensor_msgs::PointField::INT32}};
  ASSERT_EQ(m.fields.size(), fields.size());
  for (std::size_t i = 0; i < fields.size(); ++i) {
    EXPECT_EQ(m.fields[i].name, std::get<0>(fields[i]));
    EXPECT_EQ(m.fields[i].offset, std::get<1>(fields[i])) << m.fields[i].name;
    EXPECT_EQ(m.fields[i].datatype, std::get<2>(fields[i])) << m.fields[i].name;
    EXPECT_EQ(m.fields[i].count, 1u);
  }
  // The cloud holds the measured points: slits in rows, metric positions in front of the camera.
  const pcl::PointCloud<PointRDM> cloud = rdmapCloud(m);
  std::size_t measured = 0;
  for (std::uint32_t row = 0; row < cloud.height; ++row)
    for (std::uint32_t col = 0; col < cloud.width; ++col) {
      const PointRDM& p = cloud.at(col, row);
      if (!hasXYZ(p)) continue;
      ++measured;
      EXPECT_EQ(p.slit, static_cast<std::int32_t>(row));
      EXPECT_GT(p.z, 0.2f);
    }
  EXPECT_GT(measured, cloud.size() / 4);
}

TEST(RosNode, StampsEveryMessageWithItsFramesStamp) {
  const std::vector<ros::Time> stamps = cloudStamps();
  ASSERT_EQ(stamps.size(), options().frames);
  // Paced at 30 Hz: each frame is taken when it is due or later, on a fixed schedule, so a frame
  // the machine delayed does not delay the next and two stamps may be closer than a period. In
  // order, and a period apart as the median gap.
  std::vector<double> gaps;
  for (std::size_t i = 1; i < stamps.size(); ++i) {
    EXPECT_GT(stamps[i], stamps[i - 1]) << "frame " << i;
    gaps.push_back((stamps[i] - stamps[i - 1]).toSec());
  }
  std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
  EXPECT_GE(gaps[gaps.size() / 2], 0.9 / options().fps);
  const auto same = [&](const auto& inbox) {
    std::vector<ros::Time> got;
    for (const auto& item : inbox.items) got.push_back(item.message->header.stamp);
    EXPECT_EQ(got, stamps) << inbox.topic;
  };
  same(capture().floor);
  same(capture().obstacles);
  same(capture().decision);
  for (const auto& item : capture().markers.items)
    for (const auto& marker : item.message->markers)
      EXPECT_TRUE(std::binary_search(stamps.begin(), stamps.end(), marker.header.stamp));
  if (options().node_out.empty()) return;
  // The node's own record of the frames (~out): the simulator's stamps, to the microsecond.
  const auto rows = readCsv(options().node_out + "/decisions.csv");
  ASSERT_EQ(rows.size(), stamps.size());
  for (std::size_t i = 0; i < rows.size(); ++i)
    EXPECT_EQ(pcl_conversions::toPCL(stamps[i]), std::stoull(rows[i].at("stamp_us")));
}

TEST(RosNode, PublishesOneBoxPerObstacleGroupWithItsSize) {
  const auto& clouds = capture().obstacles.items;
  const auto& arrays = capture().markers.items;
  ASSERT_EQ(clouds.size(), arrays.size());
  std::size_t boxes_seen = 0;
  for (std::size_t i = 0; i < arrays.size(); ++i) {
    const auto& markers = arrays[i].message->markers;
    ASSERT_FALSE(markers.empty());
    EXPECT_EQ(markers.front().action, visualization_msgs::Marker::DELETEALL);
    const std::vector<visualization_msgs::Marker> boxes = groupBoxes(*arrays[i].message);
    std::set<std::uint32_t> labels;
    for (const pcl::PointXYZL& p : labelledCloud(*clouds[i].message)) labels.insert(p.label);
    EXPECT_EQ(boxes.size(), labels.size()) << "frame " << i;
    for (const auto& box : boxes) {
      EXPECT_EQ(box.header.frame_id, "base_footprint");
      EXPECT_GT(box.scale.x, 0.0);
      EXPECT_GT(box.scale.y, 0.0);
      EXPECT_GT(box.scale.z, 0.0);
      EXPECT_NEAR(box.pose.position.z, 0.5 * box.scale.z, 1e-9);  // from the floor up
    }
    boxes_seen += boxes.size();
  }
  EXPECT_GT(boxes_seen, 0u);
}

TEST(RosNode, GroupsAreTheScenariosObjectsWithTheirHeights) {
  const Scenario scenario = makeScenario(options().scenario);
  ASSERT_FALSE(scenario.scene.objects.empty());
  std::set<std::string> seen;
  const auto& arrays = capture().markers.items;
  for (std::size_t i = 0; i < arrays.size(); ++i) {
    for (const auto& box : groupBoxes(*arrays[i].message)) {
      // With the robot's mount on TF the camera is mount_shift further forward than it is: the
      // groups come that much further ahead.
      const Eigen::Vector3d centre(box.pose.position.x - options().mount_shift, box.pose.position.y,
                                   0.0);
      const SceneObject* object = objectUnder(scenario, scenario.worldFromRobot(i), centre, 0.01);
      ASSERT_NE(object, nullptr) << "frame " << i << ": a group at " << centre.transpose()
                                 << " where the scene has no object";
      EXPECT_NEAR(box.scale.z, object->top(), 0.005) << object->name << ", frame " << i;
      seen.insert(object->name);
    }
  }
  EXPECT_EQ(seen.size(), scenario.scene.objects.size());
}

TEST(RosNode, PublishesTheOctomapWithUpstreamsChecksum) {
  EXPECT_STREQ(ros::message_traits::md5sum<octomap_msgs::Octomap>(), kOctomapMd5);
  EXPECT_STREQ(ros::message_traits::datatype<octomap_msgs::Octomap>(), "octomap_msgs/Octomap");
  ASSERT_FALSE(capture().octomap.items.empty());
  for (const auto& item : capture().octomap.items) {
    EXPECT_EQ(item.md5, kOctomapMd5);  // what the node's connection announced
    EXPECT_TRUE(item.message->binary);
    EXPECT_EQ(item.message->id, "OcTree");
    EXPECT_DOUBLE_EQ(item.message->resolution, options().resolution);  // ~resolution
    EXPECT_EQ(item.message->header.frame_id, "odom");
  }
}

TEST(RosNode, MapDecodesIntoTheOccupiedVoxelsOfItsCloud) {
  const auto& maps = capture().octomap.items;
  const auto& cells = capture().occupied.items;
  ASSERT_EQ(maps.size(), cells.size());
  EXPECT_GE(maps.size(), options().frames / 10);  // ~map_every 10
  for (std::size_t i = 0; i < maps.size(); ++i) {
    EXPECT_EQ(maps[i].message->header.stamp, cells[i].message->header.stamp);
    const auto tree = decodeOctomap(*maps[i].message);
    const std::vector<Eigen::Vector3d> centres = occupiedCentres(*tree);
    std::vector<Eigen::Vector3d> cloud;
    for (const pcl::PointXYZ& p : xyzCloud(*cells[i].message))
      cloud.push_back(p.getVector3fMap().cast<double>());
    std::sort(cloud.begin(), cloud.end(), [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
    });
    ASSERT_EQ(cloud.size(), centres.size()) << "map " << i;
    for (std::size_t k = 0; k < centres.size(); ++k)
      EXPECT_LT((cloud[k] - centres[k]).norm(), 1e-4) << "map " << i << ", voxel " << k;
  }
  // The robot stands: nothing sweeps the floor, so the map holds nothing (docs/walk.md, "Evidence
  // over the sweep"); the decoding is compared on whatever the maps hold.
}

// octomap_full: every voxel's occupancy; the binary map is its maximum likelihood.
TEST(RosNode, FullMapIsTheBinaryMapWithItsProbabilities) {
  const auto& full = capture().octomap_full.items;
  const auto& binary = capture().octomap.items;
  ASSERT_EQ(full.size(), binary.size());
  for (std::size_t i = 0; i < full.size(); ++i) {
    EXPECT_EQ(full[i].md5, kOctomapMd5);
    EXPECT_FALSE(full[i].message->binary);
    EXPECT_EQ(full[i].message->id, "OcTree");
    EXPECT_DOUBLE_EQ(full[i].message->resolution, options().resolution);
    EXPECT_EQ(full[i].message->header.stamp, binary[i].message->header.stamp);
    const auto tree = decodeOctomap(*full[i].message);
    const auto likely = decodeOctomap(*binary[i].message);
    EXPECT_EQ(tree->size() > 0, likely->size() > 0) << "map " << i;
    std::size_t leaves = 0;
    for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it, ++leaves) {
      const octomap::OcTreeNode* node = likely->search(it.getCoordinate());
      ASSERT_NE(node, nullptr) << "map " << i << ": a voxel only the full map knows";
      EXPECT_EQ(tree->isNodeOccupied(*it), likely->isNodeOccupied(node)) << "map " << i;
      EXPECT_GT(it->getOccupancy(), 0.0);
      EXPECT_LT(it->getOccupancy(), 1.0);
    }
    EXPECT_EQ(occupiedCentres(*tree), occupiedCentres(*likely)) << "map " << i;
  }
}

// projected_map: each column of the last map seen from above, looked up voxel by voxel.
TEST(RosNode, ProjectedMapIsTheLastMapSeenFromAbove) {
  ASSERT_FALSE(capture().projected.items.empty());
  const nav_msgs::OccupancyGrid& grid = *capture().projected.items.back().message;
  const auto tree = decodeOctomap(*capture().octomap_full.items.back().message);
  EXPECT_EQ(grid.header.frame_id, "odom");
  EXPECT_FLOAT_EQ(grid.info.resolution, static_cast<float>(options().resolution));
  ASSERT_EQ(grid.data.size(), std::size_t{grid.info.width} * grid.info.height);
  ASSERT_EQ(tree->size() > 0, !grid.data.empty());
  if (grid.data.empty()) return;
  double x0, y0, z0, x1, y1, z1;
  tree->getMetricMin(x0, y0, z0);
  tree->getMetricMax(x1, y1, z1);
  const double res = grid.info.resolution;
  std::size_t known = 0;
  for (std::uint32_t row = 0; row < grid.info.height; ++row)
    for (std::uint32_t col = 0; col < grid.info.width; ++col) {
      const double x = grid.info.origin.position.x + (col + 0.5) * res;
      const double y = grid.info.origin.position.y + (row + 0.5) * res;
      int expected = -1;
      for (double z = z0 + res / 2; z < z1; z += res)
        if (const octomap::OcTreeNode* node = tree->search(x, y, z))
          expected = std::max(expected, tree->isNodeOccupied(node) ? 100 : 0);
      EXPECT_EQ(grid.data[std::size_t{row} * grid.info.width + col], expected)
          << "cell " << col << ", " << row;
      known += expected >= 0;
    }
  EXPECT_GT(known, 0u);
  EXPECT_NEAR(grid.info.origin.position.x, x0, res / 2);
  EXPECT_NEAR(grid.info.origin.position.y, y0, res / 2);
  EXPECT_NEAR(grid.info.origin.position.x + grid.info.width * res, x1, res / 2);
  EXPECT_NEAR(grid.info.origin.position.y + grid.info.height * res, y1, res / 2);
}

TEST(RosNode, MapOfAStandingRobotHoldsNothingWhereverTheOdometryPutsIt) {
  const Scenario scenario = makeScenario(options().scenario);
  const auto tree = decodeOctomap(*capture().octomap.items.back().message);
  // The odometry puts the robot at options().robot in odom: the scenario's world is then
  // world_from_robot * robot_from_odom.
  const Eigen::Isometry3d world_from_odom =
      scenario.worldFromRobot(options().frames - 1) * options().robot.inverse();
  std::map<std::string, std::size_t> per_object;
  std::size_t elsewhere = 0;
  const std::vector<Eigen::Vector3d> centres = occupiedCentres(*tree);
  for (const Eigen::Vector3d& c : centres) {
    const SceneObject* object = objectUnder(scenario, world_from_odom, c, 0.02);
    object ? ++per_object[object->name] : ++elsewhere;
  }
  // The odometry says the robot stands: no evidence accumulates from a view that never moved,
  // so neither the objects nor anything else is occupied (docs/walk.md, "Evidence over the sweep").
  for (const SceneObject& object : scenario.scene.objects)
    EXPECT_EQ(per_object[object.name], 0u) << object.name << " is in the map of a standing robot";
  EXPECT_EQ(elsewhere, 0u) << "of " << centres.size() << " occupied voxels";
}

TEST(RosNode, GivesTheMapCommandsResultsOnTheSameFrames) {
  if (options().map_out.empty()) GTEST_SKIP() << "no --map-out";
  const auto rows = readCsv(options().map_out + "/decisions.csv");
  const auto& decisions = capture().decision.items;
  const auto& arrays = capture().markers.items;
  ASSERT_EQ(rows.size(), decisions.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(decisions[i].message->command_name, rows[i].at("decision")) << "frame " << i;
    EXPECT_EQ(decisions[i].message->reason, rows[i].at("reason")) << "frame " << i;
    EXPECT_EQ(groupBoxes(*arrays[i].message).size(), std::stoul(rows[i].at("groups")));
  }
  // The last map holds exactly the voxels of map.bt.
  const auto tree = decodeOctomap(*capture().octomap.items.back().message);
  octomap::OcTree written(0.01);
  ASSERT_TRUE(written.readBinary(options().map_out + "/map.bt"));
  EXPECT_EQ(occupiedCentres(*tree), occupiedCentres(written));
}

TEST(RosNode, PublishesTheFloorAndTheDecisionOfEveryFrame) {
  for (const auto& item : capture().floor.items) {
    const multislit_ros::Floor& f = *item.message;
    EXPECT_TRUE(f.found);
    EXPECT_TRUE(f.metric);
    EXPECT_GE(f.sigma, 0.3 - 1e-9);  // FloorDetectorConfig::min_sigma .. max_sigma
    EXPECT_LE(f.sigma, 1.0 + 1e-9);
    EXPECT_NEAR(f.threshold, 3.0 * f.sigma, 1e-9);
    EXPECT_EQ(f.floor_points + f.obstacle_points, f.valid_points);
    // The plane's distance to the camera is the camera's height above the floor.
    EXPECT_NEAR(f.plane[3], makeScenario(options().scenario).mount.height, 0.01);
  }
  for (const auto& item : capture().decision.items) {
    const multislit_ros::Decision& d = *item.message;
    const std::vector<std::string> names = {"walk", "turn", "stop"};
    ASSERT_LT(d.command, names.size());
    EXPECT_EQ(d.command_name, names[d.command]);
    EXPECT_FALSE(d.reason.empty());
  }
}

TEST(RosNode, ReportsFpsDroppedFramesAndTheFloorInDiagnostics) {
  double best_fps = 0.0;
  const diagnostic_msgs::DiagnosticStatus* finished = nullptr;
  for (const auto& item : capture().diagnostics.items)
    for (const auto& s : item.message->status) {
      if (s.name != "multislit: sensor") continue;
      best_fps = std::max(best_fps, std::stod(diagnosticValue(s, "fps")));
      if (diagnosticValue(s, "state") == "finished") finished = &s;
    }
  ASSERT_NE(finished, nullptr);
  EXPECT_GT(best_fps, 0.0);
  EXPECT_EQ(diagnosticValue(*finished, "frames processed"), std::to_string(options().frames));
  EXPECT_EQ(diagnosticValue(*finished, "dropped frames"), "0");
  EXPECT_EQ(diagnosticValue(*finished, "found floor"), "true");
  EXPECT_EQ(
      diagnosticValue(*finished, "camera mount"),
      options().mount_shift != 0.0 ? "TF base_footprint -> multislit_optical" : "sensor file");
  EXPECT_EQ(finished->level, diagnostic_msgs::DiagnosticStatus::OK);
}

// The sensor file's mount, published by the node; or the robot's, which the node takes.
TEST(RosNode, TheCameraMountOnTfIsTheSensorsOrTheRobots) {
  const std::optional<Eigen::Isometry3d> mount = baseFromCamera();
  ASSERT_TRUE(mount.has_value());
  const Eigen::Isometry3d expected_mount =
      captureOptions().mount.value_or(expected().base_from_camera);
  EXPECT_LT((mount->translation() - expected_mount.translation()).norm(), 1e-6);
  EXPECT_LT((mount->linear() - expected_mount.linear()).norm(), 1e-6);
}

/// Rates and latencies of the run, for the record (printed, not asserted).
void report() {
  const auto rate = [](const auto& inbox) {
    const auto& items = inbox.items;
    const double span = items.size() > 1 ? items.back().received - items.front().received : 0.0;
    std::printf("  %-40s %4zu messages, %6.2f Hz\n", inbox.topic.c_str(), items.size(),
                span > 0 ? static_cast<double>(items.size() - 1) / span : 0.0);
  };
  std::printf("ros_node_test: %s, %zu frames, poses from %s\n", options().scenario.c_str(),
              options().frames, options().poses.c_str());
  const Capture& c = capture();
  if (!c.rdmap.items.empty())
    std::printf("  rdmap: %u x %u points, %zu bytes\n", c.rdmap.items.front().message->width,
                c.rdmap.items.front().message->height, c.rdmap.items.front().message->data.size());
  rate(c.rdmap), rate(c.floor), rate(c.obstacles), rate(c.markers), rate(c.decision);
  rate(c.octomap), rate(c.occupied), rate(c.diagnostics);
  std::vector<double> latency;
  for (const auto& item : c.rdmap.items)
    latency.push_back(1e3 * (item.received - item.message->header.stamp.toSec()));
  std::sort(latency.begin(), latency.end());
  if (!latency.empty())
    std::printf(
        "  latency, frame stamp to the cloud's receipt: median %.1f ms, p90 %.1f ms, "
        "max %.1f ms\n",
        latency[latency.size() / 2], latency[latency.size() * 9 / 10], latency.back());
  const std::vector<ros::Time> stamps = cloudStamps();
  std::vector<double> periods;
  for (std::size_t i = 1; i < stamps.size(); ++i)
    periods.push_back(1e3 * (stamps[i] - stamps[i - 1]).toSec());
  std::sort(periods.begin(), periods.end());
  if (!periods.empty())
    std::printf("  frame stamps: median period %.1f ms (min %.1f, max %.1f)\n",
                periods[periods.size() / 2], periods.front(), periods.back());
  for (const auto& item : c.diagnostics.items)
    for (const auto& s : item.message->status)
      if (diagnosticValue(s, "state") == "finished")
        for (const char* key :
             {"mean CPU time per frame [ms]", "mean latency, frame arrival to cloud published [ms]",
              "mean latency, stamp to cloud published [ms]"})
          std::printf("  node: %s %s\n", key, diagnosticValue(s, key).c_str());
}

}  // namespace
}  // namespace multislit::ros_test

int main(int argc, char** argv) {
  using namespace multislit::ros_test;
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "multislit_test", ros::init_options::AnonymousName);
  if (!parseOptions(argc, argv)) return 2;
  Capture capture(captureOptions());
  std::string missing;
  const bool complete = capture.wait(missing);
  setCapture(&capture);
  report();
  if (!complete) {
    std::fprintf(stderr, "ros_node_test: not everything came:%s\n", missing.c_str());
    return 1;
  }
  if (!options().figure.empty()) writeFigure(options().figure);
  return RUN_ALL_TESTS();
}
