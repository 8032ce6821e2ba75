#include "ros_view.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <vector>

namespace multislit::ros_test {
namespace {

constexpr double kTopHeight = 0.08;  ///< the colour scale: 0 (blue) .. this (red) [m]

/// A pinhole viewer behind the robot, right and above, looking at the floor ahead of its feet.
class Viewer {
 public:
  Viewer(const cv::Size& size, const Eigen::Vector3d& eye, const Eigen::Vector3d& target)
      : eye_(eye), centre_(0.5 * size.width, 0.5 * size.height) {
    forward_ = (target - eye).normalized();
    right_ = forward_.cross(Eigen::Vector3d::UnitZ()).normalized();
    up_ = right_.cross(forward_);
  }
  std::optional<cv::Point> project(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d = p - eye_;
    const double depth = forward_.dot(d);
    if (depth < 0.05) return std::nullopt;
    return cv::Point(static_cast<int>(std::lround(centre_.x + kFocal * right_.dot(d) / depth)),
                     static_cast<int>(std::lround(centre_.y - kFocal * up_.dot(d) / depth)));
  }
  void line(cv::Mat& image, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
            const cv::Scalar& colour, int thickness = 1) const {
    const auto pa = project(a), pb = project(b);
    if (pa && pb) cv::line(image, *pa, *pb, colour, thickness, cv::LINE_AA);
  }

 private:
  static constexpr double kFocal = 1100.0;  ///< [px]
  Eigen::Vector3d eye_, forward_, right_, up_;
  cv::Point2d centre_;
};

cv::Scalar heightColour(double height) {
  cv::Mat grey(1, 1, CV_8UC1, cv::Scalar(std::clamp(height / kTopHeight, 0.0, 1.0) * 255.0));
  cv::Mat colour;
  cv::applyColorMap(grey, colour, cv::COLORMAP_JET);
  const cv::Vec3b c = colour.at<cv::Vec3b>(0, 0);
  return cv::Scalar(c[0], c[1], c[2]);
}

void drawGrid(cv::Mat& image, const Viewer& view) {
  const cv::Scalar grey(110, 110, 110);
  for (double x = 0.0; x <= 0.601; x += 0.05) view.line(image, {x, -0.35, 0}, {x, 0.45, 0}, grey);
  for (double y = -0.35; y <= 0.451; y += 0.05) view.line(image, {0.0, y, 0}, {0.6, y, 0}, grey);
  // base_footprint's axes, as rviz draws them: x red, y green, z blue (0.1 m)
  view.line(image, {0, 0, 0}, {0.1, 0, 0}, cv::Scalar(0, 0, 255), 3);
  view.line(image, {0, 0, 0}, {0, 0.1, 0}, cv::Scalar(0, 255, 0), 3);
  view.line(image, {0, 0, 0}, {0, 0, 0.1}, cv::Scalar(255, 0, 0), 3);
}

void drawBox(cv::Mat& image, const Viewer& view, const visualization_msgs::Marker& m) {
  const Eigen::Vector3d c(m.pose.position.x, m.pose.position.y, m.pose.position.z);
  const Eigen::Vector3d h(0.5 * m.scale.x, 0.5 * m.scale.y, 0.5 * m.scale.z);
  std::array<Eigen::Vector3d, 8> corner;
  for (int i = 0; i < 8; ++i)
    corner[i] =
        c + Eigen::Vector3d(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z());
  const cv::Scalar colour(255.0 * m.color.b, 255.0 * m.color.g, 255.0 * m.color.r);
  // The faces see-through, as rviz draws a marker of alpha < 1, then the edges.
  cv::Mat faces = image.clone();
  for (int axis = 1; axis < 8; axis <<= 1)
    for (int side = 0; side < 2; ++side) {
      const int a = axis == 1 ? 2 : 1, b = axis == 4 ? 2 : 4;  // the face's two other axes
      std::vector<cv::Point> polygon;
      for (const int i : {0, a, a | b, b})
        if (const auto at = view.project(corner[i | (side ? axis : 0)])) polygon.push_back(*at);
      if (polygon.size() == 4) cv::fillConvexPoly(faces, polygon, colour, cv::LINE_AA);
    }
  cv::addWeighted(faces, 0.25, image, 0.75, 0.0, image);
  for (int i = 0; i < 8; ++i)
    for (int bit = 1; bit < 8; bit <<= 1)
      if (!(i & bit)) view.line(image, corner[i], corner[i | bit], colour, 2);
}

void drawLabel(cv::Mat& image, const Viewer& view, const visualization_msgs::Marker& m) {
  const auto at = view.project({m.pose.position.x, m.pose.position.y, m.pose.position.z});
  if (!at) return;
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  const cv::Size size = cv::getTextSize(m.text, font, 0.6, 1, nullptr);
  cv::putText(image, m.text, *at - cv::Point(size.width / 2, 0), font, 0.6,
              cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
}

void drawLegend(cv::Mat& image, const std::string& title) {
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  int y = 30;
  for (std::size_t from = 0; from < title.size(); y += 26) {  // one line per '\n'
    const std::size_t to = std::min(title.find('\n', from), title.size());
    cv::putText(image, title.substr(from, to - from), {16, y}, font, 0.6, cv::Scalar(235, 235, 235),
                1, cv::LINE_AA);
    from = to + 1;
  }
  const int x0 = 16, y0 = image.rows - 40, w = 240;
  for (int i = 0; i < w; ++i)
    cv::line(image, {x0 + i, y0}, {x0 + i, y0 + 14},
             heightColour(kTopHeight * i / static_cast<double>(w - 1)));
  cv::putText(image, "height above the floor: 0 .. 80 mm; grid 50 mm", {x0, y0 + 34}, font, 0.5,
              cv::Scalar(235, 235, 235), 1, cv::LINE_AA);
}

}  // namespace

cv::Mat renderView(const pcl::PointCloud<PointRDM>& cloud,
                   const visualization_msgs::MarkerArray& markers,
                   const Eigen::Isometry3d& base_from_camera, const std::string& title) {
  cv::Mat image(760, 1100, CV_8UC3, cv::Scalar(48, 48, 48));  // rviz's background
  const Viewer view(image.size(), {-0.30, -0.28, 0.52}, {0.24, 0.08, 0.0});
  drawGrid(image, view);
  for (const PointRDM& p : cloud) {
    if (!hasXYZ(p)) continue;
    const Eigen::Vector3d q = base_from_camera * Eigen::Vector3d(p.x, p.y, p.z);
    if (const auto at = view.project(q)) cv::circle(image, *at, 2, heightColour(q.z()), -1);
  }
  for (const visualization_msgs::Marker& m : markers.markers)
    if (m.type == visualization_msgs::Marker::CUBE) drawBox(image, view, m);
  for (const visualization_msgs::Marker& m : markers.markers)
    if (m.type == visualization_msgs::Marker::TEXT_VIEW_FACING) drawLabel(image, view, m);
  drawLegend(image, title);
  return image;
}

}  // namespace multislit::ros_test
