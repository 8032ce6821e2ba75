// The hot kernels of the RDMap plane model (private to the library): the inliers of a plane
// dk = a u + b v + c counted and summed over the model's centred arrays of u, v and dk, and the
// valid points of a cloud gathered into those arrays.
#pragma once

#include "multislit/point_types.h"

#include <pcl/types.h>

#include <cstddef>

namespace multislit::simd {

/// Points of the centred arrays within t of the plane dk = a u + b v + c, over [begin, end): the
/// hot loop of RANSAC. Also compiled for AVX2 (eight points per instruction, chosen at run time);
/// both clones make the same float operations, so they count the same.
unsigned countNear(const float* u, const float* v, const float* dk, std::size_t begin,
                   std::size_t end, float a, float b, float c, float t);

/// The sums of eq. (2) over the points of the centred arrays within t of the plane.
struct InlierSums {
  double n = 0, u = 0, v = 0, dk = 0, uu = 0, uv = 0, vv = 0, udk = 0, vdk = 0, dkdk = 0;
};

/// InlierSums of the points [0, size) of the centred arrays, in one pass (float partial sums,
/// added to double every 256 points); also compiled for AVX2.
InlierSums sumInliers(const float* u, const float* v, const float* dk, std::size_t size, float a,
                      float b, float c, float t);

/// Copies the index, u, v and dk of the valid points among points[0 .. n), n a multiple of four,
/// into the arrays, in order. Returns the number of valid points.
std::size_t gatherValidByFour(const PointRDM* points, std::size_t n, pcl::index_t* index, float* u,
                              float* v, float* dk);

}  // namespace multislit::simd
