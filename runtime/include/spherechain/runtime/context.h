// spherechain runtime — per-asset workspace (the only place the runtime allocates).
#pragma once

#include <cstdint>
#include <vector>

#include "spherechain/runtime/asset.h"
#include "spherechain/runtime/status.h"

namespace spherechain::runtime {

/// Strided, read-only view of deformed vertex positions: vertex i is three floats (x, y, z) at
/// `(const char*)data + i * stride_bytes`. Lets a game pass an interleaved vertex buffer unchanged.
/// Space: the same model space and source units as the bind pose of the asset (or any rigid motion
/// of it: world space works, spheres come out in that space). Borrowed for one job Run().
struct PositionsView {
  const void* data = nullptr;  ///< [Limit: 4-byte aligned, non-null] first vertex's x.
  uint32_t count = 0;          ///< #V [Limit: == AssetView::vertex_count, else kErrorVertexCount].
  uint32_t stride_bytes = 12;  ///< [Limit: >= 12, multiple of 4, else kErrorStride] 12 = packed xyz.
};

/// Optional parallel-for hook: the SDK owns no threads. When `run` is set, a job calls
/// `run(user, count, task, task_data)` once; the host must call `task(task_data, begin, end)` over
/// disjoint ranges covering [0, count) (on any threads, in any order) and return when all finished.
/// `task` never allocates and writes disjoint memory per index. Leave `run` null for a serial Run().
struct ParallelFor {
  using Task = void (*)(void* task_data, uint32_t begin, uint32_t end);
  void (*run)(void* user, uint32_t count, Task task, void* task_data) = nullptr;  ///< [opt]
  void* user = nullptr;  ///< [opt] passed back to `run`.
};

/// Read-only SoA view of the current spheres (#S each). Space/units: those of the positions last
/// refitted (bind pose after Init). Transient: valid until the next RefitJob::Run / Context::Init /
/// destruction of the context; do not keep it across frames.
struct SphereArrays {
  const float* x = nullptr;
  const float* y = nullptr;
  const float* z = nullptr;
  const float* r = nullptr;  ///< radius, > 0 for sane input.
  uint32_t count = 0;        ///< #S
};

/// Per-asset workspace, created once per asset (and per character instance when several share an
/// asset): SoA sphere state, the refit data copied out of the asset into SoA, per-sphere
/// chain-membership masks (used to de-duplicate M1 pairs across chains and to tag results), the
/// excluded (adjacent) pairs as per-sphere neighbour lists, and the broad phase's layout: spheres in
/// blocks of 8 (grouped by body region, split at bind pose), per pair of blocks and per method the
/// lanes to test (excluded pairs, M1's pairs sharing no chain and padding masked out), and scratch.
/// Ownership: owns its memory; after Init it no longer reads the asset bytes (jobs never touch the
/// AssetView), so the bytes may be released if no one calls SurroundingTriangles any more.
/// Thread safety: one job at a time per context; different contexts are independent.
class Context {
 public:
  Context() = default;
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  Context(Context&&) noexcept = default;
  Context& operator=(Context&&) noexcept = default;

  /// Sizes and fills the workspace for `view` and sets the spheres to the bind pose
  /// (Asset.spheres). The only allocating call of the runtime (catches std::bad_alloc).
  /// Returns kOk; kErrorNullArgument when `!view.valid()`; kErrorOutOfMemory (context left empty; a
  /// runtime built with -fno-exceptions terminates on allocation failure instead).
  /// Cost: O(#S² · log degree) time; memory ~150 B per sphere + 8 B per non-excluded sphere pair
  /// (hit keys; #S²/2 pairs at most) + ~#S²/4 B of block-pair lane tables + 2 B per excluded pair.
  Status Init(const AssetView& view);

  /// True after a successful Init.
  bool initialized() const { return sphere_count_ != 0; }
  uint32_t sphere_count() const { return sphere_count_; }  ///< #S
  uint32_t vertex_count() const { return vertex_count_; }  ///< #V the positions must have.
  uint32_t chain_count() const { return chain_count_; }    ///< number of chains (≤ kMaxChains).
  /// The asset's contact margin (Asset.contact_margin, schema v2; 0 for v1 assets) [Units: source]:
  /// what DetectJob grows every radius by unless the job overrides it.
  float contact_margin() const { return contact_margin_; }

  /// Current spheres (see SphereArrays for lifetime).
  SphereArrays spheres() const { return {x_.data(), y_.data(), z_.data(), r_.data(), sphere_count_}; }
  /// Writable spheres: lets a caller set them directly (tests, a GPU path copying back) before a
  /// DetectJob. Same lifetime as spheres().
  float* mutable_x() { return x_.data(); }
  float* mutable_y() { return y_.data(); }
  float* mutable_z() { return z_.data(); }
  float* mutable_r() { return r_.data(); }
  /// Resets the spheres to the bind pose (Asset.spheres, copied at Init). O(#S).
  void ResetToBindPose();

  /// Bitmask of the chains sphere `s` belongs to (bit c = Asset.chains[c]). [Limit: s < #S]
  uint32_t chain_mask(uint32_t s) const { return chain_mask_[s]; }
  /// True if (a, b) is an excluded (adjacent) pair (Asset.excluded_pairs), either order. O(degree).
  bool IsExcluded(uint32_t a, uint32_t b) const;
  /// Exact number of non-excluded sphere pairs (a < b) that share at least one chain: the most
  /// distinct pairs M1 can report (≤ DetectBound(view, kM1)).
  uint32_t m1_candidate_pairs() const { return m1_candidates_; }
  /// Exact number of non-excluded sphere pairs (a < b): the most pairs M2 can report.
  uint32_t m2_candidate_pairs() const { return m2_candidates_; }

  // ---- internals used by the jobs (public for the SDK's own translation units; not API) --------
  struct Internal;
  friend struct Internal;

 private:
  uint32_t sphere_count_ = 0, vertex_count_ = 0, chain_count_ = 0;
  uint32_t m1_candidates_ = 0, m2_candidates_ = 0;
  float contact_margin_ = 0.0f;
  std::vector<float> x_, y_, z_, r_;                  // current spheres, #S + kPad each (NaN padding)
  std::vector<float> bind_x_, bind_y_, bind_z_, bind_r_;  // Asset.spheres, #S each
  std::vector<uint32_t> pivot_vertices_;              // #S×12, Asset.pivot_vertices
  std::vector<float> local_x_, local_y_, local_z_;    // PivotFrame.local_center, #S + kPad each (0 padding)
  std::vector<float> offset_x_, offset_y_, offset_z_; // PivotFrame.centroid_offset, #S + kPad each
  std::vector<float> radius_scale_;                   // bind radius / PivotFrame.mean_distance, #S + kPad
  std::vector<uint32_t> chain_mask_;                  // #S
  std::vector<uint32_t> excl_offsets_;                // #S+1 into excl_neighbors_
  std::vector<uint16_t> excl_neighbors_;              // #excluded: partners b > a of each sphere a, sorted
  bool use_avx_ = false;                              // kernels: AVX (runtime dispatch) or SSE2 baseline
  uint32_t m1_tests_ = 0;                             // Σ_chains n(n−1)/2 (DetectStats::tests of M1)
  // Broad-phase layout (DetectJob, both methods): B blocks of 8 slots; spheres grouped by region
  // (Asset.sphere_regions; without it by chain mask), each group split at bind pose into blocks by a
  // kd split (halves of multiples of 8 along the longest axis of its centres), padded to 8 per group.
  uint32_t blocks_ = 0, box_pitch_ = 0, live_stride_ = 0;  // B; B rounded up to 8; ceil(B / 8)
  std::vector<uint32_t> order_;                       // 8B: sphere id per slot (padding: #S, NaN sphere)
  std::vector<uint32_t> chain_mask1_;                 // #S + 1: chain_mask_ and 0 for the padding id
  std::vector<uint64_t> allowed_[2];                  // [M1, M2] B×B lane masks of block pairs J >= I
  std::vector<uint8_t> live_[2];                      // [M1, M2] B × live_stride_: pair has a lane
  std::vector<uint32_t> key_begin_[2];                // [M1, M2] B + 1: key slots of each row block
  mutable std::vector<float> gx_, gy_, gz_, gr_;      // 8B: spheres gathered in slot order (scratch)
  mutable std::vector<float> tx_, ty_, tz_, tr_;      // 8 × box_pitch_: the same, lane-major (scratch)
  mutable std::vector<float> box_;                    // 7 × (box_pitch_ + 8): block boxes (scratch)
  mutable std::vector<uint64_t> keys_;                // hit keys, max over methods of Σ allowed lanes
  mutable std::vector<uint32_t> row_hits_;            // 3 × B: keys, box tests, sphere tests per row block
};

}  // namespace spherechain::runtime
