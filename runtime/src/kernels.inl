// Kernel bodies, included once per instruction set by kernels.cpp inside a namespace that defines:
//   V (a vector of kW floats), M (its comparison mask), kW, Set1, Load, Store, Sqrt, Gt, Blend, And,
//   Min / Max (a op b, else b when either is NaN: minps / maxps), Abs, LtMask (bit k ⇔ lane k a < b),
//   and Overlap8 (the 8-lane overlap bit mask of one row sphere against 8 spheres).
// No '#pragma once': meant to be included several times. The formulas are refit.h's and §5.2's, with
// the same operations in the same order (so the results are bit-identical across variants):
//   - BuildPivotFrame's scale max_k sqrt(d_k²) is computed as sqrt(max_k d_k²) (sqrt is monotonic
//     and correctly rounded, so the two are equal, NaN lanes included);
//   - kPaper's centre mean(p) + offset reuses the frame origin (the same expression).

// Refit of spheres [begin, end), kW at a time: scalar centroids of the 12 pivot vertices into
// per-lane arrays, then the frame, the centre and the radius in vector registers, both modes
// computed and blended per lane (degenerate pivots fall back to kPaper).
void Refit(const RefitArgs& a, uint32_t begin, uint32_t end) {
  alignas(64) float p[4][3][kW];
  alignas(64) float out[4][kW];
  for (uint32_t s0 = begin; s0 < end; s0 += kW) {
    const uint32_t n = end - s0 < kW ? end - s0 : kW;
    for (uint32_t l = 0; l < kW; ++l) {
      const uint32_t* idx = a.pivot_vertices + size_t{12} * (s0 + (l < n ? l : 0));  // pad lanes: copy lane 0
      for (int k = 0; k < 4; ++k) {
        // Positions are floats, 4-byte aligned (RefitJob::Check); TriangleCentroid: (a + b + c) · (1/3).
        const float* va = reinterpret_cast<const float*>(a.base + idx[3 * k] * a.stride);
        const float* vb = reinterpret_cast<const float*>(a.base + idx[3 * k + 1] * a.stride);
        const float* vc = reinterpret_cast<const float*>(a.base + idx[3 * k + 2] * a.stride);
        p[k][0][l] = (va[0] + vb[0] + vc[0]) * (1.0f / 3.0f);
        p[k][1][l] = (va[1] + vb[1] + vc[1]) * (1.0f / 3.0f);
        p[k][2][l] = (va[2] + vb[2] + vc[2]) * (1.0f / 3.0f);
      }
    }
    V px[4], py[4], pz[4];
    for (int k = 0; k < 4; ++k) px[k] = Load(p[k][0]), py[k] = Load(p[k][1]), pz[k] = Load(p[k][2]);
    const V quarter = Set1(0.25f), half = Set1(0.5f);
    const V ox = quarter * (px[0] + px[1] + px[2] + px[3]);
    const V oy = quarter * (py[0] + py[1] + py[2] + py[3]);
    const V oz = quarter * (pz[0] + pz[1] + pz[2] + pz[3]);
    V cx, cy, cz;
    const V paper_x = ox + Load(a.offset_x + s0), paper_y = oy + Load(a.offset_y + s0),
            paper_z = oz + Load(a.offset_z + s0);
    if (a.frame_mode) {
      V max_d2 = Set1(0.0f);
      for (int k = 0; k < 4; ++k) {
        const V dx = px[k] - ox, dy = py[k] - oy, dz = pz[k] - oz;
        const V d2 = dx * dx + dy * dy + dz * dz;
        max_d2 = Blend(Gt(d2, max_d2), d2, max_d2);
      }
      const V eps = Set1(1e-6f) * (Set1(1.0f) + Sqrt(max_d2));
      V xx = px[1] - px[0], xy = py[1] - py[0], xz = pz[1] - pz[0];
      const V xl = Sqrt(xx * xx + xy * xy + xz * xz);
      const M x_ok = Gt(xl, eps);
      xx = xx / xl, xy = xy / xl, xz = xz / xl;
      V wx = half * (px[2] + px[3]) - half * (px[0] + px[1]);
      V wy = half * (py[2] + py[3]) - half * (py[0] + py[1]);
      V wz = half * (pz[2] + pz[3]) - half * (pz[0] + pz[1]);
      const V wdx = wx * xx + wy * xy + wz * xz;
      wx = wx - wdx * xx, wy = wy - wdx * xy, wz = wz - wdx * xz;
      const V yl = Sqrt(wx * wx + wy * wy + wz * wz);
      const M ok = And(x_ok, Gt(yl, eps));
      wx = wx / yl, wy = wy / yl, wz = wz / yl;
      const V zx = xy * wz - xz * wy, zy = xz * wx - xx * wz, zz = xx * wy - xy * wx;
      const V lx = Load(a.local_x + s0), ly = Load(a.local_y + s0), lz = Load(a.local_z + s0);
      cx = Blend(ok, ox + lx * xx + ly * wx + lz * zx, paper_x);
      cy = Blend(ok, oy + lx * xy + ly * wy + lz * zy, paper_y);
      cz = Blend(ok, oz + lx * xz + ly * wz + lz * zz, paper_z);
    } else {
      cx = paper_x, cy = paper_y, cz = paper_z;
    }
    V dist[4];
    for (int k = 0; k < 4; ++k) {
      const V dx = cx - px[k], dy = cy - py[k], dz = cz - pz[k];
      dist[k] = Sqrt(dx * dx + dy * dy + dz * dz);
    }
    const V r = Load(a.radius_scale + s0) * (quarter * (dist[0] + dist[1] + dist[2] + dist[3]));
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
uint32_t BlockRow(const BroadPhaseArgs& a, uint32_t I, uint32_t* box_tests, uint32_t* sphere_tests) {
  const float* __restrict x = a.x;
  const float* __restrict y = a.y;
  const float* __restrict z = a.z;
  const float* __restrict r = a.r;
  const V zero = Set1(0.0f);
  const V lxi = Set1(a.lx[I]), hxi = Set1(a.hx[I]), lyi = Set1(a.ly[I]), hyi = Set1(a.hy[I]);
  const V lzi = Set1(a.lz[I]), hzi = Set1(a.hz[I]), bri = Set1(a.br[I]);
  const uint8_t* live = a.live + size_t{I} * a.live_stride;
  const uint64_t* allowed = a.allowed + size_t{I} * a.blocks;
  uint64_t* keys = a.keys + a.key_begin[I];
  uint32_t hits = 0, boxes = 0, spheres = 0;
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
      for (uint32_t row = 0; row < 8; ++row) {
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
