// The behaviour of the paper's walking experiment (Sec. V), driven by footsteps: walk straight
// while the next footsteps are free; turn in place until they are free when an obstacle blocks
// them further ahead; stop for 5 s when an obstacle appears suddenly very near.
#pragma once

#include "multislit/footsteps.h"
#include "multislit/obstacles.h"
#include "multislit/occupancy_map.h"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace multislit {

/// What the robot does during one frame.
enum class Command { Walk, Turn, Stop };
const char* commandName(Command command);

struct WalkerConfig {
  /// Footsteps checked ahead. The sensor sees the floor from 0.09 to 0.40 m ahead of the feet'
  /// midpoint; 6 steps of 40 mm plus the sole reach 0.33 m, so the robot decides with an obstacle
  /// still about 0.3 m ahead, after the slits have swept it a few times.
  int lookahead_steps = 6;  ///< [-]
  /// Footsteps checked when choosing the side of a turn: the whole view (12 steps, 0.55 m), so the
  /// side on which the known obstacle ends sooner wins, not the one that frees the next steps.
  int turn_lookahead_steps = 12;  ///< [-]
  double margin = 0.015;          ///< clearance around each sole [m]
  double min_height = 0.0;        ///< voxels from this height (the floor layer included) ... [m]
  double max_height = 0.25;       ///< ... to this one block a foot (the robot's knee) [m]
  int stop_frames = 150;          ///< a stop lasts 5 s at 30 Hz [frames]
  /// "Very near": an obstacle first seen at most this far from the feet (2 steps), in front of
  /// them within the soles' width plus `margin`, makes the robot stop.
  double near_distance = 0.08;  ///< [m]
  /// An obstacle is known (not sudden) when the map held occupied voxels this close to it before
  /// the frame.
  double known_margin = 0.03;  ///< [m]
  /// Only an obstacle with sudden_min_points points on its surface (Obstacle::surface) this high
  /// above the floor stops the robot: higher than the lobes a floor's texture makes in one frame
  /// (docs/walk.md), ...
  double sudden_min_height = 0.025;  ///< [m]
  /// ... and more of them than a stray run holds [-]
  int sudden_min_points = 10;
  /// ... seen in this many consecutive frames (a lobe lasts one or two), in places that overlap
  /// within known_margin.
  int sudden_frames = 2;    ///< [-]
  double max_turn = 180.0;  ///< widest turn considered when choosing a side [deg]
  bool prefer_left = true;  ///< side taken when both are as good (the paper turned left)

  void validate() const;  ///< throws std::invalid_argument naming the field
};

enum class Reason {
  PathClear,       ///< the next footsteps are free: walk
  PathBlocked,     ///< a footstep ahead touches an occupied voxel: turn
  SuddenObstacle,  ///< an obstacle appeared very near: stop (and stay stopped stop_frames)
  NoFloor          ///< the frame showed no floor: stop (fail safe, nothing is guessed)
};
const char* reasonName(Reason reason);

/// What the frame showed the walker, besides the map.
struct WalkerObservation {
  bool floor_found = false;
  std::optional<Obstacle> sudden;  ///< an obstacle that appeared very near (Walker::findSudden)
};

/// The walker's decision for one frame.
struct WalkerResult {
  Command command = Command::Stop;
  Reason reason = Reason::NoFloor;
  int turn_direction = 0;            ///< +1 left, -1 right (Turn only)
  int stop_frames_left = 0;          ///< frames of the stop still to come after this one
  std::optional<Obstacle> obstacle;  ///< the sudden obstacle (robot frame of its frame)
  std::vector<Footstep> planned;     ///< the footsteps checked
  FootstepCheck check;               ///< which one is blocked, by which voxels
};

class Walker {
 public:
  /// A box on the floor, in the world [m].
  struct Box {
    Eigen::Vector2d lo, hi;
  };

  Walker(const WalkerConfig& config, const FootConfig& foot);  ///< validates both

  const WalkerConfig& config() const { return config_; }

  /// The nearest obstacle of this frame that appeared suddenly very near the feet of the body at
  /// `body`: near, in front of the soles, tall on its surface (sudden_min_height), unknown to the
  /// map before it learns this frame, and seen so in sudden_frames consecutive frames (call once a
  /// frame: it remembers the frame's candidates).
  std::optional<Obstacle> findSudden(const ObstacleResult& obstacles, const OccupancyMap& map,
                                     const Pose2D& body);

  /// The command for the body at `body`, whose `next_foot` swings next, given the map (which has
  /// learnt this frame) and what the frame showed.
  WalkerResult step(const OccupancyMap& map, const Pose2D& body, Foot next_foot,
                    const WalkerObservation& seen);

 private:
  FootstepCheck checkAhead(const OccupancyMap& map, const Pose2D& body, Foot next_foot, int steps,
                           std::vector<Footstep>* planned = nullptr) const;
  int chooseTurn(const OccupancyMap& map, const Pose2D& body, Foot next_foot) const;

  /// A candidate sudden obstacle of the last frame: its box on the floor (world) and the frames in
  /// a row it was seen.
  struct Candidate {
    Box box;
    int frames = 0;
  };

  WalkerConfig config_;
  FootConfig foot_;
  std::vector<Candidate> candidates_;
  std::vector<Box> lines_before_;  ///< the last frame's lines below the floor (findSudden)
  int stop_left_ = 0;              ///< frames of the current stop still to come
  int turning_ = 0;                ///< side of the turn under way, 0 when not turning
};

}  // namespace multislit
