// The one translation unit that instantiates PCL templates for multislit::PointRDM (PCL ships
// precompiled instantiations only for its own point types). Other files include the declarations
// only, so PCL's heavy implementation headers are compiled once.
#define PCL_NO_PRECOMPILE
#include "multislit/point_types.h"

#include <pcl/filters/filter_indices.h>
#include <pcl/pcl_base.h>
#include <pcl/sample_consensus/lmeds.h>
#include <pcl/sample_consensus/msac.h>
#include <pcl/sample_consensus/ransac.h>
#include <pcl/filters/impl/filter_indices.hpp>
#include <pcl/impl/pcl_base.hpp>
#include <pcl/sample_consensus/impl/lmeds.hpp>
#include <pcl/sample_consensus/impl/msac.hpp>
#include <pcl/sample_consensus/impl/ransac.hpp>

// pcl::Filter subclasses (filters/: multislit::FloorFilter).
template class pcl::PCLBase<multislit::PointRDM>;
template class pcl::FilterIndices<multislit::PointRDM>;

// Sample consensus estimators for multislit::SampleConsensusModelRDMapPlane.
template class pcl::RandomSampleConsensus<multislit::PointRDM>;
template class pcl::MEstimatorSampleConsensus<multislit::PointRDM>;
template class pcl::LeastMedianSquares<multislit::PointRDM>;
