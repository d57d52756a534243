// Kernel bodies, included once per instruction set by kernels.cpp inside a namespace that defines:
//   V (a vector of kW floats), M (its comparison mask), kW, Set1, Load, Store, Sqrt, Gt, Blend, And,
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

// The skip stream (Context::Init), one compare per chunk (branch-free): `next` is the entry at `excl`.
struct ExclusionCursor {
  const uint64_t* excl;
  uint64_t next;
  inline uint32_t Apply(uint32_t bits, uint32_t chunk) {
    const bool here = static_cast<uint32_t>(next >> 32) == chunk;
    bits &= ~(here ? static_cast<uint32_t>(next) : 0u);
    excl += here;
    next = *excl;
    return bits;
  }
};

uint32_t Span(const SpanArgs& a) {
  const float* __restrict x = a.x + a.begin;
  const float* __restrict y = a.y + a.begin;
  const float* __restrict z = a.z + a.begin;
  const float* __restrict r = a.r + a.begin;
  const uint32_t rows = a.rows, columns = a.columns;
  ExclusionCursor ex{a.excl, *a.excl};
  uint32_t chunk = a.chunk, hits = 0;
  for (uint32_t i = 0; i < rows && i + 1 < columns; ++i) {
    const V xi = Set1(x[i]), yi = Set1(y[i]), zi = Set1(z[i]), ri = Set1(r[i]);
    for (uint32_t j0 = (i + 1) & ~7u; j0 < columns; j0 += 8, ++chunk) {
      uint32_t bits = ex.Apply(Overlap8(xi, yi, zi, ri, x + j0, y + j0, z + j0, r + j0), chunk);
      while (bits) [[unlikely]] {
        const uint32_t sa = a.order[a.begin + i], sb = a.order[a.begin + j0 + static_cast<uint32_t>(std::countr_zero(bits))];
        bits &= bits - 1;
        const uint64_t first_chain = static_cast<uint32_t>(std::countr_zero(a.chain_mask[sa] & a.chain_mask[sb]));
        a.keys[hits++] = first_chain << 32 | (sa < sb ? (sa << 16 | sb) : (sb << 16 | sa));
      }
    }
  }
  return hits;
}

uint32_t AllPairs(const AllPairsArgs& a) {
  const float* __restrict x = a.x;
  const float* __restrict y = a.y;
  const float* __restrict z = a.z;
  const float* __restrict r = a.r;
  const uint32_t count = a.count, capacity = a.capacity;
  ExclusionCursor ex{a.excl, *a.excl};
  uint32_t chunk = 0, distinct = 0;
  for (uint32_t i = 0; i + 1 < count; ++i) {
    const V xi = Set1(x[i]), yi = Set1(y[i]), zi = Set1(z[i]), ri = Set1(r[i]);
    for (uint32_t b0 = (i + 1) & ~7u; b0 < count; b0 += 8, ++chunk) {
      uint32_t bits = ex.Apply(Overlap8(xi, yi, zi, ri, x + b0, y + b0, z + b0, r + b0), chunk);
      while (bits) [[unlikely]] {
        const uint32_t b = b0 + static_cast<uint32_t>(std::countr_zero(bits));
        bits &= bits - 1;
        if (distinct < capacity) {
          const float dx = x[b] - x[i], dy = y[b] - y[i], dz = z[b] - z[i];
          a.out[distinct] = {static_cast<uint16_t>(i), static_cast<uint16_t>(b),
                             r[i] + r[b] - std::sqrt(dx * dx + dy * dy + dz * dz), a.chain_mask[i] & a.chain_mask[b]};
        }
        ++distinct;
      }
    }
  }
  return distinct;
}
