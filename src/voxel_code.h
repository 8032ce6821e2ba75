// A voxel's key as one number in the order of OctoMap's tree (private to the library).
#pragma once

#include <octomap/OcTreeKey.h>

#include <cstdint>

namespace multislit::detail {

/// The 8 bits of each byte spread to every third bit.
struct SpreadBits {
  std::uint32_t of[256];
};
constexpr SpreadBits spreadBitsTable() {
  SpreadBits t{};
  for (std::uint32_t b = 0; b < 256; ++b)
    for (std::uint32_t i = 0; i < 8; ++i) t.of[b] |= ((b >> i) & 1u) << (3 * i);
  return t;
}
inline constexpr SpreadBits kSpreadBits = spreadBitsTable();

/// The Morton code of a key: the bits of x, y and z interleaved, x lowest (bit i of x at bit 3 i,
/// of y at 3 i + 1, of z at 3 i + 2). Bits 3 i to 3 i + 2 are octomap::computeChildIdx(key, i),
/// the child taken at level i from the bottom, so that codes in ascending order walk the tree depth
/// first and two codes share their path from the root down to their highest differing bit.
struct VoxelCode {
  static std::uint64_t spread(octomap::key_type v) {
    return kSpreadBits.of[v & 0xffu] | std::uint64_t{kSpreadBits.of[v >> 8]} << 24;
  }
  static octomap::key_type gather(std::uint64_t v) {  // every third bit, from bit 0
    v &= 0x249249249249u;
    v = (v | v >> 2) & 0xc30c30c30c3u;
    v = (v | v >> 4) & 0xf00f00f00fu;
    v = (v | v >> 8) & 0xff0000ffu;
    return static_cast<octomap::key_type>(v | v >> 16);
  }

  static std::uint64_t of(const octomap::OcTreeKey& key) {
    return spread(key[0]) | spread(key[1]) << 1 | spread(key[2]) << 2;
  }
  static octomap::OcTreeKey key(std::uint64_t code) {
    return octomap::OcTreeKey(gather(code), gather(code >> 1), gather(code >> 2));
  }
};

}  // namespace multislit::detail
