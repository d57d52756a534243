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

/// JointRefitArgs' records [begin, end), each blending its first N influences (see JointRefitArgs):
/// rows as 4-float vectors (SSE2: three; AVX: rows 0–1 in one 8-float vector, row 2 in a 4-float one),
/// w_i broadcast, M = ((w0·M0 + w1·M1) + w2·M2) + w3·M3 row-wise; the transform multiplies each row by
/// (bx, by, bz, 1) and adds lanes as (ρ0 + ρ1) + (ρ2 + ρ3) — the SSE2 kernel through a 4×4 transpose,
/// the AVX one with in-lane swaps (lane 0 of each row: (ρ0 + ρ1) + (ρ2 + ρ3), the same two roundings).
template <int N>
__attribute__((always_inline)) inline void JointGroup(const JointRefitArgs& a, uint32_t begin, uint32_t end) {
  const float* __restrict M = a.matrices;
  float* __restrict x = a.x;
  float* __restrict y = a.y;
  float* __restrict z = a.z;
  for (uint32_t k = begin; k < end; ++k) {
    const uint32_t* off = a.offsets + size_t{4} * k;
    const float* w = a.weights + size_t{4} * k;
    const uint32_t s = a.sphere[k];
    if constexpr (kW == 4) {
      const float* m = M + off[0];
      __m128 wk = _mm_set1_ps(w[0]);
      __m128 r0 = _mm_mul_ps(wk, _mm_loadu_ps(m)), r1 = _mm_mul_ps(wk, _mm_loadu_ps(m + 4)),
             r2 = _mm_mul_ps(wk, _mm_loadu_ps(m + 8));
#pragma GCC unroll 4
      for (int i = 1; i < N; ++i) {
        m = M + off[i];
        wk = _mm_set1_ps(w[i]);
        r0 = _mm_add_ps(r0, _mm_mul_ps(wk, _mm_loadu_ps(m)));
        r1 = _mm_add_ps(r1, _mm_mul_ps(wk, _mm_loadu_ps(m + 4)));
        r2 = _mm_add_ps(r2, _mm_mul_ps(wk, _mm_loadu_ps(m + 8)));
      }
      const __m128 p = _mm_loadu_ps(a.bind + size_t{4} * k);
      __m128 a0 = _mm_mul_ps(r0, p), a1 = _mm_mul_ps(r1, p), a2 = _mm_mul_ps(r2, p), a3 = _mm_setzero_ps();
      _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
      const __m128 c = _mm_add_ps(_mm_add_ps(a0, a1), _mm_add_ps(a2, a3));
      _mm_store_ss(x + s, c);
      _mm_store_ss(y + s, _mm_shuffle_ps(c, c, 1));
      _mm_store_ss(z + s, _mm_shuffle_ps(c, c, 2));
    } else {
      const float* m = M + off[0];
      __m256 wk = _mm256_broadcast_ss(w);
      __m256 r01 = _mm256_mul_ps(wk, _mm256_loadu_ps(m));
      __m128 r2 = _mm_mul_ps(_mm256_castps256_ps128(wk), _mm_loadu_ps(m + 8));
#pragma GCC unroll 4
      for (int i = 1; i < N; ++i) {
        m = M + off[i];
        wk = _mm256_broadcast_ss(w + i);
        r01 = _mm256_add_ps(r01, _mm256_mul_ps(wk, _mm256_loadu_ps(m)));
        r2 = _mm_add_ps(r2, _mm_mul_ps(_mm256_castps256_ps128(wk), _mm_loadu_ps(m + 8)));
      }
      const __m128 p = _mm_loadu_ps(a.bind + size_t{4} * k);
      const __m256 v01 = _mm256_mul_ps(r01, _mm256_set_m128(p, p));
      const __m128 v2 = _mm_mul_ps(r2, p);
      const __m256 t01 = _mm256_add_ps(v01, _mm256_permute_ps(v01, 0xB1));  // (ρ0 + ρ1, ·, ρ2 + ρ3, ·)
      const __m128 t2 = _mm_add_ps(v2, _mm_permute_ps(v2, 0xB1));
      const __m256 u01 = _mm256_add_ps(t01, _mm256_permute_ps(t01, 0x4E));   // lane 0: (ρ0 + ρ1) + (ρ2 + ρ3)
      const __m128 u2 = _mm_add_ps(t2, _mm_permute_ps(t2, 0x4E));
      _mm_store_ss(x + s, _mm256_castps256_ps128(u01));
      _mm_store_ss(y + s, _mm256_extractf128_ps(u01, 1));
      _mm_store_ss(z + s, u2);
    }
  }
}

/// All of JointRefitArgs' records: one fixed-count loop per influence group.
inline void JointRefit(const JointRefitArgs& a) {
  JointGroup<1>(a, 0, a.group_end[0]);
  JointGroup<2>(a, a.group_end[0], a.group_end[1]);
  JointGroup<3>(a, a.group_end[1], a.group_end[2]);
  JointGroup<4>(a, a.group_end[2], a.group_end[3]);
}

/// True when the n floats at p [Limit: n a multiple of 4] are all finite: x · 0 is ±0 for a finite x and
/// NaN for a NaN or ±inf, and a sum of ±0 stays ±0 while a NaN stays NaN — so Σ x · 0 is NaN exactly when
/// some x is not finite (four accumulators of kW lanes, then 4 lanes at a time).
inline bool Finite(const float* p, uint32_t n) {
  const V zero = Set1(0.0f);
  V a0 = zero, a1 = zero, a2 = zero, a3 = zero;
  uint32_t i = 0;
  for (; i + 4 * kW <= n; i += 4 * kW) {
    a0 = a0 + Load(p + i) * zero;
    a1 = a1 + Load(p + i + kW) * zero;
    a2 = a2 + Load(p + i + 2 * kW) * zero;
    a3 = a3 + Load(p + i + 3 * kW) * zero;
  }
  for (; i + kW <= n; i += kW) a0 = a0 + Load(p + i) * zero;
  const V sum = (a0 + a1) + (a2 + a3);
  alignas(64) float lanes[kW];
  Store(lanes, sum);
  float total = 0.0f;
  for (uint32_t l = 0; l < kW; ++l) total += lanes[l];
  for (; i < n; ++i) total += p[i] * 0.0f;
  return total == total;
}
