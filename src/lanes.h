// Eight float or 32-bit integer lanes in GCC's vector extension (one AVX register, or two SSE
// ones), for the kernels compiled twice by MULTISLIT_AVX2_CLONES. Private to the core library. A
// function that returns them must be inlined into such a kernel, and its file must silence
// -Wpsabi (compiled for plain x86-64, GCC warns that their ABI needs AVX); it takes them by
// reference, as by value GCC notes an ABI change even then.
#pragma once

#include <cstdint>

namespace multislit::lanes {

typedef float F8 __attribute__((vector_size(32)));
typedef std::int32_t I8 __attribute__((vector_size(32)));
typedef std::uint32_t U8 __attribute__((vector_size(32)));

}  // namespace multislit::lanes
