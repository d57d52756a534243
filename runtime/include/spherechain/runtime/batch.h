// spherechain runtime — many characters per frame on the CPU: refit + detect over N workspaces that
// share one Model, spread through the ParallelFor hook (TBB, or the engine's job system).
#pragma once

#include <cstdint>

#include "spherechain/runtime/detect.h"
#include "spherechain/runtime/model.h"
#include "spherechain/runtime/refit.h"
#include "spherechain/runtime/status.h"

namespace spherechain::runtime {

/// Where a batch refits its characters' spheres from.
enum class RefitSource : uint8_t {
  kVertices = 0,  ///< RefitJob: each character's deformed vertex buffer (CharacterFrame::positions)
  kJoints = 1,    ///< JointRefitJob: each character's skinning matrices (CharacterFrame::joint_matrices)
};

/// One character of a BatchJob: its workspace, its frame's input, its detection output.
/// Everything borrowed for one Run(); the batch writes `*count`, `*stats`, `output` and `status`.
struct CharacterFrame {
  Workspace* workspace = nullptr;         ///< made for the batch's model; spheres overwritten
  PositionsView positions;                ///< RefitSource::kVertices: this frame's deformed vertices
  const float* joint_matrices = nullptr;  ///< RefitSource::kJoints: \#J × 12 floats (see JointRefitJob)
  Collision* output = nullptr;            ///< [opt when capacity == 0] detection records (DetectJob)
  uint32_t capacity = 0;                  ///< records `output` holds; DetectBound() never truncates
  uint32_t* count = nullptr;              ///< out: records written
  DetectStats* stats = nullptr;           ///< [opt] out: counters
  Status status = Status::kOk;            ///< out: this character's refit's error, else its detect's status
};

/// ozz-style job: for each of `character_count` characters sharing `model`, the refit (from vertices
/// or joint matrices) and then the detection (M1 or M2) of its frame — exactly what RefitJob::Run /
/// JointRefitJob::Run and DetectJob::Run give that character alone, bit for bit (tested).
/// parallel_for [opt]: one task index per `parallel_grain` characters, each character's refit and
/// detection serial inside its task (characters are independent: they share only the read-only model),
/// so the batch scales with the cores the hook brings; null: serial.
/// Cost: \#characters × (refit + detect), plus the hook's own overhead — measured on MakeHuman (128 spheres)
/// in docs/performance.md, "Many characters"; no allocation, no exceptions.
/// Thread safety: the workspaces must be distinct (one job per workspace at a time).
struct BatchJob {
  const Model* model = nullptr;              ///< initialised, shared by every character (read only)
  CharacterFrame* characters = nullptr;      ///< \#N characters [opt when character_count == 0]
  uint32_t character_count = 0;              ///< \#N
  RefitSource source = RefitSource::kVertices;
  RefitMode mode = RefitMode::kPivotFrame;   ///< kVertices only (see RefitJob)
  uint32_t joint_count = 0;                  ///< kJoints only: \#J [Limit: == Model::joint_count()]
  DetectMethod method = DetectMethod::kM1;
  float margin = -1.0f;                      ///< see DetectJob::margin (< 0: the asset's)
  float fold_margin = -1.0f;                 ///< see DetectJob::fold_margin (< 0: the asset's, if any)
  ParallelFor parallel_for;                  ///< [opt] over characters
  uint32_t parallel_grain = 4;               ///< [Limit: > 0] characters per task index

  /// True when Run() would not fail on the batch's own arguments.
  bool Validate() const { return Check() == Status::kOk; }
  /// kErrorNullArgument (model null, or characters null with character_count > 0), kErrorInvalidJob
  /// (model not initialised, unknown source / mode / method, margin or fold_margin NaN or infinite,
  /// fold_margin >= 0 on a model without a fold margin, grain 0),
  /// kErrorMissingField / kErrorJointCount (kJoints: the model has no joint weights / joint_count
  /// differs), else kOk. Per-character arguments are checked per character (their `status`).
  Status Check() const;
  /// Runs every character. Returns Check()'s error (nothing run, nothing written); else the first
  /// failed character's status in index order (every character ran: those whose own arguments are bad —
  /// a null workspace or count, a workspace made for another model (kErrorWorkspaceModel), a wrong
  /// vertex count, non-finite joint matrices... — have their status set and nothing else written);
  /// else kOkTruncated when some character's output was too small; else kOk.
  Status Run() const;
};

}  // namespace spherechain::runtime
