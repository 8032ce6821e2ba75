// The frames `multislit bench` times, with what the stages need besides the images: rendered
// once by the simulator, or read from a folder of recorded PNGs.
#pragma once

#include "cli.h"

#include "multislit/reference.h"
#include "multislit/sensor.h"

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include <string>
#include <vector>

namespace multislit::apps {

/// The frames of one run and what the stages need besides the images.
struct BenchInput {
  std::string label;  ///< scenario or folder
  int scale = 1;      ///< points per frame, times the paper's sensor
  Reference reference;
  SensorConfig sensor;  ///< the sensor and its mount on the robot
  std::vector<cv::Mat> images;
  std::vector<Eigen::Isometry3d> world_from_camera;  ///< per frame: odometry and mount
  Eigen::Isometry3d robot_from_camera = Eigen::Isometry3d::Identity();
  Eigen::Vector3d light_origin = Eigen::Vector3d::Zero();  ///< projector centre, camera frame
};

/// Renders the reference and `frames` frames of a scenario once (the simulator is slow: about
/// 0.3 s per frame); every pass of the benchmark reuses them.
BenchInput renderBenchInput(const std::string& scenario, long frames, double step, int scale);

/// The PNGs of a folder (reference.png left out), in name order, with the reference of the
/// reference options; the robot stands at the mount of --sensor, advanced along x as frames.csv
/// says when the folder has one.
BenchInput readBenchInput(const cli::ArgParser& args);

}  // namespace multislit::apps
