// DetectJob: brute-force sphere overlap tests, M1 (per chain) and M2 (all spheres), paper §5.2.
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
};

void DetectSpanTask(void* data, uint32_t begin, uint32_t end) {
  const Context& ctx = *static_cast<DetectTaskData*>(data)->ctx;
  for (uint32_t s = begin; s < end; ++s) Context::Internal::DetectSpan(ctx, s);
}

}  // namespace

// M1 tests each distinct pair sharing a chain once: spheres are grouped by chain-membership class and
// each class's span holds the class then every later class sharing a chain with it (Context::Init),
// so those pairs are (row of the class) × (later column of its span). Hits are keyed by (first common
// chain, a, b) and sorted, which is exactly the documented order (chain lists are ascending);
// raw_pairs adds, per hit, the number of chains holding the pair (the paper's per-chain count).
void Context::Internal::DetectSpan(const Context& c, uint32_t span) {
  const uint32_t* sp = c.spans_.data() + size_t{6} * span;
  const kernels::SpanArgs args{c.gx_.data(), c.gy_.data(), c.gz_.data(), c.gr_.data(), c.m1_order_.data(),
                               c.chain_mask_.data(), sp[0], sp[1], sp[2], sp[3], c.m1_excl_.data() + sp[4],
                               c.m1_keys_.data() + sp[5]};
  c.span_hits_[span] = c.use_avx_ ? kernels::SpanAvx(args) : kernels::SpanSse(args);
}

Status Context::Internal::DetectM1(const DetectJob& job) {
  const Context& c = *job.context;
  const uint32_t G = static_cast<uint32_t>(c.m1_order_.size());
  const float m = JobMargin(job);
  for (uint32_t g = 0; g < G; ++g) {  // (padding lanes gather sphere 0; the skip stream masks them)
    const uint32_t s = c.m1_order_[g];
    c.gx_[g] = c.x_[s], c.gy_[g] = c.y_[s], c.gz_[g] = c.z_[s], c.gr_[g] = c.r_[s] + m;
  }
  const uint32_t P = static_cast<uint32_t>(c.span_hits_.size());
  if (job.parallel_for.run) {
    DetectTaskData data{&c};
    job.parallel_for.run(job.parallel_for.user, P, &DetectSpanTask, &data);
  } else {
    for (uint32_t p = 0; p < P; ++p) DetectSpan(c, p);
  }
  uint64_t* keys = c.m1_keys_.data();
  uint32_t distinct = 0, raw = 0;
  for (uint32_t p = 0; p < P; ++p) {  // compact the per-span key blocks
    const uint32_t slot = c.spans_[size_t{6} * p + 5], n = c.span_hits_[p];
    if (n && slot != distinct) std::memmove(keys + distinct, keys + slot, sizeof(uint64_t) * n);
    distinct += n;
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
  const SphereArrays s = c.spheres();
  for (uint32_t k = 0; k < written; ++k) {
    const uint32_t a = static_cast<uint32_t>(keys[k] >> 16) & 0xffffu, b = static_cast<uint32_t>(keys[k]) & 0xffffu;
    const float dx = s.x[b] - s.x[a], dy = s.y[b] - s.y[a], dz = s.z[b] - s.z[a];
    job.output[k] = {static_cast<uint16_t>(a), static_cast<uint16_t>(b),
                     s.r[a] + s.r[b] - std::sqrt(dx * dx + dy * dy + dz * dz), c.chain_mask_[a] & c.chain_mask_[b]};
  }
  for (uint32_t k = 0; k < distinct; ++k) {
    const uint32_t a = static_cast<uint32_t>(keys[k] >> 16) & 0xffffu, b = static_cast<uint32_t>(keys[k]) & 0xffffu;
    raw += static_cast<uint32_t>(std::popcount(c.chain_mask_[a] & c.chain_mask_[b]));
  }
  *job.count = written;
  if (job.stats) *job.stats = {c.m1_tests_, raw, distinct};
  return distinct > written ? Status::kOkTruncated : Status::kOk;
}

Status Context::Internal::DetectM2(const DetectJob& job) {
  const Context& c = *job.context;
  const uint32_t S = c.sphere_count_;
  const float m = JobMargin(job);
  const float* r = c.r_.data();
  if (m != 0.0f) {  // grown radii (padding stays 0: its spheres are far away)
    for (uint32_t s = 0; s < S; ++s) c.mr_[s] = c.r_[s] + m;
    r = c.mr_.data();
  }
  const kernels::AllPairsArgs args{c.x_.data(), c.y_.data(), c.z_.data(), r, S, c.m2_excl_.data(),
                                   c.chain_mask_.data(), job.output, job.capacity};
  const uint32_t distinct = c.use_avx_ ? kernels::AllPairsAvx(args) : kernels::AllPairsSse(args);
  const uint32_t written = distinct < job.capacity ? distinct : job.capacity;
  if (m != 0.0f)
    for (uint32_t k = 0; k < written; ++k) job.output[k].depth -= 2.0f * m;  // depth of the spheres themselves
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
  if (!context->initialized() || (method != DetectMethod::kM1 && method != DetectMethod::kM2) ||
      !std::isfinite(margin))
    return Status::kErrorInvalidJob;
  return Status::kOk;
}

Status DetectJob::Run() const {
  if (Status s = Check(); s != Status::kOk) return s;
  return method == DetectMethod::kM1 ? Context::Internal::DetectM1(*this) : Context::Internal::DetectM2(*this);
}

}  // namespace spherechain::runtime
