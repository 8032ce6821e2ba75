// The errors of an extraction against the simulator's ground truth, shared by the extraction
// tests: sub-pixel error of every measured crossing, depth error, residual about the floor plane.
#pragma once

#include "multislit/point_types.h"
#include "multislit/sim/simulator.h"

#include <pcl/point_cloud.h>
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

namespace multislit {

inline double quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

struct Errors {
  std::size_t truth = 0, valid = 0;
  std::vector<double> subpixel;  // |u' - true u| [px]
  std::vector<double> depth;     // |z - true z| / range [-]
  double plane_std = 0;          // residual std about the least-squares plane of eq. (2) [px]
};

inline Errors compare(const pcl::PointCloud<PointRDM>& cloud,
                      const std::vector<SlitCrossing>& truth) {
  Errors e;
  e.truth = truth.size();
  std::map<std::pair<int, int>, const SlitCrossing*> by_slit_row;
  for (const SlitCrossing& t : truth) by_slit_row[{t.slit, t.row}] = &t;
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  for (const PointRDM& p : cloud) {
    if (!std::isfinite(p.dk)) continue;
    ++e.valid;
    const Eigen::Vector3d a(p.u, p.v, 1.0);
    ata += a * a.transpose();
    atb += a * p.dk;
    const auto it = by_slit_row.find({p.slit, static_cast<int>(p.v)});
    if (it == by_slit_row.end()) continue;
    e.subpixel.push_back(std::abs(p.u + p.dk - it->second->u));
    if (std::isfinite(p.z))
      e.depth.push_back(std::abs(p.z - it->second->camera_point.z()) /
                        it->second->camera_point.norm());
  }
  const Eigen::Vector3d plane = ata.ldlt().solve(atb);
  double ss = 0;
  for (const PointRDM& p : cloud)
    if (std::isfinite(p.dk)) ss += std::pow(p.dk - plane.dot(Eigen::Vector3d(p.u, p.v, 1)), 2);
  e.plane_std = std::sqrt(ss / static_cast<double>(e.valid));
  return e;
}

}  // namespace multislit
