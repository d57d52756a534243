// spherechain runtime — exact self-contacts: a narrow phase on the surrounding regions.
//
// The sphere chains (§5.2) are a broad phase: spheres sit inside the body, so a shallow contact of the
// skin can happen with no sphere pair overlapping. The paper points at the surrounding regions for
// finer work (§5.1, conclusions); this is that work, exact:
//   1. conservative bounds — per frame, the axis-aligned box of each sphere's surrounding region,
//      recomputed from the region's deformed vertices (so it contains every triangle of the region
//      whatever the deformation: no baked bound, no slack to prove);
//   2. candidate sphere pairs — boxes that overlap (closed intervals: touching counts), minus the
//      excluded pairs (the asset's, or none): #S(#S−1)/2 box tests (4,560 for 96 spheres, ~3 µs);
//   3. per candidate (a, b): the triangles of a whose box meets b's region box, and vice versa (exact:
//      once a frame per sphere, its triangles culled by their corners' Cohen–Sutherland outcodes against
//      the box of all its candidates' boxes, their boxes computed, and the box of each run of 8; then
//      per candidate by those boxes, runs first), each side then kept to the triangles meeting the box
//      of the other side's (a triangle dropped there meets no triangle box of the other side), swept
//      against each other along the longest axis of the two region boxes' overlap (sort and sweep: only
//      triangle boxes that overlap on that axis are compared); pairs sharing a corner (weld ids:
//      Asset.weld_ids) skipped; the rest tested exactly by TrianglesIntersect on prepared triangles
//      (prepared once a frame each: a float filter with a proven error bound first, then
//      Guigue–Devillers 2003 on exact orientation predicates).
// A contact is two triangles that share no (welded) corner and intersect (closed triangles: touching
// counts), owned by different spheres that are not an excluded pair (Asset.surrounding_*): exactly
// what `spherechain evaluate` counts as ground truth, so the two agree triangle pair for triangle pair.
// Restricted to the proxy's sphere pairs (NarrowPhaseJob::sphere_pairs), a model built on the reach regions
// (NarrowPhaseRegions::kReach: a triangle stands behind every sphere that reaches it at bind, not only its
// owner) finds the contacts whose triangles stand behind a reported pair — same definition, each once.
#pragma once

#include <cstdint>
#include <memory>

#include "spherechain/runtime/asset.h"
#include "spherechain/runtime/block_vector.h"
#include "spherechain/runtime/crease.h"
#include "spherechain/runtime/model.h"
#include "spherechain/runtime/detect.h"
#include "spherechain/runtime/status.h"
#include "spherechain/runtime/triangle_intersect.h"

namespace spherechain::runtime {

/// Which sphere pairs the narrow phase may report.
enum class Exclusions : uint8_t {
  kAsset = 0,  ///< skip Asset.excluded_pairs (joint neighbourhoods): what the proxy skips too
  kNone = 1,   ///< test every pair of different spheres (shows skinning artefacts at joints)
  /// The skin's own definition (crease.h): every pair of triangles that share no welded corner, intersect,
  /// and are not near on the welded bind surface (within the crease, Asset.crease, or two triangle rings),
  /// whichever spheres own them — the same sphere, an excluded pair, or none (unassigned triangles: sphere
  /// 0xFFFF in the record). Needs an asset baked with the crease rule (Asset.bind_positions and crease;
  /// else kErrorMissingField). With sphere_pairs null (the exact answer) the sphere pairs play no part:
  /// the model's patches of 16 triangles are swept against each other, and the
  /// rule is read from near bits NarrowPhaseModel::Init computed once (skin_contacts.cpp); a job with a
  /// crease wider than the asset's also asks the graph about each intersecting pair. Stats: candidate_pairs
  /// counts the pairs of patches looked at (boxes overlapping, not every pair near), box_tests the triangle
  /// boxes tested, crease_folds the intersecting pairs a wider job crease skipped. Optional penetration
  /// depths (NarrowPhaseJob::depths). With sphere_pairs (the restricted path, behind the proxy): the same
  /// rule, but only for the pairs of patches (16 triangles, grown over the bind surface) where one patch
  /// holds a triangle behind sphere a and the other one behind sphere b of a listed pair (a, b), or both
  /// hold triangles behind one listed sphere (the model's regions: reach or surrounding), and the pairs of
  /// patches that both hold a contact of the bind pose itself — a subset of the exact answer, each contact
  /// once, in the sweep's order. So a listed pair finds at least every contact between a triangle behind a
  /// and one behind b, or two behind the same one of them, whichever spheres own them. Pass the proxy's
  /// pairs and its folds (FoldPairs: the neighbours it never reports that came together).
  kCrease = 2,
};

/// One contact: two intersecting triangles (of different surrounding regions, except with
/// Exclusions::kCrease, where both may be one sphere's and an unassigned triangle's owner is 0xFFFF). POD,
/// 12 bytes.
struct TriangleContact {
  uint32_t triangle_a;  ///< source triangle index (< \#T), in sphere_a's surrounding region (owned by it)
  uint32_t triangle_b;  ///< source triangle index (< \#T), in sphere_b's surrounding region (owned by it)
  uint16_t sphere_a;    ///< sphere_a < sphere_b (kCrease: sphere_a <= sphere_b, and triangle_a < triangle_b
                        ///< when equal)
  uint16_t sphere_b;
};
static_assert(sizeof(TriangleContact) == 12);

/// How far one contact's triangles pass through each other, and which way to undo it (NarrowPhaseJob::depths,
/// Exclusions::kCrease jobs). POD, 16 bytes. The separating-axis estimate over the two triangles' face
/// normals (the normals by winding, outward for a consistently wound skin): d_ab is how far the deepest
/// corner of triangle_a lies behind triangle_b's plane, d_ba the same the other way; `depth` is the smaller,
/// and `direction` the normal that achieves it (triangle_b's normal when d_ab <= d_ba, else minus
/// triangle_a's), so moving triangle_a by depth·direction (or triangle_b by −depth·direction) leaves no
/// corner of one behind the other's plane. A local estimate: bounded by the triangles' size, not the depth
/// of a whole limb in another (the deepest contact of a region pair is the best figure of that, as
/// `spherechain check` reports per region pair). Computed in double from the float positions; a triangle whose normal is zero in
/// double gives depth 0 and direction (0, 0, 0).
struct ContactDepth {
  float depth;         ///< [Units: model] >= 0
  float direction[3];  ///< unit vector [Space: model, as the positions], or zero (see above)
};
static_assert(sizeof(ContactDepth) == 16);

/// The ContactDepth of triangles `a` and `b` (three corners each, 3 floats [Units: model]; not nullable):
/// what NarrowPhaseJob writes into `depths` for a contact (triangle_a's corners first). Meaningful for
/// intersecting triangles. Cost ~15 ns; no allocation, thread-safe.
void ContactDepthOf(const float* const a[3], const float* const b[3], ContactDepth* out);

/// Counters of one NarrowPhaseJob::Run, complete even when the output was truncated.
struct NarrowPhaseStats {
  uint32_t candidate_pairs = 0;       ///< sphere pairs whose region boxes overlap (after exclusions)
  uint32_t culled_triangles = 0;      ///< Σ over candidates of the triangles kept by the box cull (both sides)
  uint32_t box_tests = 0;             ///< triangle-box vs triangle-box tests of the sweeps, on the lists
                                      ///< after their second cull (stage 3: each side kept to the box of
                                      ///< the other's), so fewer than culled_triangles would sweep
  uint32_t adjacent_skipped = 0;      ///< box-overlapping triangle pairs skipped for sharing a welded corner
  uint32_t triangle_tests = 0;        ///< exact triangle–triangle tests (TrianglesIntersect calls)
  uint32_t degenerate_triangles = 0;  ///< triangles that reached an exact test and were found degenerate
                                      ///< (zero area, exact; once a frame each — with a kReach model once
                                      ///< for each region it lies in): they never make contacts
  uint32_t contacts = 0;              ///< intersecting triangle pairs; > capacity ⇔ truncated
  uint32_t crease_folds = 0;          ///< kCrease: intersecting pairs found near by the graph at a job crease
                                      ///< wider than the asset's (pairs near at the asset's crease are
                                      ///< skipped by their near bits before any box test, and not counted)
  uint32_t bind_contacts = 0;         ///< kCrease: contacts whose triangles intersect at bind pose too (modelling
                                      ///< artefacts; reported, NarrowPhaseModel::IntersectsAtBind names them)
  uint32_t joint_culled = 0;          ///< kCrease with joint matrices: pairs of patches with a near block
                                      ///< dismissed by the joint-matrix bound (counted in candidate_pairs)
};

struct NarrowPhaseJob;
struct NarrowPhaseInternal;  // the job's stages (narrow_phase.cpp; not API)

/// What the narrow phase needs of one asset, shared by every character (the narrow phase's Model,
/// built beside the runtime::Model from the same AssetView): the index buffer's surrounding-region
/// triangles in sphere order with their corners and weld ids (Asset.triangles, Asset.weld_ids,
/// Asset.surrounding_*), each region's distinct vertices, the excluded pairs (Asset.excluded_pairs), and
/// the sizes of the per-character scratch (NarrowPhaseWorkspace).
/// Immutable after Init: any number of NarrowPhaseWorkspaces (characters) and threads may use one at
/// once. Ownership: one block of memory, its own (Init: built on the heap, then moved into a block of
/// bytes()) or, for the narrow phase a runtime::Model holds (ModelOptions::narrow_phase), the Model's
/// block, where it also shares the Model's index of excluded pairs; after Init it no longer reads the
/// asset bytes. Move-only; moving keeps id() and leaves the source uninitialised.
class NarrowPhaseModel {
 public:
  NarrowPhaseModel() = default;
  NarrowPhaseModel(const NarrowPhaseModel&) = delete;
  NarrowPhaseModel& operator=(const NarrowPhaseModel&) = delete;
  NarrowPhaseModel(NarrowPhaseModel&&) noexcept = default;
  /// Releases this model's arrays (while the block they were carved from still exists), then takes `o`'s.
  NarrowPhaseModel& operator=(NarrowPhaseModel&& o) noexcept;

  /// Builds the per-asset data of `view`, the triangles behind each sphere per `regions` (kReach on an
  /// asset without reach regions: the surrounding regions, and the model behaves as kSurrounding's). The
  /// only allocating call (catches std::bad_alloc).
  /// Returns kOk; kErrorNullArgument when `!view.valid()`; kErrorMissingField when the asset has no
  /// `triangles` or `weld_ids` (baked before the narrow phase existed: re-bake); kErrorOutOfMemory;
  /// kErrorInvalidJob for an unknown `regions`; with the crease rule, kErrorBindPoseTangled when the sweep of
  /// the bind pose for its own contacts passes its budget (kSweepTestsPerTriangle), and kErrorCreaseTooWide
  /// when the searches of the bind surface pass theirs (kReachPerNode). The model is empty (not initialised)
  /// after a failure.
  /// Cost: O(\#T + \#V + \#S log) time; memory ~40 B per region triangle + 4 B per vertex + 4 B per
  /// (sphere, region vertex) + ~20 B per sphere; kReach also 2 B per (triangle, sphere it stands behind).
  /// An asset with the crease rule adds the rule's patches and near bits: one bounded Dijkstra per welded
  /// node (~0.26 s for MakeHuman's 26,756 triangles, RelWithDebInfo, one core) and their memory
  /// (crease_patch_bytes(): 1.54 MB in 1,722 patches for MakeHuman). With the skin weights per vertex
  /// (Asset.skin_*) also the joint-matrix cull's data (NarrowPhaseJob::joint_matrices): per patch its
  /// joints, per block of near rows a gap from 16×16 bind boxes (~20 ms more for MakeHuman).
  /// Not thread-safe on one object (nothing may use the model meanwhile).
  Status Init(const AssetView& view, NarrowPhaseRegions regions = NarrowPhaseRegions::kSurrounding);
  /// The budget of the crease rule's sweep, at Init (the bind pose's own contacts) and in each
  /// NarrowPhaseJob under Exclusions::kCrease: at most kSweepTestsPerTriangle × \#T + kSweepSlack exact
  /// triangle tests and kSweepPairsPerPatch × \#patches + kSweepSlack pairs of patches, else Init returns
  /// kErrorBindPoseTangled and the job kErrorFrameTangled. A job under the other exclusions gets the same
  /// test budget and kSweepPairsPerPatch × 16 × \#T + kSweepSlack box tests (the crease rule's at its budget
  /// of pairs of patches). Where a surface passes through itself everywhere
  /// the sweep is quadratic; the budget bounds the time and memory such positions take (a bind pose of 1,504
  /// triangles intersecting itself in 91,382 pairs took 453,738 tests, 0.41 s, at Init; MakeHuman's 26,756
  /// triangles scrambled within a millimetre took 36 s and gave 95 million contacts in one job). The real
  /// characters use a fraction of it. At Init: MakeHuman 28 tests and 3,118 pairs of patches (1,722 patches),
  /// CesiumMan 24 and 1,369 (300), BCN_Epileptic, whose clothes pass through its body, 1,402 and 1,401 (337);
  /// their frames' largest counts are in docs/runtime.md ("Frames that are no pose").
  static constexpr uint32_t kSweepTestsPerTriangle = 16, kSweepPairsPerPatch = 64, kSweepSlack = 4096;
  /// The budget of Init's searches of the welded bind surface (one bounded Dijkstra per welded node, out to the
  /// crease): at most kReachPerNode × \#nodes + kSweepSlack nodes reached in all, else Init returns
  /// kErrorCreaseTooWide. A bind pose collapsed onto a few points (every node within the crease of most
  /// others) makes those searches, and the near rows they fill, quadratic in the nodes; a mesh far denser than
  /// its crease makes them as long (a crease disc of thousands of vertices: re-bake with a smaller crease).
  /// The real characters reach 262 nodes a node on average (MakeHuman: 13,380 nodes, the most 955; a mesh of
  /// its shape about 8 times as dense, some 200,000 triangles, would reach the budget at a 3 % crease),
  /// CesiumMan 17.6, BCN_Epileptic 37.5, the repository's creature 7.
  static constexpr uint32_t kReachPerNode = 2048;
  /// The budgets of the other two steps of Init that a welded vertex shared by many triangles (a fan of
  /// thousands around one vertex) makes quadratic: growing the patches (each triangle picked scans its patch's
  /// frontier and its corners' triangles: at most kGrowPerTriangle × \#T + kSweepSlack in all) and gathering the
  /// triangles at the nodes the searches reach (at most kGatherPerNode × \#nodes + kSweepSlack). Past either,
  /// Init returns kErrorCreaseTooWide. The real characters take about 30 steps a triangle, and gather 1,576
  /// triangles a node on average (MakeHuman; CesiumMan 106, BCN_Epileptic 221, the repository's creature 42).
  static constexpr uint32_t kGrowPerTriangle = 512, kGatherPerNode = 16384;
  /// kReach when built from reach regions, else kSurrounding.
  NarrowPhaseRegions regions() const { return reach_ ? NarrowPhaseRegions::kReach : NarrowPhaseRegions::kSurrounding; }

  /// True after a successful Init (false when moved from).
  bool initialized() const { return sphere_count_ != 0 && !vert_offsets_.empty(); }
  /// A number unique to this build of the model in the process (never 0 once initialised; kept by a
  /// move): what a NarrowPhaseWorkspace records to refuse another model (kErrorWorkspaceModel).
  uint64_t id() const { return id_; }
  uint32_t sphere_count() const { return sphere_count_; }      ///< \#S
  uint32_t vertex_count() const { return vertex_count_; }      ///< \#V the positions must have
  uint32_t triangle_count() const { return triangle_count_; }  ///< \#T
  /// Triangles of the asset whose corners repeat a weld id (index-degenerate): never tested.
  uint32_t index_degenerate_triangles() const { return index_degenerate_; }
  /// Triangles in no surrounding region (Asset.unassigned at bake time): the narrow phase cannot see them.
  uint32_t unassigned_triangles() const { return unassigned_; }
  /// True if (a, b) is an excluded pair of the asset, either order. O(log degree).
  bool IsExcluded(uint32_t a, uint32_t b) const;
  /// Owning sphere of source triangle `t` [Limit: < \#T], or 0xFFFF when unassigned.
  uint16_t triangle_sphere(uint32_t t) const { return tri_sphere_[t]; }
  /// Weld id of vertex `v` [Limit: < \#V]: see Asset.weld_ids.
  uint32_t weld_id(uint32_t v) const { return weld_[v]; }
  /// True when the asset carries the crease rule (Asset.bind_positions, crease): Exclusions::kCrease works.
  bool has_crease() const { return crease_graph_.initialized(); }
  /// The asset's crease [Units: model], 0 without the rule.
  float crease() const { return crease_graph_.crease(); }
  /// The welded bind surface's edge graph (crease.h); uninitialised without the rule.
  const CreaseGraph& crease_graph() const { return crease_graph_; }
  /// True when triangles t and u (< \#T, either order) intersect at bind pose and are not near (crease
  /// rule): a contact the model already makes (a modelling artefact), reported apart. False without the
  /// rule. O(log \#bind contacts).
  bool IntersectsAtBind(uint32_t t, uint32_t u) const;
  /// The crease rule's patches of up to 16 triangles (0 without the rule).
  uint32_t crease_patch_count() const { return static_cast<uint32_t>(cl_tri_.size() / 16); }
  /// Bytes the crease rule's patches and near bits take in this model (graph and bind contacts excluded).
  size_t crease_patch_bytes() const {
    return 4 * (cl_tri_.size() + cl_vert_offsets_.size() + cl_vert_.size() + near_far_.size() + near_base_.size() +
                near_out_offsets_.size()) +
           8 * (near_out_.size() + near_win_.size()) +
           2 * (near_rows_.size() + cl_valid_.size() + group_near_.size()) + cl_local_.size() + cl_count_.size();
  }
  /// True when the asset carries the skin weights per vertex (Asset.skin_counts, schema v4) beside the
  /// crease rule: a kCrease job may pass joint matrices (NarrowPhaseJob::joint_matrices).
  bool has_joint_cull() const { return cull_joint_count_ != 0; }
  /// \#J the joint matrices must have (Asset.joint_count), 0 without the joint-matrix cull.
  uint32_t joint_count() const { return cull_joint_count_; }
  /// How many such pairs the bind pose has (computed by Init with the crease rule).
  uint32_t bind_contact_count() const { return static_cast<uint32_t>(bind_contacts_.size()); }
  /// Excluded sphere pairs FoldPairs examines (Asset.excluded_pairs; 0 without the crease rule).
  uint32_t fold_pair_count() const { return static_cast<uint32_t>(fold_pairs_.size()); }
  /// Bytes of the model's arrays in their block (the whole block when the model owns it).
  size_t bytes() const { return bytes_; }
  /// Bytes a NarrowPhaseWorkspace for this model takes (its block: what NarrowPhaseWorkspace::Init
  /// allocates, and what a runtime::Workspace adds for it).
  size_t workspace_bytes() const { return workspace_bytes_; }

  friend class NarrowPhaseWorkspace;
  friend class Model;
  friend struct NarrowPhaseJob;
  friend struct NarrowPhaseInternal;
  friend struct CreaseSweep;
  friend struct CreaseSweepAvx512;
  friend Status FoldPairs(const NarrowPhaseModel& model, const SphereArrays& spheres, float closing, Collision* out,
                          uint32_t capacity, uint32_t* count);

 private:
  uint64_t id_ = 0;
  // The crease rule (Asset.bind_positions, crease; empty without): the bind surface's graph, every
  // triangle's corners (#T×3, the index buffer), and the bind pose's own contacts (t << 32 | u, t < u, sorted).
  // Builds the model's arrays on the heap (Init's work before they move into a block).
  Status Build(const AssetView& view, NarrowPhaseRegions regions);
  // Calls f(array) on each of its arrays (BlockVector), the graph's included.
  template <class F>
  void ForEachArray(F&& f);
  // Σ of its arrays' bytes in a block; moves them into `arena` and points the jobs at its own index
  // of excluded pairs (a Model then points them at its own).
  size_t ArrayBytes();
  void MoveInto(BlockArena* arena);

  BlockPtr block_;                  // its own block (null when its arrays live in a Model's)
  size_t bytes_ = 0, workspace_bytes_ = 0;
  const uint32_t* excl_off_ = nullptr;    // the excluded-pair index the jobs read: its own or the Model's
  const uint16_t* excl_nb_ = nullptr;
  CreaseGraph crease_graph_;
  BlockVector<uint32_t> tri_v_;
  BlockVector<uint64_t> bind_contacts_;
  // The crease rule's patches (skin_contacts.cpp): the triangles that are not index-degenerate in patches
  // of up to 16 grown over the welded bind surface (cl_tri_: 16 slots per patch, ~0u padding), each
  // patch's distinct vertices (CSR cl_vert_offsets_ #C+1, cl_vert_), and every pair of patches p <= q
  // holding a near pair, a patch with itself included, each with its block of 16 rows of near bits in
  // near_rows_ (bit j of row i set when p's slot i is near q's slot j, or j is padding) or ~0u when every
  // pair of the two is near (then the pair of patches is never looked at). The blocks are in the order of
  // their pairs (p, then q). The pairs q - p < 64: two masks per p (near_win_ #C×2: bit q - p of the first
  // set when all near, of the second when q has a block, which is near_base_[p] + the second's bits below
  // it); the others in rows sorted by q (CSR near_out_offsets_ #C+1, near_out_: q << 32 | block or ~0u).
  // Per group g of 4 consecutive patches (#G = ⌈#C/4⌉) and h = g … g + 15 (group_near_ #G×16): bit i + 4j
  // set when patches 4g + i and 4h + j are skipped whole (every pair near, padding, or g == h and i > j).
  // Per patch also its triangles' corners as indices into its distinct vertices (cl_local_, 48 per patch),
  // its triangle count (cl_count_) and the mask of its slots in use (cl_valid_); per block of near rows the
  // rows and columns (bits 0-15, 16-31) that have a partner not near (near_far_).
  BlockVector<uint32_t> cl_tri_, cl_vert_offsets_, cl_vert_, near_far_, near_base_, near_out_offsets_;
  BlockVector<uint64_t> near_win_, near_out_;
  BlockVector<uint16_t> near_rows_, cl_valid_, group_near_;
  BlockVector<uint8_t> cl_local_, cl_count_;
  // The joint-matrix cull (skin_contacts.cpp; Asset.skin_*, empty without). Per patch its reference joint
  // r (the most weight over its vertices; kNone when a vertex has no influence: never culled), its slack
  // (1 − the least weight of r on its vertices, rounded up), and per other joint j of its vertices an entry
  // (CSR cl_cull_offsets_ #C+1): the joint pair (j, r) (an index into cull_pairs_: j << 16 | r, each with
  // an anchor point, cull_anchor_ #K×3, the mean bind centre of the patches using it), j's largest
  // weight there (rounded up) and the reach: distance from the anchor to the patch's bind centre + its
  // bind radius. Per block of near rows: a lower bound on the bind distance of its pairs not near
  // (near_gap_), and when the two patches' references differ the pair (r_q, r_p) with its reach for q
  // (near_cross_, near_cross_reach_; kNone: same reference).
  // The restricted path (kCrease with sphere_pairs): per sphere the patches holding a triangle of its
  // region (CSR sphere_patch_offsets_ #S+1, sphere_patches_ ascending) and per patch those spheres as bits
  // (patch_sphere_bits_: #C rows of ⌈#S/64⌉ words), the patches holding a contact of the bind pose
  // (bind_patches_, ascending; always swept, and patch_bind_ per patch), and the excluded pairs with their
  // bind centres' distance (fold_pairs_: a << 16 | b, fold_bind_distance_), what FoldPairs compares.
  BlockVector<uint32_t> sphere_patch_offsets_, sphere_patches_, bind_patches_, fold_pairs_;
  BlockVector<uint64_t> patch_sphere_bits_;
  BlockVector<uint8_t> patch_bind_;
  BlockVector<float> fold_bind_distance_;
  uint32_t cull_joint_count_ = 0;
  float cull_bind_extent_ = 0.0f;  // the bind pose's largest |coordinate|: a scale of the cull's rounding margin
  BlockVector<uint32_t> cull_pairs_, cl_ref_, cl_cull_offsets_, cl_cull_pair_, near_cross_;
  BlockVector<float> cull_anchor_, cl_slack_, cl_cull_w_, cl_cull_reach_, near_gap_, near_cross_reach_;
  bool reach_ = false;  // regions from Asset.reach_*: overlapping, owners from the surrounding regions
  uint32_t sphere_count_ = 0, vertex_count_ = 0, triangle_count_ = 0;
  BlockVector<uint32_t> behind_offsets_;  // reach_ only: CSR #T+1, the spheres each triangle stands behind
  BlockVector<uint16_t> behind_;
  uint32_t index_degenerate_ = 0, unassigned_ = 0;
  uint32_t largest_region_ = 0, largest_region_vertices_ = 0;  // triangles / distinct vertices (scratch sizes)
  BlockVector<uint32_t> weld_;                 // #V
  BlockVector<uint16_t> tri_sphere_;           // #T source triangle → owning sphere (0xFFFF none)
  // Surrounding regions in sphere order (CSR, region_offsets_ #S+1): source triangle id, its three
  // vertex indices and three weld ids; index-degenerate triangles left out.
  BlockVector<uint32_t> region_offsets_, region_tri_, region_v_, region_w_;
  BlockVector<uint32_t> vert_offsets_, vert_ids_;  // CSR #S+1: distinct vertices of each region, ascending
  BlockVector<uint32_t> region_local_;             // per slot: its corners' indices in the region's vertex list
  BlockVector<uint32_t> excl_offsets_;             // CSR #S+1: excluded partners b > a of each a
  BlockVector<uint16_t> excl_partners_;
  size_t box_pitch_ = 0;                       // #S + 4: the SoA region boxes' rows (inverted boxes after the last)
  // Per region, its pool offset (pool_offsets_, #S+1: its triangle count rounded up to a chunk of 8) into
  // the workspace's kept triangles, and its chunk offset (chunk_offsets_, #S+1: its chunk count rounded
  // up to 4) into the workspace's chunk boxes (six rows of chunk_pitch_).
  BlockVector<uint32_t> pool_offsets_;
  BlockVector<uint32_t> chunk_offsets_;
  size_t chunk_pitch_ = 0;
};

/// One character's scratch for the narrow phase of one NarrowPhaseModel (the narrow phase's Workspace):
/// region boxes, clips, the culled and kept triangles with their boxes, prepared triangles, candidate
/// pairs, sweep lists — rewritten by every Run (nothing in it outlives a Run; the job's outputs are the
/// caller's). Records the id() of the model it was made for: a job given this workspace and another
/// model answers kErrorWorkspaceModel and writes nothing.
/// Ownership: one block of memory (NarrowPhaseModel::workspace_bytes()), its own (Init) or a
/// runtime::Workspace's: ~110 B per region triangle (a prepared triangle 64 B, a box 32 B, indices) +
/// ~90 B per sphere + ~150 B per triangle and 17 B per vertex of the largest region (≈ 2.9 MB for
/// MakeHuman's 26,756 triangles by that count); with the crease rule also ~100 B per triangle and ~45 B
/// per welded vertex (7.6 MB in all for MakeHuman), and 8·⌈\#S/64⌉ + 4 B per patch of 16 triangles (the
/// restricted path's bits). Move-only; moving leaves the source uninitialised.
/// Thread safety: one job at a time per workspace; different workspaces are independent, also when they
/// share a model.
class NarrowPhaseWorkspace {
 public:
  NarrowPhaseWorkspace() = default;
  NarrowPhaseWorkspace(const NarrowPhaseWorkspace&) = delete;
  NarrowPhaseWorkspace& operator=(const NarrowPhaseWorkspace&) = delete;
  NarrowPhaseWorkspace(NarrowPhaseWorkspace&&) noexcept = default;
  /// Releases this workspace's arrays (while their block still exists), then takes `o`'s.
  NarrowPhaseWorkspace& operator=(NarrowPhaseWorkspace&& o) noexcept;

  /// Sizes the scratch for `model` in one block of model.workspace_bytes() and records model.id(). The
  /// only allocating call (catches std::bad_alloc). Returns kOk; kErrorInvalidJob (model not
  /// initialised); kErrorOutOfMemory (left empty). Cost: O(\#T + \#S) time.
  Status Init(const NarrowPhaseModel& model);

  /// True after a successful Init (false when moved from).
  bool initialized() const { return model_id_ != 0 && !box_.empty(); }
  uint64_t model_id() const { return model_id_; }  ///< NarrowPhaseModel::id() it was made for
  bool made_for(const NarrowPhaseModel& model) const { return model_id_ != 0 && model_id_ == model.id(); }

  friend struct NarrowPhaseJob;
  friend struct NarrowPhaseInternal;
  friend struct CreaseSweep;
  friend struct CreaseSweepAvx512;
  friend class NarrowPhaseModel;
  friend class Workspace;

  struct Culled {                     // culled triangles of one side of a candidate pair
    BlockVector<uint64_t> key;        // sweep order: ordered bits of the box minimum on the axis << 32 | n
    BlockVector<uint32_t> kept;       // per n (cull order): index into the region's kept triangles
    BlockVector<uint32_t> rank;       // per n (cull order): rank among those meeting the other region's box
    BlockVector<float> start;         // per n (cull order): box minimum on the axis
    BlockVector<uint32_t> bucket;     // counting-sort counters
    BlockVector<uint32_t> bucket_of;  // per n (cull order): its bucket
    BlockVector<uint32_t> slot;       // sweep order: region-order slot; 4 more (read, unused)
    BlockVector<float> lo[3], hi[3];  // sweep order: box per axis; 4 sentinels (lo +inf, hi −inf) after
  };

 private:
  // Sizes its arrays for `model`, carved from `arena` (null: the heap), and records model.id().
  Status Build(const NarrowPhaseModel& model, BlockArena* arena);
  template <class F>
  void ForEachArray(F&& f);

  BlockPtr block_;  // its own block (null when its arrays live in a Workspace's)
  uint64_t model_id_ = 0;
  // Boxes are 8 floats: min xyz, 0, max xyz, 0 (four-wide loads).
  BlockVector<float> box_;                     // #S×8 region boxes
  BlockVector<float> box_soa_;                 // the same, 6 rows (min x, y, z, max x, y, z) of the model's box pitch
  BlockVector<float> clip_;                    // #S×8: box of the candidate partners' boxes ∩ its own (or inverted)
  BlockVector<uint32_t> kept_;                 // #S: triangles of the region kept by its clip, or kNotCulled
  BlockVector<uint32_t> prepared_at_;          // per region-order triangle: its index in prepared_, or unprepared
                                               // or degenerate (reset with its region's cull: only those reach a test)
  BlockVector<PreparedTriangle> prepared_;     // the triangles prepared this frame, in the order tests met them
  uint32_t prepared_count_ = 0;                // (a pool the size of the regions, its used part small and hot)
  BlockVector<uint8_t> outcode_;               // per vertex of the largest region: cull outcodes
  BlockVector<float> corner_;                  // per vertex of the largest region: its position, 4 floats
  // Per region, from its pool offset (the model's): its triangles kept by its clip, in slot order: their
  // slot, and their box (8 floats), inverted boxes padding the last chunk.
  BlockVector<uint32_t> kept_slot_;
  BlockVector<float> kept_box_;
  // The box of each chunk of 8 kept boxes, six rows of the model's chunk pitch from the region's chunk
  // offset, inverted boxes padding.
  BlockVector<float> chunk_box_;
  BlockVector<uint64_t> records_;              // sweep steps with a hit: element << 32 | side << 31 | box << 4 | lanes
  BlockVector<uint64_t> hits_;                 // records → exact tests: position in a's list << 32 | in b's
  BlockVector<uint32_t> candidates_;           // candidate pairs a << 16 | b, up to min(#S(#S−1)/2, 16·#S + 64)
  BlockVector<uint64_t> listed_;               // reach models: #S rows of ⌈#S/64⌉ words, bit (a, b) set for
                                               // this Run's candidates (a < b); cleared before it returns
  Culled list_a_, list_b_;
  // Exclusions::kCrease (sized only for a model with the crease rule): each patch's box (per group of 4
  // consecutive patches, #G = ⌈#C/4⌉, 6 rows of 4: min x, y, z, max x, y, z; inverted padding), each
  // group's box (6 rows of #G), the sweep order of the groups (kept from frame to frame: re-sorted by
  // insertion), each patch's triangle boxes (96 floats: 6 rows of 16, inverted padding; all computed each
  // frame), prepared triangles (a pool filled in the order the tests meet them; tri_frame_ stamps each
  // triangle with its frame and slot), the rule's scratch (a job wider than the asset's crease).
  BlockVector<float> patch_box_, group_box_;
  BlockVector<uint64_t> sweep_;
  BlockVector<float> sweep_box_;        // the group boxes in sweep order (6 rows of #G + 1)
  BlockVector<uint32_t> sweep_hits_;    // one sweep step's overlapping groups (#G + 1)
  int sweep_axis_ = -1;                 // the axis sweep_ is sorted on (-1: none yet)
  BlockVector<float> patch_tri_box_;
  BlockVector<PreparedTriangle> tri_prepared_;  // this frame's prepared triangles, in the order met (#T)
  BlockVector<uint64_t> tri_frame_;             // per triangle: frame << 32 | its slot (low half ~0u: degenerate)
  // The AVX-512 copy's float filter by patch: a patch's 16 triangles as PrepareTriangle prepares them, by lane
  // (filter_pool_: 16 rows of 16 floats a patch, a pool filled in the order the pairs meet the patches),
  // the lanes it certified (finite, in the filter's range, not degenerate: filter_mask_ per slot), and per
  // patch its frame and slot (patch_filter_: frame << 32 | slot).
  BlockVector<float> filter_pool_;
  BlockVector<uint16_t> filter_mask_;
  BlockVector<uint64_t> patch_filter_;
  // The joint-matrix cull's frame: per joint pair t = |(M_j − M_r)(anchor, 1)| and f = |A_j − A_r|_F
  // (cull_t_, cull_f_), per joint a lower bound on its linear part's least singular value (cull_smin_),
  // per patch its bound E on how far its vertices stray from its reference joint's rigid motion
  // (cull_e_), and per patch the frame its triangle boxes were built in (patch_tri_frame_: with the cull
  // they are built when a pair first needs them).
  BlockVector<float> cull_t_, cull_f_, cull_smin_, cull_e_;
  BlockVector<uint32_t> patch_tri_frame_;
  // The restricted path: per patch the stamp of the last job that swept it, and for a swept patch the
  // spheres listed with one of its spheres, and those spheres, as bits (patch_partner_bits_, #C rows of
  // ⌈#S/64⌉ words).
  BlockVector<uint32_t> patch_active_;
  BlockVector<uint64_t> patch_partner_bits_;
  uint32_t active_stamp_ = 0;
  uint32_t frame_ = 0, prepared_used_ = 0, filters_used_ = 0;
  CreaseScratch crease_scratch_;
};

/// ozz-style job: exact triangle contacts between the surrounding regions of different spheres
/// (see the file comment for the three stages and the definition of a contact).
/// Output order (deterministic, a pure function of the asset and the positions): by sphere pair (a, b)
/// ascending (or in `sphere_pairs` order), then in the order the sweep meets the triangle pairs (kCrease:
/// in the order the sweep of the model's patches meets them). With a
/// kReach model the order is that of the candidate pair that reported the contact, while its record names
/// the owners (sphere_a < sphere_b, each with its own triangle), which need not be that pair.
/// Cost: O(\#V) for the region boxes, \#S(\#S−1)/2 box tests for the candidates (twice, four at a time),
/// then once per sphere with a candidate its region's vertices (an outcode each) and triangles (culled
/// by their corners' outcodes, boxes computed for those kept and for each run of 8), then per candidate
/// a box test of each side's kept runs (four at a time) and of the triangles of the runs that meet the
/// other region's box, a second cull to the other side's box, a sort of those left (counting sort into
/// buckets, then insertion: ~linear) and the sweep's box tests (four at a time); each triangle that
/// reaches an exact test is prepared once a frame (~20 ns), the test is ~8 ns when the float filter
/// separates the planes (~70 % of them), ~40 ns when the planes cross (float-filtered interval test),
/// exact evaluation only near degeneracy (~1 µs a test: a pose whose triangles are mostly coplanar or
/// coincident, such as a corrupted bind pose, pays it on nearly every test).
/// MakeHuman morph: docs/performance.md "Narrow phase", "Skin contacts". No allocation, no exceptions; serial. Thread
/// safety: the model is only read; the workspace is written (one job per workspace at a time), so
/// characters sharing a NarrowPhaseModel run in parallel, each with its own NarrowPhaseWorkspace.
struct NarrowPhaseJob {
  const NarrowPhaseModel* model = nullptr;  ///< initialised (NarrowPhaseModel::Init); only read
  NarrowPhaseWorkspace* workspace = nullptr;  ///< made for `model` (NarrowPhaseWorkspace::Init); scratch written
  PositionsView positions;                ///< deformed vertex positions, same as RefitJob's
  Exclusions exclusions = Exclusions::kAsset;
  /// kCrease only: the fold distance [Units: model]; 0 = the asset's (Asset.crease). [Limit: 0 or >= the
  /// asset's crease — a job may widen the folds, never narrow them below what was baked; not 0 with other
  /// exclusions: kErrorInvalidJob]
  float crease = 0.0f;
  /// [opt] restrict the candidates to these sphere pairs (e.g. a DetectJob's output — then only the
  /// contacts behind the proxy's pairs are searched); null = every sphere pair (the exact answer). List
  /// each pair once, as DetectJob does: a pair listed twice is searched twice and its contacts are
  /// reported twice (kCrease: the patches behind the listed spheres are swept once, whatever the listing,
  /// so each contact is reported once; see Exclusions::kCrease).
  const Collision* sphere_pairs = nullptr;
  uint32_t sphere_pair_count = 0;         ///< records in `sphere_pairs`
  TriangleContact* output = nullptr;      ///< [opt when capacity == 0] caller buffer of `capacity` records
  uint32_t capacity = 0;                  ///< records `output` holds (a job that succeeds finds at most its
                                          ///< budget's tests, NarrowPhaseModel::kSweepTestsPerTriangle × \#T
                                          ///< + kSweepSlack, too many to allocate: size it for the worst frame
                                          ///< you expect; stats stay complete)
  /// [opt] kCrease only (ignored otherwise): caller buffer of `capacity` records; depths[i] is output[i]'s
  /// penetration (ContactDepth). Null: not computed (~15 ns a contact saved).
  ContactDepth* depths = nullptr;
  /// [opt] kCrease only: the joint matrices that skinned `positions` (\#J × kJointMatrixFloats floats,
  /// JointRefitJob's layout: 3×4 row-major M_j = current transform · inverse bind, [Units: model]),
  /// for the joint-matrix cull: pairs of patches holding near pairs (neighbours on the skin) are
  /// dismissed without their triangles when the skin between them moved nearly rigidly, and only the
  /// patches a remaining pair needs get triangle boxes. The same contacts, depths and order as without.
  /// Bound (linear blend skinning; Asset.skin_* rows): a vertex v' = Σ w_j M_j v lies within
  /// E = min((1 − min w_r)·max_j e_j, Σ_j max w_j·e_j) of M_r v, r the patch's reference joint and
  /// e_j ≥ |(M_j − M_r)(v, 1)| over the patch's bind sphere; two patches with the same reference are
  /// skipped when σ_min(A_r)·gap > E_p + E_q + margin, gap a lower bound on the bind distance of their pairs
  /// not near (the least distance of their bind boxes, at Init), margin 1e-4 × the largest |coordinate| of
  /// the frame, of the bind pose and of the matrices' translations (float skinning's rounding); different
  /// references add |(M_rq − M_rp) x| over q's bind sphere. The bound needs each vertex's weights to sum to
  /// 1: a patch with a vertex whose stored weights do not sum to 255 (an asset another tool wrote; LoadAsset
  /// allows that within rounding) is never culled. [Precondition: `positions` are the asset's
  /// bind positions skinned by linear blend with these matrices and the asset's skin weights (within float
  /// rounding), as `play`, `evaluate` and an engine's CPU skinning give; other deformations (dual-quaternion
  /// skinning, blend shapes, cloth) must not pass matrices: contacts could be missed.] Null: no cull.
  const float* joint_matrices = nullptr;
  uint32_t joint_count = 0;               ///< \#J with joint_matrices [Limit: == NarrowPhaseModel::joint_count()]
  uint32_t* count = nullptr;              ///< out: records written (== min(stats.contacts, capacity))
  NarrowPhaseStats* stats = nullptr;      ///< [opt] out: counters

  /// True when Run() would not fail on arguments (does not read the positions).
  bool Validate() const { return Check() == Status::kOk; }
  /// kErrorNullArgument (model, workspace, count or positions.data null; output null with capacity > 0;
  /// sphere_pairs null with sphere_pair_count > 0), kErrorInvalidJob (model or workspace not
  /// initialised, unknown exclusions; kCrease with a crease below the asset's or not finite; a crease or joint_matrices with exclusions other than kCrease), kErrorMissingField (kCrease on an asset
  /// without the crease rule; joint_matrices on an asset without skin weights per vertex: re-bake),
  /// kErrorJointCount (joint_count != NarrowPhaseModel::joint_count()), kErrorAlignment (joint_matrices
  /// not 4-byte aligned), kErrorWorkspaceModel (the workspace was made for another model), kErrorAlignment (positions not 4-byte aligned), kErrorStride, kErrorVertexCount,
  /// kErrorIndexOutOfRange (a sphere_pairs record with a >= b or b >= \#S), else kOk.
  Status Check() const;
  /// Returns Check()'s error (outputs untouched); kErrorNonFinitePositions when a vertex of a
  /// surrounding region (kCrease: of any triangle that is not degenerate by its indices; with sphere_pairs,
  /// of a patch the job sweeps — the others are not read) is NaN/Inf
  /// (count 0, stats zero); kErrorNonFiniteJoints when a joint matrix holds
  /// a NaN or Inf (count 0, stats zero); kErrorFrameTangled when the frame's skin passes
  /// through itself beyond the sweep's budget (NarrowPhaseModel::kSweepTestsPerTriangle: positions that are
  /// no pose of this character; the job stops there: count 0, output and depths hold unspecified records,
  /// stats the counts so far); kOk; or kOkTruncated when more contacts than
  /// `capacity` exist: output holds the first `capacity` in the documented order, *count == capacity,
  /// stats complete.
  Status Run() const;
};

/// The proxy's folds: the sphere pairs the broad phase never reports (Asset.excluded_pairs, neighbours
/// along the skeleton) whose centres are now closer than at bind pose (Asset.spheres) by more than
/// `closing` — a joint bent so that the skin on either side may meet (the walking arm on the flank, the
/// thigh on the belly). With a DetectJob's pairs they are the sphere pairs of the restricted skin
/// contacts (NarrowPhaseJob, Exclusions::kCrease with sphere_pairs), measured against the skin's own
/// contacts in docs/evaluation.md. `spheres`: the frame's refit spheres (\#S, model space, the asset's
/// units); `closing` [Units: model; Limit: finite, >= 0]. Writes up to `capacity` records to `out` (a < b,
/// ascending; depth rA + rB − ‖cA − cB‖ as DetectJob's, chains 0) and the number found to *count.
/// Returns kErrorNullArgument (count null, out null with capacity > 0, a null sphere array),
/// kErrorInvalidJob (model not initialised or without the crease rule, closing not finite or < 0),
/// kErrorCountMismatch (spheres.count != \#S), kOk, or kOkTruncated (more than `capacity`: the first
/// `capacity` written, *count the number found). A NaN centre compares false: its pairs are not reported.
/// Cost: one distance per excluded pair (fold_pair_count()), no allocation. Thread safety: reads only.
Status FoldPairs(const NarrowPhaseModel& model, const SphereArrays& spheres, float closing, Collision* out,
                 uint32_t capacity, uint32_t* count);

}  // namespace spherechain::runtime
