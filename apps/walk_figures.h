// Figures of the walking experiment (multislit walk): an RDMap with its floor and obstacles as in
// the paper's Fig. 14, and the occupancy map from above with the path and every footstep.
#pragma once

#include "multislit/floor_detector.h"
#include "multislit/footsteps.h"
#include "multislit/occupancy_map.h"
#include "multislit/point_types.h"

#include <pcl/point_cloud.h>

#include <Eigen/Core>

#include <string>
#include <vector>

namespace multislit::apps {

/// Fig. 14: the RDMap of one frame in a 2.5D view (u across, v into the picture, dk up), the
/// fitted floor plane light green, floor points green, obstacle points red.
void drawRDMapFigure(const std::string& path, const std::string& title,
                     const pcl::PointCloud<PointRDM>& cloud, const FloorResult& floor);

/// A true object seen from above: a closed outline, or a circle (object_outline.h makes them
/// from the simulator's objects).
struct ObjectOutline {
  std::vector<Eigen::Vector2d> polygon;  ///< closed outline in the world [m]; empty: the circle
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  ///< the circle's centre, the label's [m]
  double radius = 0.0;                               ///< the circle's [m]
};

/// What the top view shows besides the map.
struct TopViewContent {
  std::vector<Pose2D> path;               ///< the body, every frame
  std::vector<Footstep> footsteps;        ///< every footstep, in order
  std::vector<double> clearances;         ///< of each footstep from the true objects [m]
  std::vector<ObjectOutline> objects;     ///< true objects
  std::vector<std::string> object_notes;  ///< a label per object
};

/// The map seen from above: occupied voxels coloured by height, known-free floor grey, the true
/// objects' outlines, the path and the soles (left blue, right orange, red if touching).
void drawTopView(const std::string& path, const OccupancyMap& map, const TopViewContent& content);

}  // namespace multislit::apps
