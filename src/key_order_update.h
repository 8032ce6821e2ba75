// Updates of an OctoMap tree's leaves, one voxel key after another, with the result of
// octomap::OccupancyOcTreeBase::updateNode(key, log_odds, lazy_eval = true) (private to the
// library).
#pragma once

#include <octomap/OcTree.h>

#include <array>
#include <cstdint>

namespace multislit::detail {

/// updateNode() searches the tree from the root for the voxel's leaf (to skip a leaf already at
/// its clamping bound) and then descends from the root again to update it: 32 node visits per
/// voxel. Voxels that follow each other in the order of their codes (VoxelCode) share most of their
/// path from the root, so this descends once, from the deepest node the voxel shares with the
/// previous voxel's path. The
/// tree, the nodes created and expanded and the values are those of updateNode() with lazy
/// evaluation (inner nodes are not updated; a later updateInnerOccupancy() does that).
class KeyOrderUpdate {
 public:
  /// Until the tree's structure is changed by other means (pruning, deleting, another tree).
  explicit KeyOrderUpdate(octomap::OcTree& tree);

  /// As tree.updateNode(key, log_odds, true): the voxel's node after the update, or the leaf
  /// that already stood at the bound (a pruned node may cover the voxel).
  octomap::OcTreeNode* update(const octomap::OcTreeKey& key, float log_odds);
  /// The same for the voxel of that code (VoxelCode::of(key)).
  octomap::OcTreeNode* update(std::uint64_t code, float log_odds);

 private:
  static constexpr unsigned kMaxDepth = 16;  ///< octomap's key_type holds 16 levels
  octomap::OcTree& tree_;
  unsigned depth_;   ///< the tree's depth (16 with octomap's defaults)
  float min_, max_;  ///< the clamping bounds in log-odds
  /// path_[d]: the node at depth d on the path to last_, valid for d < valid_.
  std::array<octomap::OcTreeNode*, kMaxDepth + 1> path_{};
  unsigned valid_ = 0;
  std::uint64_t last_ = 0;  ///< the code of the last voxel
};

}  // namespace multislit::detail
