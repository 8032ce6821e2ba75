// One frame's evidence for the occupancy map (private to the library): a mark per point and per
// cell of a light ray, the floor noise of each slit, the weak points, and how far the slits moved
// across the floor since the previous frame.
#pragma once

#include "multislit/floor_detector.h"
#include "multislit/occupancy_map.h"
#include "multislit/point_types.h"
#include "multislit/sweep_evidence.h"
#include "voxel_code.h"

#include <octomap/OcTree.h>
#include <pcl/point_cloud.h>

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace multislit::detail {

/// Marks as (VoxelCode::of(key) << 3 | kind): sorting gathers the marks of each voxel and puts the
/// voxels in the tree's depth-first order, in which KeyOrderUpdate descends least.
struct FrameEvidence {
  enum Kind : std::uint64_t { kRay = 0, kFloor = 1, kPending = 2, kWeak = 3, kHit = 4 };
  static constexpr int kKindBits = 3;
  std::vector<std::uint64_t> marks;
  std::vector<std::uint64_t> sort_buffer;  ///< sortMarks()'s room, kept across frames
  static constexpr int kRecentBits = 9;
  /// The last free mark (kRay, kFloor) at each hash of a mark: repeats of recent ones are left out.
  std::array<std::uint64_t, std::size_t{1} << kRecentBits> recent_free;
  /// One slit (RDMap row) in this frame: its floor points' noise and where its measured run ends.
  struct Slit {
    double sum_sq = 0.0;      ///< squared residuals of its floor points [px^2]
    std::size_t count = 0;    ///< its floor points
    std::uint32_t first = 0;  ///< first column with a floor point
    std::uint32_t last = 0;   ///< last column with a floor point
    double weak = 0.0;        ///< residual from which a point is weak [px]
  };
  std::vector<Slit> slits;
  std::vector<double> residual;         ///< per cloud point (floor inliers only) [px]
  std::vector<std::int8_t> weak_point;  ///< per cloud point: +1 weak above, -1 below, 0 not weak
  /// This frame's points of evidence for the sweep, and the voxel each one marks.
  std::vector<SweepPoint> sweep_points;
  std::vector<octomap::OcTreeKey> sweep_keys;

  /// Starts a frame's marks.
  void clearMarks() {
    marks.clear();
    recent_free.fill(~std::uint64_t{0});  // no mark: its kind bits are not a Kind
  }
  void mark(const octomap::OcTreeKey& key, Kind kind) {
    const std::uint64_t m = VoxelCode::of(key) << kKindBits | kind;
    if (kind <= kFloor) {
      // A voxel marked free once needs no second such mark (apply() asks only whether it has
      // one); rays to neighbouring floor points cross the same voxels near their top.
      std::uint64_t& seen = recent_free[(m * 0x9e3779b97f4a7c15u) >> (64 - kRecentBits)];
      if (seen == m) return;
      seen = m;
    } else if (kind != kWeak && !marks.empty() && marks.back() == m) {
      return;  // a slit's points come in order, several per voxel; weak points are counted
    }
    marks.push_back(m);
  }
  /// `marks` in ascending order of their voxels (the marks of one voxel together, in the order
  /// they were made), by a radix sort over digits of 11 bits placed where the voxels differ: a
  /// frame's voxels lie near each other, so most bits of their keys are the same.
  void sortMarks();

  /// Each slit's own noise (the outer slits, dimmer and farther, are noisier than the frame's
  /// mean), and where each slit's measured points end (a profile cut by the slit's end is biased):
  /// `slits` and, per floor inlier, `residual`.
  void measureSlits(const pcl::PointCloud<PointRDM>& cloud, const FloorResult& floor,
                    const OccupancyMapConfig& config);
  /// `weak_point`: the floor inliers far above (or below) the plane for their slit and away from
  /// its ends, in runs of min_weak_run consecutive points of one sign along the slit: an object
  /// lifts every row that crosses it, while noise lifts one row or a pair. After measureSlits().
  void flagWeakFloorPoints(const pcl::PointCloud<PointRDM>& cloud, const FloorResult& floor,
                           const OccupancyMapConfig& config);
};

/// The value std::nth_element would place at values.size() / 2 (0 when empty), by a radix select
/// over the bits of the values (three digits from the top): for floats >= 0 the order of the bits
/// is the order of the values. nth_element itself when any is negative or NaN. May reorder
/// `values`; `bits` is room kept by the caller.
float upperMedian(std::vector<float>& values, std::vector<std::uint32_t>& bits);

/// How far the slits moved across themselves on the floor since the previous frame, at each place:
/// the moves of the points seen in both frames along the direction from the first slit to the
/// last, fitted by an affine function of the place (a rigid move of the robot over the floor
/// moves the slits so: alike everywhere when walking, in proportion to the distance from the
/// turning axis when turning), far outliers left out. A point of the RDMap is one reference point,
/// so the same index is the same slit point. Standing does not move the slits.
class SlitSweep {
 public:
  /// Starts a frame of `size` points.
  void begin(std::size_t size);
  /// A floor point of the frame: its index, slit and world x, y [m].
  void add(std::size_t index, int slit, const Eigen::Vector2d& world);
  /// The move since the previous frame at world x, y [m per m] (zero without a previous frame, or
  /// when it is nowhere in the view larger than `dead_zone` [m]); this frame becomes the previous.
  SweepStep finish(double dead_zone);

 private:
  struct Seen {
    float x = 0.0f, y = 0.0f;
    std::uint32_t frame = 0;  ///< the frame it was seen in (0: never)
  };
  std::vector<Seen> seen_;
  std::uint32_t frame_ = 0;
  int first_slit_ = 0, last_slit_ = 0;
  Eigen::Vector2d first_sum_ = Eigen::Vector2d::Zero(), last_sum_ = Eigen::Vector2d::Zero();
  std::size_t first_count_ = 0, last_count_ = 0;
  std::vector<std::uint32_t> now_;  ///< indices seen this frame
  std::vector<Eigen::Vector2f> now_xy_;
  std::vector<float> moves_;
  std::vector<Eigen::Vector2f> moved_at_;     ///< where each of moves_ was measured
  std::vector<float> residuals_;              ///< of moves_ from the first fit
  std::vector<std::uint32_t> residual_bits_;  ///< room for their median
};

}  // namespace multislit::detail
