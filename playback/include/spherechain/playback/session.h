// spherechain playback — Session: the one frame pipeline of the offline tools.
//
// For one character (a loaded asset and the mesh it was baked from) a Session owns the runtime's Model and
// Workspace, the narrow phase's model(s) and workspace, and every per-frame buffer, and steps frames:
//   animate (skin frame f of an Animation, or take the caller's positions)
//   → refit the spheres (§5.1: pivot frame, the paper's mean displacement, or the joint matrices)
//   → detect the overlapping sphere pairs (M1 per chain and/or M2 over all spheres, §5.2)
//   → optionally the exact narrow phase (every sphere pair, or only behind M2's pairs).
// Each step hands a SessionFrame: views into the session's buffers, transient until the next step.
// `play` (Play(), play.h), `view`, `evaluate`, `check` and the animated debug glTF are its consumers: they
// differ in what they read from the frames and what they add to them, not in how the frames are made.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "spherechain/playback/animation_source.h"
#include "spherechain/playback/types.h"
#include "spherechain/runtime/detect.h"
#include "spherechain/runtime/model.h"
#include "spherechain/runtime/narrow_phase.h"
#include "spherechain/runtime/refit.h"

namespace spherechain::playback {

/// How the spheres follow the frame.
enum class PlayRefit : uint8_t {
  kPaper,       ///< RefitJob, RefitMode::kPaper (centre = bind centre + mean pivot displacement)
  kPivotFrame,  ///< RefitJob, RefitMode::kPivotFrame (default)
  kJoints,      ///< JointRefitJob from the frame's skinning matrices (schema v3 asset of a rigged bake)
};
/// "paper", "frame", "joints".
const char* ToString(PlayRefit r);

/// Which narrow phase a Session runs after the broad phase.
enum class SessionNarrow : uint8_t {
  kNone,   ///< none
  /// NarrowPhaseJob over every sphere pair on the surrounding regions: the exact answer. Exclusions::kCrease
  /// (with depths) when SessionOptions::crease and the asset carries the crease rule, else kAsset.
  kEvery,
  /// Only behind M2's pairs found with SessionOptions::narrow_behind_margin times the asset's contact margin,
  /// on the reach regions (NarrowPhaseRegions::kReach): what a game running the spheres as its broad phase
  /// gets. One margin for every pair (an asset's fold margin set to it: the exact narrow phase cannot cry
  /// wolf). With SessionOptions::crease and an asset that carries the rule: the skin's contacts
  /// (Exclusions::kCrease, with depths) behind those pairs and the proxy's folds (runtime::FoldPairs at
  /// SessionOptions::fold_closing; BehindPairs); else the asset's exclusions behind M2's pairs. That M2 run
  /// (and FoldPairs) is timed with the narrow phase (SessionFrame::narrow_us).
  kBehindM2,
};

/// What a Session builds and runs each frame.
struct SessionOptions {
  /// Refit and detect (a runtime Model and Workspace). false: no sphere model at all, the narrow phase
  /// alone (then `narrow` must be kEvery).
  bool spheres = true;
  PlayRefit refit = PlayRefit::kPivotFrame;
  /// With kJoints: refit from the vertices (pivot frame) first, untimed, and keep those spheres as the
  /// joint refit's reference (SessionFrame::reference).
  bool joint_reference = false;
  bool m1 = true;  ///< run DetectJob M1 (chains) with the asset's margins
  bool m2 = true;  ///< run DetectJob M2 (all spheres) with the asset's margins
  SessionNarrow narrow = SessionNarrow::kNone;
  /// kEvery, kBehindM2: the crease rule (Exclusions::kCrease, with depths) when the asset carries it; false,
  /// or an older asset: the asset's excluded pairs (Exclusions::kAsset).
  bool crease = true;
  /// kBehindM2: the broad phase's margin as a multiple of the asset's contact margin [Limit: finite, > 0].
  float narrow_behind_margin = 1.5f;
  /// kBehindM2 with the crease rule: how much closer than at bind two excluded spheres' centres must come to
  /// be a fold (runtime::FoldPairs' closing), as a multiple of the asset's contact margin [Limit: finite,
  /// >= 0]. The default, 2 (0.8 % of the height with the default margin), was chosen on the reference
  /// animations (docs/design.md: recall against cost).
  float fold_closing = 2.0f;
  /// Also build the reach regions' narrow-phase model and a workspace for it (reach_model(),
  /// reach_workspace()), for a consumer's own jobs behind the pairs (evaluate). kBehindM2 runs on such a
  /// model anyway (narrow_model()).
  bool reach_model = false;
  /// Narrow-phase contacts kept per frame [Limit: > 0]; more are counted (SessionFrame::narrow, status
  /// kOkTruncated), not kept, unless `grow_contacts`.
  uint32_t contact_capacity = 1u << 16;
  /// Grow the contact buffer until every contact of the frame fits (the job re-run on a larger buffer).
  bool grow_contacts = false;
  /// Hand each animated frame's skinning matrices in the runtime's joint layout (SessionFrame::
  /// joint_matrices) when the asset holds centre joint weights for this skin; kJoints always does.
  bool joint_matrices = false;
  /// Runs per job per frame; the timings are the minimum [Limit: 0 counts as 1]. The results are those of
  /// the last run (every run gives the same).
  uint32_t repeat = 1;
};

/// One stepped frame: views into the session's buffers. Transient: valid until the session's next
/// Step / StepBind / Run, its Init or its destruction (do not keep a pointer; copy what you need).
struct SessionFrame {
  static constexpr uint32_t kBind = 0xFFFFFFFFu;  ///< `frame` of the bind pose (StepBind)
  uint32_t frame = 0;         ///< the animation frame, kBind, or the index the caller gave Run
  std::string label;          ///< "bind", "t=0.533s", "arms_crossed t=0.500", or the caller's
  std::span<const float> positions;       ///< \#V×3 deformed positions, model space, source units
  std::span<const float> joint_matrices;  ///< \#J×12 (row-major 3×4, runtime layout), or empty
  runtime::SphereArrays spheres;          ///< the refit spheres (count 0 without SessionOptions::spheres)
  /// joint_reference under kJoints: the vertex refit's spheres as four blocks of \#S (x, y, z, r); else empty.
  std::span<const float> reference;
  std::span<const runtime::Collision> m1, m2;  ///< the pairs of the methods run (empty otherwise)
  runtime::DetectStats m1_stats, m2_stats;     ///< their counters (zero when not run)
  runtime::Exclusions exclusions = runtime::Exclusions::kAsset;  ///< what the narrow phase ran with
  std::span<const runtime::TriangleContact> contacts;  ///< the narrow phase's contacts kept (job order)
  std::span<const runtime::ContactDepth> depths;       ///< parallel to `contacts` under kCrease, else empty
  runtime::NarrowPhaseStats narrow;                    ///< its counters (complete even when truncated)
  runtime::Status narrow_status = runtime::Status::kOk;  ///< kOk, or kOkTruncated (contacts beyond capacity)
  uint32_t behind_pairs = 0;  ///< kBehindM2: M2's pairs at the wider margin the narrow phase ran behind
  uint32_t behind_folds = 0;  ///< kBehindM2 with the crease rule: the folds among them (runtime::FoldPairs)
  /// [Units: µs] the minimum over SessionOptions::repeat runs of each job; wall clock on the calling thread.
  double refit_us = 0, detect_m1_us = 0, detect_m2_us = 0, narrow_us = 0;
};

/// The sphere pairs the narrow phase runs behind under SessionNarrow::kBehindM2 (and evaluate's measure of
/// the restricted skin contacts), for the asset `view` of `model`: DetectJob M2 over `workspace`'s current
/// spheres at `margin` [Units: model] (one margin for every pair: an asset's fold margin set to it), then,
/// when `narrow` is given (the crease rule), runtime::FoldPairs(*narrow, the same spheres, `closing` [Units:
/// model]) appended. `out` grows to DetectBound(M2) (+ narrow->fold_pair_count()) when smaller (allocates
/// once); *count = the records written (M2's first, the *folds folds last; 0 without `narrow`). Returns the
/// first failing job's status (DetectJob's, FoldPairs'), else kOk. Cost: one M2 detect and one distance per
/// excluded pair.
runtime::Status BehindPairs(const runtime::AssetView& view, const runtime::Model& model, runtime::Workspace& workspace,
                            const runtime::NarrowPhaseModel* narrow, float margin, float closing,
                            std::vector<runtime::Collision>* out, uint32_t* count, uint32_t* folds);

/// The frame pipeline of one character, built once and stepped frame by frame (see the file comment).
/// Ownership: owns its runtime models, workspaces and buffers; borrows the AssetView (its bytes) and the
/// Mesh given to Init, which must outlive it and not move. Move-only. Thread safety: one call at a time;
/// two sessions are independent. Cost: Init allocates (the models: NarrowPhaseModel::Init dominates, ~0.26 s
/// for MakeHuman with the crease rule); a step skins the frame (O(Σ influences)) and runs the jobs, and
/// allocates only when a buffer grows (grow_contacts, the first frame's positions).
class Session {
 public:
  Session() = default;
  Session(Session&&) noexcept = default;
  Session& operator=(Session&&) noexcept = default;
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  /// Builds the models and workspaces `options` asks for over `view` and `mesh` [Limit: the mesh the asset
  /// was baked from — its vertex count]. Both are borrowed until the session's destruction or next Init.
  /// Errors (the session is left uninitialised): kConfig — the asset not loaded, the vertex counts differ,
  /// kJoints without centre joint weights in the asset or with another joint count than the mesh's skin,
  /// `spheres` false with a narrow phase other than kEvery, kBehindM2 with a narrow_behind_margin that is not
  /// finite and > 0 or a fold_closing that is not finite and >= 0, a zero contact_capacity (the messages say which); kFormat — a narrow phase on an asset
  /// baked before it ("narrow phase: kErrorMissingField (baked before the narrow phase existed: re-bake
  /// it)"), or on an asset whose bind pose passes through itself beyond the narrow phase's budget
  /// ("runtime Model::Init: kErrorBindPoseTangled: …", runtime_status() holds it), or whose crease reaches too
  /// much of its bind surface ("runtime Model::Init: kErrorCreaseTooWide: …"); kInternal — another
  /// runtime Init failure ("runtime Model::Init: <status>", ...; runtime_status() holds
  /// the status). Cost: the runtime Inits (allocating), the DetectBound-sized pair buffers and
  /// contact_capacity contacts (12 B each, + 16 B with depths).
  Status Init(const runtime::AssetView& view, const Mesh& mesh, const SessionOptions& options);

  /// Skins frame `f` of `animation` [Limit: f < animation.frames; made for the Init mesh] into the
  /// session's positions, then Run()s them (frame index f, the animation's label).
  /// Errors: the skinning's (Animation::Frame), Run's.
  Status Step(const Animation& animation, uint32_t f);
  /// The bind pose (Mesh::positions; under kJoints the rest pose's skinning matrices), as frame kBind
  /// labelled "bind". Errors: those of the rest pose's matrices, Run's.
  Status StepBind();
  /// The pipeline on the caller's positions (\#V×3 packed floats, borrowed for the call and viewed by
  /// frame().positions until the next step) and, under kJoints, joint matrices (\#J×12). Errors: kInternal
  /// "<job>: <status>" when a runtime job fails (job: refit, joint refit, detect, narrow phase;
  /// runtime_status() holds the status); kFormat "narrow phase (frame '<label>'): kErrorFrameTangled: …"
  /// when the positions pass through themselves beyond the narrow phase's budget (no pose of the character);
  /// kConfig for missing joint matrices under kJoints.
  Status Run(const float* positions, const float* joint_matrices, uint32_t frame, std::string label);
  /// Every frame of `animation` in order: Step, then `consume` (a returned error stops with it).
  Status Play(const Animation& animation, const std::function<Status(const SessionFrame&)>& consume);

  /// The last step's frame (see SessionFrame for its lifetime).
  const SessionFrame& frame() const { return frame_; }

  bool initialized() const { return view_.valid(); }             ///< true after a successful Init
  const SessionOptions& options() const { return options_; }      ///< what Init was given
  const runtime::AssetView& view() const { return view_; }        ///< the asset (borrowed)
  /// The runtime status of the last failure (kOk when none).
  runtime::Status runtime_status() const { return runtime_status_; }
  /// The narrow phase's exclusions under kEvery and kBehindM2 (kCrease when the rule is on), else kAsset.
  runtime::Exclusions exclusions() const { return exclusions_; }

  /// The character's Model and Workspace: the spheres' (refit, broad phase) and, with a narrow phase, the
  /// narrow phase's in the same blocks (Model::narrow_phase()); uninitialised with neither spheres nor a
  /// narrow phase. A consumer may run its own jobs on them between steps (a sweep of margins): the
  /// workspace's spheres are the last refit's until the next step.
  const runtime::Model& model() const { return model_; }
  runtime::Workspace& workspace() { return workspace_; }
  /// The narrow phase's model and workspace, held by model() and workspace() (surrounding regions; reach
  /// regions under kBehindM2), or uninitialised ones under kNone.
  const runtime::NarrowPhaseModel& narrow_model() const;
  runtime::NarrowPhaseWorkspace& narrow_workspace();
  /// The reach regions' model and workspace of SessionOptions::reach_model (else uninitialised).
  const runtime::NarrowPhaseModel& reach_model() const { return reach_; }
  runtime::NarrowPhaseWorkspace& reach_workspace() { return reach_ws_; }
  /// The skinning's scratch of the last Step (SkinningScratch::locals: the frame's node transforms).
  const SkinningScratch& skinning() const { return scratch_; }
  /// The buffers Step animated into: positions (\#V×3) and joint matrices (\#J×12, when computed).
  const std::vector<float>& positions() const { return positions_; }
  const std::vector<float>& joint_matrices() const { return joint_matrices_; }

 private:
  Status Refit(const float* positions, const float* joint_matrices);
  Status Detect();
  Status Narrow(const float* positions, const float* joint_matrices);
  Status RuntimeFailure(const char* job, runtime::Status s);

  SessionOptions options_;
  runtime::AssetView view_;
  const Mesh* mesh_ = nullptr;
  runtime::Model model_;
  runtime::Workspace workspace_;
  runtime::NarrowPhaseModel reach_;
  runtime::NarrowPhaseWorkspace reach_ws_;
  runtime::Exclusions exclusions_ = runtime::Exclusions::kAsset;
  runtime::Status runtime_status_ = runtime::Status::kOk;
  uint32_t repeat_ = 1;
  std::vector<runtime::Collision> out_m1_, out_m2_, out_behind_;
  std::vector<runtime::TriangleContact> contacts_;
  std::vector<runtime::ContactDepth> depths_;
  std::vector<float> reference_;  // joint_reference: the vertex refit's spheres (x, y, z, r blocks)
  std::vector<float> positions_, joint_matrices_;
  SkinningScratch scratch_;
  SessionFrame frame_;
};

}  // namespace spherechain::playback
