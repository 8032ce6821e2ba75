// The hot kernels of the RDMap plane model: counting and summing the inliers of a plane over
// the centred arrays, and gathering the valid points of a cloud into them.
#include "plane_kernels.h"

#include "avx2_clones.h"
#include "lanes.h"

#include "rdm_simd.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace multislit::simd {

MULTISLIT_AVX2_CLONES unsigned countNear(const float* u, const float* v, const float* dk,
                                         std::size_t begin, std::size_t end, float a, float b,
                                         float c, float t) {
  unsigned count = 0;
  for (std::size_t k = begin; k < end; ++k)
    count += std::abs(dk[k] - (a * u[k] + b * v[k] + c)) <= t;
  return count;
}

// 8 points per step in float, added to double every 256 points.
MULTISLIT_AVX2_CLONES InlierSums sumInliers(const float* u, const float* v, const float* dk,
                                            std::size_t size, float a, float b, float c, float t) {
  using lanes::F8;
  using lanes::I8;
  constexpr std::size_t kLanes = 8, kFlush = 256;
  InlierSums out;
  const F8 one = {1, 1, 1, 1, 1, 1, 1, 1};
  std::size_t k = 0;
  for (; k + kLanes <= size;) {
    F8 n = {}, su = {}, sv = {}, sd = {}, suu = {}, suv = {}, svv = {}, sud = {}, svd = {},
       sdd = {};
    for (const std::size_t stop = std::min(size, k + kFlush); k + kLanes <= stop; k += kLanes) {
      F8 pu, pv, pd;
      std::memcpy(&pu, u + k, sizeof pu);
      std::memcpy(&pv, v + k, sizeof pv);
      std::memcpy(&pd, dk + k, sizeof pd);
      const F8 r = pd - (a * pu + b * pv + c);
      const I8 in = (F8)((I8)r & 0x7fffffff) <= t;  // |r| <= t: all ones, else 0
      const F8 wu = (F8)(in & (I8)pu), wv = (F8)(in & (I8)pv), wd = (F8)(in & (I8)pd);
      n += (F8)(in & (I8)one);
      su += wu;
      sv += wv;
      sd += wd;
      suu += wu * pu;
      suv += wu * pv;
      svv += wv * pv;
      sud += wu * pd;
      svd += wv * pd;
      sdd += wd * pd;
    }
    for (std::size_t l = 0; l < kLanes; ++l) {
      out.n += n[l];
      out.u += su[l];
      out.v += sv[l];
      out.dk += sd[l];
      out.uu += suu[l];
      out.uv += suv[l];
      out.vv += svv[l];
      out.udk += sud[l];
      out.vdk += svd[l];
      out.dkdk += sdd[l];
    }
  }
  for (; k < size; ++k) {  // the last points, one by one
    if (!(std::abs(dk[k] - (a * u[k] + b * v[k] + c)) <= t)) continue;
    const double pu = u[k], pv = v[k], pd = dk[k];
    out.n += 1;
    out.u += pu;
    out.v += pv;
    out.dk += pd;
    out.uu += pu * pu;
    out.uv += pu * pv;
    out.vv += pv * pv;
    out.udk += pu * pd;
    out.vdk += pv * pd;
    out.dkdk += pd * pd;
  }
  return out;
}

// Four points at a time: their (u, v, dk, slit) transposed into one register per field, then
// stored four at once when all four are valid (nearly always).
std::size_t gatherValidByFour(const PointRDM* points, std::size_t n, pcl::index_t* index, float* u,
                              float* v, float* dk) {
  std::size_t kept = 0;
  for (std::size_t k = 0; k < n; k += 4) {
    const simd::UVDK4 p = simd::loadUVDK(points[k], points[k + 1], points[k + 2], points[k + 3]);
    const int valid = simd::validMask(p);
    const auto i = static_cast<pcl::index_t>(k);
    if (valid == 0xf) {
      _mm_storeu_si128(reinterpret_cast<__m128i*>(index + kept),
                       _mm_setr_epi32(i, i + 1, i + 2, i + 3));
      _mm_storeu_ps(u + kept, p.u);
      _mm_storeu_ps(v + kept, p.v);
      _mm_storeu_ps(dk + kept, p.dk);
      kept += 4;
      continue;
    }
    alignas(16) float lu[4], lv[4], ldk[4];
    _mm_store_ps(lu, p.u);
    _mm_store_ps(lv, p.v);
    _mm_store_ps(ldk, p.dk);
    for (int j = 0; j < 4; ++j) {  // as in cacheValidPoints()
      index[kept] = i + j;
      u[kept] = lu[j];
      v[kept] = lv[j];
      dk[kept] = ldk[j];
      kept += (valid >> j) & 1;
    }
  }
  return kept;
}

}  // namespace multislit::simd
