// The stock PCL path of `multislit bench`, to time against ours on the same frames.
#pragma once

#include "bench_input.h"
#include "bench_run.h"

namespace multislit::apps {

/// The stock PCL path on the RDMaps of our extractor (PCL has no slit extractor): metric cloud,
/// SACSegmentation, EuclideanClusterExtraction on a KdTree, OcTree::insertPointCloud.
/// `threshold`: SACSegmentation's distance threshold [m]. Times floor, clusters and map per frame.
PathRun runStockPath(const BenchInput& in, int passes, double threshold);

}  // namespace multislit::apps
