// DetectJob: brute-force sphere overlap tests, M1 (per chain) and M2 (all spheres), paper §5.2.
#include <bit>
#include <cmath>
#include <cstring>

#include "internal.h"

namespace spherechain::runtime {
namespace {

// Overlap flags of sphere (xi, yi, zi, ri) against spheres [0, n) of an SoA block, in blocks of 8
// (the arrays are padded with far-away spheres of radius 0, so reading up to n rounded up to 8 is in
// bounds and yields 0): branch-free, fixed-width inner loop the compiler vectorises even at -O2
// (11 operations per pair, as in §5.2).
inline void OverlapRow(float xi, float yi, float zi, float ri, const float* __restrict x, const float* __restrict y,
                       const float* __restrict z, const float* __restrict r, uint32_t n, uint8_t* __restrict flags) {
  for (uint32_t j0 = 0; j0 < n; j0 += 8)
    for (uint32_t k = 0; k < 8; ++k) {
      const uint32_t j = j0 + k;
      const float dx = x[j] - xi, dy = y[j] - yi, dz = z[j] - zi;
      const float rr = r[j] + ri;
      flags[j] = (dx * dx + dy * dy + dz * dz) < rr * rr;
    }
}

// Index of each set flag in [0, n), skipping 8 zero flags at a time.
template <typename F>
inline void ForEachFlag(const uint8_t* flags, uint32_t n, F&& f) {
  for (uint32_t j0 = 0; j0 < n; j0 += 8) {
    uint64_t w;
    std::memcpy(&w, flags + j0, 8);
    if (!w) continue;
    const uint32_t e = n - j0 < 8 ? n - j0 : 8;
    for (uint32_t k = 0; k < e; ++k)
      if (flags[j0 + k]) f(j0 + k);
  }
}

struct DetectTaskData {
  const Context* ctx;
};

void DetectChainTask(void* data, uint32_t begin, uint32_t end) {
  const Context& ctx = *static_cast<DetectTaskData*>(data)->ctx;
  for (uint32_t c = begin; c < end; ++c) Context::Internal::DetectChain(ctx, c);
}

inline Collision MakeCollision(const Context& ctx, uint32_t a, uint32_t b, uint32_t chains) {
  const SphereArrays s = ctx.spheres();
  const float dx = s.x[b] - s.x[a], dy = s.y[b] - s.y[a], dz = s.z[b] - s.z[a];
  return {static_cast<uint16_t>(a), static_cast<uint16_t>(b), s.r[a] + s.r[b] - std::sqrt(dx * dx + dy * dy + dz * dz),
          chains};
}

}  // namespace

// One chain: gather its spheres (SoA), test all i < j, keep non-excluded hits whose first common
// chain is this one (the distinct pairs), count all non-excluded hits (raw, the paper's count).
void Context::Internal::DetectChain(const Context& c, uint32_t chain) {
  const uint32_t off = c.chain_offsets_[chain], n = c.chain_offsets_[chain + 1] - off;
  const uint16_t* ids = c.chain_spheres_.data() + off;
  const uint32_t goff = c.gather_offsets_[chain];
  float* gx = c.gx_.data() + goff;
  float* gy = c.gy_.data() + goff;
  float* gz = c.gz_.data() + goff;
  float* gr = c.gr_.data() + goff;
  for (uint32_t i = 0; i < n; ++i) {
    gx[i] = c.x_[ids[i]];
    gy[i] = c.y_[ids[i]];
    gz[i] = c.z_[ids[i]];
    gr[i] = c.r_[ids[i]];
  }
  uint8_t row_flags[256 + 8];  // chains longer than 256 use several passes per row
  uint32_t* hits = c.chain_hits_.data() + c.chain_hits_offsets_[chain];
  uint32_t nhits = 0, raw = 0;
  for (uint32_t i = 0; i + 1 < n; ++i) {
    const uint32_t a = ids[i];
    for (uint32_t j0 = i + 1; j0 < n; j0 += 256) {
      const uint32_t m = n - j0 < 256 ? n - j0 : 256;
      OverlapRow(gx[i], gy[i], gz[i], gr[i], gx + j0, gy + j0, gz + j0, gr + j0, m, row_flags);
      ForEachFlag(row_flags, m, [&](uint32_t j) {
        const uint32_t b = ids[j0 + j];
        if (c.IsExcluded(a, b)) return;
        ++raw;
        if (static_cast<uint32_t>(std::countr_zero(c.chain_mask_[a] & c.chain_mask_[b])) == chain)
          hits[nhits++] = (a << 16) | b;
      });
    }
  }
  c.chain_hit_counts_[chain] = nhits;
  c.chain_raw_counts_[chain] = raw;
}

Status Context::Internal::DetectM1(const DetectJob& job) {
  const Context& c = *job.context;
  const uint32_t C = c.chain_count_;
  if (job.parallel_for.run) {
    DetectTaskData data{&c};
    job.parallel_for.run(job.parallel_for.user, C, &DetectChainTask, &data);
  } else {
    for (uint32_t ch = 0; ch < C; ++ch) DetectChain(c, ch);
  }
  uint32_t written = 0, distinct = 0, raw = 0, tests = 0;
  for (uint32_t ch = 0; ch < C; ++ch) {
    const uint32_t n = c.chain_offsets_[ch + 1] - c.chain_offsets_[ch];
    tests += n * (n > 0 ? n - 1 : 0) / 2;
    raw += c.chain_raw_counts_[ch];
    const uint32_t nh = c.chain_hit_counts_[ch];
    distinct += nh;
    const uint32_t* hits = c.chain_hits_.data() + c.chain_hits_offsets_[ch];
    for (uint32_t k = 0; k < nh && written < job.capacity; ++k) {
      const uint32_t a = hits[k] >> 16, b = hits[k] & 0xffffu;
      job.output[written++] = MakeCollision(c, a, b, c.chain_mask_[a] & c.chain_mask_[b]);
    }
  }
  *job.count = written;
  if (job.stats) *job.stats = {tests, raw, distinct};
  return distinct > written ? Status::kOkTruncated : Status::kOk;
}

Status Context::Internal::DetectM2(const DetectJob& job) {
  const Context& c = *job.context;
  const uint32_t S = c.sphere_count_;
  uint8_t* flags = c.flags_.data();
  const float *x = c.x_.data(), *y = c.y_.data(), *z = c.z_.data(), *r = c.r_.data();
  uint32_t written = 0, distinct = 0;
  for (uint32_t a = 0; a + 1 < S; ++a) {
    const uint32_t m = S - a - 1;
    OverlapRow(x[a], y[a], z[a], r[a], x + a + 1, y + a + 1, z + a + 1, r + a + 1, m, flags);
    ForEachFlag(flags, m, [&](uint32_t j) {
      const uint32_t b = a + 1 + j;
      if (c.IsExcluded(a, b)) return;
      ++distinct;
      if (written < job.capacity) job.output[written++] = MakeCollision(c, a, b, c.chain_mask_[a] & c.chain_mask_[b]);
    });
  }
  *job.count = written;
  if (job.stats) *job.stats = {static_cast<uint32_t>(uint64_t{S} * (S - 1) / 2), distinct, distinct};
  return distinct > written ? Status::kOkTruncated : Status::kOk;
}

uint32_t DetectBound(const AssetView& view, DetectMethod method) {
  if (!view.valid()) return 0;
  const uint64_t S = view.sphere_count;
  const uint64_t all = S * (S - 1) / 2;
  if (method == DetectMethod::kM2) return static_cast<uint32_t>(all);
  if (method != DetectMethod::kM1) return 0;
  uint64_t sum = 0;
  for (const schema::Chain* c : *view.asset->chains()) {
    const uint64_t n = c->spheres()->size();
    sum += n * (n > 0 ? n - 1 : 0) / 2;
  }
  return static_cast<uint32_t>(sum < all ? sum : all);
}

Status DetectJob::Check() const {
  if (!context || !count || (!output && capacity > 0)) return Status::kErrorNullArgument;
  if (!context->initialized() || (method != DetectMethod::kM1 && method != DetectMethod::kM2))
    return Status::kErrorInvalidJob;
  return Status::kOk;
}

Status DetectJob::Run() const {
  if (Status s = Check(); s != Status::kOk) return s;
  return method == DetectMethod::kM1 ? Context::Internal::DetectM1(*this) : Context::Internal::DetectM2(*this);
}

}  // namespace spherechain::runtime
