#include "multislit/sweep_evidence.h"

#include "config_check.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
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
  require(tall_frames >= 1 && tall_frames <= 1000, "tall_frames", "must be in [1, 1000]");
  require(min_passes >= 1 && min_passes <= 1000, "min_passes", "must be in [1, 1000]");
  require(weak_passes >= 1 && weak_passes <= 1000, "weak_passes", "must be in [1, 1000]");
  require(std::isfinite(forget_sweep) && forget_sweep > pass_gap && forget_sweep <= 100,
          "forget_sweep", "must be in (pass_gap, 100] m");
  require(neighbourhood >= 0 && neighbourhood <= 5, "neighbourhood", "must be in [0, 5] cells");
}

struct SweepEvidence::State {
  /// The sweeps at which one sign was seen in the counted frames of a pass.
  struct SignRange {
    int frames = 0;                ///< counted frames of the pass with this sign
    int run = 0;                   ///< of them in consecutive frames, up to the last one
    std::uint64_t last_frame = 0;  ///< the last one
    double run_first = 0.0;        ///< sweep at the first frame of the run [m]
    int best = 0;                  ///< the longest run
    double best_extent = 0.0;      ///< the sweep it covered [m]
    void add(double sweep, std::uint64_t frame) {
      run = frames > 0 && last_frame + 1 == frame ? run + 1 : 1;
      if (run == 1) run_first = sweep;
      last_frame = frame;
      ++frames;
      const double extent = std::abs(sweep - run_first);
      if (run > best || (run == best && extent > best_extent)) {
        best = run;
        best_extent = extent;
      }
    }
  };

  /// What one frame shows around a column (its neighbourhood).
  struct FrameFlags {
    bool above = false, below = false;  ///< any evidence of the sign
    bool strong = false;                ///< any point of an obstacle group
    bool tall = false;                  ///< a tall point
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
  std::unordered_map<std::uint64_t, FrameFlags> own;    ///< this frame, per point column
  std::unordered_map<std::uint64_t, FrameFlags> frame;  ///< this frame, per neighbourhood
  std::vector<SweepPass> passes;
};

SweepEvidence::SweepEvidence(const SweepEvidenceConfig& config)
    : config_(config), state_(std::make_unique<State>()) {
  config_.validate();
}

SweepEvidence::SweepEvidence(SweepEvidence&&) noexcept = default;
SweepEvidence& SweepEvidence::operator=(SweepEvidence&&) noexcept = default;
SweepEvidence::~SweepEvidence() = default;

std::size_t SweepEvidence::places() const { return state_->places.size(); }

void SweepEvidence::beginFrame(double step) {
  ++frame_;
  if (std::isfinite(step) && std::abs(step) > config_.dead_zone) sweep_ += step;
  // Evidence the slits have left far behind: forgotten.
  if (frame_ % 30 != 0) return;
  for (auto it = state_->places.begin(); it != state_->places.end();) {
    if (std::abs(sweep_ - it->second.last) > config_.forget_sweep)
      it = state_->places.erase(it);
    else
      ++it;
  }
}

namespace {

using SignRange = SweepEvidence::State::SignRange;
using FrameFlags = SweepEvidence::State::FrameFlags;

bool oneSigned(const SignRange& sign, const SignRange& other, double share) {
  return sign.frames > 0 && other.frames <= share * sign.frames;
}

}  // namespace

void SweepEvidence::addEvidence(const std::vector<SweepPoint>& points) {
  State& s = *state_;
  s.own.clear();
  s.frame.clear();
  for (const SweepPoint& p : points) {
    FrameFlags& f = s.own[packColumn(p.x, p.y)];
    f.above = f.above || p.above;
    f.below = f.below || !p.above;
    if (!p.strong) continue;
    f.strong = true;
    if (p.above) f.max_height = std::max(f.max_height, p.height);
    f.tall = f.tall || (p.above && p.tall);
  }
  const int n = config_.neighbourhood;
  for (const auto& [key, f] : s.own)
    for (int dx = -n; dx <= n; ++dx)
      for (int dy = -n; dy <= n; ++dy) {
        FrameFlags& g = s.frame[packColumn(columnX(key) + dx, columnY(key) + dy)];
        g.above = g.above || f.above;
        g.below = g.below || f.below;
        g.strong = g.strong || f.strong;
        g.tall = g.tall || f.tall;
        g.max_height = std::max(g.max_height, f.max_height);
      }
  const SweepEvidenceConfig& c = config_;
  for (const auto& [key, f] : s.frame) {
    State::Place& p = s.places[key];
    // A pass is consistent when one sign lasts min_frames consecutive frames over min_sweep,
    // with little of the other sign.
    const auto swept = [&](const SignRange& sign, const SignRange& other) {
      return sign.best >= c.min_frames && sign.best_extent >= c.min_sweep &&
             oneSigned(sign, other, c.max_opposite_share);
    };
    if (p.in_pass && std::abs(sweep_ - p.last) > c.pass_gap) {
      if (c.record_passes)
        s.passes.push_back(SweepPass{columnX(key), columnY(key), p.above.frames, p.below.frames,
                                     p.above.best, p.below.best, p.above.best_extent,
                                     p.below.best_extent, p.max_height, p.strong, p.verdict});
      // Consistent passes in a row: one slit after the other found the same.
      p.above_passes = swept(p.above, p.below) ? p.above_passes + 1 : 0;
      p.below_passes = swept(p.below, p.above) ? p.below_passes + 1 : 0;
      // Weak evidence alone, above and never below, slit after slit (a screw under the threshold).
      p.weak_passes =
          !p.strong && p.above.frames > 0 && p.below.frames == 0 ? p.weak_passes + 1 : 0;
      p.in_pass = false;
    }
    if (!p.in_pass) {
      p.above = p.below = SignRange{};
      p.strong = false;
      p.max_height = 0.0f;
      p.in_pass = true;
      p.counted = std::numeric_limits<double>::quiet_NaN();
    }
    // Only a view that moved is new evidence: standing or turning repeats the same lobes.
    if (!f.tall) {
      p.tall_run = 0;
    } else if (!(std::abs(sweep_ - p.counted) < c.min_step)) {  // tall, in a view that moved
      p.tall_run = p.tall_run > 0 && p.tall_frame + 1 == frame_ ? p.tall_run + 1 : 1;
      p.tall_frame = frame_;
    }
    if (!(std::abs(sweep_ - p.counted) < c.min_step)) {
      if (f.above) p.above.add(sweep_, frame_);
      if (f.below) p.below.add(sweep_, frame_);
      p.counted = sweep_;
    }
    p.last = sweep_;
    p.strong = p.strong || f.strong;
    p.max_height = std::max(p.max_height, f.max_height);

    // The verdict, from this pass and the passes before it.
    if (p.tall_run >= c.tall_frames || p.above_passes + swept(p.above, p.below) >= c.min_passes ||
        (p.weak_passes >= c.weak_passes && !onWeakLine(key)))
      p.verdict = SweepVerdict::Above;
    else if (p.below_passes + swept(p.below, p.above) >= c.min_passes)
      p.verdict = SweepVerdict::Below;
    else
      p.verdict = SweepVerdict::Pending;
  }
}

bool SweepEvidence::onWeakLine(std::uint64_t key) const {
  // A line of weak evidence (a grout line, a board gap) holds the neighbours on both sides along
  // x or along y; a screw a few mm across holds one or two cells.
  const auto weak = [&](int dx, int dy) {
    const auto it = state_->places.find(packColumn(columnX(key) + dx, columnY(key) + dy));
    return it != state_->places.end() && 2 * it->second.weak_passes >= config_.weak_passes;
  };
  return (weak(-1, 0) && weak(1, 0)) || (weak(0, -1) && weak(0, 1));
}

SweepVerdict SweepEvidence::verdictAt(std::int32_t x, std::int32_t y) const {
  const auto it = state_->places.find(packColumn(x, y));
  return it == state_->places.end() ? SweepVerdict::Pending : it->second.verdict;
}

void SweepEvidence::crop(std::int32_t x, std::int32_t y, std::int32_t half_size) {
  for (auto it = state_->places.begin(); it != state_->places.end();) {
    if (std::abs(columnX(it->first) - x) > half_size ||
        std::abs(columnY(it->first) - y) > half_size)
      it = state_->places.erase(it);
    else
      ++it;
  }
}

std::vector<SweepPass> SweepEvidence::takePasses() { return std::exchange(state_->passes, {}); }

}  // namespace multislit
