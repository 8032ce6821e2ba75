// Evidence judged over the sweep of the slits, not frame by frame. As the robot walks, each slit
// sweeps across the floor. Where a stripe crosses a dark line (grout, a board gap, carpet fibres),
// the line darkens one side of the stripe and then the other: a short lobe below the floor and one
// above, each lasting about a stripe width of travel. An object on the floor lifts every frame of
// the slit's crossing, on one side only, and again on the next slit. So a place (a column of map
// voxels) counts as occupied only when its evidence is one-signed over more travel than a lobe, in
// several frames; as a hole when the same holds below the floor. Evidence from a view that has not
// moved (standing, turning in place) adds nothing new, except for an object taller than any lobe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace multislit {

/// The rule, in travel of the slits across themselves (the sweep) and frames. With the paper's
/// gait (50 mm/s at 30 Hz) one frame is 1.7 mm of sweep.
struct SweepEvidenceConfig {
  /// A frame is new evidence at a place only when the slits moved this far across it since the
  /// place's last counted frame: standing or turning in place repeats the same view.
  double min_step = 0.0005;  ///< [m]
  /// Frame-to-frame moves of the slits smaller than this are taken as no move (noise) [m].
  double dead_zone = 0.0002;  ///< [m]
  /// A pass of a slit over a place ends when the slits moved this far with no evidence there.
  double pass_gap = 0.006;  ///< [m]
  /// Consecutive frames of one sign in a pass that occupy a place (noise comes and goes) [-]
  int min_frames = 3;
  /// Sweep between the first and last of them: more than a texture lobe lasts.
  double min_sweep = 0.003;  ///< [m]
  /// One-signed: frames with evidence of the other sign at most this share of them [-].
  double max_opposite_share = 0.25;
  /// Higher than texture lobes mostly reach: occupied after tall_frames consecutive frames of a
  /// moving view (a ball thrown in front of a walking robot), and kept while it is seen so.
  double tall_height = 0.025;  ///< [m]
  int tall_points = 3;  ///< ... of at least this many tall points in the column in a frame [-]
  int tall_frames = 2;  ///< [-]
  /// ... and not within this many columns of a column that held tall_points points of an
  /// obstacle group below the floor, in this frame or the last: a dark line along the slits pulls
  /// the stripes beside it below the floor and above it, on neighbouring slits and in
  /// neighbouring frames, as high as an object; an object lifts its slits only [columns]. 0: no
  /// such rule.
  int line_radius = 3;
  /// Consistent passes in a row, i.e. slits one after the other, that occupy a place [-]
  int min_passes = 2;
  /// ... unless a place within this many columns holds the other lobe of a dark line, which pulls
  /// the stripe above the floor on one side of it and below on the other, where an object lifts
  /// it on one side only and a hole sinks it: beside an object, consistent evidence below the
  /// floor; beside a hole, any evidence above it [columns]. 0: no such rule.
  int lobe_radius = 2;
  /// Passes in a row with only weak evidence (below the obstacle threshold), above the floor and
  /// never below, that occupy a place (a screw a few mm high) [-]
  int weak_passes = 6;
  /// Evidence the slits have left this far behind is forgotten (memory stays flat).
  double forget_sweep = 0.15;  ///< [m]
  bool record_passes = false;  ///< keep every ended pass for takePasses() (measurement)

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// One point of evidence of one frame: the map column it falls in and its side of the floor.
struct SweepPoint {
  std::int32_t x = 0, y = 0;  ///< the column: floor cell indices [cells]
  float height = 0.0f;        ///< above the floor (< 0: below) [m]
  bool above = true;          ///< above the floor (the residual's sign)
  bool strong = true;         ///< in an obstacle group (false: weak evidence)
  /// Of an obstacle group, and higher than texture lobes mostly reach
  /// (SweepEvidenceConfig::tall_height): a ball, a box.
  bool tall = false;
};

/// How far the slits moved across themselves since the previous frame, at each column: walking
/// moves them alike everywhere; turning in place moves them along their own length in front of
/// the robot and across themselves to its sides. The move at column (x, y) is
/// offset + per_x * x + per_y * y [m], columns in cells.
struct SweepStep {
  double offset = 0.0;  ///< [m]
  double per_x = 0.0;   ///< [m per cell]
  double per_y = 0.0;   ///< [m per cell]
  double middle = 0.0;  ///< the move at the middle of the view [m]
  double at(double x, double y) const { return offset + per_x * x + per_y * y; }
};

/// What the sweep says of a column this frame.
enum class SweepVerdict : std::uint8_t {
  Pending,  ///< evidence not (yet) consistent: the place stays unknown
  Above,    ///< an object: one-signed above over the sweep, or taller than any lobe
  Below     ///< a hole or a step down: one-signed below over the sweep
};

/// One pass of the slits over a place, as measured (SweepEvidenceConfig::record_passes).
struct SweepPass {
  std::int32_t x = 0, y = 0;  ///< the column [cells]
  int above_frames = 0;       ///< counted frames with evidence above the floor [-]
  int below_frames = 0;       ///< and below [-]
  int above_run = 0;          ///< the longest run of consecutive frames above [-]
  int below_run = 0;          ///< and below [-]
  double above_sweep = 0.0;   ///< sweep covered by the longest run above [m]
  double below_sweep = 0.0;   ///< and below [m]
  double max_height = 0.0;    ///< highest strong point above the floor [m]
  bool strong = false;        ///< held points of obstacle groups
  SweepVerdict verdict = SweepVerdict::Pending;  ///< what the place was judged at its end
};

/// The evidence of every place over the sweep. Not thread-safe.
class SweepEvidence {
 public:
  explicit SweepEvidence(const SweepEvidenceConfig& config = {});  ///< validates
  SweepEvidence(SweepEvidence&&) noexcept;
  SweepEvidence& operator=(SweepEvidence&&) noexcept;
  ~SweepEvidence();

  const SweepEvidenceConfig& config() const { return config_; }

  /// Starts a frame whose slits moved `step` across themselves since the previous frame [m],
  /// alike at every column.
  void beginFrame(double step);
  /// Starts a frame whose slits moved `step` across themselves, per column.
  void beginFrame(const SweepStep& step);
  /// Judges the frame's evidence; the verdict of each point's column is then verdictAt().
  void addEvidence(const std::vector<SweepPoint>& points);
  SweepVerdict verdictAt(std::int32_t x, std::int32_t y) const;

  /// The slits' travel so far at the middle of the view (the frames' `SweepStep::middle`) [m].
  double sweep() const { return sweep_; }
  /// The slits' travel so far across column (x, y) [m].
  double sweepAt(std::int32_t x, std::int32_t y) const { return total_.at(x, y); }
  std::size_t places() const;  ///< places holding evidence [-]
  /// Forgets the places farther than `half_size` cells from (x, y) along either axis.
  void crop(std::int32_t x, std::int32_t y, std::int32_t half_size);
  std::vector<SweepPass> takePasses();  ///< the passes ended since the last call

 private:
  struct State;  ///< the places and their passes (defined in the implementation)

  SweepEvidenceConfig config_;
  std::unique_ptr<State> state_;
  double sweep_ = 0.0;
  SweepStep total_;  ///< the sum of the frames' steps
  std::uint64_t frame_ = 0;
};

}  // namespace multislit
