// The voxels a straight segment crosses in an OctoMap tree, key by key (private to the library).
#pragma once

#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace multislit::detail {

/// The keys of octomap::OcTreeBaseImpl::computeRayKeys(origin, end, ray), in its order and by its
/// arithmetic (the direction in float, the distances in double, the same ties between axes), each
/// handed to a callback where it is used instead of stored in a KeyRay first.
class RayKeys {
 public:
  explicit RayKeys(const octomap::OcTree& tree)
      : resolution_(tree.getResolution()),
        factor_(1.0 / resolution_),  // as OcTreeBaseImpl::setResolution()
        max_key_(tree.coordToKey(0.0)) {}

  /// Calls visit(key) for each key of the voxels from `origin`'s (included) to `end`'s
  /// (excluded); false, visiting none, when either end lies outside the tree.
  template <typename Visit>
  bool walk(const octomap::point3d& origin, const octomap::point3d& end, Visit&& visit) const;

 private:
  /// OcTreeBaseImpl::coordToKeyChecked().
  bool toKey(const octomap::point3d& p, octomap::OcTreeKey& key) const {
    for (unsigned i = 0; i < 3; ++i) {
      const double scaled = std::floor(factor_ * static_cast<double>(p(i)));
      if (!(scaled >= -max_key_ && scaled < max_key_)) return false;  // NaN too
      key[i] = static_cast<octomap::key_type>(static_cast<int>(scaled) + max_key_);
    }
    return true;
  }

  double resolution_;  ///< [m]
  double factor_;      ///< 1 / resolution [1/m]
  int max_key_;        ///< the key of coordinate 0 (half the keys lie below it)
};

template <typename Visit>
bool RayKeys::walk(const octomap::point3d& origin, const octomap::point3d& end,
                   Visit&& visit) const {
  octomap::OcTreeKey key, key_end;
  if (!toKey(origin, key) || !toKey(end, key_end)) return false;
  if (key == key_end) return true;
  visit(key);
  // Amanatides and Woo's traversal, step for step as OctoMap's.
  octomap::point3d direction = end - origin;
  const auto length = static_cast<float>(direction.norm());
  direction /= length;
  int step[3];
  double t_max[3], t_delta[3];  // the distance to the next border along each axis, and between two
  for (unsigned i = 0; i < 3; ++i) {
    step[i] = direction(i) > 0.0 ? 1 : direction(i) < 0.0 ? -1 : 0;
    if (step[i] == 0) {
      t_max[i] = t_delta[i] = std::numeric_limits<double>::max();
      continue;
    }
    double border = (static_cast<double>(static_cast<int>(key[i]) - max_key_) + 0.5) * resolution_;
    border += static_cast<float>(step[i] * resolution_ * 0.5);
    t_max[i] = (border - static_cast<double>(origin(i))) / static_cast<double>(direction(i));
    t_delta[i] = resolution_ / static_cast<double>(std::fabs(direction(i)));
  }
  // The walk in registers: the axis of the nearest border (ties to the later axis) steps.
  double tx = t_max[0], ty = t_max[1], tz = t_max[2];
  octomap::key_type kx = key[0], ky = key[1], kz = key[2];
  const auto advance = [](octomap::key_type& k, int s, double& t, double delta) {
    k = static_cast<octomap::key_type>(k + s);
    t += delta;
  };
  for (;;) {
    if (tx < ty) {
      if (tx < tz)
        advance(kx, step[0], tx, t_delta[0]);
      else
        advance(kz, step[2], tz, t_delta[2]);
    } else if (ty < tz) {
      advance(ky, step[1], ty, t_delta[1]);
    } else {
      advance(kz, step[2], tz, t_delta[2]);
    }
    // The end's voxel, or past the end (rounding may step around the end's voxel).
    if ((kx == key_end[0] && ky == key_end[1] && kz == key_end[2]) ||
        std::min(std::min(tx, ty), tz) > length)
      return true;
    visit(octomap::OcTreeKey(kx, ky, kz));
  }
}

}  // namespace multislit::detail
