// Shared by grabber_test and grabber_gige_test: clouds compared bit for bit.
#pragma once

#include "multislit/point_types.h"

#include <pcl/point_cloud.h>

#include <cstring>
#include <vector>

namespace multislit::test {

/// The dk of every point, NaN included, in cloud order.
inline std::vector<float> dkOf(const pcl::PointCloud<PointRDM>& cloud) {
  std::vector<float> dk;
  for (const PointRDM& p : cloud.points) dk.push_back(p.dk);
  return dk;
}

// Bitwise: NaN where NaN, the same float bits elsewhere.
inline bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace multislit::test
