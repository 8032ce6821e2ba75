// The map's leaf updates one voxel after another (src/key_order_update.h), and the voxels' codes
// that order them (src/voxel_code.h), against OctoMap's own updateNode(key, log_odds, lazy_eval =
// true): the same tree, node for node and byte for byte, through new voxels, voxels at the clamping
// bounds and pruned nodes that must be expanded.
#include "key_order_update.h"
#include "voxel_code.h"

#include <octomap/OcTree.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace {

using multislit::detail::KeyOrderUpdate;
using multislit::detail::VoxelCode;

std::unique_ptr<octomap::OcTree> makeTree() {
  auto tree = std::make_unique<octomap::OcTree>(0.01);
  tree->setClampingThresMin(0.12);
  tree->setClampingThresMax(0.97);
  return tree;
}

/// Every leaf: its key, depth and log-odds, in the iterator's order.
std::string leaves(const octomap::OcTree& tree) {
  std::ostringstream out;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it)
    out << it.getKey()[0] << ' ' << it.getKey()[1] << ' ' << it.getKey()[2] << ' ' << it.getDepth()
        << ' ' << it->getLogOdds() << '\n';
  return out.str();
}

std::string binary(const octomap::OcTree& tree) {
  std::ostringstream out;
  tree.writeBinaryConst(out);
  return out.str();
}

/// Leaves above the finest level: pruned nodes, each standing for 8^n equal voxels.
std::size_t prunedLeaves(const octomap::OcTree& tree) {
  std::size_t n = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it)
    n += it.getDepth() < tree.getTreeDepth();
  return n;
}

struct Update {
  octomap::OcTreeKey key;
  float log_odds = 0.0f;
};

/// One frame of voxels in a small box, sorted and unique as the map gives them, each with an
/// update: misses on one side (its voxels reach the lower bound), hits and weak hits on the other
/// (the upper bound), so that pruning finds equal siblings; all three in a band between. Every 40
/// frames the sides swap: updates against the bound then expand the pruned nodes.
std::vector<Update> frameOf(std::mt19937& rng, int frame) {
  std::uniform_int_distribution<int> offset(-4, 4), kind(0, 49);
  std::vector<std::uint64_t> packed;
  const int shift = frame % 7;  // the box moves a little, as the robot walks
  for (int i = 0; i < 600; ++i) {
    const auto x = static_cast<std::uint64_t>(32768 + offset(rng) + shift);
    const auto y = static_cast<std::uint64_t>(32768 + offset(rng));
    const auto z = static_cast<std::uint64_t>(32768 + offset(rng) / 3);
    packed.push_back(z << 32 | y << 16 | x);
  }
  std::sort(packed.begin(), packed.end());
  packed.erase(std::unique(packed.begin(), packed.end()), packed.end());
  const float hit = octomap::logodds(0.85), weak = octomap::logodds(0.7),
              miss = octomap::logodds(0.4875);
  std::vector<Update> updates;
  for (const std::uint64_t p : packed) {
    const auto x = static_cast<octomap::key_type>(p & 0xffff);
    const int side = x < 32770 ? 0 : x < 32772 ? 10 : 25;
    const int k = kind(rng), hits = frame / 40 % 2 == 0 ? side : 25 - side;
    updates.push_back(Update{octomap::OcTreeKey(x, static_cast<octomap::key_type>(p >> 16 & 0xffff),
                                                static_cast<octomap::key_type>(p >> 32)),
                             k < hits       ? hit
                             : k < 2 * hits ? weak
                                            : miss});
  }
  return updates;
}

/// The frames of updates through KeyOrderUpdate and through updateNode(); `by_code`: each frame's
/// voxels in the order of their codes (the map's order), else in the order of (z, y, x).
void checkAgainstUpdateNode(bool by_code) {
  auto ours = makeTree(), stock = makeTree();
  std::mt19937 rng(7);
  std::size_t at_bound = 0, pruned = 0, expanded = 0;
  for (int frame = 0; frame < 400; ++frame) {
    const bool prune = frame % 40 == 39;  // as the map's crop: a pruned tree, updated after
    if (prune) {
      ours->prune();
      stock->prune();
      pruned += prunedLeaves(*ours);
    }
    const std::size_t pruned_before = prunedLeaves(*ours);
    KeyOrderUpdate update(*ours);
    std::vector<Update> updates = frameOf(rng, frame);
    if (by_code)
      std::sort(updates.begin(), updates.end(), [](const Update& a, const Update& b) {
        return VoxelCode::of(a.key) < VoxelCode::of(b.key);
      });
    for (const Update& u : updates) {
      const octomap::OcTreeNode* a = by_code ? update.update(VoxelCode::of(u.key), u.log_odds)
                                             : update.update(u.key, u.log_odds);
      const octomap::OcTreeNode* b = stock->updateNode(u.key, u.log_odds, true);
      ASSERT_TRUE(a != nullptr && b != nullptr);
      ASSERT_EQ(a->getLogOdds(), b->getLogOdds()) << "frame " << frame;
      at_bound += a->getLogOdds() <= ours->getClampingThresMinLog() ||
                  a->getLogOdds() >= ours->getClampingThresMaxLog();
    }
    expanded += prunedLeaves(*ours) < pruned_before;
    ASSERT_EQ(ours->size(), stock->size()) << "frame " << frame;
  }
  EXPECT_EQ(leaves(*ours), leaves(*stock));
  EXPECT_EQ(binary(*ours), binary(*stock));
  // The walk went through the cases it is meant to check.
  EXPECT_GT(at_bound, 10000u);
  EXPECT_GT(pruned, 20u);
  EXPECT_GE(expanded, 5u);
}

TEST(KeyOrderUpdate, GivesOctoMapsTreeThroughBoundsAndPrunedNodes) {
  checkAgainstUpdateNode(false);
}

TEST(KeyOrderUpdate, GivesOctoMapsTreeInTheOrderOfVoxelCodes) { checkAgainstUpdateNode(true); }

TEST(VoxelCode, HoldsTheChildOfEachLevelAndGivesTheKeyBack) {
  std::mt19937 rng(23);
  std::uniform_int_distribution<int> any(0, 65535);
  for (int i = 0; i < 100000; ++i) {
    const octomap::OcTreeKey key(static_cast<octomap::key_type>(any(rng)),
                                 static_cast<octomap::key_type>(any(rng)),
                                 static_cast<octomap::key_type>(any(rng)));
    const std::uint64_t code = VoxelCode::of(key);
    ASSERT_EQ(VoxelCode::key(code), key);
    ASSERT_LT(code, std::uint64_t{1} << 48);
    for (int level = 0; level < 16; ++level)
      ASSERT_EQ(code >> (3 * level) & 7u, octomap::computeChildIdx(key, level)) << level;
  }
  EXPECT_EQ(VoxelCode::of(octomap::OcTreeKey(1, 2, 4)), 1u | 2u << 3 | 4u << 6);
  EXPECT_EQ(VoxelCode::of(octomap::OcTreeKey(0xffff, 0, 0)), 0x249249249249u);
}

}  // namespace
