// SIMREEL_VECTOR_CLONES: build a hot element-wise kernel twice, for AVX2 and for the baseline
// x86-64 (SSE2), and pick one at load time (GCC function multi-versioning, an ELF ifunc).
//
// Why this cannot change results: the build uses -ffp-contract=off and the "avx2" clone does not
// enable FMA, so every lane performs the same IEEE single/double operations in the same order as
// the baseline clone; only the vector width differs. Kernels marked with it must stay
// element-wise (no reductions whose order depends on the width, other than bitwise OR/AND), so
// frames are bit-identical on machines with and without AVX2.
#pragma once

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__ELF__) && \
    !defined(SIMREEL_NO_VECTOR_CLONES)
#define SIMREEL_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define SIMREEL_VECTOR_CLONES
#endif
