// spherechain runtime — Model (what every character of one asset shares) and Workspace (one character).
#pragma once

#include <cstddef>
#include <cstdint>

#include "spherechain/runtime/asset.h"
#include "spherechain/runtime/status.h"

namespace spherechain::runtime {

/// Strided, read-only view of deformed vertex positions: vertex i is three floats (x, y, z) at
/// `(const char*)data + i * stride_bytes`. Lets a game pass an interleaved vertex buffer unchanged.
/// Space: the same model space and source units as the bind pose of the asset (or any rigid motion
/// of it: world space works, spheres come out in that space). Borrowed for one job Run().
struct PositionsView {
  const void* data = nullptr;  ///< [Limit: 4-byte aligned, non-null] first vertex's x.
  uint32_t count = 0;          ///< \#V [Limit: == Model::vertex_count(), else kErrorVertexCount].
  uint32_t stride_bytes = 12;  ///< [Limit: >= 12, multiple of 4, else kErrorStride] 12 = packed xyz.
};

/// Optional parallel-for hook: the SDK owns no threads. When `run` is set, a job calls
/// `run(user, count, task, task_data)` once; the host must call `task(task_data, begin, end)` over
/// disjoint ranges covering [0, count) (on any threads, in any order) and return when all finished.
/// `task` never allocates and writes disjoint memory per index. Leave `run` null for a serial Run().
/// (TBB: `tbb::parallel_for(tbb::blocked_range<uint32_t>(0, count), [&](auto& r) { task(task_data,
/// r.begin(), r.end()); })` — see samples/many_characters and bench/runtime_bench.cpp.)
struct ParallelFor {
  using Task = void (*)(void* task_data, uint32_t begin, uint32_t end);
  void (*run)(void* user, uint32_t count, Task task, void* task_data) = nullptr;  ///< [opt]
  void* user = nullptr;  ///< [opt] passed back to `run`.
};

/// Read-only SoA view of spheres (\#S each): centres (x, y, z) and radii r. Space/units: those of the
/// positions last refitted (model space and source units of the asset; the bind pose after Init).
/// Transient: valid until the next refit of the workspace / its Init / its destruction.
struct SphereArrays {
  const float* x = nullptr;
  const float* y = nullptr;
  const float* z = nullptr;
  const float* r = nullptr;  ///< radius, > 0 for sane input.
  uint32_t count = 0;        ///< \#S
};

/// The per-asset arrays of a Model, SoA, for readers outside the runtime (the CUDA upload, tests,
/// tools). Every pointer is owned by the Model (lifetime: until its destruction / next Init) and
/// immutable; padded arrays may be read up to 8 entries past \#S (zeros).
struct ModelArrays {
  const float *bind_x, *bind_y, *bind_z, *bind_r;  ///< \#S: Asset.spheres (bind centres, radii) [source units]
  const uint32_t* pivot_vertices;  ///< \#S×12: vertex indices (< \#V) of the 4 pivot triangles (Asset.pivot_vertices)
  const float *local_x, *local_y, *local_z;     ///< \#S + 8: PivotFrame.local_center (pivot-frame coordinates)
  const float *offset_x, *offset_y, *offset_z;  ///< \#S + 8: PivotFrame.centroid_offset [source units]
  const float* radius_scale;                    ///< \#S + 8: bind radius / PivotFrame.mean_distance (one division)
  const uint32_t* chain_mask;     ///< \#S + 1: bit c ⇔ sphere in Asset.chains[c]; [\#S] = 0
  const uint32_t* chain_offsets;  ///< \#C + 1 into chain_spheres
  const uint16_t* chain_spheres;  ///< Σ|chain|: each chain's spheres, ascending (Asset.chains)
  const uint32_t* excl_offsets;   ///< \#S + 1 into excl_neighbors (CSR by the smaller sphere a)
  const uint16_t* excl_neighbors; ///< \#excluded: partners b > a, ascending per a (Asset.excluded_pairs)
  const uint16_t* sphere_joints;  ///< \#S×4 or null: Asset.sphere_joints (schema v3, rigged bakes)
  const float* sphere_joint_weights;  ///< \#S×4 or null: Asset.sphere_joint_weights
  uint32_t excluded_count;        ///< \#excluded
  uint32_t max_chain_length;      ///< longest chain [spheres]
  /// DetectJob's broad-phase layout: B blocks of 8 slots (spheres grouped by body region, each group
  /// split at bind pose by a kd split, padded with the id \#S).
  const uint32_t* broad_order;        ///< 8B: the sphere id in each slot (padding: \#S)
  const uint64_t* broad_allowed[2];   ///< [M1, M2] B×B, row I, column J >= I: bit 8·row + l set ⇔ the
                                      ///< spheres in slots 8I + row and 8J + l are a pair the method tests
                                      ///< (two spheres, not excluded; M1: sharing a chain)
  uint32_t broad_blocks;              ///< B
};

/// Which triangles stand behind a sphere in a NarrowPhaseModel.
enum class NarrowPhaseRegions : uint8_t {
  /// Its surrounding region (Asset.surrounding_*: each triangle behind its one owner). Unrestricted, the
  /// exact answer; restricted to the proxy's pairs, the contacts whose two owners were reported.
  kSurrounding = 0,
  /// Its reach region (ReachTriangles: also the triangles of its region within the bake's reach of it,
  /// so a triangle may stand behind two or three spheres). For a job restricted to the proxy's pairs
  /// (NarrowPhaseJob::sphere_pairs): a contact is found when its triangles stand behind a reported pair,
  /// whichever spheres own them — on a coarse mesh the sphere that overlaps is often a neighbour of the
  /// owner (docs/evaluation.md "The spheres as a broad phase"). Contacts are still defined by the owners
  /// (different, not an excluded pair) and each is reported once, under the candidate pair of lowest (a, b)
  /// that covers it. Unrestricted it gives the same contacts as kSurrounding, at more cost.
  kReach = 1,
};

class NarrowPhaseModel;
class NarrowPhaseWorkspace;

/// What a Model builds besides the broad phase (Model::Init, Model::InitInPlace).
struct ModelOptions {
  /// Also build the narrow phase (the asset's NarrowPhaseModel, narrow_phase.h) into the model's block,
  /// sharing the model's index of excluded pairs; every Workspace of the model then holds its scratch
  /// (NarrowPhaseWorkspace). Needs Asset.triangles and weld_ids (else kErrorMissingField).
  bool narrow_phase = false;
  /// The triangles behind each sphere in that narrow phase (NarrowPhaseModel::Init's `regions`).
  NarrowPhaseRegions narrow_phase_regions = NarrowPhaseRegions::kSurrounding;
};

/// What every character of one asset shares, built once per asset from its AssetView: the refit data
/// in SoA (pivot vertices, pivot-frame coordinates, radius scales, bind spheres), the chain masks, the
/// excluded pairs as per-sphere neighbour lists, the centre joint weights (schema v3) and, for
/// JointRefitJob, one record a sphere grouped by the number of influences it uses (so the blend runs a
/// fixed count per group, no branch per sphere), and the broad phase's static layout — spheres in blocks of 8 (grouped by body region, Asset.sphere_regions, else by
/// chain mask; each group split at bind pose by a kd split), per pair of blocks and per method the lanes
/// to test (excluded pairs, M1's pairs sharing no chain and padding masked out).
/// With ModelOptions::narrow_phase the same block also holds the narrow phase (narrow_phase()): one
/// character is then one Model and one Workspace for every job, the narrow phase's included.
/// Immutable after Init: any number of Workspaces (characters) and threads may use one Model at once.
/// Ownership: one block of memory, the Model's own (Init) or the caller's (InitInPlace); after Init it
/// no longer reads the asset bytes (jobs never touch the AssetView). Move-only; moving keeps id().
class Model {
 public:
  Model() = default;
  Model(const Model&) = delete;
  Model& operator=(const Model&) = delete;
  Model(Model&& o) noexcept;
  Model& operator=(Model&& o) noexcept;
  ~Model();

  /// Bytes InitInPlace needs for `view` (the exact size of the Model's block), or 0 when `!view.valid()`.
  /// Cost: O(\#S) with sphere regions, else O(\#S · \#C log n + Σ over chains n² · \#C log n) (n a chain's
  /// length, the sum bounded by kMaxChainPairs); no allocation; thread-safe.
  static size_t RequiredBytes(const AssetView& view);
  /// The same for a model built with `options`. With options.narrow_phase it builds the narrow phase on
  /// the heap to measure it (NarrowPhaseModel::Init's cost: ~0.26 s for MakeHuman), so it allocates and
  /// may return 0 also when that build fails (the asset lacks its fields, its bind pose passes through itself
  /// beyond the narrow phase's budget, out of memory): InitInPlace with
  /// the same options then returns that failure's status, whatever the buffer. Thread-safe.
  static size_t RequiredBytes(const AssetView& view, const ModelOptions& options);

  /// Builds the model of `view` in one allocation of RequiredBytes(view) bytes (the only allocation),
  /// aligned to 64. Returns kOk; kErrorNullArgument (`!view.valid()`); kErrorOutOfMemory (allocation
  /// failed, or the broad phase's candidate lanes exceed 2^32) — the model is left empty on failure.
  /// Cost: O(\#S² · log degree) time (the block-pair lane tables); memory: see RequiredBytes — ~110 B a
  /// sphere (+ 52 B with joint weights) + 2 × 9 B per pair of blocks of 8 spheres + 2 B per excluded pair
  /// (32 KB for MakeHuman's 128 spheres). Picks the per-frame kernels here: SSE2, AVX or AVX-512, the
  /// best the CPU runs (SPHERECHAIN_ISA=sse2|avx caps it), all giving the same bits.
  /// Not thread-safe on one object (nothing may use the model meanwhile).
  Status Init(const AssetView& view);
  /// The same with `options`: with options.narrow_phase also the narrow phase (narrow_phase()), built on
  /// the heap and moved into the model's one block (4.9 MB more for MakeHuman with the crease rule). Also
  /// returns what NarrowPhaseModel::Init returns (kErrorMissingField, kErrorInvalidJob for unknown
  /// regions, kErrorBindPoseTangled, kErrorCreaseTooWide); the model is empty after a failure.
  Status Init(const AssetView& view, const ModelOptions& options);

  /// The same in caller memory (meshoptimizer-style): `memory` [Limit: 16-byte aligned, else
  /// kErrorAlignment] of `bytes` [Limit: >= RequiredBytes(view), else kErrorBufferTooSmall]; nothing is
  /// allocated. The memory must outlive the model and stay untouched while it is in use; the model never
  /// frees it. Returns kOk, kErrorNullArgument (invalid view or null memory), kErrorAlignment,
  /// kErrorBufferTooSmall, kErrorOutOfMemory (candidate lanes exceed 2^32); the model is empty after a
  /// failure (and the memory unspecified).
  Status InitInPlace(const AssetView& view, void* memory, size_t bytes);
  /// The same with `options` [Limit: bytes >= RequiredBytes(view, options)]. With options.narrow_phase the
  /// narrow phase is built on the heap (temporaries freed before it returns) and moved into `memory`.
  Status InitInPlace(const AssetView& view, const ModelOptions& options, void* memory, size_t bytes);

  /// Frees the model's block (none when it lives in caller memory); the model is empty after.
  void Release();

  bool initialized() const { return sphere_count_ != 0; }  ///< true after a successful Init
  /// A number unique to this build of the model in the process (never 0 once initialised; kept by a
  /// move): what a Workspace records to refuse another model (kErrorWorkspaceModel).
  uint64_t id() const { return id_; }
  uint32_t sphere_count() const { return sphere_count_; }  ///< \#S
  uint32_t vertex_count() const { return vertex_count_; }  ///< \#V the positions must have.
  uint32_t chain_count() const { return chain_count_; }    ///< number of chains (≤ kMaxChains).
  /// \#J, the skinning matrices JointRefitJob takes (Asset.joint_count); 0 when the asset holds no centre
  /// joint weights (v1/v2 or unrigged bake).
  uint32_t joint_count() const { return joint_count_; }
  /// The asset's contact margin (Asset.contact_margin, schema v2; 0 for v1 assets) [Units: source]:
  /// what DetectJob grows every radius by unless the job overrides it.
  float contact_margin() const { return contact_margin_; }
  /// The asset's fold margin (Asset.fold_margin, added within schema v3) [Units: source]: DetectJob reports a
  /// pair of two spheres of one region (Asset.sphere_regions) only when ‖cA − cB‖ < rA + rB + 2·fold_margin
  /// unless the job overrides it; < 0 (assets without the field): such pairs are tested like any other.
  float fold_margin() const { return fold_margin_; }
  /// Region of sphere `s` (Asset.sphere_regions) when the asset has a fold margin, else 0 for every sphere.
  /// [Limit: s < \#S]
  uint8_t fold_region(uint32_t s) const { return fold_region_ ? fold_region_[s] : uint8_t{0}; }
  size_t bytes() const { return bytes_; }  ///< size of the model's block
  /// The narrow phase built into the model (ModelOptions::narrow_phase), or null. Give it to a
  /// NarrowPhaseJob with Workspace::narrow_phase(); valid for the model's lifetime.
  const NarrowPhaseModel* narrow_phase() const { return narrow_; }

  /// The bind spheres (Asset.spheres), SoA; valid for the model's lifetime.
  SphereArrays bind_spheres() const { return {a_.bind_x, a_.bind_y, a_.bind_z, a_.bind_r, sphere_count_}; }
  /// All per-asset arrays (see ModelArrays); valid for the model's lifetime.
  const ModelArrays& arrays() const { return a_; }
  /// Bitmask of the chains sphere `s` belongs to (bit c = Asset.chains[c]). [Limit: s < \#S]
  uint32_t chain_mask(uint32_t s) const { return a_.chain_mask[s]; }
  /// True if (a, b) is an excluded (adjacent) pair (Asset.excluded_pairs), either order. O(degree).
  bool IsExcluded(uint32_t a, uint32_t b) const;
  /// Exact number of non-excluded sphere pairs (a < b) that share at least one chain: the most
  /// distinct pairs M1 can report (≤ DetectBound(view, kM1)).
  uint32_t m1_candidate_pairs() const { return m1_candidates_; }
  /// Exact number of non-excluded sphere pairs (a < b): the most pairs M2 can report.
  uint32_t m2_candidate_pairs() const { return m2_candidates_; }

  // ---- internals used by the jobs (the SDK's own translation units; not API) --------------------
  struct Internal;
  friend struct Internal;
  friend class Workspace;

 private:
  Status Build(const AssetView& view, unsigned char* memory, size_t bytes, NarrowPhaseModel* narrow);
  static Status BuildNarrow(const AssetView& view, const ModelOptions& options, NarrowPhaseModel& out, size_t& bytes);

  unsigned char* storage_ = nullptr;  // the block (owned when owned_)
  bool owned_ = false;
  size_t bytes_ = 0;
  uint64_t id_ = 0;
  uint32_t sphere_count_ = 0, vertex_count_ = 0, chain_count_ = 0, joint_count_ = 0;
  uint32_t m1_candidates_ = 0, m2_candidates_ = 0;
  float contact_margin_ = 0.0f;
  float fold_margin_ = -1.0f;              // Asset.fold_margin when set (>= 0), else -1
  const uint8_t* fold_region_ = nullptr;   // #S sphere regions, only with a fold margin
  ModelArrays a_{};
  NarrowPhaseModel* narrow_ = nullptr;     // in the block, after the broad phase's sections, or null
  uint8_t isa_ = 0;  // kernels::Isa picked at Init (runtime dispatch: SSE2, AVX or AVX-512)
  uint32_t m1_tests_ = 0;  // Σ_chains n(n−1)/2 (DetectStats::tests of M1)
  // Broad-phase layout (DetectJob, both methods): B blocks of 8 slots.
  uint32_t blocks_ = 0, box_pitch_ = 0, live_stride_ = 0;  // B; B rounded up to 8; ceil(B / 8)
  uint32_t key_slots_ = 0;                // max over methods of Σ allowed lanes (Workspace's keys)
  const uint32_t* order_ = nullptr;       // 8B: sphere id per slot (padding: #S, a NaN sphere)
  const uint64_t* allowed_[2] = {};       // [M1, M2] B×B lane masks of block pairs J >= I
  const uint8_t* live_[2] = {};           // [M1, M2] B × live_stride_: the pair has a lane
  const uint32_t* key_begin_[2] = {};     // [M1, M2] B + 1: key slots of each row block
  // Joint refit records (JointRefitJob; null without joint weights): one a sphere, grouped by the
  // number of influences it uses (1..4), ids ascending in a group.
  const uint32_t* joint_sphere_ = nullptr;   // #S: sphere id per record
  const uint32_t* joint_offsets_ = nullptr;  // #S × 4: matrix offsets [floats]
  const float* joint_weights_ = nullptr;     // #S × 4
  const float* joint_bind_ = nullptr;        // #S × 4: bind centre, 1
  uint32_t joint_group_end_[4] = {};         // end of the records using 1, 2, 3, 4 influences
};

/// One character's state for one Model: its current spheres (SoA, \#S + 8 each, NaN padding) and the
/// per-frame scratch of DetectJob (spheres gathered in block order, block boxes, hit keys, per-row-block
/// counters). Records the id() of the Model it was made for: a job given this workspace and another
/// model answers kErrorWorkspaceModel and writes nothing.
/// With a model holding the narrow phase (ModelOptions::narrow_phase) the block also holds its scratch
/// (narrow_phase()).
/// Ownership: one block of memory (~100 B per sphere + 8 B per candidate lane of the model: 70 KB for
/// MakeHuman's 128 spheres, 8,128 lanes; plus NarrowPhaseModel::workspace_bytes() with the narrow phase:
/// 7.6 MB for MakeHuman with the crease rule), its own (Init) or the caller's (InitInPlace). Move-only.
/// Thread safety: one job at a time per workspace; different workspaces are independent, also when they
/// share a model.
class Workspace {
 public:
  Workspace() = default;
  Workspace(const Workspace&) = delete;
  Workspace& operator=(const Workspace&) = delete;
  Workspace(Workspace&& o) noexcept;
  Workspace& operator=(Workspace&& o) noexcept;
  ~Workspace();

  /// Bytes InitInPlace needs for `model` (its narrow phase's scratch included); 0 when the model is not
  /// initialised. O(1).
  static size_t RequiredBytes(const Model& model);
  /// Sizes the workspace for `model` (one allocation, the narrow phase's scratch included when the model
  /// has one), records model.id() and sets the spheres to the bind pose. Returns kOk; kErrorInvalidJob (model not initialised); kErrorOutOfMemory (workspace left
  /// empty). Cost: O(\#S + lanes) time.
  Status Init(const Model& model);
  /// The same in caller memory: `memory` [Limit: 16-byte aligned, else kErrorAlignment] of `bytes`
  /// [Limit: >= RequiredBytes(model), else kErrorBufferTooSmall]; kErrorNullArgument for null memory.
  /// Nothing allocated; the memory must outlive the workspace.
  Status InitInPlace(const Model& model, void* memory, size_t bytes);
  /// Frees the block (none in caller memory); the workspace is empty after.
  void Release();

  bool initialized() const { return sphere_count_ != 0; }  ///< true after a successful Init
  uint64_t model_id() const { return model_id_; }          ///< Model::id() it was made for
  bool made_for(const Model& model) const { return model_id_ != 0 && model_id_ == model.id(); }
  uint32_t sphere_count() const { return sphere_count_; }  ///< \#S
  /// The narrow phase's scratch when the model has a narrow phase (Model::narrow_phase()), else null.
  /// Valid for the workspace's lifetime.
  NarrowPhaseWorkspace* narrow_phase() { return narrow_; }

  /// Current spheres (see SphereArrays for lifetime).
  SphereArrays spheres() const { return {x_, y_, z_, r_, sphere_count_}; }
  /// Writable spheres (\#S each): lets a caller set them directly (tests, a GPU path copying back)
  /// before a DetectJob. Same lifetime as spheres(). [Limit: radii >= 0, as a refit writes them: with a
  /// negative radius DetectJob may miss pairs when a fold margin applies]
  float* mutable_x() { return x_; }
  float* mutable_y() { return y_; }
  float* mutable_z() { return z_; }
  float* mutable_r() { return r_; }
  /// Resets the spheres to `model`'s bind pose. kErrorWorkspaceModel (another model: nothing written),
  /// kErrorInvalidJob (not initialised), else kOk. O(\#S).
  Status ResetToBindPose(const Model& model);

  struct Internal;
  friend struct Internal;
  friend struct Model::Internal;

 private:
  Status Build(const Model& model, unsigned char* memory);

  unsigned char* storage_ = nullptr;
  bool owned_ = false;
  uint64_t model_id_ = 0;
  uint32_t sphere_count_ = 0;
  float *x_ = nullptr, *y_ = nullptr, *z_ = nullptr, *r_ = nullptr;      // #S + 8 each (NaN padding)
  float *gx_ = nullptr, *gy_ = nullptr, *gz_ = nullptr, *gr_ = nullptr;  // 8B: spheres in slot order
  float *tx_ = nullptr, *ty_ = nullptr, *tz_ = nullptr, *tr_ = nullptr;  // 8 × box pitch: lane-major
  float* box_ = nullptr;          // 7 × (box pitch + 8): block boxes
  uint64_t* keys_ = nullptr;      // Model::key_slots_ hit keys
  uint32_t* row_hits_ = nullptr;  // 3 × B: keys, box tests, sphere tests per row block
  NarrowPhaseWorkspace* narrow_ = nullptr;  // in the block after the sections, with a narrow-phase model
};

}  // namespace spherechain::runtime
