// spherechain runtime — broad-phase self-collision: sphere overlap tests (paper §5.2).
#pragma once

#include <cstdint>

#include "spherechain/runtime/asset.h"
#include "spherechain/runtime/model.h"
#include "spherechain/runtime/status.h"

namespace spherechain::runtime {

/// Which pairs are candidates (§5.2). Both skip excluded (adjacent) pairs (Asset.excluded_pairs).
/// Both report exactly the candidates that overlap; a broad phase (blocks of 8 spheres, see DetectJob)
/// decides which candidates need the sphere test, so fewer are tested than the paper's counts.
enum class DetectMethod : uint8_t {
  /// With chains: every pair inside each chain ζ_i (Table 1), O(n_c · n²) in the paper. A pair in
  /// several chains is counted (DetectStats::tests, DetectStats::raw_pairs) once per chain, as the
  /// paper does, but evaluated once and reported once.
  kM1 = 0,
  /// Without chains: every pair of the \#S spheres, O(\#S²) in the paper.
  kM2 = 1,
};

/// One colliding pair. POD, 12 bytes, shared with the CUDA path.
struct Collision {
  uint16_t a;      ///< sphere index, a < b
  uint16_t b;      ///< sphere index
  float depth;     ///< penetration depth rA + rB − ‖cA − cB‖ of the spheres themselves [Units: source
                   ///< units]: > 0 overlapping; in (−2·m, 0] apart but within the margin m the pair was tested
                   ///< with (the contact margin, or the fold margin for two spheres of one region)
  uint32_t chains; ///< bit c set ⇔ Asset.chains[c] contains both a and b (M1: never 0; M2: may be 0)
};
static_assert(sizeof(Collision) == 12);

/// Counters of one DetectJob::Run, complete even when the output was truncated.
struct DetectStats {
  uint32_t tests = 0;           ///< overlap tests in the paper's count (M1: Σ n(n−1)/2 over chains,
                                ///< M2: \#S(\#S−1)/2; excluded pairs included)
  uint32_t raw_pairs = 0;       ///< M1: overlapping non-excluded (chain, pair) hits, duplicates across
                                ///< chains included (the paper's count); M2: == distinct_pairs
  uint32_t distinct_pairs = 0;  ///< overlapping non-excluded pairs (a < b); > capacity ⇔ truncated
  uint32_t box_tests = 0;       ///< broad phase: pairs of blocks of 8 spheres bound-tested (those that
                                ///< hold a candidate pair of the method; ≈ (\#S/8)²/2 at most)
  uint32_t sphere_tests = 0;    ///< candidate pairs in the block pairs that passed: the sphere tests
                                ///< that count (the rest of the paper's `tests` was culled)
};

/// Most Collision records a DetectJob with `method` can write for this asset: an upper bound, so a
/// buffer of this size is never truncated. M2: \#S(\#S−1)/2; M1: min(Σ_chains n(n−1)/2, \#S(\#S−1)/2).
/// 0 for an invalid view or method. Cost O(\#chains), no allocation. (Model::m1_candidate_pairs() /
/// m2_candidate_pairs() give the exact, smaller numbers.)
uint32_t DetectBound(const AssetView& view, DetectMethod method);

/// ozz-style job: reports overlapping non-excluded sphere pairs of one character's current spheres
/// (`workspace`, after RefitJob::Run, or bind pose), with `model`'s chains, exclusions and broad-phase
/// layout. Overlap: ‖cA − cB‖² < (rA + rB + 2m)² (11 operations, formulas::OverlapLanes), m the
/// contact margin (DetectJob::margin); depths by formulas::SphereDepth. The set, order, depths and counters (but box_tests and
/// sphere_tests) are exactly those of testing every candidate pair, bit for bit, NaN and infinite
/// spheres included (tests/runtime/detect_reference_test.cpp, detect_broad_phase_test.cpp compare them
/// with brute force).
/// Output order (deterministic, identical with or without parallel_for): M1 — by chain, each pair
/// under the first chain containing both a and b, rows i < j of that chain's ascending list;
/// M2 — lexicographic (a, b).
/// Broad phase (both methods): Model::Init puts the spheres in blocks of 8 (grouped by body region,
/// Asset.sphere_regions, else by chains; split at bind pose along the longest axis); per frame each
/// block gets the box of its centres and its largest |radius|, a pair of blocks is kept when the gap
/// between the boxes is below the sum of those radii (with the sphere test's own float operations:
/// conservative to the last bit), and only kept pairs run their 8×8 sphere tests (SoA, 4, 8 or 16 lanes:
/// SSE2, AVX or AVX-512, picked at Model::Init; the same pairs, depths and counters on each), masked by a
/// per-asset table of candidate lanes (excluded pairs, M1's pairs sharing no chain).
/// Blocks follow the bind pose: a pose that scatters a block's spheres (not a body's motion) culls
/// less, never wrongly.
/// Cost: O(\#S) gather and boxes + ≤ (\#S/8)²/2 block tests + 64 sphere tests per kept block pair (on
/// MakeHuman's 128 spheres over its 40-frame morph: 182 block tests, 46 kept pairs, 1,470 candidate
/// pairs tested of M2's 8,128); a sort of the hits. No allocation, no exceptions.
/// parallel_for [opt] (both methods): one task index per row block of 8 spheres (its block pairs
/// and sphere tests, into the workspace's scratch), then a serial merge and sort; same output.
/// Thread safety: one job per workspace at a time; the model is only read (shared by any number of
/// characters and threads).
struct DetectJob {
  const Model* model = nullptr;    ///< initialised; read only
  Workspace* workspace = nullptr;  ///< made for `model`: its spheres are read, its scratch written
  DetectMethod method = DetectMethod::kM1;
  Collision* output = nullptr;  ///< [opt when capacity == 0] caller buffer of `capacity` records
  uint32_t capacity = 0;        ///< records `output` holds; DetectBound() never truncates
  uint32_t* count = nullptr;    ///< out: records written (== min(distinct_pairs, capacity))
  DetectStats* stats = nullptr; ///< [opt] out: counters
  ParallelFor parallel_for;     ///< [opt]
  /// Contact margin [Units: source units]: spheres are tested with every radius grown by it (a pair is
  /// reported when ‖cA − cB‖ < rA + rB + 2·margin, as physics engines' contact offset / skin width).
  /// < 0 (default): the asset's, Model::contact_margin() (Asset.contact_margin); NaN or ±inf:
  /// kErrorInvalidJob (the C API's sc_detect reads −inf as the asset's). [Limit: finite]
  float margin = -1.0f;
  /// Fold margin [Units: source units]: a pair of two spheres of one region (Asset.sphere_regions) is
  /// reported when ‖cA − cB‖ < rA + rB + 2·fold_margin instead of 2·margin; pairs of two regions keep
  /// `margin`. Inside a region spheres meet only where a joint folds, where the refit spheres do not follow
  /// the skin the pit compresses (docs/design.md "The fold margin"). < 0 (default): the asset's,
  /// Model::fold_margin() (Asset.fold_margin; assets without one test every pair with `margin`); >= 0 on a
  /// model without a fold margin (no regions to tell the pairs apart), NaN or inf: kErrorInvalidJob.
  /// Collision::depth stays computed with `margin`. In front of the exact narrow phase (NarrowPhaseJob on
  /// these pairs), set it to `margin` (when the model has one): the narrow phase cannot cry wolf, so the fold
  /// margin would only lose a joint's fold contacts (what `play --narrow-behind` and evaluate's sweep do).
  /// Cost: one scalar overlap test per hit when the two margins differ. [Limit: finite]
  float fold_margin = -1.0f;

  /// True when Run() would not fail on arguments.
  bool Validate() const { return Check() == Status::kOk; }
  /// kErrorNullArgument (model, workspace or count null, or output null with capacity > 0),
  /// kErrorInvalidJob (model or workspace not initialised, unknown method, margin or fold_margin NaN or
  /// infinite, fold_margin >= 0 on a model without a fold margin),
  /// kErrorWorkspaceModel (workspace made for another model), else kOk.
  Status Check() const;
  /// Returns Check()'s error (outputs and workspace untouched), kOk, or kOkTruncated when more pairs overlapped
  /// than `capacity`: output holds the first `capacity` in the documented order, *count == capacity.
  Status Run() const;
};

}  // namespace spherechain::runtime
