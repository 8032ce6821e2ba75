// The sorted blocks of the slits of an organized grid of residuals, for the medians of windows
// along the slits at doubling lengths: the window of 2 half + 1 cells centred on cell
// m (half + 1) is block m of half + 1 cells and block m - 1 without its first cell, and a block
// of the next length, 2 (half + 1) cells, is two adjacent blocks of this one. So each cell is
// sorted once, in blocks of the shortest length, and every longer block and every window is a
// merge of two sorted blocks. Four blocks side by side in the four lanes of a vector: the sorting
// networks then compare whole vectors, without shuffles inside them. Private to the library:
// FloorDetector's step 6 (slit_scale.cpp).
#pragma once

#include <immintrin.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace multislit::detail {

class SlitBlocks {
 public:
  /// Sorts the blocks of `stride` cells of every slit of `cells` (rows of `width` cells, NaN
  /// where there is no candidate; a block holds the others). `cells` must stay unchanged while
  /// this is used.
  void start(const std::vector<float>& cells, std::size_t width, std::size_t stride);

  /// Writes to the start of `out` (grown as needed, never cut: it is kept from frame to frame),
  /// slit by slit, the |median| of each window of 2 stride - 1 cells centred on a candidate cell
  /// m stride that holds at least stride candidates: the value at position n / 2 of its n
  /// candidates in ascending order, for an even n the mean of it and the one before. Returns how
  /// many. Then moves on to blocks of 2 stride cells.
  std::size_t mediansThenDouble(std::vector<float>& out);

  struct Lanes {  // one vector, in containers
    __m128 x;
  };

 private:
  void sortRow(std::size_t row);
  std::size_t rowMedians(std::size_t row, float* out);  // how many it wrote

  const float* cells_ = nullptr;
  std::size_t rows_ = 0, width_ = 0, stride_ = 0;
  std::size_t blocks_ = 0;  // blocks per slit
  std::size_t groups_ = 0;  // groups of four blocks per slit
  std::size_t cap_ = 0;     // values per block: a power of two >= 4, >= stride_
  // Group g of slit s, blocks 4 g .. 4 g + 3 in lanes 0 .. 3: cap_ vectors from
  // (s groups_ + g) cap_, vector i the i-th smallest candidate of each block, +infinity past
  // the block's count.
  std::vector<Lanes> sorted_, next_;
  std::vector<std::int32_t> counts_, next_counts_;  // per block: its candidates
  std::vector<Lanes> merged_;                       // two groups' windows, merged
  std::vector<float> block_;                        // one block, sorted (blocks longer than 4)
};

}  // namespace multislit::detail
