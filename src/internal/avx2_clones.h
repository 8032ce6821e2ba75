// MULTISLIT_AVX2_CLONES: a function compiled twice, for AVX2 and for any x86-64, the version
// chosen when the program loads (an ifunc resolver). Not under ThreadSanitizer: GCC instruments
// the resolver too (__tsan_func_entry), which then runs before TSan's runtime is up and crashes
// the program in the dynamic loader; one default version there.
#pragma once

#if defined(__SANITIZE_THREAD__) || !defined(__x86_64__)
#define MULTISLIT_AVX2_CLONES
#else
#define MULTISLIT_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
#endif
