// The one translation unit that instantiates PCL templates for multislit::PointRDM (PCL ships
// precompiled instantiations only for its own point types). Other files include the declarations
// only, so PCL's heavy implementation headers are compiled once.
#define PCL_NO_PRECOMPILE
#include "multislit/plane_model.h"
#include "multislit/point_types.h"

#include <pcl/common/common.h>
#include <pcl/filters/filter_indices.h>
#include <pcl/pcl_base.h>
#include <pcl/sample_consensus/lmeds.h>
#include <pcl/sample_consensus/mlesac.h>
#include <pcl/sample_consensus/msac.h>
#include <pcl/sample_consensus/prosac.h>
#include <pcl/sample_consensus/ransac.h>
#include <pcl/sample_consensus/rmsac.h>
#include <pcl/sample_consensus/rransac.h>
#include <pcl/filters/impl/filter_indices.hpp>
#include <pcl/impl/pcl_base.hpp>
#include <pcl/sample_consensus/impl/lmeds.hpp>
#include <pcl/sample_consensus/impl/mlesac.hpp>
#include <pcl/sample_consensus/impl/msac.hpp>
#include <pcl/sample_consensus/impl/prosac.hpp>
#include <pcl/sample_consensus/impl/ransac.hpp>
#include <pcl/sample_consensus/impl/rmsac.hpp>
#include <pcl/sample_consensus/impl/rransac.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace {

bool isRDMapPlane(const pcl::SampleConsensusModel<multislit::PointRDM>& model) {
  return static_cast<int>(model.getModelType()) == multislit::kSacModelRDMapPlane;
}

}  // namespace

// MLESAC's sigma (see plane_model.h): threshold / 2 [px] for the RDMap plane model; PCL's
// threshold x median |p - median(p)| over x, y, z for any other model.
template <>
double pcl::MaximumLikelihoodSampleConsensus<multislit::PointRDM>::computeMedianAbsoluteDeviation(
    const PointCloudConstPtr& cloud, const IndicesPtr& indices, double sigma) const {
  if (isRDMapPlane(*sac_model_)) return sigma / 2.0;
  Eigen::Vector4f median;
  computeMedian(cloud, indices, median);
  std::vector<double> distances(indices->size());
  for (std::size_t i = 0; i < indices->size(); ++i) {
    Eigen::Vector4f d = (*cloud)[(*indices)[i]].getVector4fMap() - median;
    d[3] = 0.0f;
    distances[i] = d.dot(d);
  }
  return sigma * pcl::computeMedian(distances.begin(), distances.end(),
                                    static_cast<double (*)(double)>(std::sqrt));
}

// MLESAC's outlier span (see plane_model.h): the span of dk [px], at least 2 x threshold, as the
// first coordinate for the RDMap plane model; PCL's bounding box of x, y, z for any other model.
template <>
void pcl::MaximumLikelihoodSampleConsensus<multislit::PointRDM>::getMinMax(
    const PointCloudConstPtr& cloud, const IndicesPtr& indices, Eigen::Vector4f& min_p,
    Eigen::Vector4f& max_p) const {
  min_p.setConstant(std::numeric_limits<float>::max());
  max_p.setConstant(std::numeric_limits<float>::lowest());
  const bool rdmap = isRDMapPlane(*sac_model_);
  for (const auto i : *indices) {
    const multislit::PointRDM& p = (*cloud)[i];
    const Eigen::Vector4f q = rdmap ? Eigen::Vector4f(p.dk, 0.0f, 0.0f, 0.0f) : p.getVector4fMap();
    min_p = min_p.cwiseMin(q);
    max_p = max_p.cwiseMax(q);
  }
  min_p[3] = max_p[3] = 0.0f;
  if (rdmap && !indices->empty())
    max_p[0] = std::max(max_p[0], min_p[0] + 2.0f * static_cast<float>(threshold_));
}

// pcl::Filter subclasses (filters/: multislit::FloorFilter).
template class pcl::PCLBase<multislit::PointRDM>;
template class pcl::FilterIndices<multislit::PointRDM>;

// Sample consensus estimators for multislit::SampleConsensusModelRDMapPlane: all of PCL's.
template class pcl::RandomSampleConsensus<multislit::PointRDM>;
template class pcl::LeastMedianSquares<multislit::PointRDM>;
template class pcl::MEstimatorSampleConsensus<multislit::PointRDM>;
template class pcl::RandomizedRandomSampleConsensus<multislit::PointRDM>;
template class pcl::RandomizedMEstimatorSampleConsensus<multislit::PointRDM>;
template class pcl::MaximumLikelihoodSampleConsensus<multislit::PointRDM>;
template class pcl::ProgressiveSampleConsensus<multislit::PointRDM>;
