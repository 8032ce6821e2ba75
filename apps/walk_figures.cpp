#include "walk_figures.h"

#include "common.h"
#include "draw.h"

#include "multislit/plane_model.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace multislit::apps {
namespace {

const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kFloorGreen(60, 170, 60), kPlaneGreen(190, 240, 190), kObstacleRed(30, 30, 220);
const cv::Scalar kObject(150, 40, 120), kLeftFoot(210, 140, 40), kRightFoot(40, 150, 240);

/// Legend entries in a row under the title.
void legend(cv::Mat& img, int* x, const cv::Scalar& colour, const std::string& label) {
  const int y = 58;
  cv::rectangle(img, {*x, y - 10}, {*x + 14, y + 2}, colour, cv::FILLED);
  cv::rectangle(img, {*x, y - 10}, {*x + 14, y + 2}, kInk, 1);
  drawText(img, label, {*x + 20, y}, 0.45);
  int base = 0;
  *x += 40 + cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, 0.45, 1, &base).width;
}

/// An oblique view of (u, v, dk): u to the right, v into the picture, dk up (exaggerated).
struct RDMapView {
  double u0 = 0, v0 = 0, su = 1, sv = 1, gain = 1;
  cv::Point operator()(double u, double v, double dk) const {
    return {static_cast<int>(std::lround(90 + (u - u0) * su + (v - v0) * sv * 0.55)),
            static_cast<int>(std::lround(640 - (v - v0) * sv * 0.5 - dk * gain))};
  }
};

RDMapView viewOf(const pcl::PointCloud<PointRDM>& cloud, const FloorResult& floor) {
  double u0 = 1e9, u1 = -1e9, v0 = 1e9, v1 = -1e9, top = 0.0;
  for (const PointRDM& p : cloud) {
    if (!isValidRDMPoint(p)) continue;
    u0 = std::min<double>(u0, p.u);
    u1 = std::max<double>(u1, p.u);
    v0 = std::min<double>(v0, p.v);
    v1 = std::max<double>(v1, p.v);
  }
  for (std::size_t k = 0; k < floor.obstacle_residuals.size(); ++k)
    top = std::max(top, static_cast<double>(std::abs(floor.obstacle_residuals[k])));
  RDMapView view;
  view.u0 = u0;
  view.v0 = v0;
  view.su = 700.0 / std::max(1.0, u1 - u0);
  view.sv = 560.0 / std::max(1.0, v1 - v0);
  view.gain = std::min(25.0, 250.0 / std::max(1.0, top));  // px of the figure per px of dk
  return view;
}

}  // namespace

void drawRDMapFigure(const std::string& path, const std::string& title,
                     const pcl::PointCloud<PointRDM>& cloud, const FloorResult& floor) {
  const RDMapView view = viewOf(cloud, floor);
  cv::Mat img(720, 1200, CV_8UC3, kWhite);
  const auto plane = [&](double u, double v) {
    return floor.plane[0] * u + floor.plane[1] * v + floor.plane[2];
  };
  // The fitted plane over the measured (u, v) range, eq. (1).
  double u1 = view.u0 + 700.0 / view.su, v1 = view.v0 + 560.0 / view.sv;
  const std::vector<cv::Point> corners = {
      view(view.u0, view.v0, plane(view.u0, view.v0)), view(u1, view.v0, plane(u1, view.v0)),
      view(u1, v1, plane(u1, v1)), view(view.u0, v1, plane(view.u0, v1))};
  if (floor.found) cv::fillConvexPoly(img, corners, kPlaneGreen, cv::LINE_AA);
  cv::polylines(img, corners, true, kGrid, 1, cv::LINE_AA);
  for (const auto i : floor.inliers) {
    const PointRDM& p = cloud[static_cast<std::size_t>(i)];
    cv::circle(img, view(p.u, p.v, p.dk), 1, kFloorGreen, cv::FILLED);
  }
  for (const auto i : floor.obstacles) {
    const PointRDM& p = cloud[static_cast<std::size_t>(i)];
    cv::circle(img, view(p.u, p.v, p.dk), 2, kObstacleRed, cv::FILLED, cv::LINE_AA);
  }
  // Axes from the near corner.
  const cv::Point o = view(view.u0, view.v0, 0.0);
  cv::arrowedLine(img, o, view(view.u0 + 250 / view.su, view.v0, 0), kInk, 1, cv::LINE_AA);
  cv::arrowedLine(img, o, view(view.u0, view.v0 + 250 / view.sv, 0), kInk, 1, cv::LINE_AA);
  cv::arrowedLine(img, o, {o.x, o.y - 80}, kInk, 1, cv::LINE_AA);
  drawText(img, "u [px]", view(view.u0 + 260 / view.su, view.v0, 0) + cv::Point(5, 5));
  drawText(img, "v [px]", view(view.u0, view.v0 + 260 / view.sv, 0) + cv::Point(-20, -8));
  char label[160];
  std::snprintf(label, sizeof label, "dk [px] x%.0f", view.gain);
  drawText(img, label, {o.x - 40, o.y - 90});
  drawText(img, title, {30, 32}, 0.65);
  int x = 30;
  std::snprintf(label, sizeof label, "floor points (%zu)", floor.inliers.size());
  legend(img, &x, kFloorGreen, label);
  std::snprintf(label, sizeof label, "obstacle points (%zu)", floor.obstacles.size());
  legend(img, &x, kObstacleRed, label);
  std::snprintf(label, sizeof label, "floor plane dk = %.4f u %+.4f v %+.2f (eq. 1)",
                floor.plane[0], floor.plane[1], floor.plane[2]);
  legend(img, &x, kPlaneGreen, label);
  writeImage(path, img);
}

namespace {

/// Metres on the floor to pixels of the top view (x up the picture would turn the path; the
/// walking direction, world x, goes to the right).
struct TopView {
  double x0 = 0, y1 = 0, scale = 1;  // world x at the left edge, world y at the top [m], px/m
  cv::Point operator()(const Eigen::Vector2d& p) const {
    return {static_cast<int>(std::lround(40 + (p.x() - x0) * scale)),
            static_cast<int>(std::lround(80 + (y1 - p.y()) * scale))};
  }
};

TopView fit(const TopViewContent& c, cv::Size* size) {
  // No path (a walk stopped before its first frame): the view around the start.
  Eigen::Vector2d lo = c.path.empty() ? Eigen::Vector2d::Zero() : Eigen::Vector2d(1e9, 1e9);
  Eigen::Vector2d hi = c.path.empty() ? Eigen::Vector2d::Zero() : Eigen::Vector2d(-1e9, -1e9);
  for (const Pose2D& p : c.path) {
    lo = lo.cwiseMin(p.position());
    hi = hi.cwiseMax(p.position());
  }
  lo -= Eigen::Vector2d(0.15, 0.35);
  hi += Eigen::Vector2d(0.5, 0.35);  // the view reaches 0.4 m ahead
  TopView view;
  view.scale = std::min(1400.0 / (hi.x() - lo.x()), 800.0 / (hi.y() - lo.y()));
  view.x0 = lo.x();
  view.y1 = hi.y();
  *size = cv::Size(80 + static_cast<int>((hi.x() - lo.x()) * view.scale),
                   120 + static_cast<int>((hi.y() - lo.y()) * view.scale));
  return view;
}

void drawObject(cv::Mat& img, const TopView& view, const ObjectOutline& o) {
  if (o.polygon.empty()) {
    const int r = std::max(1, static_cast<int>(std::lround(o.radius * view.scale)));
    cv::circle(img, view(o.centre), r, kObject, 2, cv::LINE_AA);
    return;
  }
  std::vector<cv::Point> pts;
  for (const Eigen::Vector2d& c : o.polygon) pts.push_back(view(c));
  cv::polylines(img, pts, true, kObject, 2, cv::LINE_AA);
}

void drawMapCells(cv::Mat& img, const TopView& view, const OccupancyMap& map) {
  const octomap::OcTree& tree = map.tree();
  std::vector<MapCell> occupied;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const octomap::point3d c = it.getCoordinate();
    const double half = 0.5 * it.getSize();
    const cv::Point a = view(Eigen::Vector2d(c.x() - half, c.y() + half));
    const cv::Point b = view(Eigen::Vector2d(c.x() + half, c.y() - half));
    if (tree.isNodeOccupied(*it))
      occupied.push_back(MapCell{Eigen::Vector3d(c.x(), c.y(), c.z()), it.getSize(), 0.0});
    else if (c.z() - half < 0.5 * map.config().resolution)  // the floor seen free
      cv::rectangle(img, a, b, cv::Scalar(236, 236, 236), cv::FILLED);
  }
  std::sort(occupied.begin(), occupied.end(),
            [](const MapCell& a, const MapCell& b) { return a.centre.z() < b.centre.z(); });
  for (const MapCell& c : occupied) {  // yellow on the floor to dark red at 5 cm
    const double t = std::clamp(c.centre.z() / 0.05, 0.0, 1.0);
    const cv::Scalar colour(0, 220 - 200 * t, 255 - 120 * t);
    const double half = 0.5 * c.size;
    cv::rectangle(img, view(Eigen::Vector2d(c.centre.x() - half, c.centre.y() + half)),
                  view(Eigen::Vector2d(c.centre.x() + half, c.centre.y() - half)), colour,
                  cv::FILLED);
  }
}

}  // namespace

void drawTopView(const std::string& path, const OccupancyMap& map, const TopViewContent& c) {
  cv::Size size;
  const TopView view = fit(c, &size);
  cv::Mat img(size, CV_8UC3, kWhite);
  drawMapCells(img, view, map);
  // A 10 cm grid, coarser by tens while its lines would be under 8 px apart (a path of
  // kilometres would otherwise draw millions of lines).
  double step = 0.1;
  while (step * view.scale < 8) step *= 10;
  for (double x = std::ceil(view.x0 / step) * step; view(Eigen::Vector2d(x, 0)).x < size.width;
       x += step)
    cv::line(img, {view(Eigen::Vector2d(x, 0)).x, 75}, {view(Eigen::Vector2d(x, 0)).x, size.height},
             kGrid, 1);
  for (double y = std::floor(view.y1 / step) * step;
       view(Eigen::Vector2d(0, y)).y < size.height && view(Eigen::Vector2d(0, y)).y > 74; y -= step)
    cv::line(img, {0, view(Eigen::Vector2d(0, y)).y}, {size.width, view(Eigen::Vector2d(0, y)).y},
             kGrid, 1);
  for (std::size_t k = 0; k < c.objects.size(); ++k) {
    drawObject(img, view, c.objects[k]);
    if (k < c.object_notes.size())
      drawText(img, c.object_notes[k], view(c.objects[k].centre) + cv::Point(12, -12), 0.45,
               kObject);
  }
  std::vector<cv::Point> line;
  for (const Pose2D& p : c.path) line.push_back(view(p.position()));
  cv::polylines(img, line, false, kInk, 1, cv::LINE_AA);
  for (std::size_t k = 0; k < c.footsteps.size(); ++k) {
    std::vector<cv::Point> sole;
    for (const Eigen::Vector2d& p : c.footsteps[k].sole.corners()) sole.push_back(view(p));
    const bool touching = k < c.clearances.size() && c.clearances[k] <= 0.0;
    if (touching) cv::fillConvexPoly(img, sole, kObstacleRed, cv::LINE_AA);
    cv::polylines(img, sole, true, c.footsteps[k].foot == Foot::Left ? kLeftFoot : kRightFoot, 1,
                  cv::LINE_AA);
  }
  const std::string grid = step < 1 ? std::to_string(std::lround(step * 100)) + " cm"
                                    : std::to_string(std::llround(step)) + " m";
  drawText(img,
           "occupancy map from above, path and footsteps (" + grid + " grid; walking to the right)",
           {20, 30}, 0.6);
  int x = 20;
  legend(img, &x, cv::Scalar(0, 220, 255), "occupied voxel (yellow: floor, red: 5 cm up)");
  legend(img, &x, cv::Scalar(236, 236, 236), "floor seen free");
  legend(img, &x, kObject, "true object");
  legend(img, &x, kLeftFoot, "left sole");
  legend(img, &x, kRightFoot, "right sole");
  legend(img, &x, kObstacleRed, "sole touching an object");
  writeImage(path, img);
}

}  // namespace multislit::apps
