// DetectJob: sphere overlap tests, M1 (per chain) and M2 (all spheres), paper §5.2, behind a broad
// phase over blocks of 8 spheres (kernels::Table::block_rows: kernels.inl, kernels_avx512.inl).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

#include "internal.h"

namespace spherechain::runtime {
namespace {

// The margin a job tests with: its own when >= 0, else the asset's.
float JobMargin(const DetectJob& job) { return job.margin < 0.0f ? job.model->contact_margin() : job.margin; }
// The fold margin a job tests pairs of one region with: its own when >= 0, else the asset's; < 0: none.
float JobFoldMargin(const DetectJob& job) {
  return job.fold_margin < 0.0f ? job.model->fold_margin() : job.fold_margin;
}

struct DetectTaskData {
  const kernels::BroadPhaseArgs* args;
  uint64_t* keys;
  const uint32_t* key_begin;
  uint32_t* row_hits;
  uint32_t (*block_rows)(const kernels::BroadPhaseArgs& a, uint32_t begin, uint32_t end, uint64_t* keys,
                         uint32_t* box_tests, uint32_t* sphere_tests);
};

// parallel_for task: row blocks [begin, end), each its hit keys into its own slots of the keys
// (key_begin) and its counters into row_hits (disjoint per row block, so tasks may run in any order on
// any thread).
void DetectRowTask(void* data, uint32_t begin, uint32_t end) {
  const DetectTaskData& d = *static_cast<DetectTaskData*>(data);
  for (uint32_t I = begin; I < end; ++I) {
    uint32_t* counters = d.row_hits + size_t{3} * I;
    counters[0] = d.block_rows(*d.args, I, I + 1, d.keys + d.key_begin[I], &counters[1], &counters[2]);
  }
}

}  // namespace

// Both methods: gather the spheres (radii grown by the margin) in the layout's slot order, plain and
// lane-major; block boxes; the block-pair culls and the 8×8 tests of the kept pairs (parallel_for: one
// task index per row block, then the per-row-block key runs compacted); then the keys are sorted. Keys
// are (first common chain, M1 only) << 32 | a << 16 | b, so the sorted keys are exactly the documented order; the depths and
// the counters are computed as before the broad phase, with the same operations (bit-identical).
Status Model::Internal::Detect(const DetectJob& job) {
  const Model& c = *job.model;
  Workspace& w = *job.workspace;
  const bool m1 = job.method == DetectMethod::kM1;
  const int method = m1 ? 0 : 1;
  const float m = JobMargin(job);
  // With a fold margin the broad phase grows the radii by the larger of the two margins, and the hits of the
  // kind whose margin is the smaller are tested again on their own margin below.
  const float fold = JobFoldMargin(job);
  const float grow = fold > m ? fold : m;
  const uint32_t B = c.blocks_, P = c.box_pitch_;
  const float *x = w.x_, *y = w.y_, *z = w.z_, *r = w.r_;
  const kernels::Table& kernel = kernels::Kernels(static_cast<kernels::Isa>(c.isa_));
  // The gather and the block boxes: AVX-512 permutes the spheres out of registers and reduces the boxes
  // from the gathered slots (kernels::GatherArgs, up to 256 spheres); else one slot at a time, through
  // restrict pointers (disjoint arrays: no reloads between the stores), plus a transposed copy from which
  // BlockBoxes reduces each block's 8 lanes vertically.
  const size_t pitch = P + 8;
  float* box = w.box_;
  if (!kernel.gather_boxes({x, y, z, r, c.sphere_count_, c.order_, B, grow, w.gx_, w.gy_, w.gz_, w.gr_, box,
                            box + pitch, box + 2 * pitch, box + 3 * pitch, box + 4 * pitch, box + 5 * pitch,
                            box + 6 * pitch})) {
    const float* __restrict sx = x;
    const float* __restrict sy = y;
    const float* __restrict sz = z;
    const float* __restrict sr = r;
    const uint32_t* __restrict order = c.order_;
    float* __restrict gx = w.gx_;
    float* __restrict gy = w.gy_;
    float* __restrict gz = w.gz_;
    float* __restrict gr = w.gr_;
    float* __restrict tx = w.tx_;
    float* __restrict ty = w.ty_;
    float* __restrict tz = w.tz_;
    float* __restrict tr = w.tr_;
    for (uint32_t I = 0; I < B; ++I)  // padding slots read id #S: NaN
      for (uint32_t l = 0, g = 8 * I, t = I; l < 8; ++l, ++g, t += P) {
        const uint32_t s = order[g];
        const float px = sx[s], py = sy[s], pz = sz[s], pr = sr[s] + grow;
        gx[g] = px, gy[g] = py, gz[g] = pz, gr[g] = pr;
        tx[t] = px, ty[t] = py, tz[t] = pz, tr[t] = pr;
      }
    kernel.block_boxes({w.tx_, w.ty_, w.tz_, w.tr_, P, box, box + pitch, box + 2 * pitch, box + 3 * pitch,
                        box + 4 * pitch, box + 5 * pitch, box + 6 * pitch});
  }
  // The broad phase (kernels::BroadPhaseArgs): serial, all row blocks in one call, keys contiguous; with
  // parallel_for, one task index per row block into its own key slots, the runs compacted after.
  uint64_t* keys = w.keys_;
  uint32_t distinct = 0, box_tests = 0, sphere_tests = 0;
  {
    const kernels::BroadPhaseArgs args{w.gx_, w.gy_, w.gz_, w.gr_,
                                       box, box + pitch, box + 2 * pitch, box + 3 * pitch, box + 4 * pitch,
                                       box + 5 * pitch, box + 6 * pitch, c.order_, c.a_.chain_mask,
                                       c.allowed_[method], c.live_[method], c.blocks_, c.live_stride_, m1};
    if (job.parallel_for.run) {
      DetectTaskData data{&args, keys, c.key_begin_[method], w.row_hits_, kernel.block_rows};
      job.parallel_for.run(job.parallel_for.user, B, &DetectRowTask, &data);
      for (uint32_t I = 0; I < B; ++I) {  // compact the per-row-block key runs
        const uint32_t slot = c.key_begin_[method][I], n = w.row_hits_[size_t{3} * I];
        if (n && slot != distinct) std::memmove(keys + distinct, keys + slot, sizeof(uint64_t) * n);
        distinct += n;
        box_tests += w.row_hits_[size_t{3} * I + 1];
        sphere_tests += w.row_hits_[size_t{3} * I + 2];
      }
    } else {
      distinct = kernel.block_rows(args, 0, B, keys, &box_tests, &sphere_tests);
    }
  }
  if (fold >= 0.0f && fold != m) {  // each hit on its own kind's margin: one region (fold) or two (contact)
    uint32_t kept = 0;
    for (uint32_t k = 0; k < distinct; ++k) {
      const uint32_t a = static_cast<uint32_t>(keys[k] >> 16) & 0xffffu, b = static_cast<uint32_t>(keys[k]) & 0xffffu;
      const float mk = c.fold_region(a) == c.fold_region(b) ? fold : m;
      // The broad phase's own test (formulas::OverlapLanes on radii grown by the margin, as the gather grows
      // them), so a hit whose margin is `grow` is kept exactly as the broad phase found it.
      if (mk == grow || formulas::OverlapLanes<formulas::ScalarOps>(x[a], y[a], z[a], r[a] + mk, x[b], y[b], z[b],
                                                                    r[b] + mk))
        keys[kept++] = keys[k];
    }
    distinct = kept;
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
  const uint32_t* mask = c.a_.chain_mask;
  uint32_t raw = distinct;
  if (m1) {
    for (uint32_t k = 0; k < written; ++k) {
      const uint32_t a = static_cast<uint32_t>(keys[k] >> 16) & 0xffffu, b = static_cast<uint32_t>(keys[k]) & 0xffffu;
      job.output[k] = {static_cast<uint16_t>(a), static_cast<uint16_t>(b),
                       formulas::SphereDepth<formulas::ScalarOps>(x[a], y[a], z[a], r[a], x[b], y[b], z[b], r[b], 0.0f),
                       mask[a] & mask[b]};
    }
    raw = 0;
    for (uint32_t k = 0; k < distinct; ++k) {
      const uint32_t a = static_cast<uint32_t>(keys[k] >> 16) & 0xffffu, b = static_cast<uint32_t>(keys[k]) & 0xffffu;
      raw += static_cast<uint32_t>(std::popcount(mask[a] & mask[b]));
    }
  } else {  // M2's depth as it always was: grown radii, then 2m taken off (bit-identical results)
    for (uint32_t k = 0; k < written; ++k) {
      const uint32_t a = static_cast<uint32_t>(keys[k] >> 16) & 0xffffu, b = static_cast<uint32_t>(keys[k]) & 0xffffu;
      const float depth = formulas::SphereDepth<formulas::ScalarOps>(x[a], y[a], z[a], r[a], x[b], y[b], z[b], r[b], m);
      job.output[k] = {static_cast<uint16_t>(a), static_cast<uint16_t>(b), depth, mask[a] & mask[b]};
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
  if (!count || (!output && capacity > 0)) return Status::kErrorNullArgument;
  if (Status s = Model::Internal::CheckPair(model, workspace); s != Status::kOk) return s;
  if ((method != DetectMethod::kM1 && method != DetectMethod::kM2) || !std::isfinite(margin) ||
      !std::isfinite(fold_margin))
    return Status::kErrorInvalidJob;
  // A fold margin of the job's own needs the regions of an asset that has one (Model::fold_margin() >= 0).
  if (fold_margin >= 0.0f && model->fold_margin() < 0.0f) return Status::kErrorInvalidJob;
  return Status::kOk;
}

Status DetectJob::Run() const {
  if (Status s = Check(); s != Status::kOk) return s;
  return Model::Internal::Detect(*this);
}

}  // namespace spherechain::runtime
