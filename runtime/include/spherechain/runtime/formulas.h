// spherechain runtime — the per-frame formulas, written once for every backend: the pivot frame and
// the refit of a sphere (paper §5.1), the overlap test and the penetration depth of two spheres (§5.2).
//
// Compiled for the host (scalar: refit.h's helpers, the baker, detect.cpp's depths), for the host's SIMD
// kernels (runtime/src/kernels.cpp includes formulas.inl once per instruction set — SSE2, AVX, AVX-512 —
// with its own lane type) and for CUDA devices (cuda/src/batch.cu: SPHERECHAIN_HD is __host__ __device__ under nvcc).
// Every backend evaluates the same operations in the same order, without FMA contraction (the runtime
// is compiled with -ffp-contract=off — GCC contracts by default in C++, and the AVX-512 kernels' target
// has FMA instructions; baseline x86-64 has none; the CUDA target is compiled with --fmad=false), so
// their spheres and pairs agree bit for bit (tests/runtime/formulas_test.cpp checks every SIMD lane
// against ScalarOps). Code of one's own that calls the scalar helpers (refit.h) with FMA enabled
// (-march=native, -mfma) should pass -ffp-contract=off as well to get the same bits.
#pragma once

#include <cmath>
#include <cstdint>

#if defined(__CUDACC__)
#define SPHERECHAIN_HD __host__ __device__
#define SPHERECHAIN_HD_INLINE __host__ __device__ __forceinline__
#elif defined(__GNUC__)
#define SPHERECHAIN_HD
#define SPHERECHAIN_HD_INLINE inline __attribute__((always_inline))  // keeps the SIMD kernels' lanes in registers
#else
#define SPHERECHAIN_HD
#define SPHERECHAIN_HD_INLINE inline
#endif

namespace spherechain::runtime::formulas {

/// One-lane operations (the scalar host path and CUDA threads): the lane type `V` is a float and the
/// comparison mask `M` a bool. The SIMD kernels provide the same names over __m128 / __m256
/// (runtime/src/kernels.cpp); formulas.inl is written against this interface only.
struct ScalarOps {
  using V = float;
  using M = bool;
  SPHERECHAIN_HD static V Set1(float v) { return v; }
  SPHERECHAIN_HD static V Sqrt(V v) {
#if defined(__CUDA_ARCH__)
    return sqrtf(v);  // IEEE round-to-nearest (the CUDA target keeps -prec-sqrt=true)
#else
    return std::sqrt(v);
#endif
  }
  SPHERECHAIN_HD static M Gt(V a, V b) { return a > b; }
  SPHERECHAIN_HD static M Lt(V a, V b) { return a < b; }
  SPHERECHAIN_HD static M And(M a, M b) { return a && b; }
  SPHERECHAIN_HD static V Blend(M m, V a, V b) { return m ? a : b; }  ///< m ? a : b per lane
};

#include "spherechain/runtime/formulas.inl"

/// One coordinate of the centroid of a triangle with corners' coordinates a, b, c: (a + b + c) · (1/3).
/// The refit's pivot centroids (TriangleCentroid3, the SIMD kernels' per-lane gather, CUDA).
SPHERECHAIN_HD_INLINE float CentroidCoord(float a, float b, float c) { return (a + b + c) * (1.0f / 3.0f); }

/// Centroid of triangle (a, b, c) [3 floats each]: CentroidCoord per coordinate.
SPHERECHAIN_HD_INLINE void TriangleCentroid3(const float a[3], const float b[3], const float c[3], float out[3]) {
  for (int k = 0; k < 3; ++k) out[k] = CentroidCoord(a[k], b[k], c[k]);
}

}  // namespace spherechain::runtime::formulas
