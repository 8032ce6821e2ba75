// PCL point type of the relative disparity map (RDMap, paper Sec. III-A).
// PCL templates that have no precompiled instantiation for PointRDM are instantiated once, in
// src/pcl_instantiations.cpp (PCL_NO_PRECOMPILE is defined there and nowhere else).
#pragma once

#include <pcl/point_types.h>
#include <pcl/register_point_struct.h>

#include <cmath>
#include <cstdint>

namespace multislit {

/// One point of a slit: where it is in space and how far it moved against the reference image.
/// x, y, z are metres in the sensor (camera) frame; u, v the reference position of the point
/// (sub-pixel column, image row); dk = u' - u the relative disparity [px], positive when the
/// surface is nearer than the reference plane; slit the slit index (0 .. 14).
// PCL_ADD_POINT4D is an anonymous struct in a union, an extension PCL's point types rely on: clang
// warns at its expansion here (GCC not, the macro being from a system header).
#if defined(__clang__)
#pragma clang diagnostic push
#pragma clang diagnostic ignored "-Wgnu-anonymous-struct"
#pragma clang diagnostic ignored "-Wnested-anon-types"
#endif
struct EIGEN_ALIGN16 PointRDM {
  PCL_ADD_POINT4D;    // x, y, z [m]
  float u;            ///< reference column [px]
  float v;            ///< reference row [px]
  float dk;           ///< relative disparity u' - u [px]
  std::int32_t slit;  ///< slit index
  PCL_MAKE_ALIGNED_OPERATOR_NEW
};
#if defined(__clang__)
#pragma clang diagnostic pop
#endif

/// True when the point has a metric position: x, y and z finite (the reference has a metric scale
/// and the point was measured).
inline bool hasXYZ(const PointRDM& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

}  // namespace multislit

POINT_CLOUD_REGISTER_POINT_STRUCT(multislit::PointRDM,
                                  (float, x, x)(float, y, y)(float, z, z)(float, u, u)(float, v, v)(
                                      float, dk, dk)(std::int32_t, slit, slit))
