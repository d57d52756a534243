// Kernel bodies, included once per instruction set by kernels.cpp inside a namespace that defines:
//   V (a vector of kW floats), M (its comparison mask), kW, Set1, Load, Store, Sqrt, Gt, Blend, And,
//   Min / Max (a op b, else b when either is NaN: minps / maxps), Abs, LtMask (bit k ⇔ lane k a < b),
//   and Overlap8 (the 8-lane overlap bit mask of one row sphere against 8 spheres).
// and Ops (formulas.inl's lane interface, with formulas.inl included after it: RefitLanes, OverlapLanes).
// No '#pragma once': meant to be included several times. The per-sphere formulas are not written here:
// they are formulas.inl's (the same text the scalar path and CUDA compile), so the results are
// bit-identical across variants (tests/runtime/formulas_test.cpp checks every lane).

// Refit of spheres [begin, end), kW at a time: the centroids of the 12 pivot vertices of each lane's
// sphere (formulas::CentroidCoord per coordinate; PivotCentroids, per instruction set) in SoA registers,
// then RefitLanes — the frame, the centre and the radius in vector registers, degenerate pivots falling
// back to kPaper per lane.
void Refit(const RefitArgs& a, uint32_t begin, uint32_t end) {
  alignas(64) float out[4][kW];
  for (uint32_t s0 = begin; s0 < end; s0 += kW) {
    const uint32_t n = end - s0 < kW ? end - s0 : kW;
    V px[4], py[4], pz[4];
    PivotCentroids(a, s0, n, px, py, pz);  // pad lanes (l >= n): lane 0's sphere again
    V c[4];
    RefitLanes<Ops>(px, py, pz, Load(a.local_x + s0), Load(a.local_y + s0), Load(a.local_z + s0),
                    Load(a.offset_x + s0), Load(a.offset_y + s0), Load(a.offset_z + s0), Load(a.radius_scale + s0),
                    a.frame_mode, c);
    const V cx = c[0], cy = c[1], cz = c[2], r = c[3];
    if (n == kW) {
      Store(a.x + s0, cx), Store(a.y + s0, cy), Store(a.z + s0, cz), Store(a.r + s0, r);
    } else {
      Store(out[0], cx), Store(out[1], cy), Store(out[2], cz), Store(out[3], r);
      for (uint32_t l = 0; l < n; ++l)
        a.x[s0 + l] = out[0][l], a.y[s0 + l] = out[1][l], a.z[s0 + l] = out[2][l], a.r[s0 + l] = out[3][l];
    }
  }
}

// Block boxes (see kernels::BlockBoxArgs), kW blocks at a time: lane l of blocks I.. is contiguous in
// the transposed copy, so the reduction over a block's 8 lanes is vertical. Min(v, acc) / Max(v, acc)
// return acc when v is NaN: NaN lanes (padding, or a sphere whose coordinate or radius is NaN, which the
// sphere test never reports) leave the box as it is; an all-NaN axis leaves it empty (+inf, −inf).
void BlockBoxes(const BlockBoxArgs& a) {
  const V inf = Set1(__builtin_inff()), ninf = Set1(-__builtin_inff()), zero = Set1(0.0f);
  for (uint32_t I = 0; I < a.pitch; I += kW) {
    V lx = inf, hx = ninf, ly = inf, hy = ninf, lz = inf, hz = ninf, br = zero;
    for (uint32_t l = 0; l < 8; ++l) {
      const size_t o = size_t{l} * a.pitch + I;
      const V x = Load(a.tx + o), y = Load(a.ty + o), z = Load(a.tz + o);
      lx = Min(x, lx), hx = Max(x, hx), ly = Min(y, ly), hy = Max(y, hy), lz = Min(z, lz), hz = Max(z, hz);
      br = Max(Abs(Load(a.tr + o)), br);
    }
    Store(a.lx + I, lx), Store(a.hx + I, hx), Store(a.ly + I, ly), Store(a.hy + I, hy);
    Store(a.lz + I, lz), Store(a.hz + I, hz), Store(a.br + I, br);
  }
}

// One row block of the broad phase (see kernels::BroadPhaseArgs). The block-pair test is the sphere
// test's formula on bounds: per axis a gap g = max(loJ − hiI, loI − hiJ, 0) (NaN terms skipped), kept
// when g_x² + g_y² + g_z² < (R_I + R_J)², same operations in the same order, no FMA. It never drops a
// pair the sphere test reports: for a in I, b in J the exact |x_b − x_a| is >= each non-NaN gap term,
// and rounding is monotonic, so fl(dx) >= g per axis, fl(dx²+dy²+dz²) >= fl(g²) (squares and sums are
// monotonic on values >= 0), while |fl(r_a + r_b)| <= fl(R_I + R_J); so g² >= (R_I + R_J)² implies
// d² >= rr², i.e. no overlap. (A NaN d² or rr² never overlaps; infinite bounds only keep more pairs.)
uint32_t BlockRow(const BroadPhaseArgs& a, uint32_t I, uint64_t* keys, uint32_t* box_tests, uint32_t* sphere_tests) {
  const float* __restrict x = a.x;
  const float* __restrict y = a.y;
  const float* __restrict z = a.z;
  const float* __restrict r = a.r;
  const V zero = Set1(0.0f);
  const V lxi = Set1(a.lx[I]), hxi = Set1(a.hx[I]), lyi = Set1(a.ly[I]), hyi = Set1(a.hy[I]);
  const V lzi = Set1(a.lz[I]), hzi = Set1(a.hz[I]), bri = Set1(a.br[I]);
  const uint8_t* live = a.live + size_t{I} * a.live_stride;
  const uint64_t* allowed = a.allowed + size_t{I} * a.blocks;
  uint32_t hits = 0, boxes = 0, spheres = 0;
  V ix[8 / kW], iy[8 / kW], iz[8 / kW], ir[8 / kW];  // the row block's spheres, |grown radius|
  for (uint32_t k = 0; k < 8; k += kW) {
    const uint32_t i = 8 * I + k;
    ix[k / kW] = Load(x + i), iy[k / kW] = Load(y + i), iz[k / kW] = Load(z + i), ir[k / kW] = Abs(Load(r + i));
  }
  for (uint32_t c = 0, J0 = I; J0 < a.blocks; ++c, J0 += 8) {
    uint32_t near = live[c];
    if (!near) continue;
    boxes += static_cast<uint32_t>(std::popcount(near));
    uint32_t kept = 0;
    for (uint32_t k = 0; k < 8; k += kW) {
      const uint32_t J = J0 + k;
      const V gx = Max(Load(a.lx + J) - hxi, Max(lxi - Load(a.hx + J), zero));
      const V gy = Max(Load(a.ly + J) - hyi, Max(lyi - Load(a.hy + J), zero));
      const V gz = Max(Load(a.lz + J) - hzi, Max(lzi - Load(a.hz + J), zero));
      const V rr = Load(a.br + J) + bri;
      kept |= LtMask(gx * gx + gy * gy + gz * gz, rr * rr) << k;
    }
    near &= kept;
    while (near) {
      const uint32_t J = J0 + static_cast<uint32_t>(std::countr_zero(near));
      near &= near - 1;
      const uint64_t allow = allowed[J];
      spheres += static_cast<uint32_t>(std::popcount(allow));
      const uint32_t col = 8 * J;
      // Per row sphere, the block test against J's box (the sphere's centre a box of one point, its
      // |grown radius| the bound): only rows that can reach J's box run their 8 sphere tests. Same float
      // operations as the block test, so the same proof: never a pair the sphere test reports lost.
      // (The same cull of J's columns against I's box cost more than it saved on MakeHuman: not done.)
      const V lxj = Set1(a.lx[J]), hxj = Set1(a.hx[J]), lyj = Set1(a.ly[J]), hyj = Set1(a.hy[J]);
      const V lzj = Set1(a.lz[J]), hzj = Set1(a.hz[J]), brj = Set1(a.br[J]);
      uint32_t rows = 0;
      for (uint32_t k = 0; k < 8; k += kW) {
        const V gx = Max(lxj - ix[k / kW], Max(ix[k / kW] - hxj, zero));
        const V gy = Max(lyj - iy[k / kW], Max(iy[k / kW] - hyj, zero));
        const V gz = Max(lzj - iz[k / kW], Max(iz[k / kW] - hzj, zero));
        const V rr = brj + ir[k / kW];
        rows |= LtMask(gx * gx + gy * gy + gz * gz, rr * rr) << k;
      }
      for (; rows; rows &= rows - 1) {
        const uint32_t row = static_cast<uint32_t>(std::countr_zero(rows));
        const uint32_t lanes = static_cast<uint32_t>(allow >> (8 * row)) & 0xffu;
        if (!lanes) continue;
        const uint32_t i = 8 * I + row;
        uint32_t bits = Overlap8(Set1(x[i]), Set1(y[i]), Set1(z[i]), Set1(r[i]), x + col, y + col, z + col, r + col) & lanes;
        while (bits) [[unlikely]] {
          const uint32_t sa = a.order[i], sb = a.order[col + static_cast<uint32_t>(std::countr_zero(bits))];
          bits &= bits - 1;
          const uint64_t first_chain = a.m1 ? static_cast<uint32_t>(std::countr_zero(a.chain_mask[sa] & a.chain_mask[sb])) : 0u;
          keys[hits++] = first_chain << 32 | (sa < sb ? (sa << 16 | sb) : (sb << 16 | sa));
        }
      }
    }
  }
  *box_tests = boxes;
  *sphere_tests = spheres;
  return hits;
}

// Row blocks [begin, end), one after the other, their keys contiguous.
uint32_t BlockRows(const BroadPhaseArgs& a, uint32_t begin, uint32_t end, uint64_t* keys, uint32_t* box_tests,
                   uint32_t* sphere_tests) {
  uint32_t hits = 0, boxes = 0, spheres = 0;
  for (uint32_t I = begin; I < end; ++I) {
    uint32_t b, s;
    hits += BlockRow(a, I, keys + hits, &b, &s);
    boxes += b, spheres += s;
  }
  *box_tests = boxes;
  *sphere_tests = spheres;
  return hits;
}
