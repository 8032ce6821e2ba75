#include "multislit/floor_filter.h"

#include "multislit/plane_model.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace multislit {

FloorFilter::FloorFilter(bool extract_removed_indices)
    : pcl::FilterIndices<PointRDM>(extract_removed_indices) {
  filter_name_ = "FloorFilter";
}

void FloorFilter::setSigma(double sigma) {
  FloorDetectorConfig config = config_;
  config.sigma = sigma;
  setConfig(config);
}

void FloorFilter::setThresholdSigmas(double sigmas) {
  FloorDetectorConfig config = config_;
  config.threshold_sigmas = sigmas;
  setConfig(config);
}

void FloorFilter::setConfig(const FloorDetectorConfig& config) {
  config.validate();
  config_ = config;
}

void FloorFilter::applyFilter(pcl::Indices& indices) {
  result_ = FloorDetector(config_).detect(input_, *indices_);
  if (!negative_) {
    indices = result_.inliers;
  } else if (result_.found) {
    indices = result_.obstacles;
  } else {  // no floor: every valid point is an obstacle
    indices.clear();
    for (const auto i : *indices_)
      if (isValidRDMPoint((*input_)[i])) indices.push_back(i);
  }

  if (!extract_removed_indices_) return;
  // `indices` is a subsequence of `indices_`, in the same order.
  removed_indices_->clear();
  auto kept = indices.cbegin();
  for (const auto i : *indices_) {
    if (kept != indices.cend() && *kept == i)
      ++kept;
    else
      removed_indices_->push_back(i);
  }
}

void FloorFilter::applyFilter(PointCloud& output) {
  pcl::Indices kept;
  applyFilter(kept);
  if (keep_organized_) {
    // Every point not kept, also those outside the indices, gets the user filter value.
    std::vector<bool> keep(input_->size(), false);
    for (const auto i : kept) keep[i] = true;
    output = *input_;
    for (std::size_t i = 0; i < output.size(); ++i) {
      if (keep[i]) continue;
      PointRDM& p = output[i];
      p.x = p.y = p.z = p.dk = user_filter_value_;
    }
    output.is_dense = output.is_dense && std::isfinite(user_filter_value_);
    return;
  }
  output.resize(kept.size());
  for (std::size_t k = 0; k < kept.size(); ++k) output[k] = (*input_)[kept[k]];
  output.width = static_cast<std::uint32_t>(kept.size());
  output.height = 1;
  output.is_dense = true;
}

}  // namespace multislit
