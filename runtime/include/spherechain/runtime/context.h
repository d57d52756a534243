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
/// asset): SoA sphere state, the refit data copied out of the asset into SoA, per-chain sphere lists
/// with the excluded (adjacent) pairs as per-sphere neighbour lists, per-sphere chain-membership masks
/// (used to de-duplicate M1 pairs across chains and to tag results), and per-chain scratch for the
/// parallel M1 path.
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
  /// Returns kOk; kErrorNullArgument when `!view.valid()`; kErrorOutOfMemory (context left empty).
  /// Cost: O(#S + Σ|chain| + #excluded) time and memory (~100 B per sphere).
  Status Init(const AssetView& view);

  /// True after a successful Init.
  bool initialized() const { return sphere_count_ != 0; }
  uint32_t sphere_count() const { return sphere_count_; }  ///< #S
  uint32_t vertex_count() const { return vertex_count_; }  ///< #V the positions must have.
  uint32_t chain_count() const { return chain_count_; }    ///< number of chains (≤ kMaxChains).

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
  std::vector<float> x_, y_, z_, r_;                  // current spheres, #S + kPad each (far-away padding)
  std::vector<float> bind_x_, bind_y_, bind_z_, bind_r_;  // Asset.spheres, #S each
  std::vector<uint32_t> pivot_vertices_;              // #S×12, Asset.pivot_vertices
  std::vector<float> local_x_, local_y_, local_z_;    // PivotFrame.local_center, #S each
  std::vector<float> offset_x_, offset_y_, offset_z_; // PivotFrame.centroid_offset, #S each
  std::vector<float> radius_scale_;                   // bind radius / PivotFrame.mean_distance, #S
  std::vector<uint32_t> chain_mask_;                  // #S
  std::vector<uint32_t> chain_offsets_;               // #chains+1 into chain_spheres_
  std::vector<uint16_t> chain_spheres_;               // Σ|chain|
  std::vector<uint32_t> excl_offsets_;                // #S+1 into excl_neighbors_
  std::vector<uint16_t> excl_neighbors_;              // 2·#excluded, sorted per sphere
  std::vector<uint32_t> gather_offsets_;              // #chains+1: chain c's padded block (|c| + kPad)
  mutable std::vector<float> gx_, gy_, gz_, gr_;              // per-chain gathered spheres, padded
  std::vector<uint32_t> chain_hits_offsets_;          // #chains+1 into chain_hits_ (M1 parallel)
  mutable std::vector<uint32_t> chain_hits_;                  // packed (a << 16 | b), Σ |c|(|c|−1)/2
  mutable std::vector<uint32_t> chain_hit_counts_;            // #chains
  mutable std::vector<uint32_t> chain_raw_counts_;            // #chains
  mutable std::vector<uint8_t> flags_;                        // #S + kPad overlap flags (one row)
};

}  // namespace spherechain::runtime
