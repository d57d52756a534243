// DetectJob: sphere overlap tests, M1 (per chain) and M2 (all spheres), paper §5.2, behind a broad
// phase over blocks of 8 spheres (kernels.inl BlockRow).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

#include "internal.h"

namespace spherechain::runtime {
namespace {

// The margin a job tests with: its own when >= 0, else the asset's.
float JobMargin(const DetectJob& job) { return job.margin < 0.0f ? job.context->contact_margin() : job.margin; }

struct DetectTaskData {
  const Context* ctx;
  bool m1;
};

void DetectRowTask(void* data, uint32_t begin, uint32_t end) {
  const DetectTaskData& d = *static_cast<DetectTaskData*>(data);
  for (uint32_t I = begin; I < end; ++I) Context::Internal::DetectRowBlock(*d.ctx, d.m1, I);
}

}  // namespace

// One row block of the broad phase (kernels::BlockRow): its hit keys into its own slots of keys_ and
// its counters into row_hits_ (disjoint per row block, so tasks may run in any order on any thread).
void Context::Internal::DetectRowBlock(const Context& c, bool m1, uint32_t I) {
  const int method = m1 ? 0 : 1;
  const size_t pitch = c.box_pitch_ + 8;
  float* box = c.box_.data();
  const kernels::BroadPhaseArgs args{c.gx_.data(), c.gy_.data(), c.gz_.data(), c.gr_.data(),
                                     box, box + pitch, box + 2 * pitch, box + 3 * pitch, box + 4 * pitch,
                                     box + 5 * pitch, box + 6 * pitch, c.order_.data(), c.chain_mask1_.data(),
                                     c.allowed_[method].data(), c.live_[method].data(), c.blocks_, c.live_stride_, m1,
                                     c.keys_.data(), c.key_begin_[method].data()};
  uint32_t* counters = c.row_hits_.data() + size_t{3} * I;
  counters[0] = c.use_avx_ ? kernels::BlockRowAvx(args, I, &counters[1], &counters[2])
                           : kernels::BlockRowSse(args, I, &counters[1], &counters[2]);
}

// Both methods: gather the spheres (radii grown by the margin) in the layout's slot order, plain and
// lane-major; block boxes; per row block the cull and the 8×8 tests (parallel_for: one task index per
// row block); then the per-row-block key runs are compacted and sorted. Keys are (first common chain,
// M1 only) << 32 | a << 16 | b, so the sorted keys are exactly the documented order; the depths and
// the counters are computed as before the broad phase, with the same operations (bit-identical).
Status Context::Internal::Detect(const DetectJob& job) {
  const Context& c = *job.context;
  const bool m1 = job.method == DetectMethod::kM1;
  const int method = m1 ? 0 : 1;
  const float m = JobMargin(job);
  const uint32_t B = c.blocks_, P = c.box_pitch_;
  const float *x = c.x_.data(), *y = c.y_.data(), *z = c.z_.data(), *r = c.r_.data();
  float *gx = c.gx_.data(), *gy = c.gy_.data(), *gz = c.gz_.data(), *gr = c.gr_.data();
  float *tx = c.tx_.data(), *ty = c.ty_.data(), *tz = c.tz_.data(), *tr = c.tr_.data();
  for (uint32_t I = 0; I < B; ++I)  // padding slots read id #S: NaN
    for (uint32_t l = 0, g = 8 * I, t = I; l < 8; ++l, ++g, t += P) {
      const uint32_t s = c.order_[g];
      const float sx = x[s], sy = y[s], sz = z[s], sr = r[s] + m;
      gx[g] = sx, gy[g] = sy, gz[g] = sz, gr[g] = sr;
      tx[t] = sx, ty[t] = sy, tz[t] = sz, tr[t] = sr;
    }
  {
    const size_t pitch = P + 8;
    float* box = c.box_.data();
    const kernels::BlockBoxArgs args{c.tx_.data(), c.ty_.data(), c.tz_.data(), c.tr_.data(), P,
                                     box, box + pitch, box + 2 * pitch, box + 3 * pitch, box + 4 * pitch,
                                     box + 5 * pitch, box + 6 * pitch};
    if (c.use_avx_)
      kernels::BlockBoxesAvx(args);
    else
      kernels::BlockBoxesSse(args);
  }
  if (job.parallel_for.run) {
    DetectTaskData data{&c, m1};
    job.parallel_for.run(job.parallel_for.user, B, &DetectRowTask, &data);
  } else {
    for (uint32_t I = 0; I < B; ++I) DetectRowBlock(c, m1, I);
  }
  uint64_t* keys = c.keys_.data();
  uint32_t distinct = 0, box_tests = 0, sphere_tests = 0;
  for (uint32_t I = 0; I < B; ++I) {  // compact the per-row-block key runs
    const uint32_t slot = c.key_begin_[method][I], n = c.row_hits_[size_t{3} * I];
    if (n && slot != distinct) std::memmove(keys + distinct, keys + slot, sizeof(uint64_t) * n);
    distinct += n;
    box_tests += c.row_hits_[size_t{3} * I + 1];
    sphere_tests += c.row_hits_[size_t{3} * I + 2];
  }
  if (distinct <= 32) {  // a handful of hits per frame: insertion sort
    for (uint32_t i = 1; i < distinct; ++i) {
      const uint64_t k = keys[i];
      uint32_t j = i;
      for (; j > 0 && keys[j - 1] > k; --j) keys[j] = keys[j - 1];
      keys[j] = k;
    }
  } else {
    std::sort(keys, keys + distinct);
  }
  const uint32_t written = distinct < job.capacity ? distinct : job.capacity;
  uint32_t raw = distinct;
  if (m1) {
    for (uint32_t k = 0; k < written; ++k) {
      const uint32_t a = static_cast<uint32_t>(keys[k] >> 16) & 0xffffu, b = static_cast<uint32_t>(keys[k]) & 0xffffu;
      const float dx = x[b] - x[a], dy = y[b] - y[a], dz = z[b] - z[a];
      job.output[k] = {static_cast<uint16_t>(a), static_cast<uint16_t>(b),
                       r[a] + r[b] - std::sqrt(dx * dx + dy * dy + dz * dz), c.chain_mask_[a] & c.chain_mask_[b]};
    }
    raw = 0;
    for (uint32_t k = 0; k < distinct; ++k) {
      const uint32_t a = static_cast<uint32_t>(keys[k] >> 16) & 0xffffu, b = static_cast<uint32_t>(keys[k]) & 0xffffu;
      raw += static_cast<uint32_t>(std::popcount(c.chain_mask_[a] & c.chain_mask_[b]));
    }
  } else {  // M2's depth as it always was: grown radii, then 2m taken off (bit-identical results)
    for (uint32_t k = 0; k < written; ++k) {
      const uint32_t a = static_cast<uint32_t>(keys[k] >> 16) & 0xffffu, b = static_cast<uint32_t>(keys[k]) & 0xffffu;
      const float dx = x[b] - x[a], dy = y[b] - y[a], dz = z[b] - z[a];
      const float ra = m != 0.0f ? r[a] + m : r[a], rb = m != 0.0f ? r[b] + m : r[b];
      float depth = ra + rb - std::sqrt(dx * dx + dy * dy + dz * dz);
      if (m != 0.0f) depth -= 2.0f * m;
      job.output[k] = {static_cast<uint16_t>(a), static_cast<uint16_t>(b), depth, c.chain_mask_[a] & c.chain_mask_[b]};
    }
  }
  *job.count = written;
  const uint32_t S = c.sphere_count_;
  if (job.stats) {
    job.stats->tests = m1 ? c.m1_tests_ : static_cast<uint32_t>(uint64_t{S} * (S - 1) / 2);
    job.stats->raw_pairs = raw;
    job.stats->distinct_pairs = distinct;
    job.stats->box_tests = box_tests;
    job.stats->sphere_tests = sphere_tests;
  }
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
  if (!context->initialized() || (method != DetectMethod::kM1 && method != DetectMethod::kM2) ||
      !std::isfinite(margin))
    return Status::kErrorInvalidJob;
  return Status::kOk;
}

Status DetectJob::Run() const {
  if (Status s = Check(); s != Status::kOk) return s;
  return Context::Internal::Detect(*this);
}

}  // namespace spherechain::runtime
