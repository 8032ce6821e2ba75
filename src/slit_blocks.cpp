#include "slit_blocks.h"

#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace multislit::detail {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

/// In each group of four lanes, compare-exchange lanes j and j + d (d = 2, then d = 1).
inline __m128 sortedFour(__m128 x) {
  __m128 t = _mm_shuffle_ps(x, x, _MM_SHUFFLE(1, 0, 3, 2));
  x = _mm_shuffle_ps(_mm_min_ps(x, t), _mm_max_ps(x, t), _MM_SHUFFLE(3, 2, 1, 0));
  t = _mm_shuffle_ps(x, x, _MM_SHUFFLE(2, 3, 0, 1));
  const __m128 lo = _mm_min_ps(x, t), hi = _mm_max_ps(x, t);             // lanes: 01 01 23 23
  const __m128 mixed = _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0));  // min01 min23 max01 max23
  return _mm_shuffle_ps(mixed, mixed, _MM_SHUFFLE(3, 1, 2, 0));
}

/// The four lanes of x in ascending order: each pair of lanes in order, the second pair
/// reversed, and the two compare-exchange stages of sortedFour on that rise and fall.
inline __m128 sortFour(__m128 x) {
  const __m128 t = _mm_shuffle_ps(x, x, _MM_SHUFFLE(2, 3, 0, 1));
  const __m128 lo = _mm_min_ps(x, t), hi = _mm_max_ps(x, t);             // lanes: 01 01 23 23
  const __m128 mixed = _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0));  // min01 min23 max01 max23
  return sortedFour(_mm_shuffle_ps(mixed, mixed, _MM_SHUFFLE(1, 3, 2, 0)));
}

/// Merges ascending a[0, cap) and b[0, cap) (cap a power of two >= 4) into out[0, 2 cap): a
/// followed by b reversed rises then falls, and Batcher's bitonic network of half-cleaners sorts
/// that, in vector lanes without a branch on the values. Values only: which of two equal values
/// comes first is not kept (the medians are taken as |median|, so not even the sign of a zero).
/// `x`: room for 2 cap / 4 vectors; with a length known when compiling, they stay in registers.
inline void mergeSorted(const float* a, const float* b, std::size_t cap, float* out, __m128* x) {
  const std::size_t lanes = 2 * cap / 4;
  for (std::size_t j = 0; j < lanes / 2; ++j) {
    x[j] = _mm_loadu_ps(a + 4 * j);
    const __m128 y = _mm_loadu_ps(b + 4 * j);
    x[lanes - 1 - j] = _mm_shuffle_ps(y, y, _MM_SHUFFLE(0, 1, 2, 3));
  }
  for (std::size_t d = lanes / 2; d >= 1; d /= 2)
    for (std::size_t i = 0; i < lanes; i += 2 * d)
      for (std::size_t j = i; j < i + d; ++j) {
        const __m128 lo = _mm_min_ps(x[j], x[j + d]), hi = _mm_max_ps(x[j], x[j + d]);
        x[j] = lo;
        x[j + d] = hi;
      }
  for (std::size_t j = 0; j < lanes; ++j) _mm_storeu_ps(out + 4 * j, sortedFour(x[j]));
}

template <std::size_t kCap>
void mergeFixed(const float* a, const float* b, float* out) {
  __m128 x[2 * kCap / 4];
  mergeSorted(a, b, kCap, out, x);
}

/// mergeSorted; `room` for the vectors of the blocks longer than 16.
template <class Lanes>
void mergeBlocks(const float* a, const float* b, std::size_t cap, float* out,
                 std::vector<Lanes>& room) {
  switch (cap) {
    case 4:
      return mergeFixed<4>(a, b, out);
    case 8:
      return mergeFixed<8>(a, b, out);
    case 16:
      return mergeFixed<16>(a, b, out);
    default:  // a struct of one __m128: the same address as its member
      room.resize(2 * cap / 4);
      return mergeSorted(a, b, cap, out, &room.front().x);
  }
}

/// The median of ascending `u` without one value equal to `skip` (none when `skip` is NaN):
/// of the n values left, the one at position n / 2, for an even n the mean of it and the one
/// before. Leaving out a value equal to `skip` moves every later one down by one, and a value is
/// later exactly when it is not below `skip`.
/// Without branches on the values (reading u[n / 2 + 1]: `u` must hold it), as which way they go
/// is unpredictable.
float medianWithout(const float* u, std::size_t n, float skip) {
  const auto at = [&](std::size_t p) {
    const float here = u[p], after = u[p + 1];
    return !(here >= skip) ? here : after;
  };
  const std::size_t p = n / 2;
  const float mid = at(p), before = at(p > 0 ? p - 1 : 0);
  return n % 2 == 0 ? 0.5f * (mid + before) : mid;
}

}  // namespace

void SlitBlocks::start(const std::vector<float>& cells, std::size_t width, std::size_t stride) {
  cells_ = cells.data();
  width_ = width;
  rows_ = width == 0 ? 0 : cells.size() / width;
  stride_ = std::max<std::size_t>(stride, 1);
  blocks_ = (width_ + stride_ - 1) / stride_;
  cap_ = 4;
  while (cap_ < stride_) cap_ *= 2;
  sorted_.resize(rows_ * blocks_ * cap_);
  counts_.resize(rows_ * blocks_);
  for (std::size_t row = 0; row < rows_; ++row) sortRow(row);
}

void SlitBlocks::sortRow(std::size_t row) {
  if (cap_ == 4) return sortRowByFour(row);
  const float* cells = cells_ + row * width_;
  for (std::size_t m = 0; m < blocks_; ++m) {
    // Insertion sort: a block of the shortest length holds a few cells.
    float* out = sorted_.data() + (row * blocks_ + m) * cap_;
    std::uint32_t n = 0;
    for (std::size_t j = m * stride_; j < std::min(width_, (m + 1) * stride_); ++j) {
      const float x = cells[j];
      if (std::isnan(x)) continue;
      std::uint32_t i = n++;
      for (; i > 0 && out[i - 1] > x; --i) out[i] = out[i - 1];
      out[i] = x;
    }
    std::fill(out + n, out + cap_, kInf);
    counts_[row * blocks_ + m] = n;
  }
}

/// Blocks of at most four cells, each sorted in one vector: no candidate (NaN) is +infinity.
void SlitBlocks::sortRowByFour(std::size_t row) {
  const float* cells = cells_ + row * width_;
  const __m128 inf = _mm_set1_ps(kInf);
  for (std::size_t m = 0; m < blocks_; ++m) {
    const float none = std::nanf("");  // past the slit's end: no candidate
    alignas(16) float block[4] = {none, none, none, none};
    const std::size_t first = m * stride_;
    std::copy(cells + first, cells + std::min(width_, first + stride_), block);
    const __m128 x = _mm_load_ps(block);
    const __m128 nan = _mm_cmpunord_ps(x, x);
    const __m128 keys = _mm_or_ps(_mm_and_ps(nan, inf), _mm_andnot_ps(nan, x));
    _mm_storeu_ps(sorted_.data() + (row * blocks_ + m) * 4, sortFour(keys));
    constexpr std::uint8_t kNone[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};
    counts_[row * blocks_ + m] = 4u - kNone[_mm_movemask_ps(nan)];
  }
}

void SlitBlocks::mediansThenDouble(std::vector<float>& out) {
  const std::size_t next_blocks = (blocks_ + 1) / 2;
  next_.resize(rows_ * next_blocks * 2 * cap_);
  next_counts_.resize(rows_ * next_blocks);
  pair_.resize(2 * cap_);
  // Each window's median is written, then kept or not: no branch on it.
  const std::size_t first = out.size();
  out.resize(first + rows_ * blocks_);
  std::size_t taken = 0;
  for (std::size_t row = 0; row < rows_; ++row)
    taken += rowMedians(row, out.data() + first + taken);
  out.resize(first + taken);
  std::swap(sorted_, next_);
  std::swap(counts_, next_counts_);
  stride_ *= 2;
  cap_ *= 2;
  blocks_ = next_blocks;
}

std::size_t SlitBlocks::rowMedians(std::size_t row, float* out) {
  std::size_t taken = 0;
  const float* cells = cells_ + row * width_;
  const float* sorted = sorted_.data() + row * blocks_ * cap_;
  const std::uint32_t* counts = counts_.data() + row * blocks_;
  const std::size_t next_blocks = (blocks_ + 1) / 2;
  float* next = next_.data() + row * next_blocks * 2 * cap_;
  std::uint32_t* next_counts = next_counts_.data() + row * next_blocks;
  for (std::size_t m = 0; m < blocks_; ++m) {
    const float* u = sorted + m * cap_;  // the window's candidates ascending
    std::size_t n = counts[m];
    float skip = std::nanf("");
    if (m > 0) {
      // Blocks m - 1 and m; when m - 1 is even, they are the next length's block (m - 1) / 2.
      const bool pairs = m % 2 == 1;
      float* merged = pairs ? next + (m - 1) * cap_ : pair_.data();
      mergeBlocks(sorted + (m - 1) * cap_, u, cap_, merged, room_);
      n += counts[m - 1];
      if (pairs) next_counts[m / 2] = static_cast<std::uint32_t>(n);
      u = merged;
      skip = cells[(m - 1) * stride_];
      n -= !std::isnan(skip);  // the first cell of block m - 1 lies outside the window
    }
    if (m % 2 == 0 && m + 1 == blocks_) {  // the last block, alone in the next length's last one
      float* last = next + m * cap_;
      std::copy(sorted + m * cap_, sorted + (m + 1) * cap_, last);
      std::fill(last + cap_, last + 2 * cap_, kInf);
      next_counts[m / 2] = counts[m];
    }
    const float centre = cells[m * stride_];
    out[taken] = std::abs(medianWithout(u, n, skip));
    taken += !std::isnan(centre) && n >= stride_;
  }
  return taken;
}

}  // namespace multislit::detail
