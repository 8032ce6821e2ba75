// The ROS node: the frames of a camera, a recording or the simulator through the Extractor and
// the Pipeline, each frame's results published on the node's topics (ros_messages.h), the robot's
// poses from TF, odometry or its own (ros_poses.h), diagnostics once a period.
#pragma once

#include "map_input.h"
#include "map_outputs.h"
#include "node_config.h"
#include "ros_poses.h"

#include "multislit/extractor.h"
#include "multislit/pipeline.h"

#include <ros/node_handle.h>
#include <ros/publisher.h>
#include <ros/time.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace multislit::ros_node {

/// What the node counted since it started.
struct NodeCounts {
  std::size_t processed = 0;   ///< frames through the whole chain
  std::size_t no_pose = 0;     ///< frames without a pose, skipped
  std::size_t bad_frames = 0;  ///< frames the extractor refused
  std::size_t seq_gaps = 0;    ///< frames the source numbered but never delivered
  std::size_t no_floor = 0;    ///< processed frames without a floor
  std::optional<std::uint64_t> last_seq;
  std::optional<std::uint64_t> last_stamp_us;  ///< of the last frame processed
  bool last_floor = false;                     ///< the last frame's floor was found
  double last_sigma = 0.0;                     ///< [px]
  std::size_t last_groups = 0;
  std::string last_decision = "none";
  double latency_sum = 0.0;       ///< frame stamp to its cloud's publication, summed [s]
  double node_latency_sum = 0.0;  ///< frame's arrival at the node to the same, summed [s]
  double processing_sum = 0.0;    ///< CPU time of extraction and pipeline, summed [s]
  std::size_t published = 0;      ///< frames in the two sums
};

class Node {
 public:
  /// Opens the input, builds the reference and the pipeline, advertises. Throws on a wrong
  /// configuration or an input that cannot be opened.
  Node(const NodeConfig& config, ros::NodeHandle& nh, ros::NodeHandle& private_nh);

  /// Runs the frames until the source ends, ~frames are done or ROS shuts down; writes ~out
  /// then. Throws std::runtime_error when the subscribers waited for do not come.
  void run();
  const NodeCounts& counts() const { return counts_; }

 private:
  void waitForSubscribers() const;
  void processFrame(const Frame& frame);
  void publishFrame(const Frame& frame, const pcl::PointCloud<PointRDM>& cloud,
                    const PipelineResult& result, const PipelineInput& input);
  void publishMap(const ros::Time& stamp);
  void publishDiagnostics(bool now, const std::string& state);
  std_msgs::Header header(const ros::Time& stamp, const std::string& frame) const;

  NodeConfig config_;
  apps::MapInput in_;
  Pipeline pipeline_;
  Extractor extractor_;
  RosPoses poses_;
  std::optional<apps::MapRecorder> recorder_;
  ros::Publisher rdmap_, floor_, obstacles_, markers_, octomap_, octomap_full_, projected_,
      occupied_, decision_, diagnostics_;
  tf2_ros::TransformBroadcaster tf_;
  tf2_ros::StaticTransformBroadcaster static_tf_;
  NodeCounts counts_;
  std::size_t map_published_at_ = 0;  ///< counts_.processed when the map was last published
  std::string last_miss_;             ///< said once per kind
  ros::WallTime last_diagnostics_;
  std::size_t processed_at_diagnostics_ = 0, dropped_at_diagnostics_ = 0;
};

}  // namespace multislit::ros_node
