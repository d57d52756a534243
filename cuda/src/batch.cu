// Batch: fused refit + detect kernels (one launch per frame) and their host-side setup.
//
// Kernel design (see Strategy in batch.h):
//  - SphereKernel: a block per instance, a thread per sphere, or `split` threads per sphere when the
//    batch has few instances (kThreadPerSphere); the pairs dealt out evenly (circular order);
//  - GroupKernel:  a warp per instance, 4 per block (kWarpPerInstance);
//  - BoxKernel: a block per instance (with few instances up to SPHERECHAIN_CUDA_FEW_BLOCKS, 8), the CPU
//    DetectJob's blocks of 8 spheres
//    and their bounds, then the sphere tests of the block pairs kept (kBlockBoxes, the default);
//  - ChainKernel: a block per (instance, chain), a thread per chain sphere (kBlockPerChain, M1).
// Each refits the spheres it needs into shared memory (DevRefitSphere: runtime/formulas.h, the formulas
// the CPU's scalar path and SIMD kernels compile), syncs, runs
// the overlap tests on the radii grown by the instance's contact margin (FrameParams::margin, else its
// asset's: DetectJob's JobMargin; the stored spheres keep their own radii) — by its fold margin instead for
// two spheres of one region when the asset has one (PairMargin) — and appends hits (with the
// spheres' own depth) to one device array with warp-aggregated atomicAdd
// (cooperative_groups::coalesced_threads), counting per instance. When the spheres do not fit in
// 48 KiB of shared memory the kernels keep them in the batch's global sphere buffer instead. With few
// instances, SphereKernel and BoxKernel count into a work set that the frame's last block publishes
// (FinishBlock), so the frame is one launch; otherwise Run clears the counters with a memset first.
#include <cooperative_groups.h>
#include <cuda/atomic>

#include <algorithm>
#include <cmath>
#include <new>
#include <utility>

#include "internal.h"
#include "spherechain/cuda/batch.h"
#include "spherechain/runtime/formulas.h"

namespace spherechain::cuda::detail {

// The per-frame formulas are runtime/formulas.h's (SPHERECHAIN_HD = __host__ __device__ under nvcc), one
// lane per thread; the target is compiled with --fmad=false like the host (no FMA contraction), so the
// spheres and pairs are the CPU's bit for bit. Only the device memory access is written here.
using Ops = runtime::formulas::ScalarOps;

/// formulas::RefitLanes of sphere `s` from its four pivot triangles' centroids (px, py, pz)[k]
/// (formulas::TriangleCentroid3): kPivotFrame with its kPaper fallback, or kPaper. Returns (x, y, z, r).
__device__ __forceinline__ float4 DevRefitFromCentroids(const DeviceAssetDesc& a, uint32_t s, const float* px,
                                                        const float* py, const float* pz, bool frame_mode) {
  const float4 local = __ldg(a.frame_local + s);  // (local_center, radius_scale)
  const float4 off = __ldg(a.frame_offset + s);   // (centroid_offset, 0)
  float out[4];
  runtime::formulas::RefitLanes<Ops>(px, py, pz, local.x, local.y, local.z, off.x, off.y, off.z, local.w, frame_mode,
                                     out);
  return make_float4(out[0], out[1], out[2], out[3]);
}

/// DevRefitFromCentroids from the 12 pivot vertices: `vertex(k, c)` is coordinate c of triangle k / 3's
/// corner k % 3. Returns (x, y, z, r).
template <typename VertexFn>
__device__ __forceinline__ float4 DevRefitFromPivots(const DeviceAssetDesc& a, uint32_t s, VertexFn vertex, bool frame_mode) {
  float px[4], py[4], pz[4];
#pragma unroll
  for (int k = 0; k < 4; ++k) {
    float v[3][3], c[3];
#pragma unroll
    for (int t = 0; t < 3; ++t)
#pragma unroll
      for (int d = 0; d < 3; ++d) v[t][d] = vertex(3 * k + t, d);
    runtime::formulas::TriangleCentroid3(v[0], v[1], v[2], c);
    px[k] = c[0], py[k] = c[1], pz[k] = c[2];
  }
  return DevRefitFromCentroids(a, s, px, py, pz, frame_mode);
}

/// RefitJob for one sphere `s`: 12 vertex reads (strided, read-only path), then DevRefitFromPivots.
/// Returns (x, y, z, r).
__device__ __forceinline__ float4 DevRefitSphere(const DeviceAssetDesc& a, const char* base, uint32_t stride,
                                                 uint32_t s, bool frame_mode) {
  const uint32_t* idx = a.pivot_vertices + size_t{12} * s;
  return DevRefitFromPivots(
      a, s,
      [&](int k, int c) { return __ldg(reinterpret_cast<const float*>(base + size_t{__ldg(idx + k)} * stride) + c); },
      frame_mode);
}

/// JointRefitJob for one sphere `s` (runtime/src/kernels.cpp JointRefitScalar, the same roundings):
/// M = ((w0·M_j0 + w1·M_j1) + w2·M_j2) + w3·M_j3 per element over influence 0 and then influences 1, 2, 3
/// while their weight is not 0, then per row (ρ0·bx + ρ1·by) + (ρ2·bz + ρ3); radius = the bind radius.
/// Returns (x, y, z, r).
__device__ __forceinline__ float4 DevJointSphere(const DeviceAssetDesc& a, const float* matrices, uint32_t s) {
  const uint4 off = __ldg(a.joint_offsets + s);
  const float4 w = __ldg(a.joint_weights + s);
  const float4 b = __ldg(a.bind + s);
  float m[12];
  const float* M = matrices + off.x;
#pragma unroll
  for (int e = 0; e < 12; ++e) m[e] = w.x * __ldg(M + e);
  auto blend = [&](uint32_t offset, float weight) {
    const float* N = matrices + offset;
#pragma unroll
    for (int e = 0; e < 12; ++e) m[e] = m[e] + weight * __ldg(N + e);
  };
  if (w.y != 0.0f) {
    blend(off.y, w.y);
    if (w.z != 0.0f) {
      blend(off.z, w.z);
      if (w.w != 0.0f) blend(off.w, w.w);
    }
  }
  float c[3];
#pragma unroll
  for (int row = 0; row < 3; ++row) {
    const float* p = m + 4 * row;
    c[row] = (p[0] * b.x + p[1] * b.y) + (p[2] * b.z + p[3] * 1.0f);
  }
  return make_float4(c[0], c[1], c[2], b.w);
}

/// DetectJob's overlap test (formulas::OverlapLanes) on the radii grown by the margin m (one float add
/// each, as DetectJob's gather does; with m == 0 that is r itself).
__device__ __forceinline__ bool DevOverlap(const float4& A, const float4& B, float m) {
  return runtime::formulas::OverlapLanes<Ops>(A.x, A.y, A.z, A.w + m, B.x, B.y, B.z, B.w + m);
}

/// The reported depth (formulas::SphereDepth): `grow` = 0 as M1 (own radii); `grow` = m as M2 with a
/// margin m ≠ 0.
__device__ __forceinline__ float DevDepth(const float4& A, const float4& B, float grow) {
  return runtime::formulas::SphereDepth<Ops>(A.x, A.y, A.z, A.w, B.x, B.y, B.z, B.w, grow);
}

/// True when (a, b), a < b, is an excluded (adjacent) pair: scan of a's sorted partner list.
__device__ __forceinline__ bool DevIsExcluded(const DeviceAssetDesc& d, uint32_t a, uint32_t b) {
  for (uint32_t i = __ldg(d.excl_offsets + a), e = __ldg(d.excl_offsets + a + 1); i < e; ++i) {
    const uint32_t n = d.excl_neighbors[i];
    if (n >= b) return n == b;
  }
  return false;
}

}  // namespace spherechain::cuda::detail

namespace cg = cooperative_groups;

namespace spherechain::cuda {
namespace {

using detail::DeviceInstance;

constexpr uint32_t kFlagFrameMode = 1u;     // RefitMode::kPivotFrame
constexpr uint32_t kFlagWriteSpheres = 2u;  // FrameParams::write_spheres
constexpr uint32_t kFlagM1 = 4u;            // DetectMethod::kM1
constexpr uint32_t kFlagJoints = 8u;        // RefitSource::kJoints
constexpr uint32_t kFlagPublish = 16u;      // counters kept in the work set, published by the frame's last block
constexpr uint32_t kNoSphere = 0xFFFFu;     // DeviceAssetDesc::slot_spheres padding
constexpr uint32_t kWarpsPerBlock = 4;      // kWarpPerInstance: instances per block
constexpr size_t kSharedLimit = 48 * 1024;  // default dynamic shared memory per block

struct KernelParams {
  DeviceAssetDesc asset0;  // the batch's asset when it has one (BoxKernel kOneAsset reads it from here)
  const DeviceAssetDesc* assets;
  const DeviceInstance* instances;
  BatchCollision* pairs;
  uint32_t* counters;  // [0] total, [1] overflow, [2 + i] per instance: the set the blocks add to
  uint32_t* published; // kFlagPublish: Batch::counters(), written by the frame's last block (FinishBlock)
  uint32_t* ticket;    // kFlagPublish: blocks finished so far (0 between frames)
  float4* spheres;     // Σ#S: output, and the sphere store when not in shared memory
  uint32_t instance_count;
  uint32_t capacity;
  uint32_t shared_spheres;  // spheres per group slice of shared memory
  uint32_t chains_per_instance;
  uint32_t split;     // SphereKernel: threads per sphere (1 when there are many instances)
  uint32_t blocks_per_instance;  // BoxKernel: blocks sharing an instance's block pairs (1 when there are many)
  uint32_t max_blocks, max_block_pairs;  // BoxKernel: shared memory layout
  uint32_t flags;
  float margin;       // FrameParams::margin: >= 0 for every instance, < 0 each instance's asset's
  float fold_margin;  // FrameParams::fold_margin: >= 0 for every instance (each asset has one), < 0 the asset's
};

// The contact margin instance spheres of asset `A` are tested with (as DetectJob's JobMargin).
__device__ __forceinline__ float InstanceMargin(const KernelParams& p, const DeviceAssetDesc& A) {
  return p.margin < 0.0f ? A.contact_margin : p.margin;
}

// The fold margin pairs of one region of asset `A` are tested with (as DetectJob's JobFoldMargin); < 0: none.
__device__ __forceinline__ float InstanceFoldMargin(const KernelParams& p, const DeviceAssetDesc& A) {
  return A.fold_margin < 0.0f ? -1.0f : (p.fold_margin < 0.0f ? A.fold_margin : p.fold_margin);
}

// The margin pair (a, b) is tested with: the fold margin when both spheres lie in one region (`region_a`
// is a's) and the asset has one, else the contact margin m. The CPU's broad phase grows the radii by the
// larger of the two and tests the other kind's hits again on their own margin, so its result is this test.
__device__ __forceinline__ float PairMargin(const DeviceAssetDesc& A, float m, float fold, uint32_t region_a,
                                            uint32_t b) {
  return fold >= 0.0f && __ldg(A.sphere_regions + b) == region_a ? fold : m;
}

// Region of sphere a for PairMargin (0 when the asset has no fold margin: then no region is read).
__device__ __forceinline__ uint32_t FoldRegion(const DeviceAssetDesc& A, float fold, uint32_t a) {
  return fold >= 0.0f ? __ldg(A.sphere_regions + a) : 0u;
}

// Sphere s of instance I refitted from the frame's source (FrameParams::source).
__device__ __forceinline__ float4 RefitSphere(const KernelParams& p, const DeviceAssetDesc& A, const DeviceInstance& I,
                                              uint32_t s) {
  if (p.flags & kFlagJoints) return detail::DevJointSphere(A, I.joint_matrices, s);
  return detail::DevRefitSphere(A, I.positions, I.stride_bytes, s, p.flags & kFlagFrameMode);
}

// Appends one pair: one atomicAdd per coalesced group of hitting threads. `grow`: see DevDepth (0 for
// M1, the margin for M2).
__device__ __forceinline__ void Emit(const KernelParams& p, uint32_t inst, uint32_t a, uint32_t b, const float4& A,
                                     const float4& B, uint32_t chains, float grow) {
  const float depth = detail::DevDepth(A, B, grow);
  cg::coalesced_group g = cg::coalesced_threads();
  uint32_t base = 0;
  if (g.thread_rank() == 0) base = atomicAdd(p.counters, g.size());
  base = g.shfl(base, 0);
  const uint32_t slot = base + g.thread_rank();
  if (slot < p.capacity) {
    reinterpret_cast<uint4*>(p.pairs)[slot] = make_uint4(inst, a | (b << 16), __float_as_uint(depth), chains);
  } else {
    atomicExch(p.counters + 1, 1u);
    __threadfence();  // rare; seen by the frame's last block (FinishBlock) before it publishes
  }
}

// End of a block of SphereKernel / BoxKernel under kFlagPublish (few instances: Run enqueues no memset;
// every thread must call; `block_hits` a shared word zeroed before the kernel's first __syncthreads):
// the block adds its hits to instance `inst`'s counter of the work set p.counters (zero when a frame
// starts), then takes a ticket (an acquire-release atomic: it releases this block's counter updates, which
// the barrier ordered before it, and acquires every earlier block's). The block that takes the last ticket
// moves the work set into Batch::counters() and zeroes it and the ticket for the next frame.
__device__ __forceinline__ void FinishBlock(const KernelParams& p, uint32_t inst, uint32_t hits, uint32_t* block_hits) {
  __shared__ uint32_t last;
  hits = __reduce_add_sync(0xffffffffu, hits);
  if ((threadIdx.x & 31u) == 0 && hits) atomicAdd(block_hits, hits);
  __syncthreads();
  if (threadIdx.x == 0) {
    if (*block_hits) atomicAdd(p.counters + 2 + inst, *block_hits);
    // release: this block's counter updates; acquire: every earlier block's
    last = ::cuda::atomic_ref<uint32_t, ::cuda::thread_scope_device>(*p.ticket).fetch_add(1u, ::cuda::memory_order_acq_rel) ==
           gridDim.x - 1;
  }
  __syncthreads();
  if (!last) return;
  for (uint32_t i = threadIdx.x; i < 2 + p.instance_count; i += blockDim.x) p.published[i] = atomicExch(p.counters + i, 0u);
  if (threadIdx.x == 0) *p.ticket = 0u;
}

// Adds each warp's hit count to instance `inst`'s counter (every lane of the warp must call).
__device__ __forceinline__ void AddInstanceCount(const KernelParams& p, uint32_t inst, uint32_t hits) {
  hits = __reduce_add_sync(0xffffffffu, hits);
  if ((threadIdx.x & 31u) == 0 && hits) atomicAdd(p.counters + 2 + inst, hits);
}

// kWarpPerInstance: a warp per instance, kWarpsPerBlock instances per block.
template <bool kShared>
__global__ void GroupKernel(KernelParams p) {
  extern __shared__ float4 smem[];
  const uint32_t group = threadIdx.x / 32u, lane = threadIdx.x % 32u;
  const uint32_t inst = blockIdx.x * (blockDim.x / 32u) + group;
  if (inst >= p.instance_count) return;  // whole warp
  const DeviceInstance I = p.instances[inst];
  const DeviceAssetDesc& A = p.assets[I.asset];
  const uint32_t S = A.sphere_count;
  const bool write = p.flags & kFlagWriteSpheres, m1 = p.flags & kFlagM1;
  const float m = InstanceMargin(p, A), grow = m1 ? 0.0f : m;  // depth rounding as DetectM1 / DetectM2
  const float fold = InstanceFoldMargin(p, A);
  float4* sph = kShared ? smem + size_t{group} * p.shared_spheres : p.spheres + I.sphere_offset;

  for (uint32_t s = lane; s < S; s += 32u) {
    const float4 v = RefitSphere(p, A, I, s);
    sph[s] = v;
    if (kShared && write) p.spheres[I.sphere_offset + s] = v;
  }
  __syncwarp();

  const uint32_t* mask = A.chain_mask;
  uint32_t hits = 0;
  // Sphere a broadcast to the warp; lanes take b = a + 1 + lane, a + 33 + lane, ...
  for (uint32_t a = 0; a + 1 < S; ++a) {
    const float4 SA = sph[a];
    const uint32_t ma = __ldg(mask + a);
    if (m1 && !ma) continue;  // uniform across the warp
    const uint32_t ra = FoldRegion(A, fold, a);
    for (uint32_t b = a + 1 + lane; b < S; b += 32u) {
      const uint32_t common = ma & __ldg(mask + b);
      if (m1 && !common) continue;
      const float4 SB = sph[b];
      if (detail::DevOverlap(SA, SB, PairMargin(A, m, fold, ra, b)) && !detail::DevIsExcluded(A, a, b)) {
        ++hits;
        Emit(p, inst, a, b, SA, SB, common, grow);
      }
    }
  }
  AddInstanceCount(p, inst, hits);
}

// kThreadPerSphere: a block per instance. The block refits the spheres into shared memory, with each one's
// chain mask and fold region beside it, then deals out the S(S−1)/2 pairs evenly: sphere a meets
// b = a + k (mod S) for k = 1 .. ⌊(S−1)/2⌋, and also k = S/2 when S is even and a < S/2 — every unordered
// pair once, every sphere ⌊S/2⌋ or ⌊(S−1)/2⌋ tests, so no thread waits on a longer row (a row per
// sphere, b > a, gives sphere 0 S−1 tests and the last none). With `split` > 1 (few instances: more
// threads per instance shorten the frame) the k range of each sphere is cut into `split` slices, one
// per thread. Each pair is tested and reported in index order (lower index first), so the floats are
// DetectJob's.
// kMany (split == 1): blocks of at most 256 threads, registers capped so that SPHERECHAIN_CUDA_SPHERE_BLOCKS
// such blocks fit an SM (6: 40 registers, 12 blocks of MakeHuman's 128 threads; a compile-time tuning
// knob, measured in docs/performance.md); else blocks of up to 1024 threads.
#ifndef SPHERECHAIN_CUDA_SPHERE_BLOCKS
#define SPHERECHAIN_CUDA_SPHERE_BLOCKS 6
#endif
// kBlockBoxes from vertices, many instances: its own register cap, SPHERECHAIN_CUDA_VERTEX_BLOCKS blocks of
// 256 threads an SM (a compile-time tuning knob; 3, 4, 5 and 6 measured in docs/performance.md: 6, the
// joint refit's 40 registers, is the fastest at 100,000 characters, 5 by 1 % at 10,000).
#ifndef SPHERECHAIN_CUDA_VERTEX_BLOCKS
#define SPHERECHAIN_CUDA_VERTEX_BLOCKS 6
#endif
template <bool kShared, bool kMany>
__global__ void __launch_bounds__(kMany ? 256 : 1024, kMany ? SPHERECHAIN_CUDA_SPHERE_BLOCKS : 1)
    SphereKernel(KernelParams p) {
  extern __shared__ float4 smem[];
  const uint32_t inst = blockIdx.x;
  if (inst >= p.instance_count) return;  // whole block
  const DeviceInstance I = p.instances[inst];
  const DeviceAssetDesc& A = p.assets[I.asset];
  const uint32_t S = A.sphere_count, T = blockDim.x;
  const bool write = p.flags & kFlagWriteSpheres, m1 = p.flags & kFlagM1;
  const float m = InstanceMargin(p, A), grow = m1 ? 0.0f : m;  // depth rounding as DetectM1 / DetectM2
  const float fold = InstanceFoldMargin(p, A);
  float4* sph = kShared ? smem : p.spheres + I.sphere_offset;
  uint2* meta = reinterpret_cast<uint2*>(smem + p.shared_spheres);  // kShared: (chain mask, fold region)
  __shared__ uint32_t block_hits;
  if (threadIdx.x == 0) block_hits = 0;

  for (uint32_t s = threadIdx.x; s < S; s += T) {
    const float4 v = RefitSphere(p, A, I, s);
    sph[s] = v;
    if (kShared) {
      meta[s] = make_uint2(__ldg(A.chain_mask + s), FoldRegion(A, fold, s));
      if (write) p.spheres[I.sphere_offset + s] = v;
    }
  }
  __syncthreads();

  auto meta_of = [&](uint32_t s) {
    return kShared ? meta[s] : make_uint2(__ldg(A.chain_mask + s), FoldRegion(A, fold, s));
  };
  const uint32_t split = p.split, half = (S - 1) / 2, chunk = (S / 2 + split - 1) / split;
  uint32_t hits = 0;
  for (uint32_t w = threadIdx.x; w < S * split; w += T) {
    const uint32_t a = w % S, part = w / S;
    const uint32_t k_end = min(half + ((S % 2 == 0 && a < S / 2) ? 1u : 0u), (part + 1) * chunk);
    uint32_t k = part * chunk + 1;
    if (k > k_end) continue;
    const float4 SA = sph[a];
    const uint2 MA = meta_of(a);
    uint32_t b = a + k;
    if (b >= S) b -= S;
    for (; k <= k_end; ++k, b = b + 1 == S ? 0 : b + 1) {
      const uint2 MB = meta_of(b);
      const uint32_t common = MA.x & MB.x;
      if (m1 && !common) continue;
      const float4 SB = sph[b];
      const bool a_first = a < b;
      const float4 P = a_first ? SA : SB;
      const float4 Q = a_first ? SB : SA;
      const uint32_t lo = a_first ? a : b, hi = a_first ? b : a;
      const float mp = fold >= 0.0f && MA.y == MB.y ? fold : m;
      if (detail::DevOverlap(P, Q, mp) && !detail::DevIsExcluded(A, lo, hi)) {
        ++hits;
        Emit(p, inst, lo, hi, P, Q, common, grow);
      }
    }
  }
  if (p.flags & kFlagPublish)
    FinishBlock(p, inst, hits, &block_hits);
  else
    AddInstanceCount(p, inst, hits);
}

// kBlockBoxes' shared memory, byte offsets (host and device compute it alike): the spheres by slot
// (float4; padding slots NaN), each slot's (chain mask, fold region | sphere id << 16), the blocks' bounds (lo xyz + grown
// radius, hi xyz), the kept block pairs, and two words (kept count, block hits).
struct BoxLayout {
  uint32_t meta, lo, hi, kept, words, bytes;
};
__host__ __device__ inline BoxLayout MakeBoxLayout(uint32_t max_blocks, uint32_t max_block_pairs) {
  BoxLayout L{};
  uint32_t o = 16u * 8u * max_blocks;
  L.meta = o, o += 8u * 8u * max_blocks;
  L.lo = o, o += 16u * max_blocks;
  L.hi = o, o += 16u * max_blocks;
  L.kept = o, o += 16u * max_block_pairs;
  L.words = o, o += 16u;
  L.bytes = o;
  return L;
}

// kBlockBoxes: `blocks_per_instance` blocks per instance (1 with many instances), DetectJob's broad phase
// (kernels.inl BlockBoxes / BlockRow).
// 1. refit each slot's sphere (every block of the instance refits them all); 2. per block the box of its
// centres and its largest radius grown by M, the larger of the margin and the fold margin (NaN terms
// skipped); 3. per block pair with a lane of the method (this block's share: every
// blocks_per_instance-th), the gap test of BlockRow — per axis g = max(loJ − hiI, loI − hiJ, 0), kept when
// g_x² + g_y² + g_z² < (R_I + R_J)², which never drops a pair the sphere test reports (the monotonic
// rounding argument in kernels.inl) — kept pairs appended to shared memory; 4. the allowed lanes of the
// kept pairs, 64 per pair dealt over the threads: the sphere test with the pair's own margin (DetectJob's
// floats: the test and the depth are symmetric in the two spheres), reported (lower id, higher id).
// kMany: blocks of at most 256 threads under a register cap (SPHERECHAIN_CUDA_SPHERE_BLOCKS from joints,
// SPHERECHAIN_CUDA_VERTEX_BLOCKS from vertices); else SPHERECHAIN_CUDA_FEW_THREADS (512).
// kOneAsset (a batch of one asset): the asset's descriptor is read from the kernel's parameters, so the
// reads of the instance, the slots and the first block pair do not wait on a read of the asset table.
// Few instances (fewer than 4 an SM): up to SPHERECHAIN_CUDA_FEW_BLOCKS blocks an instance, of
// SPHERECHAIN_CUDA_FEW_THREADS threads each (compile-time tuning knobs, measured in docs/performance.md).
#ifndef SPHERECHAIN_CUDA_FEW_BLOCKS
#define SPHERECHAIN_CUDA_FEW_BLOCKS 8
#endif
#ifndef SPHERECHAIN_CUDA_FEW_THREADS
#define SPHERECHAIN_CUDA_FEW_THREADS 512
#endif
static_assert(SPHERECHAIN_CUDA_FEW_BLOCKS >= 1, "SPHERECHAIN_CUDA_FEW_BLOCKS: at least one block an instance");
static_assert(SPHERECHAIN_CUDA_FEW_THREADS % 32 == 0 && SPHERECHAIN_CUDA_FEW_THREADS >= 32 &&
                  SPHERECHAIN_CUDA_FEW_THREADS <= 1024,
              "SPHERECHAIN_CUDA_FEW_THREADS: whole warps (the counts are reduced a warp at a time), at most 1024");
// meta's second word packs a sphere's fold region (8 bits: Asset.sphere_regions) and its id (< 65535).
static_assert(runtime::kMaxSpheres <= 0xFFFFu, "sphere ids must fit the 16 bits of BoxKernel's meta");
template <bool kMany, bool kJoints, bool kOneAsset>
__global__ void __launch_bounds__(kMany ? 256 : SPHERECHAIN_CUDA_FEW_THREADS,
                                  kMany ? (kJoints ? SPHERECHAIN_CUDA_SPHERE_BLOCKS : SPHERECHAIN_CUDA_VERTEX_BLOCKS) : 1)
    BoxKernel(const __grid_constant__ KernelParams p) {
  extern __shared__ float4 smem[];
  const uint32_t G = p.blocks_per_instance, inst = blockIdx.x / G, part = blockIdx.x % G;
  if (inst >= p.instance_count) return;  // whole block (never: the grid is N·G blocks)
  const DeviceInstance I = p.instances[inst];
  const DeviceAssetDesc& A = kOneAsset ? p.asset0 : p.assets[I.asset];
  const uint32_t B = A.block_count, slots = 8 * B, T = blockDim.x;
  const bool write = (p.flags & kFlagWriteSpheres) && part == 0, m1 = p.flags & kFlagM1;
  const float m = InstanceMargin(p, A), grow = m1 ? 0.0f : m;  // depth rounding as DetectM1 / DetectM2
  const float fold = InstanceFoldMargin(p, A);
  const float M = fold >= 0.0f ? fmaxf(m, fold) : m;
  const BoxLayout L = MakeBoxLayout(p.max_blocks, p.max_block_pairs);
  char* const base = reinterpret_cast<char*>(smem);
  float4* sph = smem;                                          // 8 · max_blocks
  uint2* meta = reinterpret_cast<uint2*>(base + L.meta);       // 8 · max_blocks
  float4* lo = reinterpret_cast<float4*>(base + L.lo);         // max_blocks: lo xyz, R
  float4* hi = reinterpret_cast<float4*>(base + L.hi);         // max_blocks: hi xyz
  uint4* kept = reinterpret_cast<uint4*>(base + L.kept);       // max_block_pairs
  uint32_t* words = reinterpret_cast<uint32_t*>(base + L.words);  // [0] kept count, [1] block hits
  if (threadIdx.x == 0) words[0] = words[1] = 0;
  // Few instances: this thread's first block pair (step 3) is read now, so that the read overlaps the
  // refit (with many, the registers it would hold through the refit cost more than the wait).
  const uint4* pairs = A.block_pairs[m1 ? 0 : 1];
  const uint32_t pair_count = A.block_pair_count[m1 ? 0 : 1], first_pair = threadIdx.x * G + part;
  const uint4 prefetched =
      !kMany && first_pair < pair_count ? __ldg(pairs + first_pair) : make_uint4(0u, 0u, 0u, 0u);

  // meta[s] = (chain mask, fold region | sphere id << 16)
  for (uint32_t s = threadIdx.x; s < slots; s += T) {
    const uint32_t id = A.slot_spheres[s];
    if (id == kNoSphere) {
      sph[s] = make_float4(__int_as_float(0x7fc00000), 0.0f, 0.0f, __int_as_float(0x7fc00000));
      meta[s] = make_uint2(0u, kNoSphere << 16);  // never tested (no lane allows it); were it, id 0xFFFF
      continue;
    }
    const float4 v = kJoints ? detail::DevJointSphere(A, I.joint_matrices, id)
                             : detail::DevRefitSphere(A, I.positions, I.stride_bytes, id, p.flags & kFlagFrameMode);
    sph[s] = v;
    meta[s] = make_uint2(__ldg(A.chain_mask + id), FoldRegion(A, fold, id) | id << 16);
    if (write) p.spheres[I.sphere_offset + id] = v;
  }
  __syncthreads();

  for (uint32_t b = threadIdx.x; b < B; b += T) {
    float lx = INFINITY, ly = INFINITY, lz = INFINITY, hx = -INFINITY, hy = -INFINITY, hz = -INFINITY, R = 0.0f;
    for (uint32_t l = 0; l < 8; ++l) {
      const float4 v = sph[8 * b + l];
      lx = fminf(lx, v.x), hx = fmaxf(hx, v.x), ly = fminf(ly, v.y), hy = fmaxf(hy, v.y);
      lz = fminf(lz, v.z), hz = fmaxf(hz, v.z), R = fmaxf(R, fabsf(v.w + M));
    }
    lo[b] = make_float4(lx, ly, lz, R);
    hi[b] = make_float4(hx, hy, hz, 0.0f);
  }
  __syncthreads();

  for (uint32_t w = first_pair; w < pair_count; w += T * G) {
    const uint4 e = !kMany && w == first_pair ? prefetched : __ldg(pairs + w);
    const uint32_t bi = e.x & 0xFFFFu, bj = e.x >> 16;
    const float4 li = lo[bi], hi_i = hi[bi], lj = lo[bj], hj = hi[bj];
    const float gx = fmaxf(fmaxf(lj.x - hi_i.x, li.x - hj.x), 0.0f);
    const float gy = fmaxf(fmaxf(lj.y - hi_i.y, li.y - hj.y), 0.0f);
    const float gz = fmaxf(fmaxf(lj.z - hi_i.z, li.z - hj.z), 0.0f);
    const float rr = li.w + lj.w;
    if (gx * gx + gy * gy + gz * gz < rr * rr) kept[atomicAdd(words, 1u)] = e;
  }
  __syncthreads();

  uint32_t hits = 0;
  for (uint32_t w = threadIdx.x, n = 64 * words[0]; w < n; w += T) {
    const uint4 e = kept[w >> 6];
    const uint32_t lane = w & 63u;
    if (!(((lane < 32 ? e.y : e.z) >> (lane & 31u)) & 1u)) continue;
    const uint32_t ps = 8 * (e.x & 0xFFFFu) + (lane >> 3), qs = 8 * (e.x >> 16) + (lane & 7u);
    const float4 P = sph[ps], Q = sph[qs];
    const uint2 MP = meta[ps], MQ = meta[qs];
    const float mp = fold >= 0.0f && ((MP.y ^ MQ.y) & 0xFFFFu) == 0 ? fold : m;
    if (detail::DevOverlap(P, Q, mp)) {
      const uint32_t a = MP.y >> 16, b = MQ.y >> 16;
      ++hits;
      Emit(p, inst, min(a, b), max(a, b), P, Q, MP.x & MQ.x, grow);
    }
  }
  if (p.flags & kFlagPublish)
    FinishBlock(p, inst, hits, words + 1);
  else
    AddInstanceCount(p, inst, hits);
}

// M1, a block per (instance, chain), a thread per chain sphere (§6, M1 mapping).
template <bool kShared>
__global__ void ChainKernel(KernelParams p) {
  extern __shared__ float4 smem[];
  const uint32_t inst = blockIdx.x / p.chains_per_instance, chain = blockIdx.x % p.chains_per_instance;
  if (inst >= p.instance_count) return;
  const DeviceInstance I = p.instances[inst];
  const DeviceAssetDesc& A = p.assets[I.asset];
  if (chain >= A.chain_count && chain != 0) return;  // whole block
  const bool write = p.flags & kFlagWriteSpheres;
  const float m = InstanceMargin(p, A), fold = InstanceFoldMargin(p, A);
  const uint32_t* mask = A.chain_mask;
  uint32_t off = 0, n = 0;
  if (chain < A.chain_count) {
    off = __ldg(A.chain_offsets + chain);
    n = __ldg(A.chain_offsets + chain + 1) - off;
  }
  const uint16_t* ids = A.chain_spheres + off;
  float4* global = p.spheres + I.sphere_offset;

  // Refit the chain's spheres (shared: by chain position; global: by sphere index — blocks of other
  // chains may write the same sphere, always with the same bits). Each sphere is written to the
  // output by its first chain's block; chain 0's block also refits the chainless spheres.
  for (uint32_t i = threadIdx.x; i < n; i += blockDim.x) {
    const uint32_t s = ids[i];
    const float4 v = RefitSphere(p, A, I, s);
    if (kShared) {
      smem[i] = v;
      if (write && uint32_t(__ffs(__ldg(mask + s)) - 1) == chain) global[s] = v;
    } else {
      global[s] = v;
    }
  }
  if (write && chain == 0)
    for (uint32_t s = threadIdx.x; s < A.sphere_count; s += blockDim.x)
      if (!__ldg(mask + s)) global[s] = RefitSphere(p, A, I, s);
  __syncthreads();

  uint32_t hits = 0;
  for (uint32_t i = threadIdx.x; i < n; i += blockDim.x) {
    const uint32_t a = ids[i];
    const float4 SA = kShared ? smem[i] : global[a];
    const uint32_t ma = __ldg(mask + a);
    const uint32_t ra = FoldRegion(A, fold, a);
    for (uint32_t j = i + 1; j < n; ++j) {
      const uint32_t b = ids[j];
      const float4 SB = kShared ? smem[j] : global[b];
      if (!detail::DevOverlap(SA, SB, PairMargin(A, m, fold, ra, b))) continue;
      const uint32_t common = ma & __ldg(mask + b);
      // Reported once: by the first chain containing both (as the CPU DetectM1).
      if (uint32_t(__ffs(common) - 1) != chain || detail::DevIsExcluded(A, a, b)) continue;
      ++hits;
      Emit(p, inst, a, b, SA, SB, common, 0.0f);  // M1: depth from the own radii
    }
  }
  AddInstanceCount(p, inst, hits);
}

uint32_t RoundUp32(uint32_t v) { return (v + 31u) & ~31u; }

// The counters' device block: Batch::counters() [2 + N], the work set of kFlagPublish frames [2 + N] (zero
// between frames), the ticket.
size_t CounterBytes(uint32_t instance_count) { return sizeof(uint32_t) * (2 * (2 + size_t{instance_count}) + 1); }

void FreeAll(void** ptrs, size_t n) {
  for (size_t i = 0; i < n; ++i)
    if (ptrs[i]) (void)cudaFree(ptrs[i]);
}

}  // namespace

Batch::Batch(Batch&& o) noexcept { *this = std::move(o); }

Batch& Batch::operator=(Batch&& o) noexcept {
  if (this != &o) {
    Release();
    host_assets_ = std::exchange(o.host_assets_, nullptr);
    asset_count_ = std::exchange(o.asset_count_, 0);
    instance_count_ = std::exchange(o.instance_count_, 0);
    capacity_ = std::exchange(o.capacity_, 0);
    total_spheres_ = std::exchange(o.total_spheres_, 0);
    max_spheres_ = std::exchange(o.max_spheres_, 0);
    max_blocks_ = std::exchange(o.max_blocks_, 0);
    max_block_pairs_ = std::exchange(o.max_block_pairs_, 0);
    asset0_ = std::exchange(o.asset0_, DeviceAssetDesc{});
    max_chains_ = std::exchange(o.max_chains_, 0);
    max_chain_length_ = std::exchange(o.max_chain_length_, 0);
    sm_count_ = std::exchange(o.sm_count_, 1);
    frame_position_bytes_ = std::exchange(o.frame_position_bytes_, 0);
    frame_joint_bytes_ = std::exchange(o.frame_joint_bytes_, 0);
    every_asset_folds_ = std::exchange(o.every_asset_folds_, false);
    all_positions_ = std::exchange(o.all_positions_, false);
    all_joints_ = std::exchange(o.all_joints_, false);
    sphere_offsets_ = std::move(o.sphere_offsets_);
    table_ = std::exchange(o.table_, nullptr);
    asset_table_ = std::exchange(o.asset_table_, nullptr);
    instance_table_ = std::exchange(o.instance_table_, nullptr);
    pairs_ = std::exchange(o.pairs_, nullptr);
    counters_ = std::exchange(o.counters_, nullptr);
    spheres_ = std::exchange(o.spheres_, nullptr);
  }
  return *this;
}

Batch::~Batch() { Release(); }

void Batch::Release() {
  void* ptrs[] = {table_, pairs_, counters_, spheres_};
  FreeAll(ptrs, 4);
  host_assets_ = nullptr;
  asset_count_ = instance_count_ = capacity_ = total_spheres_ = 0;
  max_spheres_ = max_chains_ = max_chain_length_ = max_blocks_ = max_block_pairs_ = 0;
  asset0_ = DeviceAssetDesc{};
  sm_count_ = 1;
  frame_position_bytes_ = frame_joint_bytes_ = 0;
  every_asset_folds_ = all_positions_ = all_joints_ = false;
  sphere_offsets_.clear();
  table_ = asset_table_ = instance_table_ = nullptr;
  pairs_ = nullptr;
  counters_ = nullptr;
  spheres_ = nullptr;
}

namespace {

Status CheckInstances(const DeviceAsset* const* assets, uint32_t asset_count, const Instance* instances,
                      uint32_t instance_count) {
  for (uint32_t i = 0; i < instance_count; ++i) {
    const Instance& in = instances[i];
    if (!in.positions && !in.joint_matrices) return Status::kErrorNullArgument;
    if (in.asset >= asset_count) return Status::kErrorInvalidJob;
    if (in.positions) {
      if (reinterpret_cast<uintptr_t>(in.positions) % alignof(float) != 0) return Status::kErrorAlignment;
      if (in.stride_bytes < 3 * sizeof(float) || in.stride_bytes % sizeof(float) != 0) return Status::kErrorStride;
      if (in.vertex_count != assets[in.asset]->vertex_count()) return Status::kErrorVertexCount;
    }
    if (in.joint_matrices) {
      if (reinterpret_cast<uintptr_t>(in.joint_matrices) % alignof(float) != 0) return Status::kErrorAlignment;
      if (assets[in.asset]->joint_count() == 0) return Status::kErrorMissingField;
      if (in.joint_count != assets[in.asset]->joint_count()) return Status::kErrorJointCount;
    }
  }
  return Status::kOk;
}

}  // namespace

Status Batch::Init(const DeviceAsset* const* assets, uint32_t asset_count, const Instance* instances,
                   uint32_t instance_count, uint32_t capacity) {
  Release();
  if (!assets || !instances || asset_count == 0 || instance_count == 0) return Status::kErrorNullArgument;
  if (asset_count > 65536u || instance_count > (1u << 26)) return Status::kErrorInvalidJob;
  for (uint32_t k = 0; k < asset_count; ++k)
    if (!assets[k] || !assets[k]->valid()) return Status::kErrorInvalidJob;
  if (Status s = CheckInstances(assets, asset_count, instances, instance_count); s != Status::kOk) return s;

  uint64_t total_spheres = 0, pairs_bound = 0;
  uint32_t max_s = 0, max_c = 0, max_len = 0, max_blocks = 0, max_block_pairs = 0;
  try {
    sphere_offsets_.resize(instance_count);
  } catch (const std::bad_alloc&) {
    return Status::kErrorOutOfMemory;
  }
  for (uint32_t i = 0; i < instance_count; ++i) {
    const DeviceAssetDesc& d = assets[instances[i].asset]->desc();
    sphere_offsets_[i] = static_cast<uint32_t>(total_spheres);
    total_spheres += d.sphere_count;
    pairs_bound += uint64_t{d.sphere_count} * (d.sphere_count - 1) / 2 - d.excluded_count;
    max_s = std::max(max_s, d.sphere_count);
    max_c = std::max(max_c, d.chain_count);
    max_len = std::max(max_len, d.max_chain_length);
    max_blocks = std::max(max_blocks, d.block_count);
    max_block_pairs = std::max({max_block_pairs, d.block_pair_count[0], d.block_pair_count[1]});
  }
  if (total_spheres > UINT32_MAX) {
    Release();
    return Status::kErrorInvalidJob;
  }
  if (capacity == 0) capacity = static_cast<uint32_t>(std::min<uint64_t>(std::max<uint64_t>(pairs_bound, 1), 1u << 31));

  int dev = 0, sms = 1;
  if (Status s = detail::CudaStatus(cudaGetDevice(&dev)); s != Status::kOk) return Release(), s;
  if (Status s = detail::CudaStatus(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, dev));
      s != Status::kOk)
    return Release(), s;

  const size_t asset_bytes = sizeof(DeviceAssetDesc) * asset_count;
  const size_t inst_off = (asset_bytes + 63) & ~size_t{63};
  const size_t table_bytes = inst_off + sizeof(DeviceInstance) * instance_count;
  Status st = detail::CudaStatus(cudaMalloc(&table_, table_bytes));
  if (st == Status::kOk) st = detail::CudaStatus(cudaMalloc(reinterpret_cast<void**>(&pairs_), sizeof(BatchCollision) * capacity));
  if (st == Status::kOk)
    st = detail::CudaStatus(cudaMalloc(reinterpret_cast<void**>(&counters_), CounterBytes(instance_count)));
  if (st == Status::kOk) st = detail::CudaStatus(cudaMalloc(reinterpret_cast<void**>(&spheres_), sizeof(float4) * total_spheres));
  if (st != Status::kOk) return Release(), st;
  asset_table_ = table_;
  instance_table_ = static_cast<char*>(table_) + inst_off;

  try {
    std::vector<DeviceAssetDesc> descs(asset_count);
    for (uint32_t k = 0; k < asset_count; ++k) descs[k] = assets[k]->desc();
    asset0_ = descs[0];  // a one-asset batch's kBlockBoxes reads it from the kernel's parameters
    st = detail::CudaStatus(cudaMemcpy(asset_table_, descs.data(), asset_bytes, cudaMemcpyHostToDevice));
  } catch (const std::bad_alloc&) {
    st = Status::kErrorOutOfMemory;
  }
  if (st == Status::kOk) st = detail::CudaStatus(cudaMemset(counters_, 0, CounterBytes(instance_count)));
  if (st != Status::kOk) return Release(), st;

  host_assets_ = assets;
  asset_count_ = asset_count;
  capacity_ = capacity;
  total_spheres_ = static_cast<uint32_t>(total_spheres);
  max_spheres_ = max_s;
  max_blocks_ = max_blocks;
  max_block_pairs_ = max_block_pairs;
  max_chains_ = max_c;
  max_chain_length_ = max_len;
  sm_count_ = static_cast<uint32_t>(sms);
  every_asset_folds_ = true;
  for (uint32_t k = 0; k < asset_count; ++k) every_asset_folds_ = every_asset_folds_ && assets[k]->fold_margin() >= 0.0f;
  instance_count_ = instance_count;
  if (st = Upload(instances, instance_count); st != Status::kOk) Release();
  return st;
}

Status Batch::Upload(const Instance* instances, uint32_t instance_count) {
  uint64_t pos_bytes = 0, joint_bytes = 0;
  bool all_positions = true, all_joints = true;
  for (uint32_t i = 0; i < instance_count; ++i) {
    const Instance& in = instances[i];
    all_positions = all_positions && in.positions;
    all_joints = all_joints && in.joint_matrices;
    if (in.positions) pos_bytes += uint64_t{host_assets_[in.asset]->sphere_count()} * 12 * 12;
    if (in.joint_matrices) joint_bytes += uint64_t{in.joint_count} * 12 * sizeof(float);
  }
  frame_position_bytes_ = pos_bytes;
  frame_joint_bytes_ = joint_bytes;
  all_positions_ = all_positions;
  all_joints_ = all_joints;
  try {
    std::vector<DeviceInstance> table(instance_count);
    for (uint32_t i = 0; i < instance_count; ++i)
      table[i] = {static_cast<const char*>(instances[i].positions), instances[i].joint_matrices, instances[i].stride_bytes,
                  instances[i].asset, sphere_offsets_[i], 0u};
    return detail::CudaStatus(
        cudaMemcpy(instance_table_, table.data(), sizeof(DeviceInstance) * instance_count, cudaMemcpyHostToDevice));
  } catch (const std::bad_alloc&) {
    return Status::kErrorOutOfMemory;
  }
}

Status Batch::SetInstances(const Instance* instances, uint32_t instance_count) {
  if (!initialized()) return Status::kErrorInvalidJob;
  if (!instances) return Status::kErrorNullArgument;
  if (instance_count != instance_count_) return Status::kErrorInvalidJob;
  if (Status s = CheckInstances(host_assets_, asset_count_, instances, instance_count); s != Status::kOk) return s;
  for (uint32_t i = 0; i < instance_count; ++i) {  // sphere layout must stay (same #S per instance)
    const uint32_t next = i + 1 < instance_count ? sphere_offsets_[i + 1] : total_spheres_;
    if (host_assets_[instances[i].asset]->sphere_count() != next - sphere_offsets_[i]) return Status::kErrorInvalidJob;
  }
  return Upload(instances, instance_count);
}

Status Batch::Run(const FrameParams& params, cudaStream_t stream) const {
  if (!initialized()) return Status::kErrorInvalidJob;
  const bool joints = params.source == runtime::RefitSource::kJoints;
  if (!joints && params.source != runtime::RefitSource::kVertices) return Status::kErrorInvalidJob;
  if (!joints && params.mode != runtime::RefitMode::kPaper && params.mode != runtime::RefitMode::kPivotFrame)
    return Status::kErrorInvalidJob;
  const bool m1 = params.method == runtime::DetectMethod::kM1;
  if (!m1 && params.method != runtime::DetectMethod::kM2) return Status::kErrorInvalidJob;
  if (!std::isfinite(params.margin) || !std::isfinite(params.fold_margin)) return Status::kErrorInvalidJob;  // as DetectJob::Check
  // A fold margin of the frame's own needs regions: every asset of the batch must have one (checked at Init).
  if (params.fold_margin >= 0.0f && !every_asset_folds_) return Status::kErrorInvalidJob;
  if (!(joints ? all_joints_ : all_positions_)) return Status::kErrorNullArgument;  // the source's input, per instance
  Strategy strategy = params.strategy;
  const bool few = instance_count_ < 4 * sm_count_;
  const uint32_t box_threads = few ? SPHERECHAIN_CUDA_FEW_THREADS : std::clamp(RoundUp32(8 * max_blocks_), 32u, 256u);
  const size_t box_shm = MakeBoxLayout(max_blocks_, max_block_pairs_).bytes;
  if (strategy == Strategy::kAuto || (strategy == Strategy::kBlockBoxes && box_shm > kSharedLimit))
    strategy = box_shm <= kSharedLimit ? Strategy::kBlockBoxes : Strategy::kThreadPerSphere;
  if (strategy == Strategy::kBlockPerChain && !m1) return Status::kErrorInvalidJob;
  if (strategy != Strategy::kThreadPerSphere && strategy != Strategy::kBlockPerChain &&
      strategy != Strategy::kWarpPerInstance && strategy != Strategy::kBlockBoxes)
    return Status::kErrorInvalidJob;
  // Few instances, a block (or a few) per instance: the kernel's last block publishes the counters, so the
  // frame is one launch without a memset (FinishBlock).
  const bool publish = few && (strategy == Strategy::kBlockBoxes || strategy == Strategy::kThreadPerSphere);

  KernelParams p;
  p.assets = static_cast<const DeviceAssetDesc*>(asset_table_);
  p.instances = static_cast<const DeviceInstance*>(instance_table_);
  p.pairs = pairs_;
  p.counters = publish ? counters_ + 2 + instance_count_ : counters_;
  p.published = counters_;
  p.ticket = counters_ + 2 * (2 + size_t{instance_count_});
  p.spheres = spheres_;
  p.instance_count = instance_count_;
  p.capacity = capacity_;
  p.shared_spheres = max_spheres_;
  p.chains_per_instance = std::max(max_chains_, 1u);
  p.split = 1;
  p.blocks_per_instance = 1;
  p.max_blocks = max_blocks_;
  p.max_block_pairs = max_block_pairs_;
  p.margin = params.margin;
  p.fold_margin = params.fold_margin;
  p.flags = (params.mode == runtime::RefitMode::kPivotFrame ? kFlagFrameMode : 0u) |
            (params.write_spheres ? kFlagWriteSpheres : 0u) | (m1 ? kFlagM1 : 0u) | (joints ? kFlagJoints : 0u) |
            (publish ? kFlagPublish : 0u);

  if (!publish)
    if (Status s = detail::CudaStatus(cudaMemsetAsync(counters_, 0, sizeof(uint32_t) * (2 + size_t{instance_count_}), stream));
        s != Status::kOk)
      return s;

  switch (strategy) {
    case Strategy::kThreadPerSphere: {
      // Few instances: up to 1024 threads per instance (split threads per sphere) to shorten the frame.
      const uint32_t per_sphere = RoundUp32(max_spheres_);
      p.split = few ? std::clamp(1024u / std::max(per_sphere, 1u), 1u, 8u) : 1u;
      const uint32_t threads = std::clamp(per_sphere * p.split, 32u, p.split > 1 ? 1024u : 256u);
      const size_t shm = (sizeof(float4) + sizeof(uint2)) * max_spheres_;
      const bool many = p.split == 1;
      if (shm <= kSharedLimit && many)
        SphereKernel<true, true><<<instance_count_, threads, shm, stream>>>(p);
      else if (shm <= kSharedLimit)
        SphereKernel<true, false><<<instance_count_, threads, shm, stream>>>(p);
      else if (many)
        SphereKernel<false, true><<<instance_count_, threads, 0, stream>>>(p);
      else
        SphereKernel<false, false><<<instance_count_, threads, 0, stream>>>(p);
      break;
    }
    case Strategy::kBlockBoxes: {
      // Few instances: up to 8 blocks share an instance's block pairs (each refits all its spheres), so
      // a frame of one character takes a shorter path through the block-pair and sphere tests.
      p.blocks_per_instance = few ? std::clamp(sm_count_ / instance_count_, 1u, uint32_t{SPHERECHAIN_CUDA_FEW_BLOCKS}) : 1u;
      const uint32_t blocks = instance_count_ * p.blocks_per_instance;
      auto launch = [&](auto kernel) { kernel<<<blocks, box_threads, box_shm, stream>>>(p); };
      const bool one = asset_count_ == 1;
      if (one) p.asset0 = asset0_;
      if (few && joints)
        one ? launch(BoxKernel<false, true, true>) : launch(BoxKernel<false, true, false>);
      else if (few)
        one ? launch(BoxKernel<false, false, true>) : launch(BoxKernel<false, false, false>);
      else if (joints)
        one ? launch(BoxKernel<true, true, true>) : launch(BoxKernel<true, true, false>);
      else
        one ? launch(BoxKernel<true, false, true>) : launch(BoxKernel<true, false, false>);
      break;
    }
    case Strategy::kWarpPerInstance: {
      const uint32_t blocks = (instance_count_ + kWarpsPerBlock - 1) / kWarpsPerBlock;
      const size_t shm = sizeof(float4) * max_spheres_ * kWarpsPerBlock;
      if (shm <= kSharedLimit)
        GroupKernel<true><<<blocks, 32 * kWarpsPerBlock, shm, stream>>>(p);
      else
        GroupKernel<false><<<blocks, 32 * kWarpsPerBlock, 0, stream>>>(p);
      break;
    }
    case Strategy::kBlockPerChain: {
      const uint32_t threads = std::clamp(RoundUp32(max_chain_length_), 32u, 256u);
      const uint64_t blocks = uint64_t{instance_count_} * p.chains_per_instance;
      if (blocks > 0x7fffffffu) return Status::kErrorInvalidJob;
      const size_t shm = sizeof(float4) * max_chain_length_;
      if (shm <= kSharedLimit)
        ChainKernel<true><<<static_cast<uint32_t>(blocks), threads, shm, stream>>>(p);
      else
        ChainKernel<false><<<static_cast<uint32_t>(blocks), threads, 0, stream>>>(p);
      break;
    }
    default: return Status::kErrorInvalidJob;
  }
  return detail::CudaStatus(cudaGetLastError());
}

Status Batch::Download(cudaStream_t stream, HostResults* out, bool with_spheres) const {
  if (!out) return Status::kErrorNullArgument;
  if (!initialized()) return Status::kErrorInvalidJob;
  if (Status s = detail::CudaStatus(cudaStreamSynchronize(stream)); s != Status::kOk) return s;
  try {
    std::vector<uint32_t> counters(2 + size_t{instance_count_});
    if (Status s = detail::CudaStatus(
            cudaMemcpy(counters.data(), counters_, sizeof(uint32_t) * counters.size(), cudaMemcpyDeviceToHost));
        s != Status::kOk)
      return s;
    out->total = counters[0];
    out->overflow = counters[1] != 0;
    out->instance_counts.assign(counters.begin() + 2, counters.end());
    out->pairs.resize(std::min(out->total, capacity_));
    if (!out->pairs.empty())
      if (Status s = detail::CudaStatus(cudaMemcpy(out->pairs.data(), pairs_, sizeof(BatchCollision) * out->pairs.size(),
                                                   cudaMemcpyDeviceToHost));
          s != Status::kOk)
        return s;
    out->spheres.clear();
    if (with_spheres) {
      out->spheres.resize(total_spheres_);
      if (Status s = detail::CudaStatus(
              cudaMemcpy(out->spheres.data(), spheres_, sizeof(float4) * total_spheres_, cudaMemcpyDeviceToHost));
          s != Status::kOk)
        return s;
    }
  } catch (const std::bad_alloc&) {
    return Status::kErrorOutOfMemory;
  }
  return out->overflow ? Status::kOkTruncated : Status::kOk;
}

}  // namespace spherechain::cuda
