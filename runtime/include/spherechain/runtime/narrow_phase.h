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
#pragma once

#include <cstdint>
#include <vector>

#include "spherechain/runtime/asset.h"
#include "spherechain/runtime/model.h"
#include "spherechain/runtime/detect.h"
#include "spherechain/runtime/status.h"
#include "spherechain/runtime/triangle_intersect.h"

namespace spherechain::runtime {

/// Which sphere pairs the narrow phase may report.
enum class Exclusions : uint8_t {
  kAsset = 0,  ///< skip Asset.excluded_pairs (joint neighbourhoods): what the proxy skips too
  kNone = 1,   ///< test every pair of different spheres (shows skinning artefacts at joints)
};

/// One contact: two intersecting triangles of different surrounding regions. POD, 12 bytes.
struct TriangleContact {
  uint32_t triangle_a;  ///< source triangle index (< #T), in sphere_a's surrounding region
  uint32_t triangle_b;  ///< source triangle index (< #T), in sphere_b's surrounding region
  uint16_t sphere_a;    ///< sphere_a < sphere_b
  uint16_t sphere_b;
};
static_assert(sizeof(TriangleContact) == 12);

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
                                      ///< (zero area, exact; once a frame each): they never make contacts
  uint32_t contacts = 0;              ///< intersecting triangle pairs; > capacity ⇔ truncated
};

/// What the narrow phase needs of one asset: the index buffer and weld ids (Asset.triangles,
/// Asset.weld_ids), the surrounding regions in sphere order, each region's vertex list, the excluded
/// pairs; plus per-frame scratch (region boxes, triangle boxes, candidate pairs, culled lists).
/// Ownership: owns its memory; after Init it no longer reads the asset bytes.
/// Thread safety: one job at a time per context (Run writes the scratch); contexts are independent.
struct NarrowPhaseJob;

struct NarrowPhaseJob;

class NarrowPhaseContext {
 public:
  NarrowPhaseContext() = default;
  NarrowPhaseContext(const NarrowPhaseContext&) = delete;
  NarrowPhaseContext& operator=(const NarrowPhaseContext&) = delete;
  NarrowPhaseContext(NarrowPhaseContext&&) noexcept = default;
  NarrowPhaseContext& operator=(NarrowPhaseContext&&) noexcept = default;

  /// Sizes and fills the context for `view`. The only allocating call (catches std::bad_alloc).
  /// Returns kOk; kErrorNullArgument when `!view.valid()`; kErrorMissingField when the asset has no
  /// `triangles` or `weld_ids` (baked before the narrow phase existed: re-bake); kErrorOutOfMemory
  /// (context left empty). Cost: O(#T + #V + #S) time; memory ~150 B per triangle + 5 B per
  /// (sphere, region vertex) + ~100 B per sphere + ~150 B per triangle and 17 B per vertex of the
  /// largest region.
  Status Init(const AssetView& view);

  bool initialized() const { return sphere_count_ != 0; }
  uint32_t sphere_count() const { return sphere_count_; }      ///< #S
  uint32_t vertex_count() const { return vertex_count_; }      ///< #V the positions must have
  uint32_t triangle_count() const { return triangle_count_; }  ///< #T
  /// Triangles of the asset whose corners repeat a weld id (index-degenerate): never tested.
  uint32_t index_degenerate_triangles() const { return index_degenerate_; }
  /// Triangles in no surrounding region (Asset.unassigned at bake time): the narrow phase cannot see them.
  uint32_t unassigned_triangles() const { return unassigned_; }
  /// True if (a, b) is an excluded pair of the asset, either order. O(log degree).
  bool IsExcluded(uint32_t a, uint32_t b) const;
  /// Owning sphere of source triangle `t` (< #T), or 0xFFFF when unassigned.
  uint16_t triangle_sphere(uint32_t t) const { return tri_sphere_[t]; }
  /// Weld id of vertex `v` (< #V): see Asset.weld_ids.
  uint32_t weld_id(uint32_t v) const { return weld_[v]; }

  struct Internal;
  friend struct Internal;
  friend struct NarrowPhaseJob;

 private:
  uint32_t sphere_count_ = 0, vertex_count_ = 0, triangle_count_ = 0;
  uint32_t index_degenerate_ = 0, unassigned_ = 0;
  std::vector<uint32_t> weld_;                 // #V
  std::vector<uint16_t> tri_sphere_;           // #T source triangle → owning sphere (0xFFFF none)
  // Surrounding regions in sphere order (CSR, region_offsets_ #S+1): source triangle id, its three
  // vertex indices and three weld ids; index-degenerate triangles left out.
  std::vector<uint32_t> region_offsets_, region_tri_, region_v_, region_w_;
  std::vector<uint32_t> vert_offsets_, vert_ids_;  // CSR #S+1: distinct vertices of each region, ascending
  std::vector<uint32_t> region_local_;             // per slot: its corners' indices in the region's vertex list
  std::vector<uint32_t> excl_offsets_;             // CSR #S+1: excluded partners b > a of each a
  std::vector<uint16_t> excl_partners_;
  // Per-frame scratch. Boxes are 8 floats: min xyz, 0, max xyz, 0 (four-wide loads).
  std::vector<float> box_;                     // #S×8 region boxes
  std::vector<float> box_soa_;                 // the same, 6 rows (min x, y, z, max x, y, z) of box_pitch_
  size_t box_pitch_ = 0;                       // #S + 4: inverted boxes after the last
  std::vector<float> clip_;                    // #S×8: box of the candidate partners' boxes ∩ its own (or inverted)
  std::vector<uint32_t> kept_;                 // #S: triangles of the region kept by its clip, or kNotCulled
  std::vector<uint32_t> prepared_at_;          // per region-order triangle: its index in prepared_, or unprepared
                                               // or degenerate (reset with its region's cull: only those reach a test)
  std::vector<PreparedTriangle> prepared_;     // the triangles prepared this frame, in the order tests met them
  uint32_t prepared_count_ = 0;                // (a pool the size of the regions, its used part small and hot)
  std::vector<uint8_t> outcode_;               // per vertex of the largest region: cull outcodes
  std::vector<float> corner_;                  // per vertex of the largest region: its position, 4 floats
  // Per region, from its pool offset (pool_offsets_, #S+1: its triangle count rounded up to a chunk of
  // 8): its triangles kept by its clip, in slot order: their slot, and their box (8 floats), inverted
  // boxes padding the last chunk.
  std::vector<uint32_t> pool_offsets_;
  std::vector<uint32_t> kept_slot_;
  std::vector<float> kept_box_;
  // The box of each chunk of 8 kept boxes, six rows of chunk_pitch_ from the region's chunk offset
  // (chunk_offsets_, #S+1: its chunk count rounded up to 4), inverted boxes padding.
  std::vector<uint32_t> chunk_offsets_;
  std::vector<float> chunk_box_;
  size_t chunk_pitch_ = 0;
  std::vector<uint64_t> records_;              // sweep steps with a hit: element << 32 | side << 31 | box << 4 | lanes
  std::vector<uint64_t> hits_;                 // records → exact tests: position in a's list << 32 | in b's
  std::vector<uint32_t> candidates_;           // candidate pairs a << 16 | b, up to min(#S(#S−1)/2, 16·#S + 64)
  struct Culled {                     // culled triangles of one side of a candidate pair
    std::vector<uint64_t> key;        // sweep order: ordered bits of the box minimum on the axis << 32 | n
    std::vector<uint32_t> kept;       // per n (cull order): index into the region's kept triangles
    std::vector<uint32_t> rank;       // per n (cull order): rank among those meeting the other region's box
    std::vector<float> start;         // per n (cull order): box minimum on the axis
    std::vector<uint32_t> bucket;     // counting-sort counters
    std::vector<uint32_t> bucket_of;  // per n (cull order): its bucket
    std::vector<uint32_t> slot;       // sweep order: region-order slot; 4 more (read, unused)
    std::vector<float> lo[3], hi[3];  // sweep order: box per axis; 4 sentinels (lo +inf, hi −inf) after
  };
  Culled list_a_, list_b_;
};

/// ozz-style job: exact triangle contacts between the surrounding regions of different spheres
/// (see the file comment for the three stages and the definition of a contact).
/// Output order (deterministic, a pure function of the asset and the positions): by sphere pair (a, b)
/// ascending (or in `sphere_pairs` order), then in the order the sweep meets the triangle pairs.
/// Cost: O(#V) for the region boxes, #S(#S−1)/2 box tests for the candidates (twice, four at a time),
/// then once per sphere with a candidate its region's vertices (an outcode each) and triangles (culled
/// by their corners' outcodes, boxes computed for those kept and for each run of 8), then per candidate
/// a box test of each side's kept runs (four at a time) and of the triangles of the runs that meet the
/// other region's box, a second cull to the other side's box, a sort of those left (counting sort into
/// buckets, then insertion: ~linear) and the sweep's box tests (four at a time); each triangle that
/// reaches an exact test is prepared once a frame (~20 ns), the test is ~8 ns when the float filter
/// separates the planes (~70 % of them), ~40 ns when the planes cross (float-filtered interval test),
/// exact evaluation only near degeneracy.
/// MakeHuman morph: see README "Exact self-contacts". No allocation, no exceptions; serial.
struct NarrowPhaseJob {
  NarrowPhaseContext* context = nullptr;  ///< initialised; scratch written: one job per context at a time
  PositionsView positions;                ///< deformed vertex positions, same as RefitJob's
  Exclusions exclusions = Exclusions::kAsset;
  /// [opt] restrict the candidates to these sphere pairs (e.g. a DetectJob's output — then only the
  /// contacts behind the proxy's pairs are searched); null = every sphere pair (the exact answer).
  const Collision* sphere_pairs = nullptr;
  uint32_t sphere_pair_count = 0;         ///< records in `sphere_pairs`
  TriangleContact* output = nullptr;      ///< [opt when capacity == 0] caller buffer of `capacity` records
  uint32_t capacity = 0;                  ///< records `output` holds (no useful upper bound exists:
                                          ///< size it for the worst frame you expect; stats stay complete)
  uint32_t* count = nullptr;              ///< out: records written (== min(stats.contacts, capacity))
  NarrowPhaseStats* stats = nullptr;      ///< [opt] out: counters

  /// True when Run() would not fail on arguments (does not read the positions).
  bool Validate() const { return Check() == Status::kOk; }
  /// kErrorNullArgument (context, count or positions.data null; output null with capacity > 0;
  /// sphere_pairs null with sphere_pair_count > 0), kErrorInvalidJob (context not initialised, unknown
  /// exclusions), kErrorAlignment (positions not 4-byte aligned), kErrorStride, kErrorVertexCount,
  /// kErrorIndexOutOfRange (a sphere_pairs record with a >= b or b >= #S), else kOk.
  Status Check() const;
  /// Returns Check()'s error (outputs untouched); kErrorNonFinitePositions when a vertex of a
  /// surrounding region is NaN/Inf (count 0, stats zero); kOk; or kOkTruncated when more contacts than
  /// `capacity` exist: output holds the first `capacity` in the documented order, *count == capacity,
  /// stats complete.
  Status Run() const;
};

}  // namespace spherechain::runtime
