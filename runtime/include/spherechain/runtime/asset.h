// spherechain runtime — loading a .sphc collision asset zero-copy.
#pragma once

#include <cstddef>
#include <cstdint>

#include "spherechain/runtime/schema/spherechain_generated.h"
#include "spherechain/runtime/status.h"

namespace spherechain::runtime {

/// The schema version this SDK writes and reads (schemas/spherechain.fbs, Asset.schema_version). Bump
/// on any change old readers cannot read or would misread; keep a golden asset per version in
/// tests/data/golden/. v2 added Asset.contact_margin, fit_method and coverage; v3 joint_count,
/// sphere_joints and sphere_joint_weights (the refit from joint matrices, JointRefitJob); v4 Asset.regions
/// (a creature's limbs and trunk, the baker's any-skeleton path: region values index it). The baker writes
/// the lowest version that reads an asset correctly — 3 for the paper's five regions (no `regions`), 4
/// with `regions` — so a v3 reader refuses a creature (kErrorVersionTooNew) rather than misname its regions.
inline constexpr uint32_t kSchemaVersion = 4;
/// The version of an asset without Asset.regions (the paper's five regions): what the baker writes for
/// a standing body, readable by v3 SDKs.
inline constexpr uint32_t kPaperSchemaVersion = 3;
/// Most regions an asset may name (Asset.regions; region values are bytes).
inline constexpr uint32_t kMaxRegions = 32;
/// Most joints an asset may name (Asset.joint_count): joint indices are uint16.
inline constexpr uint32_t kMaxJoints = 65536;
/// The oldest schema version this SDK still reads: v1 and v2 assets load, with what later versions
/// added absent (v1: contact margin 0 — their spheres were tested unmargined —, fit "paper", no
/// coverage; v1 and v2: no joint weights, so JointRefitJob answers kErrorMissingField — re-bake).
inline constexpr uint32_t kMinSchemaVersion = 1;
/// FlatBuffers file_identifier of a .sphc asset.
inline constexpr char kFileIdentifier[5] = "SPHC";
/// Largest asset LoadAsset accepts [bytes] (FlatBuffers' own limit is 2 GiB).
inline constexpr size_t kMaxAssetBytes = size_t{1} << 30;
/// Most spheres per asset (sphere indices are uint16 in the schema).
inline constexpr uint32_t kMaxSpheres = 65535;
/// Most chains per asset (Collision::chains is a 32-bit mask; the paper uses 6, Table 1).
inline constexpr uint32_t kMaxChains = 32;
/// Σ over chains of |ζ|(|ζ|−1)/2 [Limit]: bounds the M1 workspace and DetectBound (a 4,096-sphere
/// character in 32 chains of 256 spheres is 1.04 M pairs). Larger → kErrorTooManyChains.
inline constexpr uint64_t kMaxChainPairs = uint64_t{1} << 21;
/// Pivot polygons per sphere (§5.1; BakeParams.pivots_per_sphere must be 4 in schema v1).
inline constexpr uint32_t kPivotsPerSphere = 4;

/// Verified, read-only, zero-copy view of a loaded asset.
/// Ownership: borrows the bytes passed to LoadAsset; they must stay alive and unmodified for as long
/// as the view (or any pointer obtained from it) is used. Copying the view is cheap (POD).
/// All counts below were checked against each other by LoadAsset.
struct AssetView {
  /// Root table of the FlatBuffer (schemas/spherechain.fbs `Asset`); null when not loaded.
  const schema::Asset* asset = nullptr;
  uint32_t sphere_count = 0;    ///< \#S = len(Asset.spheres), 1..kMaxSpheres.
  uint32_t vertex_count = 0;    ///< \#V = Asset.fingerprint.vertex_count (the game's vertex buffer length).
  uint32_t triangle_count = 0;  ///< \#T = Asset.fingerprint.triangle_count.
  uint32_t chain_count = 0;     ///< len(Asset.chains), 0..kMaxChains.

  /// True after a successful LoadAsset.
  bool valid() const { return asset != nullptr; }
};

/// Loads (checks, does not copy) a .sphc asset.
///
/// @param bytes  the whole file. [Limit: 8-byte aligned — the buffer holds uint64 fields and the
///               accessors read them in place; memory from new/malloc/`std::vector<uint8_t>` or an
///               mmap satisfies this] Borrowed for the lifetime of `*out`.
/// @param size   [bytes] [Limit: 8..kMaxAssetBytes]
/// @param out    receives the view; reset to an empty view on every failure.
///
/// Checks, in order (each failure its own status):
///  1. envelope: kErrorNullArgument, kErrorAlignment, kErrorAssetTooSmall, kErrorAssetTooLarge,
///     kErrorIdentifier ("SPHC"), kErrorCorrupt (root offset out of bounds),
///     kErrorVersionTooOld / kErrorVersionTooNew (schema_version below kMinSchemaVersion / above
///     kSchemaVersion — read before the
///     full verification so an asset from another SDK version gets the clear message);
///  2. flatbuffers::Verifier (alignment checked, max depth 8 — the schema nests 3 deep — and max
///     tables 16 + 1024 chains + 65536 mesh parts + 256 forced bake findings + 256 regions): kErrorCorrupt;
///  3. semantics: kErrorMissingField, kErrorNoSpheres, kErrorTooManySpheres, kErrorTooManyChains,
///     kErrorCountMismatch (\#S in spheres, pivot_frames, 4·\#S pivot_triangles, 12·\#S pivot_vertices,
///     \#S+1 surrounding_offsets, optional spheres_phi1/phi2/sphere_regions/sphere_labels; \#T in
///     optional triangle_regions/triangle_spheres; pivots_per_sphere == 4 when params present),
///     kErrorIndexOutOfRange (chain / excluded-pair / triangle_spheres sphere indices < \#S,
///     surrounding / pivot triangles < \#T, pivot vertices < \#V, optional `triangles` indices < \#V —
///     3·\#T of them, else kErrorCountMismatch —, optional `weld_ids`: \#V entries, weld_ids[v] <= v and
///     weld_ids[weld_ids[v]] == weld_ids[v], else kErrorIndexOutOfRange), kErrorOffsets, kErrorNonFinite,
///     kErrorRadius, kErrorPivotFrame, kErrorChainOrder, kErrorExcludedPairs, kErrorContactMargin
///     (contact_margin < 0; NaN or inf: kErrorNonFinite), the optional fold_margin (NaN or inf:
///     kErrorNonFinite; >= 0 without sphere_regions: kErrorMissingField), the optional crease rule
///     (bind_positions: 3·\#V finite floats, else kErrorCountMismatch / kErrorNonFinite; crease NaN or inf:
///     kErrorNonFinite; crease == 0, or > 0 without bind_positions, triangles and weld_ids:
///     kErrorMissingField), joint_count <= kMaxJoints (kErrorIndexOutOfRange), and the optional v3 joint
///     weights: sphere_joints and sphere_joint_weights both present or both absent, 4·\#S each
///     (kErrorCountMismatch), joint indices < joint_count (kErrorIndexOutOfRange), weights finite,
///     >= 0, none after a 0 (the refit's blend ends at the first 0) and summing to 1 ± 1e-3 per sphere (kErrorSkinWeights); the optional v4 skin weights
///     per vertex: skin_counts, skin_joints and skin_weights all present or all absent
///     (kErrorMissingField), \#V counts and as many joints and weights as they add up to, only with the
///     crease rule (kErrorCountMismatch), joints < joint_count (kErrorIndexOutOfRange), each vertex's
///     rounded weights summing to 255 within half its count (kErrorSkinWeights); the optional v4 regions: 2 to
///     kMaxRegions, exactly one Trunk and it the last, every sphere_regions / triangle_regions value below
///     their count, or below 5 (the paper's regions) without Asset.regions (kErrorRegions).
/// Returns kOk with `*out` filled.
/// Cost: O(size) reads, no allocation, no exceptions; thread-safe (pure function of its inputs).
/// Untrusted input: every truncated prefix and bit flip gives an error or a valid view (a flipped bit of a
/// float may still be a valid asset), never a crash (tested).
Status LoadAsset(const void* bytes, size_t size, AssetView* out);

/// Span of triangle indices (into the source mesh's triangle order, < \#T).
struct TriangleSpan {
  const uint32_t* data = nullptr;  ///< Borrowed from the asset bytes; null when count == 0.
  uint32_t count = 0;
};

/// The triangles of sphere `sphere`'s surrounding region (§5.1: triangles whose nearest sphere it
/// is) — what a narrow phase tests when the sphere collides. Source: Asset.surrounding_offsets /
/// surrounding_triangles. [Limit: sphere < view.sphere_count; otherwise (programmer error) asserts in
/// debug and returns an empty span]. Cost: O(1), no allocation. Lifetime: the asset bytes.
TriangleSpan SurroundingTriangles(const AssetView& view, uint32_t sphere);

/// The triangles behind sphere `sphere` when the proxy reports it: its reach region (Asset.reach_offsets /
/// reach_triangles: its surrounding region and the other triangles of its region within the bake's
/// reach of its surface at bind pose — baker regions.h AddReachRegions), ascending. Reach regions
/// overlap (a triangle near two spheres is behind both; Asset.triangle_spheres keeps its one owner). An
/// asset baked before them: the surrounding region (SurroundingTriangles). [Limit: sphere <
/// view.sphere_count; otherwise asserts in debug and returns an empty span]. Cost: O(1), no allocation.
/// Lifetime: the asset bytes.
TriangleSpan ReachTriangles(const AssetView& view, uint32_t sphere);

/// Regions of the asset (what Asset.sphere_regions / triangle_regions values mean): len(Asset.regions) when
/// the asset lists them (a creature's limbs and trunk, or a biped's extended layout: ten regions, R9 torso),
/// else 5 — the paper's R0 left_arm, R1 right_arm, R2 left_leg, R3 right_leg, R4 torso. 0 for an invalid
/// view. Cost O(1).
uint32_t RegionCount(const AssetView& view);
/// Name of region `region`: Asset.regions[region].name ("HindLeg_L", "Tail", "trunk"), or the paper's
/// "left_arm" … "torso"; "" when `region` >= RegionCount(view). Never null. Lifetime: the asset bytes
/// (or static). Cost O(1).
const char* RegionName(const AssetView& view, uint32_t region);
/// True for the trunk: the last region (a creature's trunk, the extended layout's R9 torso, the paper's R4
/// torso). Cost O(1).
bool IsTrunkRegion(const AssetView& view, uint32_t region);

/// The four pivot triangles of `sphere` (Asset.pivot_triangles[4·sphere ..]), each < \#T; empty span
/// on out-of-range `sphere`. Cost O(1). Lifetime: the asset bytes.
TriangleSpan PivotTriangles(const AssetView& view, uint32_t sphere);

}  // namespace spherechain::runtime
