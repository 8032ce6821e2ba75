// multislit_ros: the multi-slit sensor in a ROS 1 graph. Runs a camera (~camera), a recording
// (~sequence) or the simulator (~simulate) through the chain of `multislit map` and publishes the
// organized RDMap, the floor, the obstacle groups, the OctoMap, the walker's decision and
// diagnostics (docs/ros.md: topics, frames and parameters). When the frames end the node stays up,
// its map latched, until it is shut down (Ctrl-C, rosnode kill, roslaunch).
//   build/apps/ros/pkg/multislit_ros/multislit_ros _camera:=192.168.1.20 _poses:=tf
//       _calibration:=calib.yaml _sensor:=sensor.yaml   (on one line)
#include "node.h"
#include "node_config.h"

#include <ros/ros.h>

#include <exception>

int main(int argc, char** argv) {
  ros::init(argc, argv, "multislit");
  ros::NodeHandle nh;
  ros::NodeHandle private_nh("~");
  try {
    const multislit::ros_node::NodeConfig config = multislit::ros_node::readNodeConfig(private_nh);
    for (const std::string& name : multislit::ros_node::unknownParameters(private_nh))
      ROS_WARN_STREAM("unknown parameter " << name << " (ignored)");
    ros::AsyncSpinner spinner(1);  // odometry and TF arrive while the main thread runs frames
    spinner.start();
    multislit::ros_node::Node node(config, nh, private_nh);
    node.run();
    ros::waitForShutdown();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("multislit: " << e.what());
    return 1;
  }
  return 0;
}
