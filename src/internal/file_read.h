// Reading a whole input file into memory, bounded, and without blocking on a FIFO (private to the
// library).
#pragma once

#include <cstddef>
#include <string>

namespace multislit::detail {

/// How long a pipe or device may send nothing before reading it is given up [ms].
constexpr int kMaxStreamSilenceMs = 10000;

/// The bytes of `path`, at most `max_bytes`. Throws std::runtime_error naming `what` and the file
/// when it is missing, a folder, larger than `max_bytes`, or a pipe or device that sends nothing
/// (for kMaxStreamSilenceMs) or is interrupted by a signal. It is opened without blocking: a FIFO
/// nobody writes to gives nothing at once instead of waiting for ever. Pipes and devices
/// (/dev/stdin) cannot be sized first, so they are read up to the limit and refused beyond it.
std::string readWholeFile(const std::string& path, const std::string& what, std::size_t max_bytes);

}  // namespace multislit::detail
