#include "slit_selection.h"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace multislit {
namespace {

// How far a slit's course may turn from the median course of the longest tracks [rad]: on a plane
// the fan's perspective turns the outer slits by a few degrees.
constexpr double kMaxCourseAngle = 20.0 * M_PI / 180.0;

/// Position of a track across the fan's direction `normal`, at its middle point.
double across(const Track& t, const Eigen::Vector2d& normal) {
  const Centre& m = t.points[t.points.size() / 2];
  return normal.dot(Eigen::Vector2d(m.u, m.row));
}

/// The direction of a track from its first to its last point, as an angle in (-pi/2, pi/2].
double direction(const Track& t) {
  const double a = std::atan2(t.lastRow() - t.firstRow(), t.points.back().u - t.points.front().u);
  return a > M_PI / 2 ? a - M_PI : a <= -M_PI / 2 ? a + M_PI : a;
}

/// The unit normal of the fan (pointing down and to the right), from the slits' mean direction.
Eigen::Vector2d fanNormal(const std::vector<Track>& slits) {
  Eigen::Vector2d along = Eigen::Vector2d::Zero();
  for (const Track& t : slits)
    along += Eigen::Vector2d(t.points.back().u - t.points.front().u, t.lastRow() - t.firstRow());
  Eigen::Vector2d normal(along.y(), -along.x());
  if (normal.x() + normal.y() < 0) normal = -normal;
  return normal.norm() > 0 ? normal.normalized() : Eigen::Vector2d(1, 0);
}

/// The indices of `count` positions of `at` (sorted) at least `gap` apart with the largest sum of
/// `weight`; empty when no such set exists. Dynamic programming over (last chosen, how many).
std::vector<std::size_t> heaviestApart(const std::vector<double>& at,
                                       const std::vector<double>& weight, std::size_t count,
                                       double gap) {
  const std::size_t n = at.size();
  constexpr double kNone = -std::numeric_limits<double>::infinity();
  // best[k][i]: the heaviest k + 1 chosen ending with i; from[k][i] the one before it.
  std::vector<std::vector<double>> best(count, std::vector<double>(n, kNone));
  std::vector<std::vector<std::size_t>> from(count, std::vector<std::size_t>(n, n));
  for (std::size_t i = 0; i < n; ++i) best[0][i] = weight[i];
  for (std::size_t k = 1; k < count; ++k)
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < i && at[i] - at[j] >= gap; ++j)
        if (best[k - 1][j] > kNone && best[k - 1][j] + weight[i] > best[k][i]) {
          best[k][i] = best[k - 1][j] + weight[i];
          from[k][i] = j;
        }
  const auto last = std::max_element(best[count - 1].begin(), best[count - 1].end());
  if (n == 0 || *last == kNone) return {};
  std::vector<std::size_t> chosen(count);
  std::size_t i = static_cast<std::size_t>(last - best[count - 1].begin());
  for (std::size_t k = count; k-- > 0;) {
    chosen[k] = i;
    i = from[k][i];
  }
  return chosen;
}

/// Drops the tracks (sorted longest first) whose course turns more than kMaxCourseAngle from the
/// median course of the `expected` longest: the slits on a plane run nearly parallel, a track
/// across them (floor grain, a tile's edge) is none of them.
void dropAcrossCourse(std::vector<Track>& tracks, std::size_t expected) {
  std::vector<double> angles;
  for (std::size_t k = 0; k < expected && k < tracks.size(); ++k)
    angles.push_back(direction(tracks[k]));
  if (angles.empty()) return;
  const double course = upperMedian(angles);
  tracks.erase(std::remove_if(tracks.begin(), tracks.end(),
                              [&](const Track& t) {
                                const double d = std::abs(direction(t) - course);
                                return std::min(d, M_PI - d) > kMaxCourseAngle;
                              }),
               tracks.end());
}

/// Half the pattern's spacing across the fan, from the `expected` longest tracks.
double halfSpacing(const std::vector<Track>& tracks, std::size_t expected,
                   const Eigen::Vector2d& normal) {
  std::vector<double> longest;
  for (std::size_t k = 0; k < expected; ++k) longest.push_back(across(tracks[k], normal));
  std::sort(longest.begin(), longest.end());
  std::vector<double> spacing;
  for (std::size_t k = 1; k < longest.size(); ++k) spacing.push_back(longest[k] - longest[k - 1]);
  return spacing.empty() ? 0.0 : 0.5 * upperMedian(spacing);
}

/// The first track left over that is as long as half the median slit and lies apart from every
/// slit (one slit too many); -1 when none.
long extraSlit(const std::vector<double>& at, const std::vector<double>& weight,
               const std::vector<std::size_t>& chosen, double gap) {
  std::vector<double> lengths;
  for (std::size_t i : chosen) lengths.push_back(weight[i]);
  const double slit_length = upperMedian(lengths);
  for (std::size_t i = 0; i < at.size(); ++i) {
    const bool is_slit = std::find(chosen.begin(), chosen.end(), i) != chosen.end();
    const bool apart = std::all_of(chosen.begin(), chosen.end(),
                                   [&](std::size_t j) { return std::abs(at[i] - at[j]) >= gap; });
    if (!is_slit && apart && weight[i] >= 0.5 * slit_length) return static_cast<long>(i);
  }
  return -1;
}

}  // namespace

std::string describeTracks(const std::vector<Track>& tracks) {
  std::ostringstream s;
  for (std::size_t k = 0; k < tracks.size() && k < 20; ++k)
    s << (k ? ", " : "") << "rows " << tracks[k].firstRow() << "-" << tracks[k].lastRow();
  if (tracks.size() > 20) s << ", ...";
  return s.str();
}

std::vector<Track> selectSlits(std::vector<Track> tracks, const ReferenceConfig& config,
                               const std::string& what, int* dropped) {
  const auto expected = static_cast<std::size_t>(config.expected_slits);
  const std::size_t all = tracks.size();
  tracks.erase(std::remove_if(tracks.begin(), tracks.end(),
                              [&](const Track& t) {
                                return static_cast<int>(t.points.size()) < config.min_rows;
                              }),
               tracks.end());
  std::stable_sort(tracks.begin(), tracks.end(), [](const Track& a, const Track& b) {
    return a.points.size() > b.points.size();
  });
  auto refuse = [&](const std::string& why) {
    std::ostringstream msg;
    msg << what << ": " << why;
    if (!tracks.empty()) msg << " (" << describeTracks(tracks) << ")";
    if (tracks.empty()) msg << ": is the laser on, and is this an image of a plane?";
    throw std::runtime_error(msg.str());
  };
  const std::string found =
      "found " + std::to_string(tracks.size()) + " slits, expected " + std::to_string(expected);
  if (tracks.size() < expected) refuse(found);
  dropAcrossCourse(tracks, expected);
  if (tracks.size() < expected) refuse(found + " along the pattern's course");
  const Eigen::Vector2d normal =
      fanNormal(std::vector<Track>(tracks.begin(), tracks.begin() + static_cast<long>(expected)));
  const double gap = halfSpacing(tracks, expected, normal);
  // Every long track by its place across the fan; the heaviest set apart are the slits.
  std::sort(tracks.begin(), tracks.end(),
            [&](const Track& a, const Track& b) { return across(a, normal) < across(b, normal); });
  std::vector<double> at, weight;
  for (const Track& t : tracks) {
    at.push_back(across(t, normal));
    weight.push_back(static_cast<double>(t.points.size()));
  }
  const std::vector<std::size_t> chosen = heaviestApart(at, weight, expected, gap);
  if (chosen.empty())
    refuse("found no " + std::to_string(expected) + " slit-like tracks " +
           std::to_string(static_cast<int>(gap)) + " px apart (half the pattern's spacing)");
  if (const long extra = extraSlit(at, weight, chosen, gap); extra >= 0)
    refuse("found " + std::to_string(expected + 1) + " or more slits, expected " +
           std::to_string(expected) + ": " +
           describeTracks({tracks[static_cast<std::size_t>(extra)]}) +
           " lies apart from the others and is as long as a slit");
  std::vector<Track> slits;
  for (std::size_t i : chosen) slits.push_back(std::move(tracks[i]));
  *dropped = static_cast<int>(all - expected);
  return slits;
}

}  // namespace multislit
