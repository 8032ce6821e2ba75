#include "slit_course.h"

#include <Eigen/Dense>

#include <cmath>
#include <limits>

namespace multislit {
namespace {

/// A slit's course u = a + b r + c r^2, r = row / 100 (coef: a, b, c), and the median |residual|
/// of the points it was fitted to [px].
struct Course {
  Eigen::Vector3d coef = Eigen::Vector3d::Zero();
  double spread = 0;
  double at(int row) const {  // u at an image row [px]
    const double r = row / 100.0;
    return coef(0) + coef(1) * r + coef(2) * r * r;
  }
};

/// |u - course.at(row)| of each of `pts` [px].
std::vector<double> distances(const std::vector<Centre>& pts, const Course& course) {
  std::vector<double> d;
  d.reserve(pts.size());
  for (const Centre& c : pts) d.push_back(std::abs(c.u - course.at(c.row)));
  return d;
}

/// Their median [px].
double medianDistance(const std::vector<Centre>& pts, const Course& course) {
  return upperMedian(distances(pts, course));
}

/// The course through `pts` by least squares, refitted without the points beyond three robust
/// sigmas (centres cut by a dark line or a speckle grain); with `curvature` given, c is fixed to
/// it.
Course fitCourse(const std::vector<Centre>& pts, const double* curvature = nullptr) {
  const auto n = static_cast<long>(pts.size());
  const int unknowns = curvature ? 2 : 3;
  Eigen::MatrixXd a(n, unknowns);
  Eigen::VectorXd b(n), weight = Eigen::VectorXd::Ones(n), x;
  for (long i = 0; i < n; ++i) {
    const double r = pts[static_cast<std::size_t>(i)].row / 100.0;
    a(i, 0) = 1.0;
    a(i, 1) = r;
    if (!curvature) a(i, 2) = r * r;
    b(i) = pts[static_cast<std::size_t>(i)].u - (curvature ? *curvature * r * r : 0.0);
  }
  Course c;
  for (int pass = 0; pass < 2; ++pass) {
    x = (weight.asDiagonal() * a).colPivHouseholderQr().solve(weight.asDiagonal() * b);
    c.coef << x(0), x(1), curvature ? *curvature : x(2);
    const std::vector<double> d = distances(pts, c);
    c.spread = upperMedian(d);
    for (long i = 0; i < n; ++i)
      weight(i) = d[static_cast<std::size_t>(i)] <= std::max(1.0, 4.5 * c.spread) ? 1.0 : 0.0;
  }
  return c;
}

/// The curvature the projector gives its slits (the pattern's distortion), as the median over
/// the tracks long enough to show it; 0 when none is.
double patternCurvature(const std::vector<Track>& tracks) {
  constexpr std::size_t kLong = 80;  // [rows]
  std::vector<double> c;
  for (const Track& t : tracks)
    if (t.points.size() >= kLong) c.push_back(fitCourse(t.points).coef(2));
  if (c.empty()) return 0;
  return upperMedian(c);
}

/// Column of track `t` at `row`, linear between its points (rows outside: its end's column).
double columnAt(const Track& t, int row) {
  const auto& p = t.points;
  const auto it =
      std::lower_bound(p.begin(), p.end(), row, [](const Centre& c, int r) { return c.row < r; });
  if (it == p.begin()) return p.front().u;
  if (it == p.end()) return p.back().u;
  const Centre& hi = *it;
  const Centre& lo = *(it - 1);
  if (hi.row == row) return hi.u;
  return lo.u + (hi.u - lo.u) * (row - lo.row) / static_cast<double>(hi.row - lo.row);
}

/// How far apart the courses of `a` and `b` (b starting no higher than a) pass [px]: over the
/// rows both cover, the median distance; over a gap, the median distance from one course with
/// the pattern's `curvature` through the ends of both (`scatter`: that of each end alone). Infinite
/// when b lies wholly inside a's rows (a second profile beside the slit), or when the ends are too
/// short to tell a course across the gap.
double courseMismatch(const Track& a, const Track& b, double curvature, double* scatter) {
  constexpr std::size_t kFit = 80;  // rows of each end that give its course
  constexpr std::size_t kMinEnd = 20;
  const auto& pa = a.points;
  const auto& pb = b.points;
  *scatter = 0;
  if (b.firstRow() <= a.lastRow()) {
    if (b.lastRow() <= a.lastRow()) return std::numeric_limits<double>::infinity();
    std::vector<double> d;
    for (const Centre& c : pb)
      if (c.row <= a.lastRow()) d.push_back(std::abs(c.u - columnAt(a, c.row)));
    return upperMedian(d);
  }
  const std::vector<Centre> end_a(pa.end() - static_cast<long>(std::min(kFit, pa.size())),
                                  pa.end());
  const std::vector<Centre> end_b(pb.begin(),
                                  pb.begin() + static_cast<long>(std::min(kFit, pb.size())));
  // Ends must be long enough for their slopes to say where they go: a quarter of the gap.
  const int span_a = end_a.back().row - end_a.front().row,
            span_b = end_b.back().row - end_b.front().row;
  if (end_a.size() < kMinEnd || end_b.size() < kMinEnd ||
      4 * std::min(span_a, span_b) < b.firstRow() - a.lastRow())
    return std::numeric_limits<double>::infinity();
  std::vector<Centre> both = end_a;
  both.insert(both.end(), end_b.begin(), end_b.end());
  *scatter = std::max(fitCourse(end_a, &curvature).spread, fitCourse(end_b, &curvature).spread);
  // Each end on the joint course, not the median of both: over a long gap the course that fits
  // one end can cross the other (a grain ridge above a curved slit) and leave half its points on
  // it, which the median of all would call a fit.
  const Course joint = fitCourse(both, &curvature);
  return std::max(medianDistance(end_a, joint), medianDistance(end_b, joint));
}

/// b's points below a's end appended to a (a speckled slit followed twice keeps one course).
void append(Track& a, const Track& b) {
  for (const Centre& c : b.points)
    if (c.row > a.lastRow()) a.points.push_back(c);
}

}  // namespace

// 3. Pieces of one slit, broken by speckle, a dark stain or an occluder, or followed twice where
// speckle made its centre jump, are joined when their courses meet (a slit is a smooth curve).
int joinTracks(std::vector<Track>& tracks, int max_join_gap, double tolerance) {
  constexpr std::size_t kMinPiece = 5;  // [rows] shorter pieces have no course to extrapolate
  tracks.erase(std::remove_if(tracks.begin(), tracks.end(),
                              [](const Track& t) { return t.points.size() < kMinPiece; }),
               tracks.end());
  const double curvature = patternCurvature(tracks);
  int joined = 0;
  for (;;) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t best_a = 0, best_b = 0;
    for (std::size_t a = 0; a < tracks.size(); ++a)
      for (std::size_t b = 0; b < tracks.size(); ++b) {
        const int gap = tracks[b].firstRow() - tracks[a].lastRow();
        const bool later = tracks[b].firstRow() > tracks[a].firstRow() ||
                           (tracks[b].firstRow() == tracks[a].firstRow() && b > a);
        if (a == b || !later || gap > max_join_gap) continue;
        double scatter = 0;
        const double miss = courseMismatch(tracks[a], tracks[b], curvature, &scatter);
        // One course: the joint fit is about as good as the pieces' own (their scatter).
        const double limit = std::max(tolerance, 2 * scatter);
        if (miss <= limit && miss < best) best = miss, best_a = a, best_b = b;
      }
    if (!std::isfinite(best)) return joined;
    append(tracks[best_a], tracks[best_b]);
    tracks.erase(tracks.begin() + static_cast<long>(best_b));
    ++joined;
  }
}

}  // namespace multislit
