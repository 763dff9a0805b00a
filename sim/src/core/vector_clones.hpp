// SIMREEL_VECTOR_CLONES: build a hot element-wise kernel three times, for AVX-512 (8 doubles a
// vector, 32 registers), for AVX2 (4 doubles, 16 registers) and for the baseline x86-64 (SSE2),
// and pick one at load time (GCC function multi-versioning, an ELF ifunc).
//
// Why this cannot change results: the build uses -ffp-contract=off, so although AVX-512F has
// fused multiply-add instructions (and the "avx2" clone does not enable FMA) no multiply and add
// are ever fused, and every lane performs the same IEEE single/double operations in the same
// order as the baseline clone; only the vector width differs. Kernels marked with it must stay
// element-wise (no reductions whose order depends on the width, other than bitwise OR/AND), so
// frames are bit-identical on machines with and without AVX2 or AVX-512: the determinism pins
// and goldens of tests/, recorded where the AVX2 clone ran, pass where the AVX-512 one runs.
// Issue 19: the AVX-512 clone made the resting-on-a-plane lanes and the curl noise 1.4x faster
// on a Xeon with AVX-512 (the AVX2 lanes spilled for want of registers).
#pragma once

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__ELF__) && \
    !defined(SIMREEL_NO_VECTOR_CLONES)
#define SIMREEL_VECTOR_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
/// 1 where GCC's per-function targets work (x86-64 ELF): a kernel that a compiler cannot
/// vectorise by itself (a compress) may then carry a hand-written AVX-512 form beside its
/// scalar one, picked at run time by __builtin_cpu_supports.
#define SIMREEL_HAS_VECTOR_CLONES 1
#else
#define SIMREEL_VECTOR_CLONES
#define SIMREEL_HAS_VECTOR_CLONES 0
#endif

#if SIMREEL_HAS_VECTOR_CLONES
/// True where the CPU runs AVX-512F, the target of the 512-bit hand-written forms (row_lanes.cpp,
/// noise.cpp); callers keep the answer in a static.
inline bool cpu_has_avx512f() {
  __builtin_cpu_init();  // (may run before the constructors that would do it)
  return __builtin_cpu_supports("avx512f");
}

/// True where the CPU runs AVX2, the target of the four-lane hand-written forms (the pair
/// searches, the plane tests, the row kernels); callers keep the answer in a static.
inline bool cpu_has_avx2() {
  __builtin_cpu_init();  // (may run before the constructors that would do it)
  return __builtin_cpu_supports("avx2");
}

/// True where the CPU runs AVX-512F with AVX-512VL, the target of the hand-written forms beside
/// scalar ones (pair_forces.cpp, particle_pairs.cpp); callers keep the answer in a static.
inline bool cpu_has_avx512vl() {
  __builtin_cpu_init();  // (may run before the constructors that would do it)
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
}
#endif
