// Four RDMap points at a time in SSE registers (private to the library).
#pragma once

#include "multislit/point_types.h"

#include <immintrin.h>

#include <cstddef>

namespace multislit::simd {

static_assert(offsetof(PointRDM, v) == offsetof(PointRDM, u) + 4 &&
                  offsetof(PointRDM, dk) == offsetof(PointRDM, u) + 8 &&
                  offsetof(PointRDM, slit) == offsetof(PointRDM, u) + 12,
              "loadUVDK() reads u, v, dk and slit as four adjacent 32-bit fields");

/// u, v and dk of four points, one register per field (lane j: point j).
struct UVDK4 {
  __m128 u, v, dk;
};

/// Loads (u, v, dk, slit) of each point, adjacent in PointRDM, and transposes them.
inline UVDK4 loadUVDK(const PointRDM& p0, const PointRDM& p1, const PointRDM& p2,
                      const PointRDM& p3) {
  __m128 u = _mm_loadu_ps(&p0.u), v = _mm_loadu_ps(&p1.u), dk = _mm_loadu_ps(&p2.u),
         slit = _mm_loadu_ps(&p3.u);
  _MM_TRANSPOSE4_PS(u, v, dk, slit);
  return {u, v, dk};
}

/// planeResidual() of the four points, dk - (a u + b v + c), with its float operations in its
/// order: the same bits.
inline __m128 planeResiduals(const UVDK4& p, __m128 a, __m128 b, __m128 c) {
  return _mm_sub_ps(p.dk, _mm_add_ps(_mm_add_ps(_mm_mul_ps(a, p.u), _mm_mul_ps(b, p.v)), c));
}

/// isValidRDMPoint() of the four points: bit j set when point j is valid.
inline int validMask(const UVDK4& p) {
  const __m128 finite =
      _mm_add_ps(_mm_add_ps(_mm_sub_ps(p.u, p.u), _mm_sub_ps(p.v, p.v)), _mm_sub_ps(p.dk, p.dk));
  return _mm_movemask_ps(_mm_cmpeq_ps(finite, _mm_setzero_ps()));
}

}  // namespace multislit::simd
