#include "multislit/sim/floor_albedo.h"

#include "avx2_clones.h"

#include <algorithm>
#include <cmath>

namespace multislit {
namespace {

// A hash of a lattice point in [0, 1).
double hash01(int64_t x, int64_t y, uint64_t seed) {
  uint64_t h = seed * 0x9E3779B97F4A7C15ULL ^ static_cast<uint64_t>(x) * 0xBF58476D1CE4E5B9ULL ^
               static_cast<uint64_t>(y) * 0x94D049BB133111EBULL;
  h ^= h >> 31;
  h *= 0xD6E8FEB86659FD93ULL;
  h ^= h >> 32;
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

// weight x the value noise at the n points (x[i] sx - x0, y[i] sy - y0) of the lattice whose
// hashes `table` holds (`columns` a row), added to g[i]: Octave::noise() in a loop without
// branches, which the compiler vectorizes. Every point must lie within the table.
MULTISLIT_AVX2_CLONES void addNoiseRow(const double* __restrict x, const double* __restrict y,
                                       double* __restrict g, int n, const double* __restrict table,
                                       int columns, double sx, double sy, double x0, double y0,
                                       double weight) {
  for (int i = 0; i < n; ++i) {
    const double xs = x[i] * sx - x0, ys = y[i] * sy - y0;
    const int ix = static_cast<int>(xs), iy = static_cast<int>(ys);
    const double tx = xs - ix, ty = ys - iy;
    const int k = iy * columns + ix;
    const double a = table[k], b = table[k + 1], c = table[k + columns], d = table[k + columns + 1];
    const double smooth_x = tx * tx * (3 - 2 * tx), smooth_y = ty * ty * (3 - 2 * ty);
    const double ab = a + (b - a) * smooth_x, cd = c + (d - c) * smooth_x;
    g[i] += weight * (2.0 * (ab + (cd - ab) * smooth_y) - 1.0);
  }
}

}  // namespace

FloorAlbedo::RowBox FloorAlbedo::boxOf(const double* x, const double* y, int n) {
  RowBox box;
  if (n <= 0) return box;
  box.lo_x = box.hi_x = x[0], box.lo_y = box.hi_y = y[0];
  for (int i = 0; i < n; ++i) {
    box.finite &= std::isfinite(x[i]) && std::isfinite(y[i]);
    box.lo_x = std::min(box.lo_x, x[i]), box.hi_x = std::max(box.hi_x, x[i]);
    box.lo_y = std::min(box.lo_y, y[i]), box.hi_y = std::max(box.hi_y, y[i]);
  }
  return box;
}

bool FloorAlbedo::Octave::addRow(const double* x, const double* y, const RowBox& box, double* g,
                                 int n) const {
  if (table.empty() || columns > (1 << 20) || !box.finite) return false;
  const double x_hi = static_cast<double>(columns - 1), y_hi = static_cast<double>(rows - 1);
  const double ox = static_cast<double>(x0), oy = static_cast<double>(y0);
  // A cell of margin: a box made of a row's ends may miss a point by rounding.
  const double lo_x = box.lo_x * scale_x - ox, hi_x = box.hi_x * scale_x - ox;
  const double lo_y = box.lo_y * scale_y - oy, hi_y = box.hi_y * scale_y - oy;
  if (!(lo_x >= 1 && hi_x < x_hi - 1 && lo_y >= 1 && hi_y < y_hi - 1)) return false;
  addNoiseRow(x, y, g, n, table.data(), static_cast<int>(columns), scale_x, scale_y, ox, oy,
              weight);
  return true;
}

void FloorAlbedo::row(const double* x, const double* y, const RowBox& box, double* out,
                      int n) const {
  bool tabulated = floor_.texture != FloorTexture::Tiles;
  if (tabulated) {
    std::fill(out, out + n, 0.0);
    for (int k = 0; k < count_ && tabulated; ++k) tabulated = octaves_[k].addRow(x, y, box, out, n);
  }
  if (!tabulated) {
    for (int i = 0; i < n; ++i) out[i] = at(x[i], y[i]);
    return;
  }
  for (int i = 0; i < n; ++i)
    out[i] = clamp01(floor_.albedo * (1.0 + floor_.texture_amplitude * out[i]));
}

void FloorAlbedo::Octave::corners(int64_t cx, int64_t cy, double& a, double& b, double& c,
                                  double& d) const {
  a = hash01(cx, cy, seed);
  b = hash01(cx + 1, cy, seed);
  c = hash01(cx, cy + 1, seed);
  d = hash01(cx + 1, cy + 1, seed);
}

void FloorAlbedo::Octave::tabulate(const Eigen::AlignedBox2d& region) {
  if (region.isEmpty() || !region.min().allFinite() || !region.max().allFinite()) return;
  // A cell more on every side: row() wants a cell of margin around its points.
  const double lo_x = floorOf(region.min().x() * scale_x) - 1,
               lo_y = floorOf(region.min().y() * scale_y) - 1;
  const double hi_x = floorOf(region.max().x() * scale_x) + 1,
               hi_y = floorOf(region.max().y() * scale_y) + 1;
  const double n_x = hi_x - lo_x + 2, n_y = hi_y - lo_y + 2;  // the last cell's far corners too
  if (!(n_x * n_y <= static_cast<double>(kMaxTable)) || std::abs(lo_x) > 0x1p52 ||
      std::abs(lo_y) > 0x1p52)
    return;
  x0 = latticeCell(lo_x);
  y0 = latticeCell(lo_y);
  columns = static_cast<int64_t>(n_x);
  rows = static_cast<int64_t>(n_y);
  table.resize(static_cast<std::size_t>(columns * rows));
  for (int64_t r = 0; r < rows; ++r)
    for (int64_t k = 0; k < columns; ++k)
      table[static_cast<std::size_t>(r * columns + k)] = hash01(x0 + k, y0 + r, seed);
}

FloorAlbedo::FloorAlbedo(const FloorConfig& floor, const Eigen::AlignedBox2d& region)
    : floor_(floor) {
  const double s = floor.texture_scale;
  const uint64_t seed = floor.texture_seed;
  auto add = [&](double cell_x, double cell_y, double weight, uint64_t octave_seed) {
    Octave& o = octaves_[count_++];
    o.scale_x = 1.0 / cell_x;
    o.scale_y = 1.0 / cell_y;
    o.weight = weight;
    o.seed = octave_seed;
  };
  switch (floor.texture) {
    case FloorTexture::Wood:  // long features along world x (the walking direction)
      add(6 * s, s, 0.55, seed);
      add(2 * s, 0.5 * s, 0.30, seed + 1);
      add(s, 0.35 * s, 0.15, seed + 2);
      break;
    case FloorTexture::Carpet:  // fibre tufts of size s and a finer octave, high contrast
      add(s, s, 0.65, seed);
      add(0.45 * s, 0.45 * s, 0.35, seed + 1);
      break;
    case FloorTexture::Tiles:  // each tile's faint mottle
      add(0.01, 0.01, 0.03, seed + 3);
      tile_x0_ = hash01(-1, 0, seed);
      tile_y0_ = hash01(0, -1, seed);
      break;
  }
  for (int k = 0; k < count_; ++k) octaves_[k].tabulate(region);
}

// Square tiles of edge texture_scale (the grid shifted by the seed), each with its own shade and a
// faint mottle, separated by grout lines of grout_width centred on the tile edges.
double FloorAlbedo::tileAlbedo(double x, double y) const {
  const double s = floor_.texture_scale;
  const double gx = x / s + tile_x0_, gy = y / s + tile_y0_;
  const double fx = floorOf(gx), fy = floorOf(gy);
  const double edge = s * std::min({gx - fx, 1 - (gx - fx), gy - fy, 1 - (gy - fy)});
  if (edge < 0.5 * floor_.grout_width) return floor_.grout_albedo;
  const double shade = 2 * hash01(latticeCell(fx), latticeCell(fy), floor_.texture_seed) - 1;
  return floor_.albedo *
         (1.0 + floor_.texture_amplitude * shade + octaves_[0].weight * octaves_[0].noise(x, y));
}

}  // namespace multislit
