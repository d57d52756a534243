// AVX-512 kernels (16 lanes, mask registers, two-source permutes), included once by kernels.cpp inside
// namespace avx512 — compiled for AVX-512 F/VL/DQ/BW there, after Ops and formulas.inl — and picked at
// Model::Init only when the CPU has them (kernels::Supported). No '#pragma once'.
// The per-sphere and per-pair arithmetic is formulas.inl's, in the same order and without FMA, so every
// lane gives the scalar formula's bits (tests/runtime/formulas_test.cpp, kernels_test.cpp); what differs
// from the SSE2 / AVX kernels is only how the operands reach the lanes.

inline __m512 Set1(float v) { return _mm512_set1_ps(v); }

// ---- RefitJob ----------------------------------------------------------------------------------------

/// Four vertices, one per 128-bit lane, (x, y, z, next float): lane q from byte offset off[12 q].
__attribute__((always_inline)) inline __m512 Quad(const char* base, const uint32_t* off) {
  __m512 v = _mm512_castps128_ps512(_mm_loadu_ps(reinterpret_cast<const float*>(base + off[0])));
  v = _mm512_insertf32x4(v, _mm_loadu_ps(reinterpret_cast<const float*>(base + off[12])), 1);
  v = _mm512_insertf32x4(v, _mm_loadu_ps(reinterpret_cast<const float*>(base + off[24])), 2);
  v = _mm512_insertf32x4(v, _mm_loadu_ps(reinterpret_cast<const float*>(base + off[36])), 3);
  return v;
}

/// Refit of spheres [begin, end), 16 at a time. Per chunk of 16 spheres: the 192 pivot-vertex indices
/// times the stride in four vector multiplies (byte offsets fit 32 bits: checked once), then per group
/// of 4 spheres and pivot k the three corners as 4-vertex vectors (one 128-bit lane a sphere), summed and
/// scaled lane-wise — formulas::CentroidCoord's ((a + b) + c) · (1/3) per coordinate, as the SSE2 / AVX
/// kernels do it — and transposed to SoA by two-source permutes (7 per pivot for 16 spheres); then
/// formulas.inl's RefitLanes on 16 lanes. A chunk that is not full, or reads the buffer's last vertex
/// (which may end the buffer: the 4-float read would pass it), or offsets beyond 32 bits go to the AVX
/// kernel (`tail`), which gives the same bits.
void Refit(const RefitArgs& a, uint32_t begin, uint32_t end, void (*tail)(const RefitArgs&, uint32_t, uint32_t)) {
  if (uint64_t{a.last_vertex} * a.stride > 0xffffffffull - 16) return tail(a, begin, end);
  const char* const base = a.base;
  const __m512i stride = _mm512_set1_epi32(static_cast<int>(a.stride));
  const __m512i last = _mm512_set1_epi32(static_cast<int>(a.last_vertex));
  const __m512 third = _mm512_set1_ps(1.0f / 3.0f);
  // Lane selections: x and y of pivot centroids of spheres 0–3 / 4–7 (first source) and 8–11 / 12–15
  // (second), then the halves joined.
  const __m512i sel_xy = _mm512_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28, 1, 5, 9, 13, 17, 21, 25, 29);
  const __m512i sel_z = _mm512_setr_epi32(2, 6, 10, 14, 18, 22, 26, 30, 2, 6, 10, 14, 18, 22, 26, 30);
  const __m512i lo = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 16, 17, 18, 19, 20, 21, 22, 23);
  const __m512i hi = _mm512_setr_epi32(8, 9, 10, 11, 12, 13, 14, 15, 24, 25, 26, 27, 28, 29, 30, 31);
  alignas(64) uint32_t off[192];  // [lane][12]: byte offset of the lane's pivot vertex v
  uint32_t s0 = begin;
  for (; s0 + 16 <= end; s0 += 16) {
    const uint32_t* idx = a.pivot_vertices + size_t{12} * s0;
    __mmask16 at_end = 0;
#pragma GCC unroll 12
    for (int i = 0; i < 12; ++i) {
      const __m512i v = _mm512_loadu_si512(idx + 16 * i);
      at_end |= _mm512_cmpeq_epi32_mask(v, last);
      _mm512_store_si512(off + 16 * i, _mm512_mullo_epi32(v, stride));
    }
    if (at_end) [[unlikely]] {
      tail(a, s0, s0 + 16);
      continue;
    }
    __m512 px[4], py[4], pz[4];
#pragma GCC unroll 4
    for (int k = 0; k < 4; ++k) {
      __m512 c[4];  // group q: spheres 4q .. 4q+3, one per 128-bit lane (x, y, z, ·)
#pragma GCC unroll 4
      for (int q = 0; q < 4; ++q) {
        const uint32_t* o = off + 48 * q + 3 * k;
        c[q] = ((Quad(base, o) + Quad(base, o + 1)) + Quad(base, o + 2)) * third;
      }
      const __m512 xy01 = _mm512_permutex2var_ps(c[0], sel_xy, c[1]), xy23 = _mm512_permutex2var_ps(c[2], sel_xy, c[3]);
      const __m512 z01 = _mm512_permutex2var_ps(c[0], sel_z, c[1]), z23 = _mm512_permutex2var_ps(c[2], sel_z, c[3]);
      px[k] = _mm512_permutex2var_ps(xy01, lo, xy23);
      py[k] = _mm512_permutex2var_ps(xy01, hi, xy23);
      pz[k] = _mm512_permutex2var_ps(z01, lo, z23);
    }
    __m512 c[4];
    RefitLanes<Ops>(px, py, pz, _mm512_loadu_ps(a.local_x + s0), _mm512_loadu_ps(a.local_y + s0),
                    _mm512_loadu_ps(a.local_z + s0), _mm512_loadu_ps(a.offset_x + s0), _mm512_loadu_ps(a.offset_y + s0),
                    _mm512_loadu_ps(a.offset_z + s0), _mm512_loadu_ps(a.radius_scale + s0), a.frame_mode, c);
    _mm512_storeu_ps(a.x + s0, c[0]);
    _mm512_storeu_ps(a.y + s0, c[1]);
    _mm512_storeu_ps(a.z + s0, c[2]);
    _mm512_storeu_ps(a.r + s0, c[3]);
  }
  if (s0 < end) tail(a, s0, end);
}

// ---- DetectJob ---------------------------------------------------------------------------------------

/// One array of the gather (see GatherArgs): out[g] = src[idx[g]] (+ margin), g < n (a multiple of 8),
/// by two-source permutes over the sources held in registers (32 floats a permute: ids >> 5 pick it);
/// id #S (padding) gives NaN.
__attribute__((always_inline)) inline void GatherOne(const __m512* src, uint32_t pairs, uint32_t S,
                                                     const uint32_t* idx, uint32_t n, bool grow, __m512 margin,
                                                     float* out) {
  const __m512i pad = _mm512_set1_epi32(static_cast<int>(S));
  const __m512 nan = _mm512_set1_ps(__builtin_nanf(""));
  for (uint32_t g = 0; g < n; g += 16) {
    const __mmask16 m = n - g >= 16 ? __mmask16(0xffff) : __mmask16(0x00ff);
    const __m512i id = _mm512_maskz_loadu_epi32(m, idx + g);
    const __m512i pair = _mm512_srli_epi32(id, 5);
    __m512 v = _mm512_permutex2var_ps(src[0], id, src[1]);
    for (uint32_t q = 1; q < pairs; ++q)
      v = _mm512_mask_mov_ps(v, _mm512_cmpeq_epi32_mask(pair, _mm512_set1_epi32(static_cast<int>(q))),
                             _mm512_permutex2var_ps(src[2 * q], id, src[2 * q + 1]));
    if (grow) v = v + margin;
    v = _mm512_mask_mov_ps(v, _mm512_cmpeq_epi32_mask(id, pad), nan);
    _mm512_mask_storeu_ps(out + g, m, v);
  }
}

/// Per block of 8 lanes, 8 blocks (64 values in 4 vectors, two blocks each) → 8 values: the minimum
/// (`max` false) or maximum over each block's lanes, by three levels of two-source permutes (no NaN in
/// the inputs).
__attribute__((always_inline)) inline __m256 Reduce8(const __m512 v[4], bool max) {
  const __m512i lo4 = _mm512_setr_epi32(0, 1, 2, 3, 8, 9, 10, 11, 16, 17, 18, 19, 24, 25, 26, 27);
  const __m512i hi4 = _mm512_setr_epi32(4, 5, 6, 7, 12, 13, 14, 15, 20, 21, 22, 23, 28, 29, 30, 31);
  const __m512i lo2 = _mm512_setr_epi32(0, 1, 4, 5, 8, 9, 12, 13, 16, 17, 20, 21, 24, 25, 28, 29);
  const __m512i hi2 = _mm512_setr_epi32(2, 3, 6, 7, 10, 11, 14, 15, 18, 19, 22, 23, 26, 27, 30, 31);
  const __m512i even = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 0, 2, 4, 6, 8, 10, 12, 14);
  const __m512i odd = _mm512_setr_epi32(1, 3, 5, 7, 9, 11, 13, 15, 1, 3, 5, 7, 9, 11, 13, 15);
  auto op = [max](__m512 a, __m512 b) { return max ? _mm512_max_ps(a, b) : _mm512_min_ps(a, b); };
  // Blocks 0–3: 4 lanes each; blocks 4–7 the same.
  const __m512 a = op(_mm512_permutex2var_ps(v[0], lo4, v[1]), _mm512_permutex2var_ps(v[0], hi4, v[1]));
  const __m512 b = op(_mm512_permutex2var_ps(v[2], lo4, v[3]), _mm512_permutex2var_ps(v[2], hi4, v[3]));
  const __m512 c = op(_mm512_permutex2var_ps(a, lo2, b), _mm512_permutex2var_ps(a, hi2, b));  // 2 lanes a block
  return _mm512_castps512_ps256(op(_mm512_permutexvar_ps(even, c), _mm512_permutexvar_ps(odd, c)));
}

/// The gather and the block boxes (GatherArgs) for #S <= kMaxGatherSpheres: each of x, y, z, r loaded
/// into at most 16 registers once (masked: nothing read past #S) and permuted into slot order; then the
/// boxes 8 blocks at a time from the gathered slots, NaN lanes (and slots past the blocks) replaced by
/// the neutral bound (+inf for a minimum, −inf for a maximum, 0 for the largest |r|), as BlockBoxes skips
/// them.
bool GatherBoxes(const GatherArgs& a) {
  const uint32_t S = a.sphere_count;
  if (S > kMaxGatherSpheres) return false;
  const uint32_t pairs = (S + 31) / 32, slots = 8 * a.blocks;
  const __m512 margin = _mm512_set1_ps(a.margin);
  const float* in[4] = {a.x, a.y, a.z, a.r};
  float* out[4] = {a.gx, a.gy, a.gz, a.gr};
  for (int c = 0; c < 4; ++c) {
    __m512 src[kMaxGatherSpheres / 16];
    for (uint32_t i = 0; i < 2 * pairs; ++i) {
      const uint32_t first = 16 * i;
      const __mmask16 m = first >= S ? __mmask16(0) : S - first >= 16 ? __mmask16(0xffff) : __mmask16((1u << (S - first)) - 1);
      src[i] = _mm512_maskz_loadu_ps(m, in[c] + first);
    }
    GatherOne(src, pairs, S, a.src, slots, c == 3, margin, out[c]);
  }
  const __m512 inf = _mm512_set1_ps(__builtin_inff()), ninf = _mm512_set1_ps(-__builtin_inff());
  const __m512 zero = _mm512_setzero_ps();
  float* lo[3] = {a.lx, a.ly, a.lz};
  float* hi[3] = {a.hx, a.hy, a.hz};
  for (uint32_t I0 = 0; I0 < a.blocks; I0 += 8) {
    __mmask16 valid[4];
    for (uint32_t q = 0; q < 4; ++q) {
      const uint32_t first = 8 * I0 + 16 * q;
      valid[q] = first >= slots ? __mmask16(0) : slots - first >= 16 ? __mmask16(0xffff) : __mmask16(0x00ff);
    }
    for (int c = 0; c < 3; ++c) {
      __m512 l[4], h[4];
      for (uint32_t q = 0; q < 4; ++q) {
        const __m512 v = _mm512_maskz_loadu_ps(valid[q], out[c] + 8 * I0 + 16 * q);
        const __mmask16 ok = valid[q] & _mm512_cmp_ps_mask(v, v, _CMP_ORD_Q);
        l[q] = _mm512_mask_mov_ps(inf, ok, v), h[q] = _mm512_mask_mov_ps(ninf, ok, v);
      }
      _mm256_storeu_ps(lo[c] + I0, Reduce8(l, false));
      _mm256_storeu_ps(hi[c] + I0, Reduce8(h, true));
    }
    __m512 rv[4];
    for (uint32_t q = 0; q < 4; ++q) {
      const __m512 v = _mm512_maskz_loadu_ps(valid[q], a.gr + 8 * I0 + 16 * q);
      const __mmask16 ok = valid[q] & _mm512_cmp_ps_mask(v, v, _CMP_ORD_Q);
      rv[q] = _mm512_mask_mov_ps(zero, ok, _mm512_abs_ps(v));
    }
    _mm256_storeu_ps(a.br + I0, Reduce8(rv, true));
  }
  return true;
}

/// Row blocks [begin, end) of the broad phase (see BroadPhaseArgs), in two passes over a short list:
/// first the block-pair tests of each row, 16 blocks J at a time (the same per-lane operations as
/// kernels.inl's BlockRow, so the same pairs are kept and the same counters come out), the kept pairs
/// appended as I << 16 | J (register compress); then per kept pair its 64 sphere tests as four 16-lane
/// tests — rows 2p and 2p + 1 of block I (broadcast) against the 8 spheres of block J repeated — without
/// the 8-lane kernels' row cull (the sphere test alone decides a hit, so the same hits come out). One
/// loop over the kept pairs instead of a loop per row: fewer unpredictable branches.
uint32_t BlockRows(const BroadPhaseArgs& a, uint32_t begin, uint32_t end, uint64_t* keys, uint32_t* box_tests,
                   uint32_t* sphere_tests) {
  const float* __restrict x = a.x;
  const float* __restrict y = a.y;
  const float* __restrict z = a.z;
  const float* __restrict r = a.r;
  const __m512 zero = _mm512_setzero_ps();
  const __m512i iota = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  const __m512i pair_sel = _mm512_setr_epi32(0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1);
  constexpr uint32_t kList = 256;
  alignas(64) uint32_t list[kList + 16];
  uint32_t hits = 0, boxes = 0, spheres = 0, n = 0;
  auto test_pairs = [&] {
    for (uint32_t e = 0; e < n; ++e) {
      const uint32_t I = list[e] >> 16, J = list[e] & 0xffffu;
      const uint64_t allow = a.allowed[size_t{I} * a.blocks + J];
      spheres += static_cast<uint32_t>(std::popcount(allow));
      const uint32_t row = 8 * I, col = 8 * J;
      const __m512 cx = _mm512_broadcast_f32x8(_mm256_loadu_ps(x + col)), cy = _mm512_broadcast_f32x8(_mm256_loadu_ps(y + col));
      const __m512 cz = _mm512_broadcast_f32x8(_mm256_loadu_ps(z + col)), cr = _mm512_broadcast_f32x8(_mm256_loadu_ps(r + col));
      const __m512 bx = _mm512_castps256_ps512(_mm256_loadu_ps(x + row)), by = _mm512_castps256_ps512(_mm256_loadu_ps(y + row));
      const __m512 bz = _mm512_castps256_ps512(_mm256_loadu_ps(z + row)), br = _mm512_castps256_ps512(_mm256_loadu_ps(r + row));
      uint64_t bits = 0;
#pragma GCC unroll 4
      for (uint32_t p = 0; p < 4; ++p) {  // rows 2p (lanes 0–7) and 2p + 1 (lanes 8–15)
        const __m512i sel = _mm512_add_epi32(pair_sel, _mm512_set1_epi32(static_cast<int>(2 * p)));
        bits |= uint64_t{OverlapLanes<Ops>(_mm512_permutexvar_ps(sel, bx), _mm512_permutexvar_ps(sel, by),
                                           _mm512_permutexvar_ps(sel, bz), _mm512_permutexvar_ps(sel, br), cx, cy,
                                           cz, cr)} << (16 * p);
      }
      bits &= allow;  // bit 8·row + lane, as `allowed`
      while (bits) [[unlikely]] {
        const uint32_t b = static_cast<uint32_t>(std::countr_zero(bits));
        bits &= bits - 1;
        const uint32_t sa = a.order[row + (b >> 3)], sb = a.order[col + (b & 7)];
        const uint64_t first_chain = a.m1 ? static_cast<uint32_t>(std::countr_zero(a.chain_mask[sa] & a.chain_mask[sb])) : 0u;
        keys[hits++] = first_chain << 32 | (sa < sb ? (sa << 16 | sb) : (sb << 16 | sa));
      }
    }
    n = 0;
  };
  for (uint32_t I = begin; I < end; ++I) {
    const __m512 lxi = Set1(a.lx[I]), hxi = Set1(a.hx[I]), lyi = Set1(a.ly[I]), hyi = Set1(a.hy[I]);
    const __m512 lzi = Set1(a.lz[I]), hzi = Set1(a.hz[I]), bri = Set1(a.br[I]);
    const uint8_t* live = a.live + size_t{I} * a.live_stride;
    for (uint32_t c = 0, J0 = I; J0 < a.blocks; c += 2, J0 += 16) {
      uint32_t near = live[c];
      if (c + 1 < a.live_stride) near |= uint32_t{live[c + 1]} << 8;
      if (!near) continue;
      boxes += static_cast<uint32_t>(std::popcount(near));
      const __mmask16 m = static_cast<__mmask16>(near);  // live blocks only: nothing read past the boxes
      const __m512 gx = _mm512_max_ps(_mm512_maskz_loadu_ps(m, a.lx + J0) - hxi, _mm512_max_ps(lxi - _mm512_maskz_loadu_ps(m, a.hx + J0), zero));
      const __m512 gy = _mm512_max_ps(_mm512_maskz_loadu_ps(m, a.ly + J0) - hyi, _mm512_max_ps(lyi - _mm512_maskz_loadu_ps(m, a.hy + J0), zero));
      const __m512 gz = _mm512_max_ps(_mm512_maskz_loadu_ps(m, a.lz + J0) - hzi, _mm512_max_ps(lzi - _mm512_maskz_loadu_ps(m, a.hz + J0), zero));
      const __m512 rb = _mm512_maskz_loadu_ps(m, a.br + J0) + bri;
      const __mmask16 kept = m & _mm512_cmp_ps_mask(gx * gx + gy * gy + gz * gz, rb * rb, _CMP_LT_OQ);
      const __m512i ids = _mm512_add_epi32(iota, _mm512_set1_epi32(static_cast<int>(I << 16 | J0)));
      _mm512_storeu_si512(list + n, _mm512_maskz_compress_epi32(kept, ids));
      n += static_cast<uint32_t>(std::popcount(static_cast<uint32_t>(kept)));
      if (n > kList - 16) test_pairs();
    }
  }
  test_pairs();
  *box_tests = boxes;
  *sphere_tests = spheres;
  return hits;
}

// ---- JointRefitJob -----------------------------------------------------------------------------------

/// Records [begin, end) with N influences each: the 3×4 matrix as one 12-float vector (masked load:
/// nothing read past the last matrix), M = ((w0·M0 + w1·M1) + w2·M2) + w3·M3, times (b, 1) repeated per
/// row, then per 128-bit lane (ρ0 + ρ1) + (ρ2 + ρ3) by two in-lane swaps (the SSE2 kernel's roundings).
template <int N>
__attribute__((always_inline)) inline void JointGroup(const JointRefitArgs& a, uint32_t begin, uint32_t end) {
  const float* __restrict M = a.matrices;
  float* __restrict x = a.x;
  float* __restrict y = a.y;
  float* __restrict z = a.z;
  constexpr __mmask16 k12 = 0x0fff;
  for (uint32_t k = begin; k < end; ++k) {
    const uint32_t* off = a.offsets + size_t{4} * k;
    const float* w = a.weights + size_t{4} * k;
    __m512 m = _mm512_set1_ps(w[0]) * _mm512_maskz_loadu_ps(k12, M + off[0]);
#pragma GCC unroll 4
    for (int i = 1; i < N; ++i) m = m + _mm512_set1_ps(w[i]) * _mm512_maskz_loadu_ps(k12, M + off[i]);
    const __m512 v = m * _mm512_broadcast_f32x4(_mm_loadu_ps(a.bind + size_t{4} * k));
    const __m512 t = v + _mm512_permute_ps(v, 0xB1);
    const __m512 u = t + _mm512_permute_ps(t, 0x4E);
    const uint32_t s = a.sphere[k];
    _mm_store_ss(x + s, _mm512_castps512_ps128(u));
    _mm_store_ss(y + s, _mm512_extractf32x4_ps(u, 1));
    _mm_store_ss(z + s, _mm512_extractf32x4_ps(u, 2));
  }
}

void JointRefit(const JointRefitArgs& a) {
  JointGroup<1>(a, 0, a.group_end[0]);
  JointGroup<2>(a, a.group_end[0], a.group_end[1]);
  JointGroup<3>(a, a.group_end[1], a.group_end[2]);
  JointGroup<4>(a, a.group_end[2], a.group_end[3]);
}

/// All n floats finite (n a multiple of 4): Σ x · 0 over 16 lanes, four accumulators, masked tail.
bool Finite(const float* p, uint32_t n) {
  const __m512 zero = _mm512_setzero_ps();
  __m512 a0 = zero, a1 = zero, a2 = zero, a3 = zero;
  uint32_t i = 0;
  for (; i + 64 <= n; i += 64) {
    a0 = a0 + _mm512_loadu_ps(p + i) * zero;
    a1 = a1 + _mm512_loadu_ps(p + i + 16) * zero;
    a2 = a2 + _mm512_loadu_ps(p + i + 32) * zero;
    a3 = a3 + _mm512_loadu_ps(p + i + 48) * zero;
  }
  for (; i < n; i += 16) {
    const __mmask16 m = n - i >= 16 ? __mmask16(0xffff) : __mmask16((1u << (n - i)) - 1);
    a0 = a0 + _mm512_maskz_loadu_ps(m, p + i) * zero;
  }
  const __m512 sum = (a0 + a1) + (a2 + a3);
  return _mm512_cmp_ps_mask(sum, sum, _CMP_UNORD_Q) == 0;
}
