// spherechain playback — Play(): an animation of the character an asset was baked from, run through the
// runtime frame by frame (refit the spheres to the skinned vertices §5.1, detect overlapping sphere pairs
// with M1 and/or M2 §5.2, optionally the exact narrow phase), with per-job timings — what `spherechain
// play` prints, as a report a C++ caller (a test, a tool) can read. A consumer of the frame pipeline
// (Session, session.h): it keeps each frame's results and adds the tracking measure and the summary.
//
// The bind pose is played first (the undeformed Mesh::positions: a correct asset reports no pair there),
// then frames 0..N−1 of the animation (animation_source.h).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "spherechain/playback/animation_source.h"
#include "spherechain/playback/session.h"
#include "spherechain/playback/types.h"
#include "spherechain/runtime/detect.h"
#include "spherechain/runtime/narrow_phase.h"
#include "spherechain/runtime/refit.h"

namespace spherechain::playback {

/// What Play() runs.
struct PlayOptions {
  bool m1 = true;                         ///< run DetectJob M1 (chains)
  bool m2 = true;                         ///< run DetectJob M2 (all spheres)
  /// How the spheres follow the frame (PlayRefit, session.h); under kJoints the pivot-frame refit of the same
  /// frame is its reference (FrameReport::joint_error).
  PlayRefit refit = PlayRefit::kPivotFrame;
  uint32_t repeat = 5;                    ///< runs per job per frame; timings are the minimum [Limit: 0 counts as 1]
  bool narrow_phase = false;              ///< also NarrowPhaseJob (exact triangle contacts of the surrounding regions)
  /// With narrow_phase: 0 (default) — the narrow phase over every surrounding region (the exact answer); > 0 —
  /// only behind DetectJob M2's pairs found with this many times the asset's contact margin, on the reach regions
  /// (NarrowPhaseRegions::kReach; what a game running the spheres as its broad phase gets: docs/evaluation.md
  /// "The spheres as a broad phase"; 1.5 there), with every pair on that margin (an asset's fold margin set to
  /// it: the exact narrow phase cannot cry wolf). That M2 run is timed into FrameReport::narrow_us with the
  /// narrow phase.
  /// [Limit: finite, >= 0; otherwise Play answers kConfig]
  float narrow_behind_margin = 0.0f;
  /// With narrow_phase over every region (narrow_behind_margin 0) on an asset baked with the crease rule
  /// (Asset.crease): the skin's definition, Exclusions::kCrease — every self-contact whichever spheres own
  /// it (a contact's sphere is 0xFFFF for an unassigned triangle; its region -1). false, or an older asset:
  /// the asset's excluded pairs (Exclusions::kAsset).
  bool crease = true;
  uint32_t contact_capacity = 1u << 16;   ///< narrow-phase contacts kept per frame (more are counted, not kept)
  bool keep_spheres = false;              ///< fill FrameReport::spheres (\#S×4 per frame)
  /// [opt] called after each animation frame (not the bind pose) is skinned and measured: the frame index,
  /// its deformed positions (\#V×3, model space, source units) and, when the asset holds centre joint weights
  /// for this skin (Asset.sphere_joints, joint_count == \#joints), its skinning matrices in JointRefitJob's
  /// layout (\#J×12, row-major 3×4), else null. Borrowed for the call. A returned error stops Play with it.
  std::function<Status(uint32_t frame, const std::vector<float>& positions, const std::vector<float>* joint_matrices)>
      on_frame;
};

/// One played frame (or the bind pose).
struct FrameReport {
  uint32_t frame = 0;     ///< animation frame index (0 for the bind pose)
  std::string label;      ///< "bind", "t=0.533s" or "arms_crossed t=0.500"
  runtime::DetectStats m1, m2;  ///< counters of the methods run (zero otherwise)
  double refit_us = 0, detect_m1_us = 0, detect_m2_us = 0;  ///< [Units: µs] min over PlayOptions::repeat runs
  /// |ΔF| of the refit spheres against the bind pose over every (sphere, surrounding-region vertex):
  /// F = r − ‖c − v‖, ΔF = F(frame) − F(bind); 0 when a sphere moves and scales exactly with its surface.
  double tracking_mean = 0, tracking_max = 0;  ///< [Units: source units]
  std::vector<double> joint_error;  ///< kJoints: per sphere ‖c_joints − c_pivot_frame‖ / r_pivot_frame [%], \#S
  std::vector<std::pair<int, int>> regions;  ///< region pairs (min, max) of `pairs`, sorted, each once
  std::vector<runtime::Collision> pairs;     ///< M2's colliding pairs when run, else M1's (runtime order)
  runtime::NarrowPhaseStats narrow;          ///< narrow_phase: counters
  double narrow_us = 0;                      ///< narrow_phase [Units: µs]
  std::vector<runtime::TriangleContact> contacts;   ///< narrow_phase: the frame's contacts (≤ contact_capacity)
  std::vector<std::pair<int, int>> contact_regions; ///< narrow_phase: region pairs of the contacts, sorted
  /// narrow_phase under the crease rule: per contact_regions entry, its deepest contact's depth [Units: model]
  /// (runtime::ContactDepth); empty otherwise
  std::vector<float> contact_region_depth;
  std::vector<runtime::ContactDepth> depths;        ///< crease rule: per contact (parallel to `contacts`), else empty
  uint32_t narrow_pairs = 0;                 ///< narrow_behind_margin > 0: the sphere pairs the narrow phase ran
                                             ///< behind (M2's, and with the crease rule the folds)
  uint32_t narrow_folds = 0;                 ///< of those, the proxy's folds (crease rule; SessionFrame::behind_folds)
  std::vector<float> spheres;  ///< keep_spheres: the refit spheres, \#S×4 (x, y, z, r), source units, model space
};

/// Totals over the animation frames (the bind pose excluded).
struct PlaySummary {
  uint32_t frames = 0, frames_with_pairs = 0;
  double mean_refit_us = 0, mean_detect_m1_us = 0, mean_detect_m2_us = 0;
  double mean_pairs_m1_raw = 0, mean_pairs_m1 = 0, mean_pairs_m2 = 0;
  uint32_t max_pairs_m1_raw = 0, max_pairs_m2 = 0;
  double tracking_mean = 0, tracking_max = 0;  ///< mean of the frames' means, max of their maxima
  /// kJoints: joint_error over spheres × frames [%] (0 otherwise).
  double joint_error_median = 0, joint_error_p95 = 0, joint_error_max = 0;
  uint64_t contacts = 0, frames_with_contacts = 0;  ///< narrow phase
  double narrow_median_us = 0, narrow_max_us = 0;
  /// Region pairs touching (from FrameReport::regions) → number of frames, sorted by pair.
  std::vector<std::pair<std::pair<int, int>, uint32_t>> region_frames;
};

/// The report of one Play().
struct PlayReport {
  std::string animation;          ///< Animation::Describe()
  uint32_t sphere_count = 0, chain_count = 0;
  FrameReport bind;               ///< the bind pose
  std::vector<FrameReport> frames;  ///< animation frames 0..N−1
  PlaySummary summary;
};

/// Plays `animation` over `mesh` [Limit: the mesh the asset was baked from — vertex count equal to
/// the asset's; a skin] with `asset` (a loaded view; borrowed for the call) as described above.
/// Errors: kConfig — the vertex count differs; kJoints without centre joint weights in the asset
/// ("... has no joint weights ...: re-bake it") or with another joint count than the skin's; a
/// narrow_behind_margin that is negative or not finite (an asset baked before reach regions runs behind its
/// surrounding regions: runtime ReachTriangles); a contact_capacity of 0 with the narrow phase; kFormat — the
/// narrow phase on an asset without its data
/// ("narrow phase: kErrorMissingField (...: re-bake it)"); kInternal — a runtime job failed (the message names
/// the job and its status); the skinning's errors; on_frame's errors.
/// Cost: per frame one skinning (O(Σ influences)), (repeat ×) refit and detect runs, the tracking
/// measure O(Σ surrounding-region vertices); allocates (report, runtime Model/Workspace, scratch); owns
/// no threads; thread-safe for distinct arguments (on_frame is called on the calling thread). Timings are
/// wall-clock on the calling thread (a loaded machine inflates them; the minimum over `repeat` damps it).
/// Ownership: the report owns everything it holds; `mesh`, `asset` and `animation` are borrowed for the call.
Result<PlayReport> Play(const Mesh& mesh, const runtime::AssetView& asset, const Animation& animation,
                        const PlayOptions& options = {});

/// Summary of `frames` (what Play() stores in PlayReport::summary).
PlaySummary Summarize(const std::vector<FrameReport>& frames);

/// "R0-R4 R1-R4": region pairs, space-separated; "-" when empty.
std::string RegionPairsText(const std::vector<std::pair<int, int>>& pairs);

}  // namespace spherechain::playback
