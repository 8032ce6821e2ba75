#include "multislit/sweep_evidence.h"

#include "config_check.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <unordered_map>
#include <unordered_set>
#include <utility>

namespace multislit {

namespace {

std::uint64_t packColumn(std::int32_t x, std::int32_t y) {
  return std::uint64_t{static_cast<std::uint32_t>(x)} << 32 | static_cast<std::uint32_t>(y);
}

std::int32_t columnX(std::uint64_t key) { return static_cast<std::int32_t>(key >> 32); }
std::int32_t columnY(std::uint64_t key) { return static_cast<std::int32_t>(key & 0xffffffffu); }

}  // namespace

void SweepEvidenceConfig::validate() const {
  constexpr detail::FieldCheck require("SweepEvidenceConfig");
  require(std::isfinite(min_step) && min_step >= 0 && min_step <= 0.05, "min_step",
          "must be in [0, 0.05] m");
  require(std::isfinite(dead_zone) && dead_zone >= 0 && dead_zone <= 0.01, "dead_zone",
          "must be in [0, 0.01] m");
  require(std::isfinite(pass_gap) && pass_gap > 0 && pass_gap <= 0.5, "pass_gap",
          "must be in (0, 0.5] m");
  require(min_frames >= 1 && min_frames <= 1000, "min_frames", "must be in [1, 1000]");
  require(std::isfinite(min_sweep) && min_sweep >= 0 && min_sweep <= 0.5, "min_sweep",
          "must be in [0, 0.5] m");
  require(std::isfinite(max_opposite_share) && max_opposite_share >= 0 && max_opposite_share <= 1,
          "max_opposite_share", "must be in [0, 1]");
  require(std::isfinite(tall_height) && tall_height > 0 && tall_height <= 1, "tall_height",
          "must be in (0, 1] m");
  require(tall_points >= 1 && tall_points <= 100000, "tall_points", "must be in [1, 100000]");
  require(tall_frames >= 1 && tall_frames <= 1000, "tall_frames", "must be in [1, 1000]");
  require(min_passes >= 1 && min_passes <= 1000, "min_passes", "must be in [1, 1000]");
  require(weak_passes >= 1 && weak_passes <= 1000, "weak_passes", "must be in [1, 1000]");
  require(line_radius >= 0 && line_radius <= 100, "line_radius", "must be in [0, 100] columns");
  require(lobe_radius >= 0 && lobe_radius <= 100, "lobe_radius", "must be in [0, 100] columns");
  require(std::isfinite(forget_sweep) && forget_sweep > pass_gap && forget_sweep <= 100,
          "forget_sweep", "must be in (pass_gap, 100] m");
}

struct SweepEvidence::State {
  /// The counted frames of a pass with one sign, and the longest run of consecutive ones.
  struct SignRange {
    int frames = 0;                ///< counted frames of the pass with this sign
    int run = 0;                   ///< of them in consecutive frames, up to the last one
    std::uint64_t last_frame = 0;  ///< the last one
    double run_first = 0.0;        ///< sweep at the first frame of the run [m]
    int best = 0;                  ///< the longest run
    double best_extent = 0.0;      ///< the sweep it covered [m]
    void add(double sweep, std::uint64_t at_frame) {
      run = frames > 0 && last_frame + 1 == at_frame ? run + 1 : 1;
      if (run == 1) run_first = sweep;
      last_frame = at_frame;
      ++frames;
      const double extent = std::abs(sweep - run_first);
      if (run > best || (run == best && extent > best_extent)) {
        best = run;
        best_extent = extent;
      }
    }
    /// Seen, and the other sign in at most `share` of as many frames.
    bool oneSigned(const SignRange& other, double share) const {
      return frames > 0 && other.frames <= share * frames;
    }
  };

  /// What one frame shows in a column.
  struct FrameFlags {
    bool above = false, below = false;  ///< any evidence of the sign
    bool strong = false;                ///< any point of an obstacle group
    int tall = 0;                       ///< tall points
    int sunk = 0;                       ///< strong points below the floor
    float max_height = 0.0f;            ///< of the strong points [m]
  };

  /// One place: the pass of the slits over it under way, and what earlier passes left.
  struct Place {
    SignRange above, below;  ///< counted frames of the pass under way
    double last = 0.0;       ///< sweep at the last evidence [m]
    double counted = 0.0;    ///< sweep at the last counted frame [m]
    bool in_pass = false;
    bool strong = false;           ///< the pass held strong evidence
    float max_height = 0.0f;       ///< [m]
    int tall_run = 0;              ///< consecutive frames with tall evidence, up to now
    std::uint64_t tall_frame = 0;  ///< the last of them
    int above_passes = 0;          ///< ended consistent passes above, in a row
    int below_passes = 0;          ///< and below
    int weak_passes = 0;           ///< ended passes of weak evidence above only, in a row
    SweepVerdict verdict = SweepVerdict::Pending;  ///< judged this frame or last
  };

  std::unordered_map<std::uint64_t, Place> places;
  std::unordered_map<std::uint64_t, FrameFlags> frame;  ///< this frame, per column
  /// Columns with tall_points strong points below the floor, this frame and the last.
  std::unordered_set<std::uint64_t> sunk, sunk_before;
  std::vector<SweepPass> passes;

  /// A pass is consistent when one sign lasts min_frames consecutive frames over min_sweep, with
  /// little of the other sign.
  static bool consistent(const SignRange& sign, const SignRange& other,
                         const SweepEvidenceConfig& c) {
    return sign.best >= c.min_frames && sign.best_extent >= c.min_sweep &&
           sign.oneSigned(other, c.max_opposite_share);
  }
  void endPass(std::uint64_t key, Place& place, const SweepEvidenceConfig& c);
  /// The frame's evidence into the pass under way, at `sweep` in frame `frame`.
  static void update(Place& place, const FrameFlags& flags, const SweepEvidenceConfig& c,
                     double sweep, std::uint64_t frame);
  SweepVerdict judge(std::uint64_t key, const Place& place, const SweepEvidenceConfig& c) const;
  /// The place (dx, dy) columns from `key`; nullptr when it holds no evidence.
  const Place* neighbour(std::uint64_t key, int dx, int dy) const {
    const auto it = places.find(packColumn(columnX(key) + dx, columnY(key) + dy));
    return it == places.end() ? nullptr : &it->second;
  }
  /// Weak passes above the floor, or evidence above it in the pass under way.
  static bool weakOrUnderWayAbove(const Place& p) {
    return p.weak_passes > 0 || (p.in_pass && p.above.frames > 0);
  }
  /// Whether a place within lobe_radius of `key` holds a dark line's other lobe: evidence above
  /// the floor beside a hole (`above`), consistent evidence below it beside an object.
  bool nearOtherLobe(std::uint64_t key, bool above, const SweepEvidenceConfig& c) const;
  /// Whether a column within `radius` of `key` was sunk this frame or the last.
  bool nearSunk(std::uint64_t key, int radius) const;
  /// Tall evidence beside strong evidence below the floor is dropped (a dark line's lobes).
  void dropBesideLines(const SweepEvidenceConfig& c);
  /// A line of weak evidence (a grout line, a board gap) gives the neighbours on both sides along
  /// x or along y weak passes too; a screw a few mm across lies in one or two cells.
  bool onWeakLine(std::uint64_t key) const;

  template <typename Drop>
  void forget(Drop drop) {
    for (auto it = places.begin(); it != places.end();)
      it = drop(*it) ? places.erase(it) : std::next(it);
  }
};

namespace {

/// Frames between two sweeps of the places for those left far behind.
constexpr std::uint64_t kForgetInterval = 30;

}  // namespace

SweepEvidence::SweepEvidence(const SweepEvidenceConfig& config)
    : config_(config), state_(std::make_unique<State>()) {
  config_.validate();
}

SweepEvidence::SweepEvidence(SweepEvidence&&) noexcept = default;
SweepEvidence& SweepEvidence::operator=(SweepEvidence&&) noexcept = default;
SweepEvidence::~SweepEvidence() = default;

std::size_t SweepEvidence::places() const { return state_->places.size(); }

void SweepEvidence::beginFrame(double step) {
  SweepStep uniform;
  if (std::abs(step) > config_.dead_zone) uniform.offset = uniform.middle = step;
  beginFrame(uniform);
}

void SweepEvidence::beginFrame(const SweepStep& step) {
  ++frame_;
  const bool finite = std::isfinite(step.offset) && std::isfinite(step.per_x) &&
                      std::isfinite(step.per_y) && std::isfinite(step.middle);
  if (finite) {
    total_.offset += step.offset;
    total_.per_x += step.per_x;
    total_.per_y += step.per_y;
    sweep_ += step.middle;
  }
  if (frame_ % kForgetInterval != 0) return;
  // Evidence the slits have left far behind: forgotten.
  state_->forget([&](const auto& place) {
    return std::abs(sweepAt(columnX(place.first), columnY(place.first)) - place.second.last) >
           config_.forget_sweep;
  });
}

void SweepEvidence::addEvidence(const std::vector<SweepPoint>& points) {
  State& s = *state_;
  s.frame.clear();
  for (const SweepPoint& p : points) {
    State::FrameFlags& f = s.frame[packColumn(p.x, p.y)];
    f.above = f.above || p.above;
    f.below = f.below || !p.above;
    if (!p.strong) continue;
    f.strong = true;
    if (p.above) f.max_height = std::max(f.max_height, p.height);
    f.tall += p.above && p.tall;
    f.sunk += !p.above;
  }
  s.dropBesideLines(config_);
  for (const auto& [key, f] : s.frame) {
    State::Place& place = s.places[key];
    const double sweep = sweepAt(columnX(key), columnY(key));
    if (place.in_pass && std::abs(sweep - place.last) > config_.pass_gap)
      s.endPass(key, place, config_);
    State::update(place, f, config_, sweep, frame_);
    place.verdict = s.judge(key, place, config_);
  }
}

void SweepEvidence::State::endPass(std::uint64_t key, Place& p, const SweepEvidenceConfig& c) {
  if (c.record_passes)
    passes.push_back(SweepPass{columnX(key), columnY(key), p.above.frames, p.below.frames,
                               p.above.best, p.below.best, p.above.best_extent, p.below.best_extent,
                               p.max_height, p.strong, p.verdict});
  // Consistent passes in a row: one slit after the other found the same.
  p.above_passes = consistent(p.above, p.below, c) ? p.above_passes + 1 : 0;
  p.below_passes = consistent(p.below, p.above, c) ? p.below_passes + 1 : 0;
  // Weak evidence alone, above and never below, slit after slit (a screw under the threshold).
  p.weak_passes = !p.strong && p.above.frames > 0 && p.below.frames == 0 ? p.weak_passes + 1 : 0;
  p.in_pass = false;
}

void SweepEvidence::State::update(Place& p, const FrameFlags& f, const SweepEvidenceConfig& c,
                                  double sweep, std::uint64_t frame) {
  if (!p.in_pass) {
    p.above = p.below = SignRange{};
    p.strong = false;
    p.max_height = 0.0f;
    p.in_pass = true;
    p.counted = std::numeric_limits<double>::quiet_NaN();
  }
  // Only a view that moved is new evidence: standing or turning repeats the same lobes.
  const bool moved = !(std::abs(sweep - p.counted) < c.min_step);
  if (f.tall < c.tall_points) {
    p.tall_run = 0;
  } else if (moved) {
    p.tall_run = p.tall_run > 0 && p.tall_frame + 1 == frame ? p.tall_run + 1 : 1;
    p.tall_frame = frame;
  }
  if (moved) {
    if (f.above) p.above.add(sweep, frame);
    if (f.below) p.below.add(sweep, frame);
    p.counted = sweep;
  }
  p.last = sweep;
  p.strong = p.strong || f.strong;
  p.max_height = std::max(p.max_height, f.max_height);
}

SweepVerdict SweepEvidence::State::judge(std::uint64_t key, const Place& p,
                                         const SweepEvidenceConfig& c) const {
  const bool above = p.above_passes + consistent(p.above, p.below, c) >= c.min_passes;
  const bool below = p.below_passes + consistent(p.below, p.above, c) >= c.min_passes;
  if (p.tall_run >= c.tall_frames || (above && !nearOtherLobe(key, false, c)) ||
      (p.weak_passes >= c.weak_passes && !onWeakLine(key)))
    return SweepVerdict::Above;
  if (below && !nearOtherLobe(key, true, c)) return SweepVerdict::Below;
  return SweepVerdict::Pending;
}

bool SweepEvidence::State::nearOtherLobe(std::uint64_t key, bool above,
                                         const SweepEvidenceConfig& c) const {
  const int r = c.lobe_radius;
  for (int dx = -r; dx <= r; ++dx)
    for (int dy = -r; dy <= r; ++dy) {
      const Place* q = neighbour(key, dx, dy);
      if (q == nullptr || (dx == 0 && dy == 0)) continue;
      // Beside a hole, anything above the floor is a line's other lobe; an object is known by
      // consistent evidence below beside it.
      if (above ? q->above_passes > 0 || weakOrUnderWayAbove(*q)
                : q->below_passes > 0 || consistent(q->below, q->above, c))
        return true;
    }
  return false;
}

void SweepEvidence::State::dropBesideLines(const SweepEvidenceConfig& c) {
  sunk_before.swap(sunk);
  sunk.clear();
  for (const auto& [key, f] : frame)
    if (f.sunk >= c.tall_points) sunk.insert(key);
  if (c.line_radius == 0) return;
  // A dark line along the slits lifts the stripe on one side as high as an object and sinks the
  // other: tall evidence beside a line below the floor is the line's other lobe.
  for (auto& [key, f] : frame)
    if (f.tall > 0 && nearSunk(key, c.line_radius)) f.tall = 0;
}

bool SweepEvidence::State::nearSunk(std::uint64_t key, int radius) const {
  for (int dx = -radius; dx <= radius; ++dx)
    for (int dy = -radius; dy <= radius; ++dy) {
      const std::uint64_t near = packColumn(columnX(key) + dx, columnY(key) + dy);
      if (sunk.count(near) != 0 || sunk_before.count(near) != 0) return true;
    }
  return false;
}

bool SweepEvidence::State::onWeakLine(std::uint64_t key) const {
  const auto weak = [&](int dx, int dy) {
    const Place* p = neighbour(key, dx, dy);
    return p != nullptr && weakOrUnderWayAbove(*p);
  };
  // A line at an angle to the map's axes steps over to the next row or column of cells.
  const auto weakAcross = [&](int dx, int dy) {  // (dx, dy) or a cell beside it, across
    const int sx = std::abs(dy), sy = std::abs(dx);
    return weak(dx, dy) || weak(dx + sx, dy + sy) || weak(dx - sx, dy - sy);
  };
  return (weakAcross(-1, 0) && weakAcross(1, 0)) || (weakAcross(0, -1) && weakAcross(0, 1));
}

SweepVerdict SweepEvidence::verdictAt(std::int32_t x, std::int32_t y) const {
  const auto it = state_->places.find(packColumn(x, y));
  return it == state_->places.end() ? SweepVerdict::Pending : it->second.verdict;
}

void SweepEvidence::crop(std::int32_t x, std::int32_t y, std::int32_t half_size) {
  state_->forget([&](const auto& place) {
    return std::abs(columnX(place.first) - x) > half_size ||
           std::abs(columnY(place.first) - y) > half_size;
  });
}

std::vector<SweepPass> SweepEvidence::takePasses() { return std::exchange(state_->passes, {}); }

}  // namespace multislit
