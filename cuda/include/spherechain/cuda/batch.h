// spherechain cuda — refit + detect for one or many character instances per launch (paper §5.1, §5.2, §6).
#pragma once

#include <cstdint>
#include <vector>

#include "spherechain/cuda/asset.h"
#include "spherechain/cuda/status.h"
#include "spherechain/runtime/batch.h"
#include "spherechain/runtime/detect.h"
#include "spherechain/runtime/refit.h"

namespace spherechain::cuda {

/// How the fused refit+detect kernel maps work to threads (paper §6 compares M1/M2 on the GPU).
/// All strategies report the same pair set for a given DetectMethod and margin (the CPU DetectJob's
/// set with the same DetectJob::margin).
enum class Strategy : uint8_t {
  /// kBlockBoxes (the fastest at every batch size measured on an H200 with MakeHuman:
  /// docs/performance.md, "GPU").
  kAuto = 0,
  /// A block per instance, a thread per sphere: thread a refits sphere a into shared memory, then
  /// tests it against every higher-index sphere b > a (M1: only b sharing a chain with a). The paper's
  /// M2 GPU mapping. Block size = \#S rounded up to 32, at most 256 (larger \#S: threads loop).
  kThreadPerSphere = 1,
  /// M1 only: a block per (instance, chain), a thread per chain sphere: the block refits its chain's
  /// spheres into shared memory (a sphere in k chains is refitted k times), thread i tests chain
  /// sphere i against chain spheres j > i; a pair is reported by the first chain holding both (as
  /// the CPU). The paper's M1 GPU mapping. kErrorInvalidJob with M2.
  kBlockPerChain = 2,
  /// Batched: a warp per instance, 4 instances per 128-thread block; lanes refit spheres, then for
  /// each sphere a the lanes test b > a in parallel. Fills the GPU with many small characters.
  kWarpPerInstance = 3,
  /// A block per instance with the CPU DetectJob's broad phase: the block refits the spheres into shared
  /// memory in the model's blocks of 8 (grouped by body region, kd-split at bind pose), bounds each block
  /// (box of centres, largest radius grown by the margin), keeps the block pairs whose gap is below the
  /// radii (DetectJob's conservative test: it never drops a pair the sphere test reports), and tests only
  /// their allowed lanes (not excluded; M1: sharing a chain) — far fewer sphere tests than all S(S−1)/2.
  /// Few instances (fewer than 4 an SM): blocks of 512 threads, up to 8 per instance (each refits all its
  /// spheres and tests a share of its block pairs; compile-time knobs SPHERECHAIN_CUDA_FEW_THREADS and
  /// SPHERECHAIN_CUDA_FEW_BLOCKS). Needs the blocks in 48 KiB of shared memory (else
  /// kThreadPerSphere runs instead).
  kBlockBoxes = 4,
};

/// One character instance of a batch (host struct, copied to the device by Batch::Init /
/// SetInstances). It carries the input of either refit source (FrameParams::source), or both.
struct Instance {
  /// DEVICE pointer to the deformed positions, vertex i = 3 floats (x, y, z) at
  /// `(const char*)positions + i * stride_bytes` — runtime::PositionsView on the device. Same space
  /// and units as the asset's bind pose (or a rigid motion of it). [Limit: 4-byte aligned; may be null
  /// when `joint_matrices` is set, and then Run with RefitSource::kVertices gives kErrorNullArgument]
  /// Read by every Batch::Run from vertices; must stay valid (and be written by the caller's skinning
  /// before Run on the same stream, or synchronised) for as long as the batch runs.
  const void* positions = nullptr;
  uint32_t vertex_count = 0;   ///< \#V [Limit: == the asset's vertex_count when `positions` is set, else
                               ///< kErrorVertexCount]
  uint32_t stride_bytes = 12;  ///< [Limit: >= 12, multiple of 4 when `positions` is set, else kErrorStride]
  uint32_t asset = 0;          ///< slot in the `assets` array passed to Batch::Init [Limit: < asset_count]
  /// [opt] DEVICE pointer to \#J skinning matrices, 12 floats each, packed: the layout JointRefitJob reads
  /// (runtime::kJointMatrixFloats, 3×4 row-major; runtime::JointMatrixFromColumnMajor converts glTF's),
  /// in the skin's joint order. Read by every Batch::Run from joints, with the same lifetime rules as
  /// `positions`. [Limit: 4-byte aligned (kErrorAlignment); the asset must hold joint weights
  /// (DeviceAsset::joint_count() > 0, else kErrorMissingField)]
  const float* joint_matrices = nullptr;
  uint32_t joint_count = 0;    ///< \#J [Limit: == DeviceAsset::joint_count() when `joint_matrices` is set,
                               ///< else kErrorJointCount]
};

/// One colliding pair of one instance: runtime::Collision (same fields, same values as the CPU
/// DetectJob) tagged with its instance. POD, 16 bytes, device output record.
struct BatchCollision {
  uint32_t instance;         ///< index into the instance table
  runtime::Collision pair;   ///< a < b, chains mask, depth of the spheres themselves rA + rB − ‖cA − cB‖
                             ///< [source units] (in (−2·margin, 0] for pairs apart but within the margin)
};
static_assert(sizeof(BatchCollision) == 16);

/// Per-frame parameters of Batch::Run.
struct FrameParams {
  runtime::RefitMode mode = runtime::RefitMode::kPivotFrame;  ///< as RefitJob::mode (§5.1)
  runtime::DetectMethod method = runtime::DetectMethod::kM1;  ///< as DetectJob::method (§5.2)
  Strategy strategy = Strategy::kAuto;                        ///< kernel mapping (see Strategy)
  bool write_spheres = false;  ///< also store the refitted spheres in spheres() (costs 16 B/sphere;
                               ///< their own radii, never grown by the margin)
  /// Contact margin [Units: source units], as DetectJob::margin: spheres are tested with every radius
  /// grown by it (a pair is reported when ‖cA − cB‖ < rA + rB + 2·margin, as physics engines' contact
  /// offset / skin width); BatchCollision depths stay the spheres' own.
  /// < 0 (default): each instance uses its own asset's, DeviceAsset::contact_margin()
  /// (Asset.contact_margin; 0 for v1 assets); >= 0: this margin for every instance of the batch;
  /// NaN or ±inf: Run returns kErrorInvalidJob. [Limit: finite]
  float margin = -1.0f;
  /// Fold margin [Units: source units], as DetectJob::fold_margin: a pair of two spheres of one region
  /// (Asset.sphere_regions) is reported when ‖cA − cB‖ < rA + rB + 2·fold_margin instead of 2·margin; pairs of
  /// two regions keep `margin`. < 0 (default): each instance uses its own asset's, DeviceAsset::fold_margin()
  /// (an asset without one tests every pair with `margin`); >= 0: this fold margin for every instance, and
  /// then every asset of the batch must have one (else kErrorInvalidJob, as DetectJob); NaN or ±inf:
  /// kErrorInvalidJob. [Limit: finite]
  float fold_margin = -1.0f;
  /// What the spheres are refitted from, as runtime::BatchJob::source: kVertices — each instance's
  /// `positions` (RefitJob with `mode`, paper §5.1); kJoints — each instance's `joint_matrices`
  /// (JointRefitJob: every centre skinned like a vertex by the sphere's four joint weights, radius = bind
  /// radius; `mode` is not read). Both give the CPU job's spheres bit for bit. Unlike JointRefitJob, which
  /// refuses non-finite matrices (kErrorNonFiniteJoints) before writing, a batch does not scan the
  /// matrices: a NaN or infinite one gives non-finite spheres, which never overlap.
  runtime::RefitSource source = runtime::RefitSource::kVertices;
};

/// Host copy of one frame's results (Batch::Download). Allocates; for tests and tools, not the
/// per-frame path.
struct HostResults {
  std::vector<BatchCollision> pairs;     ///< min(total, capacity) records, in no particular order
  std::vector<uint32_t> instance_counts; ///< per instance: distinct overlapping non-excluded pairs
                                         ///< (complete even when the output overflowed)
  std::vector<float4> spheres;           ///< Σ\#S (when FrameParams::write_spheres; else empty)
  uint32_t total = 0;                    ///< Σ instance_counts (may exceed capacity)
  bool overflow = false;                 ///< total > capacity: `pairs` holds an arbitrary subset
};

/// A set of character instances refitted and tested together, with its device outputs.
/// Setup (Init / SetInstances / Release) allocates and synchronises; Run() does neither: it enqueues
/// one kernel on the caller's stream — preceded by a cudaMemsetAsync of the counters, except with few
/// instances (fewer than 4 an SM) under kBlockBoxes or kThreadPerSphere, where the frame's last block
/// publishes the counters itself — so a frame can be captured into a CUDA graph and replayed (the
/// positions are re-read at every replay).
/// Outputs (device memory owned by the batch; transient: overwritten by the next Run, valid once the
/// stream reaches the end of that Run's work):
///  - pairs(): BatchCollision[capacity], compacted with atomics, order unspecified (sort to compare);
///  - counters(): uint32[2 + N]: [0] total pairs (all instances; may exceed capacity), [1] overflow
///    flag (1 ⇔ total > capacity), [2 + i] instance i's distinct pairs;
///  - spheres() [opt]: float4 (x, y, z, r) per sphere, instance i's at sphere_offset(i).
/// Thread safety: one Run at a time per batch object (outputs are shared); different batches are
/// independent. Referenced DeviceAssets must outlive the batch.
class Batch {
 public:
  Batch() = default;
  Batch(const Batch&) = delete;
  Batch& operator=(const Batch&) = delete;
  Batch(Batch&& o) noexcept;
  Batch& operator=(Batch&& o) noexcept;
  ~Batch();

  /// Validates the instance table and allocates the device tables and outputs.
  /// @param assets          host array of `asset_count` uploaded assets (borrowed; must outlive the
  ///                        batch) [Limit: 1..65536, each valid()]
  /// @param instances       host array of `instance_count` instances (copied) [Limit: 1..2^26]
  /// @param capacity        BatchCollision records in pairs(); 0 = Σ over instances of the exact
  ///                        non-excluded pair count of its asset (never truncates, M1 or M2; clamped
  ///                        to 2^31). Memory: 16 B per record.
  /// Returns kOk; kErrorNullArgument (also an instance with neither positions nor joint matrices);
  /// kErrorInvalidJob (asset slot out of range, asset not uploaded, counts out of limits);
  /// kErrorAlignment / kErrorStride / kErrorVertexCount / kErrorMissingField / kErrorJointCount (the
  /// first bad instance, see Instance; the batch is left empty); kErrorOutOfMemory; kErrorCuda.
  /// Cost: O(\#assets + N) host work, allocations, synchronous copies.
  Status Init(const DeviceAsset* const* assets, uint32_t asset_count, const Instance* instances,
              uint32_t instance_count, uint32_t capacity = 0);

  /// Replaces the instance table (same instance_count as Init; e.g. new positions pointers), with the
  /// same checks as Init. Synchronous (device-wide cudaMemcpy): call between frames, not inside a
  /// graph capture. Graphs captured before remain valid (the table lives at the same address).
  Status SetInstances(const Instance* instances, uint32_t instance_count);

  /// Enqueues one frame on `stream` (0 = legacy default stream): count from zero, refit every
  /// instance's spheres from its positions and report overlapping non-excluded pairs. Overlap, as
  /// the CPU DetectJob (same float operations, so the same pair set): ‖cB − cA‖² < ((rB + m) + (rA + m))²,
  /// m the instance's margin (FrameParams::margin, or its asset's when < 0) — for two spheres of one region of
  /// an asset with a fold margin, m is the fold margin (FrameParams::fold_margin, or the asset's); the
  /// reported depth is
  /// rounded as DetectJob's for the method (M1: rA + rB − ‖·‖; M2 with m ≠ 0: ((rA + m) + (rB + m) − ‖·‖)
  /// − 2m). Asynchronous, no allocation, no synchronisation: capturable (cudaStreamBeginCapture …
  /// EndCapture).
  /// Returns kOk (enqueued; read the overflow flag for truncation); kErrorNullArgument (the source's
  /// input missing on some instance: positions for kVertices, joint_matrices for kJoints; nothing
  /// enqueued); kErrorInvalidJob (not initialised, unknown source/mode/method/strategy, kBlockPerChain with M2, margin or fold_margin NaN or infinite,
  /// fold_margin >= 0 with an asset of the batch that has no fold margin; nothing enqueued,
  /// outputs untouched); kErrorCuda (launch failed: LastCudaError()). Non-finite positions give
  /// non-finite spheres, which never overlap.
  /// Cost: one kernel; per sphere 12 vertex reads (144 B) + ~120 flops from vertices, or 1–4 matrix
  /// reads (48 B each, shared by the spheres of a joint) + ≤ 100 flops from joints; per tested pair 12
  /// flops (the CPU's 11, whose radii are grown beforehand, plus the column sphere's margin add).
  Status Run(const FrameParams& params, cudaStream_t stream) const;

  /// Copies the last frame's outputs to `out` after synchronising `stream` (allocates host vectors).
  /// `with_spheres`: also copy spheres() (only meaningful when the last Run wrote them).
  /// Returns kOk, kOkTruncated (overflow), kErrorNullArgument, kErrorInvalidJob (not initialised),
  /// kErrorCuda (also reports asynchronous errors of the frame's kernel).
  Status Download(cudaStream_t stream, HostResults* out, bool with_spheres = false) const;

  /// Releases the device memory (synchronising). Safe on an empty batch.
  void Release();

  bool initialized() const { return instance_count_ != 0; }       ///< after a successful Init
  uint32_t instance_count() const { return instance_count_; }     ///< N
  uint32_t capacity() const { return capacity_; }                 ///< records in pairs()
  uint32_t total_spheres() const { return total_spheres_; }       ///< Σ\#S over instances
  /// Index of instance i's first sphere in spheres(). [Limit: i < N]
  uint32_t sphere_offset(uint32_t i) const { return sphere_offsets_[i]; }
  const BatchCollision* pairs() const { return pairs_; }  ///< DEVICE, [capacity]
  const uint32_t* counters() const { return counters_; }  ///< DEVICE, [2 + N] (see class comment)
  const float4* spheres() const { return spheres_; }      ///< DEVICE, [total_spheres]

  /// Bytes of positions a frame reads (12 vertices × 12 B per sphere, Σ over instances): the
  /// "useful" traffic for bandwidth figures (the hardware moves whole 32 B sectors).
  uint64_t frame_position_bytes() const { return frame_position_bytes_; }
  /// Bytes of joint matrices a frame from joints reads at most (\#J × 48 B, Σ over instances that have
  /// them).
  uint64_t frame_joint_bytes() const { return frame_joint_bytes_; }

 private:
  Status Upload(const Instance* instances, uint32_t instance_count);

  const DeviceAsset* const* host_assets_ = nullptr;
  uint32_t asset_count_ = 0;
  uint32_t instance_count_ = 0, capacity_ = 0, total_spheres_ = 0;
  uint32_t max_spheres_ = 0, max_chains_ = 0, max_chain_length_ = 0, sm_count_ = 1;
  uint32_t max_blocks_ = 0, max_block_pairs_ = 0;  // over the batch's assets (kBlockBoxes' shared memory)
  uint64_t frame_position_bytes_ = 0, frame_joint_bytes_ = 0;
  bool every_asset_folds_ = false;  // every asset of Init has a fold margin (FrameParams::fold_margin >= 0 allowed)
  bool all_positions_ = false, all_joints_ = false;  // every instance has positions / joint matrices
  DeviceAssetDesc asset0_{};  // the first asset's descriptor as Init uploaded it (a one-asset batch's
                              // kBlockBoxes kernel reads it from its parameters)
  std::vector<uint32_t> sphere_offsets_;
  void* table_ = nullptr;          // device: DeviceAssetDesc[asset_count] + internal instance table
  void* asset_table_ = nullptr;    // into table_
  void* instance_table_ = nullptr; // into table_
  BatchCollision* pairs_ = nullptr;
  uint32_t* counters_ = nullptr;
  float4* spheres_ = nullptr;
};

}  // namespace spherechain::cuda
