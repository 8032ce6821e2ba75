// The floor's albedo texture (FloorConfig): wood grain, tiles with grout or carpet fibres, as
// value noise on integer lattices.
#pragma once

#include "multislit/sim/scene.h"

#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>
#include <vector>

namespace multislit {

/// The floor's reflectance at world points. The lattice hashes over `region` (the floor a frame
/// sees) are tabulated when it is made, so a point there costs a few multiplications per octave;
/// a point elsewhere hashes its cell's corners. Immutable: share it between threads.
class FloorAlbedo {
 public:
  /// At most this many lattice points are tabulated per octave; a larger region is hashed.
  static constexpr std::size_t kMaxTable = std::size_t{1} << 22;

  explicit FloorAlbedo(const FloorConfig& floor,
                       const Eigen::AlignedBox2d& region = Eigen::AlignedBox2d());
  /// at() of the n points (x[i], y[i]) into out[i] (to rounding), a row of pixels at a time:
  /// where the row lies in the tables, in vector instructions.
  void row(const double* x, const double* y, double* out, int n) const {
    row(x, y, boxOf(x, y, n), out, n);
  }
  /// A box around points [m]; finite false when a coordinate may be NaN or infinite.
  struct RowBox {
    double lo_x = 0, hi_x = 0, lo_y = 0, hi_y = 0;
    bool finite = true;
  };
  /// The smallest box around the n points (x[i], y[i]).
  static RowBox boxOf(const double* x, const double* y, int n);
  /// row() given a box around the points: the tables serve the row when the box lies a cell
  /// inside them (the margin takes the box's rounding), else every point is hashed.
  void row(const double* x, const double* y, const RowBox& box, double* out, int n) const;
  /// Reflectance at 660 nm of the floor at world (x, y) [m], in [0, 1].
  double at(double x, double y) const {
    if (floor_.texture == FloorTexture::Tiles) return clamp01(tileAlbedo(x, y));
    double g = 0;
    for (int k = 0; k < count_; ++k) g += octaves_[k].weight * octaves_[k].noise(x, y);
    return clamp01(floor_.albedo * (1.0 + floor_.texture_amplitude * g));
  }

 private:
  /// One octave of value noise: lattice cells of 1 / scale_x by 1 / scale_y metres; in [-1, 1].
  struct Octave {
    double scale_x = 1, scale_y = 1, weight = 0;
    uint64_t seed = 0;
    int64_t x0 = 0, y0 = 0, columns = 1, rows = 1;  // the tabulated lattice points (1: none)
    std::vector<double> table;                      // hash01 of each, row-major

    double noise(double x, double y) const {
      x *= scale_x;
      y *= scale_y;
      const double fx = floorOf(x), fy = floorOf(y);
      const int64_t cx = latticeCell(fx), cy = latticeCell(fy);
      double a, b, c, d;  // the hashes at the cell's corners
      if (static_cast<uint64_t>(cx - x0) < static_cast<uint64_t>(columns - 1) &&
          static_cast<uint64_t>(cy - y0) < static_cast<uint64_t>(rows - 1)) {
        const double* p = &table[static_cast<std::size_t>((cy - y0) * columns + (cx - x0))];
        a = p[0];
        b = p[1];
        c = p[columns];
        d = p[columns + 1];
      } else {
        corners(cx, cy, a, b, c, d);
      }
      const double tx = x - fx, ty = y - fy;
      const double sx = tx * tx * (3 - 2 * tx), sy = ty * ty * (3 - 2 * ty);
      const double ab = a + (b - a) * sx, cd = c + (d - c) * sx;
      return 2.0 * (ab + (cd - ab) * sy) - 1.0;
    }
    void corners(int64_t cx, int64_t cy, double& a, double& b, double& c, double& d) const;
    void tabulate(const Eigen::AlignedBox2d& region);
    /// Adds weight x noise() at the n points inside `box` to g[i]; false (nothing added) when
    /// the box is not inside the table.
    bool addRow(const double* x, const double* y, const RowBox& box, double* g, int n) const;
  };
  double tileAlbedo(double x, double y) const;
  static double clamp01(double v) { return v < 0 ? 0 : v > 1 ? 1 : v; }
  /// std::floor without a call into libm (x86-64 before SSE4.1 has no rounding instruction).
  static double floorOf(double x) {
    if (!(std::abs(x) < 0x1p52)) return std::floor(x);
    const double t = static_cast<double>(static_cast<int64_t>(x));
    return t > x ? t - 1 : t;
  }
  /// The lattice cell of a floored coordinate, wrapped modulo 2^62: any finite coordinate (a
  /// floor point near the horizon, a texture of 1e-20 m: fuzz/fuzz_scene) converts to an integer
  /// without overflow, which is undefined; the pattern repeats after 2^62 cells. Not finite: 0.
  static int64_t latticeCell(double floored) {
    if (std::abs(floored) < 0x1p62) return static_cast<int64_t>(floored);
    return std::isfinite(floored) ? static_cast<int64_t>(std::fmod(floored, 0x1p62)) : 0;
  }

  FloorConfig floor_;
  Octave octaves_[3];
  int count_ = 0;                     // octaves in use
  double tile_x0_ = 0, tile_y0_ = 0;  // the tile grid's shift [tiles]
};

}  // namespace multislit
