#include "ros_checks.h"

#include "ros_view.h"

#include "multislit/extractor.h"
#include "multislit/sensor.h"
#include "multislit/sim/simulated_source.h"

#include <pcl_conversions/pcl_conversions.h>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace multislit::ros_test {
namespace {

TestOptions g_options;
const Capture* g_capture = nullptr;

std::vector<std::string> split(const std::string& text, char by) {
  std::vector<std::string> parts;
  std::stringstream s(text);
  for (std::string part; std::getline(s, part, by);) parts.push_back(part);
  return parts;
}

Eigen::Isometry3d robotPose(const std::string& text) {
  const std::vector<std::string> v = split(text, ',');
  if (v.size() != 3) throw std::invalid_argument("--robot X,Y,YAW_DEG, not '" + text + "'");
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(std::stod(v[0]), std::stod(v[1]), 0.0);
  t.linear() = Eigen::AngleAxisd(std::stod(v[2]) * M_PI / 180.0, Eigen::Vector3d::UnitZ())
                   .toRotationMatrix();
  return t;
}

template <typename PointT>
pcl::PointCloud<PointT> fromMessage(const sensor_msgs::PointCloud2& message) {
  pcl::PointCloud<PointT> cloud;
  pcl::fromROSMsg(message, cloud);
  return cloud;
}

double segmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                       const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / std::max(ab.squaredNorm(), 1e-12), 0.0, 1.0);
  return (p - (a + t * ab)).norm();
}

}  // namespace

bool parseOptions(int argc, char** argv) {
  try {
    for (int i = 1; i < argc; i += 2) {
      const std::string key = argv[i];
      if (i + 1 >= argc) throw std::invalid_argument(key + " needs a value");
      const std::string value = argv[i + 1];
      if (key == "--scenario")
        g_options.scenario = value;
      else if (key == "--frames")
        g_options.frames = std::stoul(value);
      else if (key == "--poses")
        g_options.poses = value;
      else if (key == "--robot")
        g_options.robot = robotPose(value);
      else if (key == "--node-out")
        g_options.node_out = value;
      else if (key == "--map-out")
        g_options.map_out = value;
      else if (key == "--figure")
        g_options.figure = value;
      else if (key == "--fps")
        g_options.fps = std::stod(value);
      else if (key == "--resolution")
        g_options.resolution = std::stod(value);
      else if (key == "--mount-shift")
        g_options.mount_shift = std::stod(value);
      else if (key == "--timeout")
        g_options.timeout = std::stod(value);
      else
        throw std::invalid_argument("unknown option " + key);
    }
    if (g_options.frames == 0) throw std::invalid_argument("--frames N is needed");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ros_node_test: %s\n", e.what());
    return false;
  }
  return true;
}

const TestOptions& options() { return g_options; }

CaptureOptions captureOptions() {
  CaptureOptions c;
  c.frames = g_options.frames;
  c.poses = g_options.poses;
  c.robot = g_options.robot;
  c.timeout = g_options.timeout;
  if (g_options.mount_shift != 0.0)
    c.mount = Eigen::Translation3d(g_options.mount_shift, 0.0, 0.0) * expected().base_from_camera;
  return c;
}

void setCapture(const Capture* capture) { g_capture = capture; }
const Capture& capture() { return *g_capture; }

const Expected& expected() {
  static const Expected e = [] {
    Expected x;
    SimulatorSourceConfig config;
    config.scenario = g_options.scenario;
    const SimulatorSource source(config);
    const Extractor extractor(source.makeReference());
    const Reference& ref = extractor.reference();
    pcl::PointCloud<PointRDM> cloud;
    extractor.extract(cv::Mat::zeros(ref.image_height, ref.image_width, CV_8UC1), cloud);
    x.rdmap_width = cloud.width;
    x.rdmap_height = cloud.height;
    SensorConfig sensor;
    sensor.mount = source.scenario().mount;
    x.base_from_camera = SensorGeometry(sensor).robotFromCamera();
    return x;
  }();
  return e;
}

std::vector<ros::Time> cloudStamps() {
  std::vector<ros::Time> stamps;
  for (const auto& item : capture().rdmap.items) stamps.push_back(item.message->header.stamp);
  return stamps;
}

std::vector<std::map<std::string, std::string>> readCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = split(line, ',');
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    const std::vector<std::string> cells = split(line, ',');
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < header.size() && i < cells.size(); ++i) row[header[i]] = cells[i];
    rows.push_back(row);
  }
  return rows;
}

pcl::PointCloud<PointRDM> rdmapCloud(const sensor_msgs::PointCloud2& m) {
  return fromMessage<PointRDM>(m);
}
pcl::PointCloud<pcl::PointXYZL> labelledCloud(const sensor_msgs::PointCloud2& m) {
  return fromMessage<pcl::PointXYZL>(m);
}
pcl::PointCloud<pcl::PointXYZ> xyzCloud(const sensor_msgs::PointCloud2& m) {
  return fromMessage<pcl::PointXYZ>(m);
}

std::vector<visualization_msgs::Marker> groupBoxes(const visualization_msgs::MarkerArray& array) {
  std::vector<visualization_msgs::Marker> boxes;
  for (const auto& m : array.markers)
    if (m.ns == "obstacle_groups" && m.type == visualization_msgs::Marker::CUBE &&
        m.action == visualization_msgs::Marker::ADD)
      boxes.push_back(m);
  return boxes;
}

const SceneObject* objectUnder(const Scenario& scenario, const Eigen::Isometry3d& world_from_frame,
                               const Eigen::Vector3d& p, double margin) {
  const Eigen::Vector2d w = (world_from_frame * p).head<2>();
  for (const SceneObject& o : scenario.scene.objects) {
    bool under = false;
    if (o.type == ShapeType::Sphere) {
      under = (w - o.centre.head<2>()).norm() <= o.radius + margin;
    } else if (o.type == ShapeType::Box) {
      const Eigen::Vector2d d =
          Eigen::Rotation2Dd(-o.yaw * M_PI / 180.0) * (w - o.centre.head<2>());
      under = std::abs(d.x()) <= 0.5 * o.size.x() + margin &&
              std::abs(d.y()) <= 0.5 * o.size.y() + margin;
    } else {
      under = segmentDistance(w, o.axis_start.head<2>(), o.axis_end.head<2>()) <= o.radius + margin;
    }
    if (under) return &o;
  }
  return nullptr;
}

std::unique_ptr<octomap::OcTree> decodeOctomap(const octomap_msgs::Octomap& message) {
  auto tree = std::make_unique<octomap::OcTree>(message.resolution);
  std::stringstream data(std::string(message.data.begin(), message.data.end()));
  if (message.binary)
    tree->readBinaryData(data);
  else
    tree->readData(data);
  return tree;
}

std::vector<Eigen::Vector3d> occupiedCentres(const octomap::OcTree& tree) {
  std::vector<Eigen::Vector3d> centres;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it)
    if (tree.isNodeOccupied(*it)) {
      const octomap::point3d c = it.getCoordinate();
      centres.emplace_back(c.x(), c.y(), c.z());
    }
  std::sort(centres.begin(), centres.end(), [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  });
  return centres;
}

std::optional<Eigen::Isometry3d> baseFromCamera() {
  for (const auto& item : capture().tf_static.items)
    for (const geometry_msgs::TransformStamped& t : item.message->transforms) {
      if (t.header.frame_id != "base_footprint" || t.child_frame_id != "multislit_optical")
        continue;
      const auto& q = t.transform.rotation;
      Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
      pose.linear() = Eigen::Quaterniond(q.w, q.x, q.y, q.z).toRotationMatrix();
      pose.translation() = Eigen::Vector3d(t.transform.translation.x, t.transform.translation.y,
                                           t.transform.translation.z);
      return pose;
    }
  return std::nullopt;
}

void writeFigure(const std::string& path) {
  const auto& cloud = *capture().rdmap.items.back().message;
  visualization_msgs::MarkerArray markers;
  for (const auto& item : capture().markers.items)
    if (!item.message->markers.empty() &&
        item.message->markers.front().header.stamp == cloud.header.stamp)
      markers = *item.message;
  const std::size_t groups = groupBoxes(markers).size();
  char title[200];
  std::snprintf(title, sizeof title,
                "multislit_ros on the simulator (%s), frame %zu, fixed frame base_footprint:\n"
                "/multislit/rdmap (points) and /multislit/obstacle_markers (%zu groups)",
                g_options.scenario.c_str(), capture().rdmap.items.size() - 1, groups);
  const cv::Mat image = renderView(rdmapCloud(cloud), markers,
                                   baseFromCamera().value_or(expected().base_from_camera), title);
  if (!cv::imwrite(path, image, {cv::IMWRITE_PNG_COMPRESSION, 9}))
    throw std::runtime_error("cannot write " + path);
}

}  // namespace multislit::ros_test
