#include "ros_messages.h"

#include <pcl_conversions/pcl_conversions.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>
#include <string>

namespace multislit::ros_node {
namespace {

/// A height on a blue (floor) .. green .. red (walker's knee, 0.25 m) scale.
std_msgs::ColorRGBA heightColour(double height) {
  const double t = std::clamp(height / 0.25, 0.0, 1.0);
  std_msgs::ColorRGBA c;
  c.r = static_cast<float>(std::clamp(2.0 * t - 0.5, 0.0, 1.0));
  c.g = static_cast<float>(1.0 - std::abs(2.0 * t - 1.0));
  c.b = static_cast<float>(std::clamp(1.0 - 2.0 * t, 0.0, 1.0));
  c.a = 0.6f;
  return c;
}

visualization_msgs::Marker groupMarker(const Obstacle& o, const std_msgs::Header& header, int id,
                                       const char* ns, int type) {
  visualization_msgs::Marker m;
  m.header = header;
  m.ns = ns;
  m.id = id;
  m.type = type;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.position.x = 0.5 * (o.min.x() + o.max.x());
  m.pose.position.y = 0.5 * (o.min.y() + o.max.y());
  m.pose.position.z = 0.5 * o.height;
  m.pose.orientation.w = 1.0;
  m.color = heightColour(o.height);
  return m;
}

template <typename PointT>
sensor_msgs::PointCloud2 toMessage(const pcl::PointCloud<PointT>& cloud,
                                   const std_msgs::Header& header) {
  sensor_msgs::PointCloud2 message;
  pcl::toROSMsg(cloud, message);
  message.header = header;
  return message;
}

}  // namespace

sensor_msgs::PointCloud2 rdmapMessage(const pcl::PointCloud<PointRDM>& cloud,
                                      const std_msgs::Header& header) {
  return toMessage(cloud, header);
}

sensor_msgs::PointCloud2 obstacleCloudMessage(const pcl::PointCloud<PointRDM>& cloud,
                                              const ObstacleResult& obstacles,
                                              const std_msgs::Header& header) {
  pcl::PointCloud<pcl::PointXYZL> points;
  for (std::size_t g = 0; g < obstacles.obstacles.size(); ++g)
    for (const pcl::index_t i : obstacles.obstacles[g].indices) {
      const PointRDM& p = cloud[static_cast<std::size_t>(i)];
      pcl::PointXYZL q;
      q.x = p.x;
      q.y = p.y;
      q.z = p.z;
      q.label = static_cast<std::uint32_t>(g);
      points.push_back(q);
    }
  points.is_dense = false;  // points without a metric position keep NaN
  return toMessage(points, header);
}

visualization_msgs::MarkerArray obstacleMarkers(const ObstacleResult& obstacles,
                                                const std_msgs::Header& header) {
  visualization_msgs::MarkerArray array;
  visualization_msgs::Marker clear;
  clear.header = header;
  clear.action = visualization_msgs::Marker::DELETEALL;
  array.markers.push_back(clear);
  for (std::size_t g = 0; g < obstacles.obstacles.size(); ++g) {
    const Obstacle& o = obstacles.obstacles[g];
    const int id = static_cast<int>(g);
    visualization_msgs::Marker box =
        groupMarker(o, header, id, kGroupBoxes, visualization_msgs::Marker::CUBE);
    box.scale.x = std::max(o.length, 1e-3);
    box.scale.y = std::max(o.width, 1e-3);
    box.scale.z = std::max(o.height, 1e-3);
    array.markers.push_back(box);
    visualization_msgs::Marker label =
        groupMarker(o, header, id, kGroupLabels, visualization_msgs::Marker::TEXT_VIEW_FACING);
    char text[96];
    std::snprintf(text, sizeof text, "%.0f x %.0f, h %.0f mm", 1e3 * o.length, 1e3 * o.width,
                  1e3 * o.height);
    label.text = text;
    label.pose.position.z = o.height + 0.02;
    label.scale.z = 0.015;  // text height [m]
    label.color.r = label.color.g = label.color.b = label.color.a = 1.0f;
    array.markers.push_back(label);
  }
  return array;
}

octomap_msgs::Octomap octomapMessage(const octomap::OcTree& tree, const std_msgs::Header& header) {
  octomap_msgs::Octomap message;
  message.header = header;
  message.binary = true;
  message.id = tree.getTreeType();
  message.resolution = tree.getResolution();
  std::stringstream data;
  tree.writeBinaryData(data);
  const std::string bytes = data.str();
  message.data.assign(bytes.begin(), bytes.end());
  return message;
}

octomap_msgs::Octomap octomapFullMessage(const octomap::OcTree& tree,
                                         const std_msgs::Header& header) {
  octomap_msgs::Octomap message;
  message.header = header;
  message.binary = false;
  message.id = tree.getTreeType();
  message.resolution = tree.getResolution();
  std::stringstream data;
  tree.writeData(data);
  const std::string bytes = data.str();
  message.data.assign(bytes.begin(), bytes.end());
  return message;
}

nav_msgs::OccupancyGrid projectedMapMessage(const octomap::OcTree& tree,
                                            const std_msgs::Header& header) {
  nav_msgs::OccupancyGrid grid;
  grid.header = header;
  grid.info.map_load_time = header.stamp;
  const double res = tree.getResolution();
  grid.info.resolution = static_cast<float>(res);
  grid.info.origin.orientation.w = 1.0;
  if (tree.size() == 0) return grid;  // nothing known: an empty grid
  double x0, y0, z0, x1, y1, z1;
  tree.getMetricMin(x0, y0, z0);
  tree.getMetricMax(x1, y1, z1);
  // The keys of the first and last voxel columns (the extent's edges lie on voxel faces).
  const octomap::OcTreeKey lo = tree.coordToKey(x0 + res / 2, y0 + res / 2, z0 + res / 2);
  const octomap::OcTreeKey hi = tree.coordToKey(x1 - res / 2, y1 - res / 2, z1 - res / 2);
  grid.info.width = static_cast<std::uint32_t>(hi[0] - lo[0] + 1);
  grid.info.height = static_cast<std::uint32_t>(hi[1] - lo[1] + 1);
  grid.info.origin.position.x = tree.keyToCoord(lo[0]) - res / 2;
  grid.info.origin.position.y = tree.keyToCoord(lo[1]) - res / 2;
  grid.data.assign(std::size_t{grid.info.width} * grid.info.height, -1);
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const std::int8_t value = tree.isNodeOccupied(*it) ? 100 : 0;
    // A leaf may be a pruned cube of several voxels: every column under it.
    const int n = static_cast<int>(std::lround(it.getSize() / res));
    const octomap::OcTreeKey first = tree.coordToKey(
        it.getX() - it.getSize() / 2 + res / 2, it.getY() - it.getSize() / 2 + res / 2, it.getZ());
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        std::int8_t& cell = grid.data[std::size_t{grid.info.width} * (first[1] + j - lo[1]) +
                                      (first[0] + i - lo[0])];
        cell = std::max(cell, value);
      }
  }
  return grid;
}

sensor_msgs::PointCloud2 occupiedCellsMessage(const octomap::OcTree& tree,
                                              const std_msgs::Header& header) {
  pcl::PointCloud<pcl::PointXYZ> centres;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it)
    if (tree.isNodeOccupied(*it)) {
      const octomap::point3d c = it.getCoordinate();
      centres.push_back(pcl::PointXYZ(c.x(), c.y(), c.z()));
    }
  return toMessage(centres, header);
}

multislit_ros::Floor floorMessage(const FloorResult& floor, const MetricFloor& metric,
                                  const std_msgs::Header& header) {
  multislit_ros::Floor m;
  m.header = header;
  m.found = floor.found;
  for (int i = 0; i < 3; ++i) m.rdmap_plane[i] = floor.plane[i];
  m.metric = floor.found && metric.valid;
  if (m.metric) {
    for (int i = 0; i < 3; ++i) m.plane[i] = metric.normal[i];
    m.plane[3] = metric.offset;
  }
  m.sigma = floor.sigma;
  m.threshold = floor.threshold;
  m.residual_std = floor.residual_std;
  m.valid_points = static_cast<std::uint32_t>(floor.valid_points);
  m.floor_points = static_cast<std::uint32_t>(floor.inliers.size());
  m.obstacle_points = static_cast<std::uint32_t>(floor.obstacles.size());
  return m;
}

multislit_ros::Decision decisionMessage(const WalkerResult& decision,
                                        const std_msgs::Header& header) {
  multislit_ros::Decision m;
  m.header = header;
  m.command = decision.command == Command::Walk   ? multislit_ros::Decision::WALK
              : decision.command == Command::Turn ? multislit_ros::Decision::TURN
                                                  : multislit_ros::Decision::STOP;
  m.command_name = commandName(decision.command);
  m.reason = reasonName(decision.reason);
  m.turn_direction = static_cast<std::int8_t>(decision.turn_direction);
  m.stop_frames_left = decision.stop_frames_left;
  return m;
}

geometry_msgs::TransformStamped transformMessage(const Eigen::Isometry3d& parent_from_child,
                                                 const std_msgs::Header& header,
                                                 const std::string& child_frame) {
  geometry_msgs::TransformStamped t;
  t.header = header;
  t.child_frame_id = child_frame;
  const Eigen::Vector3d p = parent_from_child.translation();
  const Eigen::Quaterniond q(parent_from_child.rotation());
  t.transform.translation.x = p.x();
  t.transform.translation.y = p.y();
  t.transform.translation.z = p.z();
  t.transform.rotation.x = q.x();
  t.transform.rotation.y = q.y();
  t.transform.rotation.z = q.z();
  t.transform.rotation.w = q.w();
  return t;
}

}  // namespace multislit::ros_node
