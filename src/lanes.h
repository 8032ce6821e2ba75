// Eight float or 32-bit integer lanes in GCC's vector extension (one AVX register, or two SSE
// ones), for the kernels compiled twice by MULTISLIT_AVX2_CLONES. Private to the core library. A
// function that takes or returns them must be inlined into such a kernel, and its file must
// silence -Wpsabi: compiled for plain x86-64, GCC warns that their ABI needs AVX.
#pragma once

#include <cstdint>

namespace multislit::lanes {

typedef float F8 __attribute__((vector_size(32)));
typedef std::int32_t I8 __attribute__((vector_size(32)));
typedef std::uint32_t U8 __attribute__((vector_size(32)));

}  // namespace multislit::lanes
