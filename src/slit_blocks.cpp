#include "slit_blocks.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace multislit::detail {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

inline void compareExchange(__m128& lo, __m128& hi) {
  const __m128 a = lo;
  lo = _mm_min_ps(a, hi);
  hi = _mm_max_ps(a, hi);
}

/// Sorts x[0, 2 cap) lane by lane (cap a power of two), x[0, cap) rising and x[cap, 2 cap)
/// falling in each lane: Batcher's bitonic network of half-cleaners, no branch on the values.
/// Values only: which of two equal values comes first is not kept (the medians are taken as
/// |median|, so not even the sign of a zero matters).
/// kCap > 0: cap known when compiling, the network unrolled.
template <std::size_t kCap>
inline void mergeLanes(__m128* x, std::size_t cap) {
  if (kCap > 0) cap = kCap;
#pragma GCC unroll 8
  for (std::size_t d = cap; d >= 1; d /= 2)
#pragma GCC unroll 32
    for (std::size_t i = 0; i < 2 * cap; i += 2 * d)
#pragma GCC unroll 32
      for (std::size_t j = i; j < i + d; ++j) compareExchange(x[j], x[j + d]);
}

/// The lanes shifted up by one, lane 0 from lane 3 of `before`: block m - 1 beside block m.
inline __m128 shiftedIn(__m128 before, __m128 x) {
  const __m128 t = _mm_shuffle_ps(before, x, _MM_SHUFFLE(0, 0, 3, 3));  // b3 b3 x0 x0
  return _mm_shuffle_ps(t, x, _MM_SHUFFLE(2, 1, 2, 0));                 // b3 x0 x1 x2
}

/// The windows of one group: x[i] = (block m - 1 ascending) for i < cap, then block m
/// descending, for the blocks m of `group`'s four lanes (`before`: the group before, or
/// nullptr), merged in `x`. With a length known when compiling, the vectors stay in registers.
template <std::size_t kCap>
void mergeGroup(const SlitBlocks::Lanes* group, const SlitBlocks::Lanes* before, std::size_t cap,
                SlitBlocks::Lanes* out) {
  constexpr std::size_t kFixed = kCap > 0 ? 2 * kCap : 1;
  __m128 fixed[kFixed];
  __m128* x = kCap > 0 ? fixed : &out->x;  // longer blocks: merged where they are written
  if (kCap > 0) cap = kCap;
  const __m128 inf = _mm_set1_ps(kInf);
#pragma GCC unroll 16
  for (std::size_t i = 0; i < cap; ++i) {
    x[i] = shiftedIn(before ? before[i].x : inf, group[i].x);
    x[2 * cap - 1 - i] = group[i].x;
  }
  mergeLanes<kCap>(x, cap);
  if (kCap > 0)
#pragma GCC unroll 32
    for (std::size_t i = 0; i < 2 * cap; ++i) out[i].x = x[i];
}

void mergeGroup(const SlitBlocks::Lanes* group, const SlitBlocks::Lanes* before, std::size_t cap,
                SlitBlocks::Lanes* out) {
  switch (cap) {
    case 4:
      return mergeGroup<4>(group, before, cap, out);
    case 8:
      return mergeGroup<8>(group, before, cap, out);
    case 16:
      return mergeGroup<16>(group, before, cap, out);
    default:
      return mergeGroup<0>(group, before, cap, out);
  }
}

/// The median of the ascending values u[0], u[4], u[8], ... without one value equal to `skip`
/// (none when `skip` is NaN): of the n values left, the one at position n / 2, for an even n the
/// mean of it and the one before. Leaving out a value equal to `skip` moves every later one down
/// by one, and a value is later exactly when it is not below `skip`. Without branches on the
/// values (reading u[4 (n / 2 + 1)]: `u` must hold it), as which way they go is unpredictable.
float medianWithout(const float* u, std::size_t n, float skip) {
  const __m128 s = _mm_set_ss(skip);
  const auto at = [&](std::size_t p) {  // in vector registers: compilers make a branch of ?:
    const __m128 here = _mm_load_ss(u + 4 * p), after = _mm_load_ss(u + 4 * (p + 1));
    const __m128 later = _mm_cmpge_ss(here, s);  // false when `skip` is NaN
    return _mm_cvtss_f32(_mm_or_ps(_mm_and_ps(later, after), _mm_andnot_ps(later, here)));
  };
  const std::size_t p = n / 2;
  const float mid = at(p), before = at(p > 0 ? p - 1 : 0);
  return n % 2 == 0 ? 0.5f * (mid + before) : mid;
}

/// Sorts four vectors lane by lane: a network of five compare-exchanges.
inline void sortFour(__m128* v) {
  compareExchange(v[0], v[1]);
  compareExchange(v[2], v[3]);
  compareExchange(v[0], v[2]);
  compareExchange(v[1], v[3]);
  compareExchange(v[1], v[2]);
}

}  // namespace

void SlitBlocks::start(const std::vector<float>& cells, std::size_t width, std::size_t stride) {
  cells_ = cells.data();
  width_ = width;
  rows_ = width == 0 ? 0 : cells.size() / width;
  stride_ = std::max<std::size_t>(stride, 1);
  blocks_ = (width_ + stride_ - 1) / stride_;
  groups_ = (blocks_ + 3) / 4;
  cap_ = 4;
  while (cap_ < stride_) cap_ *= 2;
  sorted_.resize(rows_ * groups_ * cap_);
  counts_.resize(rows_ * groups_ * 4);
  for (std::size_t row = 0; row < rows_; ++row) sortRow(row);
}

/// Each group's 4 stride cells, NaN past the slit's end, placed block by block in the lanes and
/// sorted there; no candidate (NaN) becomes +infinity, past the candidates.
void SlitBlocks::sortRow(std::size_t row) {
  const float* cells = cells_ + row * width_;
  alignas(16) float lanes[16];
  std::vector<float>& block = block_;
  block.resize(cap_);
  for (std::size_t g = 0; g < groups_; ++g) {
    Lanes* out = sorted_.data() + (row * groups_ + g) * cap_;
    std::int32_t* counts = counts_.data() + (row * groups_ + g) * 4;
    if (cap_ == 4 && stride_ == 4) {  // the default: a transpose of 16 cells
      std::fill(lanes, lanes + 16, std::nanf(""));
      std::copy(cells + 16 * g, cells + std::min(width_, 16 * g + 16), lanes);
      __m128 v[4] = {_mm_load_ps(lanes), _mm_load_ps(lanes + 4), _mm_load_ps(lanes + 8),
                     _mm_load_ps(lanes + 12)};
      _MM_TRANSPOSE4_PS(v[0], v[1], v[2], v[3]);  // v[i]: cell i of each block
      __m128i missing = _mm_setzero_si128();
      for (__m128& x : v) {
        const __m128 nan = _mm_cmpunord_ps(x, x);
        missing = _mm_sub_epi32(missing, _mm_castps_si128(nan));  // -1 per NaN
        x = _mm_or_ps(_mm_and_ps(nan, _mm_set1_ps(kInf)), _mm_andnot_ps(nan, x));
      }
      sortFour(v);
      for (std::size_t i = 0; i < 4; ++i) out[i].x = v[i];
      _mm_storeu_si128(reinterpret_cast<__m128i*>(counts),
                       _mm_sub_epi32(_mm_set1_epi32(4), missing));
      continue;
    }
    for (std::size_t j = 0; j < 4; ++j) {  // insertion sort, block by block
      std::size_t n = 0;
      const std::size_t first = (4 * g + j) * stride_;
      for (std::size_t k = first; k < std::min(width_, first + stride_); ++k) {
        const float x = cells[k];
        if (std::isnan(x)) continue;
        std::size_t i = n++;
        for (; i > 0 && block[i - 1] > x; --i) block[i] = block[i - 1];
        block[i] = x;
      }
      for (std::size_t i = 0; i < cap_; ++i)
        reinterpret_cast<float*>(&out[i].x)[j] = i < n ? block[i] : kInf;
      counts[j] = static_cast<std::int32_t>(n);
    }
  }
}

std::size_t SlitBlocks::mediansThenDouble(std::vector<float>& out) {
  const std::size_t next_groups = (groups_ + 1) / 2;
  next_.resize(rows_ * next_groups * 2 * cap_);
  next_counts_.resize(rows_ * next_groups * 4);
  merged_.resize(2 * 2 * cap_);
  // Each window's median is written, then kept or not: no branch on it.
  if (out.size() < rows_ * blocks_) out.resize(rows_ * blocks_);
  std::size_t taken = 0;
  for (std::size_t row = 0; row < rows_; ++row) taken += rowMedians(row, out.data() + taken);
  std::swap(sorted_, next_);
  std::swap(counts_, next_counts_);
  stride_ *= 2;
  cap_ *= 2;
  blocks_ = (blocks_ + 1) / 2;
  groups_ = next_groups;
  return taken;
}

std::size_t SlitBlocks::rowMedians(std::size_t row, float* out) {
  const float* cells = cells_ + row * width_;
  const Lanes* sorted = sorted_.data() + row * groups_ * cap_;
  const std::int32_t* counts = counts_.data() + row * groups_ * 4;
  const std::size_t next_groups = (groups_ + 1) / 2;
  Lanes* next = next_.data() + row * next_groups * 2 * cap_;
  std::int32_t* next_counts = next_counts_.data() + row * next_groups * 4;
  const std::size_t merged_size = 2 * cap_;
  alignas(16) std::int32_t totals[8] = {};  // per window: the candidates of its two blocks
  std::size_t taken = 0;
  for (std::size_t g = 0; g < 2 * next_groups; ++g) {
    Lanes* merged = merged_.data() + (g % 2) * merged_size;
    __m128i total = _mm_setzero_si128();
    if (g < groups_) {
      mergeGroup(sorted + g * cap_, g > 0 ? sorted + (g - 1) * cap_ : nullptr, cap_, merged);
      const __m128 here = _mm_loadu_ps(reinterpret_cast<const float*>(counts + 4 * g));
      const __m128 before = g > 0 ? _mm_loadu_ps(reinterpret_cast<const float*>(counts + 4 * g - 4))
                                  : _mm_setzero_ps();
      total = _mm_add_epi32(_mm_castps_si128(here), _mm_castps_si128(shiftedIn(before, here)));
    } else {  // no group: its windows are empty
      std::fill(merged, merged + merged_size, Lanes{_mm_set1_ps(kInf)});
    }
    _mm_store_si128(reinterpret_cast<__m128i*>(totals + 4 * (g % 2)), total);
    for (std::size_t j = 0, m = 4 * g; j < 4 && m < blocks_; ++j, ++m) {
      const float skip = m > 0 ? cells[(m - 1) * stride_] : std::nanf("");
      const std::size_t n = static_cast<std::size_t>(totals[4 * (g % 2) + j]) - !std::isnan(skip);
      out[taken] = std::abs(medianWithout(reinterpret_cast<const float*>(merged) + j, n, skip));
      taken += !std::isnan(cells[m * stride_]) && n >= stride_;
    }
    if (g % 2 == 0) continue;
    // The windows of odd m, lanes 1 and 3 of the two groups, are the next length's blocks.
    const Lanes* even = merged_.data();
    const std::size_t ng = g / 2;
    for (std::size_t i = 0; i < merged_size; ++i)
      next[ng * merged_size + i].x =
          _mm_shuffle_ps(even[i].x, merged[i].x, _MM_SHUFFLE(3, 1, 3, 1));
    for (std::size_t j = 0; j < 4; ++j) next_counts[4 * ng + j] = totals[2 * j + 1];
  }
  return taken;
}

}  // namespace multislit::detail
