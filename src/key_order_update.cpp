#include "key_order_update.h"

#include "voxel_code.h"

#include <algorithm>
#include <cstdint>
#include <limits>

namespace multislit::detail {

KeyOrderUpdate::KeyOrderUpdate(octomap::OcTree& tree)
    : tree_(tree),
      depth_(tree.getTreeDepth()),
      min_(tree.getClampingThresMinLog()),
      max_(tree.getClampingThresMaxLog()) {}

octomap::OcTreeNode* KeyOrderUpdate::update(const octomap::OcTreeKey& key, float log_odds) {
  return update(VoxelCode::of(key), log_odds);
}

octomap::OcTreeNode* KeyOrderUpdate::update(std::uint64_t code, float log_odds) {
  octomap::OcTreeNode* root = tree_.getRoot();
  if (root == nullptr || depth_ > kMaxDepth) {  // updateNode() creates the root
    valid_ = 0;
    return tree_.updateNode(VoxelCode::key(code), log_odds, true);
  }
  // updateNode()'s early abort: the leaf its search finds already stands at the bound.
  const auto atBound = [&](const octomap::OcTreeNode* leaf) {
    return (log_odds >= 0 && leaf->getLogOdds() >= max_) ||
           (log_odds <= 0 && leaf->getLogOdds() <= min_);
  };
  // The deepest node on both paths: the levels above the highest level in which the codes differ.
  unsigned d = 0;
  if (valid_ > 0 && path_[0] == root) {
    const std::uint64_t differ = code ^ last_;
    const auto differing_levels = static_cast<unsigned>(
        differ == 0
            ? 0
            : (std::numeric_limits<std::uint64_t>::digits - 1 - __builtin_clzll(differ)) / 3 + 1);
    d = std::min(depth_ - differing_levels, valid_ - 1);
  }
  octomap::OcTreeNode* node = d == 0 ? root : path_[d];
  bool searched = false;  // the search's leaf was passed and is not at the bound, or there is none
  bool created = false;   // `node` was created by this update
  for (; d < depth_; ++d) {
    path_[d] = node;
    const auto pos = static_cast<unsigned>(code >> (3 * (depth_ - 1 - d)) & 7u);  // computeChildIdx
    if (!tree_.nodeChildExists(node, pos)) {
      if (!tree_.nodeHasChildren(node) && !created) {  // a pruned leaf covers the voxel
        if (!searched && atBound(node)) {
          valid_ = d + 1;
          last_ = code;
          return node;
        }
        tree_.expandNode(node);
      } else {
        tree_.createNodeChild(node, pos);
        created = true;
      }
      searched = true;
    }
    node = tree_.getNodeChild(node, pos);
  }
  path_[depth_] = node;
  valid_ = depth_ + 1;
  last_ = code;
  if (!searched && atBound(node)) return node;
  tree_.OccupancyOcTreeBase::updateNodeLogOdds(node, log_odds);  // not overridden: no virtual call
  return node;
}

}  // namespace multislit::detail
