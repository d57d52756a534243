// x86 helpers of the refit kernel, included once per instruction set by kernels.cpp (namespaces sse and
// avx, so the AVX copy is VEX-encoded). No '#pragma once': meant to be included several times.

/// Vertex at byte offset `at` of the positions as (x, y, z, w): w is the next float of the buffer, read
/// but never used. [Limit: not the buffer's last vertex (RefitArgs::last_vertex), which may end the
/// buffer: Vertex4Last]
inline __m128 Vertex4(const char* base, size_t at) { return _mm_loadu_ps(reinterpret_cast<const float*>(base + at)); }
/// Any vertex (also the buffer's last) as (x, y, z, 0): three scalar reads.
inline __m128 Vertex4Last(const char* base, size_t at) {
  const float* p = reinterpret_cast<const float*>(base + at);
  return _mm_set_ps(0.0f, p[2], p[1], p[0]);
}

/// The four pivot centroids of sphere s as (x, y, z, ·): formulas::CentroidCoord lane-wise,
/// ((a + b) + c) · (1/3) — the same float operations in the same order as the scalar formula, so the
/// same bits in x, y and z. One vector load a vertex; the three scalar reads only for a sphere one of
/// whose 12 pivot vertices is the buffer's last (one compare of the 12 indices a sphere). Base and
/// stride are read into locals once (the stores through `out` could alias the arguments otherwise).
__attribute__((always_inline)) inline void SphereCentroids(const RefitArgs& a, uint32_t s, __m128 out[4]) {
  const char* const base = a.base;
  const size_t stride = a.stride;
  const uint32_t* idx = a.pivot_vertices + size_t{12} * s;
  const __m128i last = _mm_set1_epi32(static_cast<int>(a.last_vertex));
  const __m128i i0 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(idx));
  const __m128i i1 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(idx + 4));
  const __m128i i2 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(idx + 8));
  const __m128i at_end =
      _mm_or_si128(_mm_or_si128(_mm_cmpeq_epi32(i0, last), _mm_cmpeq_epi32(i1, last)), _mm_cmpeq_epi32(i2, last));
  const __m128 third = _mm_set1_ps(1.0f / 3.0f);
  __m128 c[4];
  if (_mm_movemask_epi8(at_end) == 0) [[likely]] {
#pragma GCC unroll 4
    for (int k = 0; k < 4; ++k)
      c[k] = _mm_mul_ps(_mm_add_ps(_mm_add_ps(Vertex4(base, idx[3 * k] * stride), Vertex4(base, idx[3 * k + 1] * stride)),
                                   Vertex4(base, idx[3 * k + 2] * stride)),
                        third);
  } else {
#pragma GCC unroll 4
    for (int k = 0; k < 4; ++k)
      c[k] = _mm_mul_ps(
          _mm_add_ps(_mm_add_ps(Vertex4Last(base, idx[3 * k] * stride), Vertex4Last(base, idx[3 * k + 1] * stride)),
                     Vertex4Last(base, idx[3 * k + 2] * stride)),
          third);
  }
#pragma GCC unroll 4
  for (int k = 0; k < 4; ++k) out[k] = c[k];
}

/// Centroids of spheres s0 .. s0 + 3 (lanes l >= n: sphere `pad` instead) transposed to SoA:
/// x[k], y[k], z[k] hold pivot k's centroid coordinate of lanes 0..3.
__attribute__((always_inline)) inline void PivotCentroids4(const RefitArgs& a, uint32_t s0, uint32_t n, uint32_t pad, __m128 x[4], __m128 y[4],
                            __m128 z[4]) {
  __m128 q[4][4];  // [lane][pivot]
#pragma GCC unroll 4
  for (uint32_t l = 0; l < 4; ++l) SphereCentroids(a, l < n ? s0 + l : pad, q[l]);
#pragma GCC unroll 4
  for (int k = 0; k < 4; ++k) {
    __m128 r0 = q[0][k], r1 = q[1][k], r2 = q[2][k], r3 = q[3][k];
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
    x[k] = r0, y[k] = r1, z[k] = r2;
  }
}
