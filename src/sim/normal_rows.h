// Standard normal deviates for the simulator's noise, a row of pixels at a time (private to it).
// Each pixel's deviate depends only on its row's stream and its column, so the bytes do not
// depend on how rows are shared between threads nor on which pixels draw.
#pragma once

#include <cstdint>

namespace multislit {

/// The stream of one image row: its seed, frame, row and noise source (speckle, sensor).
std::uint32_t rowStream(std::uint64_t seed, std::uint64_t frame, std::uint64_t row,
                        std::uint64_t source);

/// out[c] for the columns c in [0, n) of the row whose stream is `stream`: a 32-bit hash of the
/// stream and column through the inverse normal distribution function, tabulated (2048 cells per
/// half, the outermost cell in 4096 finer ones) and interpolated: within 1e-3 sigma of the exact
/// quantile to 3 sigma, 1e-2 sigma beyond; deviates reach 6.2 sigma. In vector instructions where
/// the processor has them.
void normalRow(std::uint32_t stream, float* out, int n);

}  // namespace multislit
