// spherechain runtime — status codes (Recast-style: an outcome plus detail).
#pragma once

#include <cstdint>

namespace spherechain::runtime {

/// Outcome of every fallible runtime call. Layout (Recast dtStatus-like):
/// bit 31 set = failure; for failures the low 16 bits are the error code;
/// for successes the low bits are detail flags (kDetailTruncated = 1).
/// Never thrown; `[[nodiscard]]` so a caller cannot drop it silently.
/// Use `Succeeded()` / `Failed()` / `IsTruncated()` rather than comparing with kOk when a
/// success-with-detail is acceptable. `ToString()` names every value.
enum class [[nodiscard]] Status : uint32_t {
  // ---- successes (bit 31 clear) -----------------------------------------------------------------
  kOk = 0x0000'0000u,           ///< Success, outputs complete.
  kOkTruncated = 0x0000'0001u,  ///< Success, but the caller's output buffer was too small: it holds
                                ///< the first `capacity` results and the count out equals `capacity`.

  // ---- argument / programmer errors -------------------------------------------------------------
  kErrorNullArgument = 0x8000'0001u,  ///< A required pointer was null (or size 0 with a non-null ask).
  kErrorAlignment = 0x8000'0002u,     ///< Asset bytes not 8-byte aligned, or positions not 4-byte aligned.
  kErrorInvalidJob = 0x8000'0003u,    ///< Job fields inconsistent (unknown mode/method, model or
                                      ///< workspace not initialised, parallel_grain 0).
  kErrorVertexCount = 0x8000'0004u,   ///< PositionsView::count != asset fingerprint.vertex_count.
  kErrorStride = 0x8000'0005u,        ///< PositionsView::stride_bytes < 12 or not a multiple of 4.
  kErrorOutOfMemory = 0x8000'0006u,   ///< Model / Workspace / NarrowPhaseModel / NarrowPhaseWorkspace::Init could not allocate.
  kErrorNonFinitePositions = 0x8000'0007u,  ///< A deformed vertex position is NaN or infinite
                                            ///< (NarrowPhaseJob checks the positions it reads).
  kErrorJointCount = 0x8000'0008u,    ///< JointRefitJob::joint_count != the asset's Asset.joint_count.
  kErrorNonFiniteJoints = 0x8000'0009u,  ///< A joint matrix holds a NaN or an infinity (JointRefitJob
                                         ///< checks all \#J before writing, those no sphere follows too).
  kErrorWorkspaceModel = 0x8000'000Au,   ///< The Workspace was made for another Model (Workspace::Init
                                         ///< records Model::id(); NarrowPhaseWorkspace likewise
                                         ///< NarrowPhaseModel::id()): the job wrote nothing.
  kErrorBufferTooSmall = 0x8000'000Bu,   ///< Caller memory smaller than RequiredBytes() (Model /
                                         ///< Workspace::InitInPlace): nothing built.
  kErrorFrameTangled = 0x8000'000Cu,     ///< NarrowPhaseJob: the frame's skin passes through
                                         ///< itself so much that the job ran past its budget
                                         ///< (NarrowPhaseModel::kSweepTestsPerTriangle …): positions that are
                                         ///< no pose of this character (uninitialised, collapsed, scrambled).
                                         ///< Count 0, stats as far as it got; real frames use a fraction.

  // ---- asset envelope (LoadAsset) ---------------------------------------------------------------
  kErrorAssetTooSmall = 0x8000'0101u,   ///< Fewer bytes than a FlatBuffer header (8) — truncated file.
  kErrorAssetTooLarge = 0x8000'0102u,   ///< More than kMaxAssetBytes.
  kErrorIdentifier = 0x8000'0103u,      ///< file_identifier is not "SPHC" (not a .sphc asset).
  kErrorVersionTooOld = 0x8000'0104u,   ///< schema_version < kMinSchemaVersion (re-bake with this SDK).
  kErrorVersionTooNew = 0x8000'0105u,   ///< schema_version > kSchemaVersion (asset from a newer SDK).
  kErrorCorrupt = 0x8000'0106u,         ///< FlatBuffers Verifier rejected the buffer (offsets out of
                                        ///< bounds, truncated, too deep, too many tables, misaligned).

  // ---- asset semantics (LoadAsset) --------------------------------------------------------------
  kErrorMissingField = 0x8000'0201u,     ///< A field the runtime needs is absent (fingerprint, spheres,
                                         ///< chains, surrounding_*, pivot_*).
  kErrorNoSpheres = 0x8000'0202u,        ///< spheres is empty.
  kErrorTooManySpheres = 0x8000'0203u,   ///< \#S > kMaxSpheres (indices are uint16).
  kErrorTooManyChains = 0x8000'0204u,    ///< \#chains > kMaxChains (chain bitmask is 32 bits), or the chains'
                                         ///< candidate pairs Σ|ζ|(|ζ|−1)/2 > kMaxChainPairs.
  kErrorCountMismatch = 0x8000'0205u,    ///< An array's length disagrees with \#S, \#T or 4·\#S / 12·\#S.
  kErrorIndexOutOfRange = 0x8000'0206u,  ///< A sphere index >= \#S, triangle index >= \#T, vertex
                                         ///< index >= \#V or joint index >= joint_count, or joint_count >
                                         ///< kMaxJoints.
  kErrorOffsets = 0x8000'0207u,          ///< surrounding_offsets (or reach_offsets) not starting at 0,
                                         ///< not monotone, or not ending at len(surrounding_triangles)
                                         ///< (reach_triangles); a sphere's reach triangles not ascending.
  kErrorNonFinite = 0x8000'0208u,        ///< A NaN or infinite float (centre, radius, pivot frame,
                                         ///< contact_margin).
  kErrorRadius = 0x8000'0209u,           ///< A sphere radius <= 0.
  kErrorPivotFrame = 0x8000'020Au,       ///< PivotFrame.mean_distance <= 0, or so small that a radius / it
                                         ///< is not a finite float.
  kErrorChainOrder = 0x8000'020Bu,       ///< A chain's sphere list is not strictly ascending (sorted, unique).
  kErrorExcludedPairs = 0x8000'020Cu,    ///< An excluded pair with a >= b, or the list not strictly
                                         ///< ascending by (a, b).
  kErrorContactMargin = 0x8000'020Du,    ///< Asset.contact_margin < 0 (schema v2).
  kErrorSkinWeights = 0x8000'020Eu,      ///< A sphere's joint weight is negative or not finite, or its four
                                         ///< weights have one after a 0 or do not sum to 1 ± 1e-3 (schema v3), or a
                                         ///< vertex's rounded skin_weights do not sum to 255 (v4).
  kErrorRegions = 0x8000'020Fu,          ///< Asset.regions (schema v4) malformed: fewer than 2 or more than
                                         ///< kMaxRegions regions, a Trunk that is not exactly the last one,
                                         ///< or a sphere_regions / triangle_regions value past them
                                         ///< (past the paper's five without Asset.regions).

  // ---- what a loaded asset cannot build (Model / NarrowPhaseModel::Init) -------------------------
  kErrorBindPoseTangled = 0x8000'0301u,  ///< NarrowPhaseModel::Init (and a Model with its narrow phase): the
                                         ///< bind pose (Asset.bind_positions) passes through itself so much
                                         ///< that its sweep ran past NarrowPhaseModel::kSweepTests… (a
                                         ///< broken or mutated mesh; real characters use a fraction of it).
  kErrorCreaseTooWide = 0x8000'0302u,    ///< NarrowPhaseModel::Init (and a Model with its narrow phase): the
                                         ///< crease (Asset.crease) reaches so many welded vertices of the bind
                                         ///< surface from each that its searches ran past
                                         ///< NarrowPhaseModel::kReachPerNode: a bind pose collapsed onto a few
                                         ///< points, or a mesh far denser than its crease (MakeHuman uses an
                                         ///< eighth of it; re-bake with a smaller crease_rel). Also when the
                                         ///< patches' growth or gathering runs past kGrowPerTriangle /
                                         ///< kGatherPerNode: a welded vertex shared by thousands of triangles.
};

/// True for kOk and every success-with-detail (kOkTruncated). Cost: one compare.
constexpr bool Succeeded(Status s) { return (static_cast<uint32_t>(s) & 0x8000'0000u) == 0; }
/// True for every kError*.
constexpr bool Failed(Status s) { return !Succeeded(s); }
/// True when a success carries the "output truncated" detail.
constexpr bool IsTruncated(Status s) { return s == Status::kOkTruncated; }

/// Static, NUL-terminated English name of `s` (e.g. "kErrorVersionTooNew: asset schema_version is
/// newer than this SDK"). Never null; unknown values give "unknown status". Lifetime: static.
const char* ToString(Status s);

}  // namespace spherechain::runtime
