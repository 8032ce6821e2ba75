// One frame's results as ROS messages: plain conversions, no node, no master (so that a test or
// a tool can make them too). Stamps and frames come in the header given.
#pragma once

#include "multislit/floor_detector.h"
#include "multislit/obstacles.h"
#include "multislit/point_types.h"
#include "multislit/walker.h"

#include <geometry_msgs/TransformStamped.h>
#include <multislit_ros/Decision.h>
#include <multislit_ros/Floor.h>
#include <nav_msgs/OccupancyGrid.h>
#include <octomap_msgs/Octomap.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

#include <octomap/OcTree.h>
#include <pcl/point_cloud.h>

#include <Eigen/Geometry>

namespace multislit::ros_node {

/// The organized RDMap with every field of PointRDM: x, y, z, u, v, dk (float32), slit (int32).
sensor_msgs::PointCloud2 rdmapMessage(const pcl::PointCloud<PointRDM>& cloud,
                                      const std_msgs::Header& header);

/// The points of the obstacle groups (x, y, z of the RDMap's frame) with the group's index as
/// `label` (0: the nearest to the feet); unorganized.
sensor_msgs::PointCloud2 obstacleCloudMessage(const pcl::PointCloud<PointRDM>& cloud,
                                              const ObstacleResult& obstacles,
                                              const std_msgs::Header& header);

/// Marker namespaces of obstacleMarkers().
inline constexpr const char* kGroupBoxes = "obstacle_groups";
inline constexpr const char* kGroupLabels = "obstacle_sizes";

/// One box per obstacle group (robot frame: `header` names the base frame), from the floor to
/// its height over its length and width, coloured by height, and its size as text above it;
/// the first marker deletes the previous frame's.
visualization_msgs::MarkerArray obstacleMarkers(const ObstacleResult& obstacles,
                                                const std_msgs::Header& header);

/// The map as octomap_msgs/Octomap, as octomap_msgs' binaryMapToMsg makes it: binary
/// (occupied / free per voxel, OcTree::writeBinaryData), id "OcTree", the tree's resolution.
octomap_msgs::Octomap octomapMessage(const octomap::OcTree& tree, const std_msgs::Header& header);

/// The map as octomap_msgs' fullMapToMsg makes it: not binary (every voxel's occupancy,
/// OcTree::writeData), id "OcTree", the tree's resolution.
octomap_msgs::Octomap octomapFullMessage(const octomap::OcTree& tree,
                                         const std_msgs::Header& header);

/// The map seen from above, as octomap_server's projected_map: one cell per voxel column over the
/// map's extent, 100 where a voxel of the column is occupied, 0 where one is known and none is
/// occupied, -1 where none is known.
nav_msgs::OccupancyGrid projectedMapMessage(const octomap::OcTree& tree,
                                            const std_msgs::Header& header);

/// The centres of the map's occupied voxels (x, y, z).
sensor_msgs::PointCloud2 occupiedCellsMessage(const octomap::OcTree& tree,
                                              const std_msgs::Header& header);

/// The frame's floor: the RDMap plane (eq. 1), the metric plane and the measured noise.
multislit_ros::Floor floorMessage(const FloorResult& floor, const MetricFloor& metric,
                                  const std_msgs::Header& header);

multislit_ros::Decision decisionMessage(const WalkerResult& decision,
                                        const std_msgs::Header& header);

/// `parent_from_child` as TF's transform from header.frame_id to `child_frame`.
geometry_msgs::TransformStamped transformMessage(const Eigen::Isometry3d& parent_from_child,
                                                 const std_msgs::Header& header,
                                                 const std::string& child_frame);

}  // namespace multislit::ros_node
