// spherechain evaluate — animation QA: plays every clip of a character, finds every self-contact the skin
// makes on every frame (the runtime's crease rule, Exclusions::kCrease, with its depths), groups them into
// events (a region pair over a run of frames, with its deepest penetration) and judges each against a
// policy (a depth threshold per region pair, allowed pairs), optionally against a baseline of an earlier
// run. What `spherechain check` runs, as a library call (the CLI, tests and Python use it alike).
//
// A contact is the runtime's (narrow_phase.h, crease.h): two triangles sharing no welded corner that
// intersect and are not within the asset's crease of each other on the welded bind surface. Contacts whose
// triangles intersect at bind pose already (modelling artefacts, NarrowPhaseModel::IntersectsAtBind) are
// counted per clip and belong to no event. Depths are runtime::ContactDepth (separating-axis estimate).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "spherechain/import/types.h"
#include "spherechain/runtime/asset.h"

namespace spherechain::evaluate {

/// A region pair (lower region index first), region indices of the asset (Asset.triangle_regions).
using CheckPair = std::pair<int, int>;

/// What counts as a failure. Depths are in model units (the asset's, i.e. the mesh's source units).
struct CheckPolicy {
  double max_depth = 0;                            ///< [Units: model] [Limit: > 0] an event deeper fails its clip
  std::map<CheckPair, double> pair_max_depth;      ///< [opt] per region pair, replaces max_depth [Units: model]
  std::vector<CheckPair> allow;                    ///< [opt] region pairs that never fail (still listed)
  /// The threshold of `pair` (pair_max_depth, else max_depth); +inf for an allowed pair.
  double Threshold(const CheckPair& pair) const;
};

/// The body height: the bind pose's extent along the mesh's up axis [Units: model]; 0 for an empty mesh.
double BodyHeight(const import::Mesh& mesh);

/// Parses a depth: "1cm", "5mm", "0.02m" (needs `unit_scale_m` > 0: metres per model unit, import
/// Mesh::unit_scale_m), "1%" (of `height`, model units) or a bare number (model units); the number is
/// decimal ("2", "0.5", "1e-3"; no hexadecimal, sign, "inf" or leading space), a space allowed before its unit. Errors: kConfig
/// "'x' is not a depth (…)", or "'1cm': the character's units are unknown; give the depth in model units or %".
import::Result<double> ParseDepth(const std::string& text, double height, double unit_scale_m);

/// Reads a policy file: {"allow": ["left_hand-head", "R1-R4"], "max_depth": {"left_arm-torso": "2cm"},
/// "default_max_depth": "1%"} — region pairs by name (runtime::RegionName) or symbol ("R3"), joined by '-';
/// depths as ParseDepth. Fills `policy` (max_depth only when "default_max_depth" is present). Errors: kIo
/// (unreadable), kFormat (not JSON, a key of another type), kConfig (an unknown key, an unknown region — the
/// message lists the regions —, a bad depth, one region pair given twice in "max_depth" under two spellings,
/// e.g. "R3-R4" and "ForeLeg_L-ForeLeg_R", both keys named). Cost: one file read.
import::Status LoadCheckPolicy(const std::string& path, const runtime::AssetView& asset, double height,
                               double unit_scale_m, CheckPolicy* policy);

/// What to play and judge.
struct CheckOptions {
  std::string mesh_name = "mesh";    ///< the character's file, for messages and the reports
  std::string asset_name = "asset";  ///< the asset's file, for messages
  std::vector<std::string> clips;  ///< [opt] clip names to check, each once (kConfig); empty: every clip of the mesh
  /// [opt] key poses (files, or folders of *.json; playback::LoadPose) played as one extra clip named "morph"
  /// (the paper's Bézier morph, playback morph.h): how a mesh without clips (MakeHuman) is checked. When
  /// the character has a clip named "morph" of its own, the morph is "morph (key poses)" (CheckClip::morph
  /// tells them apart in any case).
  std::vector<std::string> poses;
  uint32_t morph_frames = 40;      ///< frames of the morph [Limit: >= 2 × \#poses; kConfig "--morph-frames N is too few …"]
  double fps = 30;                 ///< clip sampling rate [Units: frames/s] [Limit: (0, 1000]]: a clip of
                                   ///< duration d plays max(1, ceil(d · fps)) frames at t = d · f / frames,
                                   ///< the frames of `play/evaluate/view --clip C --frames N`
  /// Play each clip at its own key times instead (the sorted union of its channels' key times within
  /// [0, duration]; the morph keeps morph_frames): the poses the animator set, no more, no fewer.
  bool key_times = false;
  CheckPolicy policy;              ///< max_depth 0: 1 % of the height
  uint32_t max_frames = 100000;    ///< [Limit: > 0] a clip longer than this many frames is refused (kConfig)
  /// [opt] called after each frame: (clip index, clip count, frame, frames of the clip).
  std::function<void(size_t, size_t, uint32_t, uint32_t)> progress;
};

/// One event: contacts of one region pair over consecutive frames of one clip.
struct CheckEvent {
  CheckPair regions;           ///< (a, b), a <= b; −1 for a triangle of no region
  std::string name;            ///< "left_hand-head" (region names, runtime::RegionName)
  uint32_t first_frame = 0, last_frame = 0;  ///< inclusive; every frame between has a contact of the pair
  float first_time = 0, last_time = 0;       ///< [Units: s] playback::Animation::FrameTime
  uint32_t max_contacts = 0;   ///< most contacts of the pair in one of its frames
  float depth = 0;             ///< deepest ContactDepth::depth over the event [Units: model]
  uint32_t deepest_frame = 0;  ///< where it is
  float deepest_time = 0;      ///< [Units: s]
  uint32_t triangles[2] = {0, 0};      ///< the deepest contact's triangles (source indices; the pair's order)
  std::string joints[2];               ///< the joint weighing most on each triangle (node name; "" when unskinned)
  float point[3] = {0, 0, 0};          ///< the deepest contact's midpoint (centroids' mean) [Space: model]
  /// every contact of the pair at deepest_frame, (triangle of regions.first, of regions.second), source indices
  std::vector<std::pair<uint32_t, uint32_t>> contacts;
  double threshold = 0;                ///< CheckPolicy::Threshold [Units: model] (+inf: allowed)
  bool over_threshold = false;         ///< depth > threshold: the policy's verdict, whatever the baseline
  bool failed = false;                 ///< over_threshold and, with a baseline, a regression (fails the run)
  std::string baseline;                ///< with a baseline: "new", "deeper", "known"; else ""
};

/// One clip's result.
struct CheckClip {
  std::string name;             ///< clip name ("morph" for CheckOptions::poses; see there)
  bool morph = false;           ///< the morph through CheckOptions::poses, not a clip of the character
  float duration = 0;           ///< [Units: s]
  uint32_t frames = 0;          ///< frames played
  uint32_t frames_with_contacts = 0;
  uint64_t contacts = 0;        ///< over the frames (bind-pose intersections excluded)
  uint64_t bind_contacts = 0;   ///< contacts that intersect at bind pose too (no event)
  std::vector<CheckEvent> events;  ///< by first frame, then region pair
  std::vector<std::string> fixed;  ///< with a baseline: its failing (region pair) names this run does not fail
  double seconds = 0;           ///< wall-clock of the clip's frames (skinning + narrow phase)
  bool failed() const;          ///< some event failed
  float deepest() const;        ///< the deepest event's depth (0 when none) [Units: model]
};

/// Everything a check found.
struct CheckReport {
  std::string mesh_name;             ///< CheckOptions: for the reports
  double height = 0;                 ///< body height [Units: model] (bind pose along its up axis)
  double unit_scale_m = 0;           ///< metres per model unit, 0 when unknown
  double max_depth = 0;              ///< the default threshold used [Units: model]
  float crease = 0;                  ///< the asset's crease [Units: model]
  uint64_t positions_hash = 0;       ///< the mesh fingerprint (schema Fingerprint), what a baseline must match
  std::vector<CheckClip> clips;
  bool failed() const;               ///< some clip failed
};

/// Plays and judges as the header says. `mesh` is the character `asset` was baked from (fingerprint
/// checked) with its clips; `asset` must carry the crease rule (Asset.crease, bind_positions).
/// Errors: kConfig — the fingerprint differs, the asset has no crease rule ("re-bake it"), an unknown clip
/// (the message lists the clips), no clips and no poses ("nothing to check"), fps or a policy out of limits,
/// a clip over max_frames; kFormat — the asset predates the narrow phase; the poses' and skinning's errors;
/// kInternal — a runtime job failed. Cost per frame: one linear-blend skinning and one narrow-phase job
/// (~1.5 ms on 27k triangles, one core); Init ~1 s on 27k triangles; allocates; owns no threads.
import::Result<CheckReport> CheckClips(const runtime::AssetView& asset, const import::Mesh& mesh,
                                       const CheckOptions& options);

/// The deformed positions of frame `frame` of `clip` (a CheckClips result of the same `mesh` and `options`):
/// \#V×3 floats, model space, into `positions` — the frame an event's picture shows. Errors: kConfig (a frame
/// past the clip's, a clip the options do not name), the skinning's.
import::Status CheckFrame(const import::Mesh& mesh, const CheckOptions& options, const CheckClip& clip,
                          uint32_t frame, std::vector<float>* positions);

/// Marks regressions against `baseline` (CheckReportJson of an earlier run of the same character):
/// an event fails only when it failed its policy and its clip's region pair failed no event of the
/// baseline ("new") or failed one shallower by more than 5 % ("deeper"; else "known"); the baseline's
/// failing pairs that fail no event now go to CheckClip::fixed. The baseline's failing events are those
/// over their threshold ("over_threshold"; "failed" in reports that predate it), so a report written with a
/// baseline serves as the next one. Errors: kConfig — the baseline is of another character (its
/// "fingerprint" differs) or not a check report (a value of the wrong type: the message says which).
import::Status ApplyBaseline(const nlohmann::json& baseline, CheckReport* report);

/// The report as JSON: {"mesh", "fingerprint", "height", "max_depth", "crease", "failed", "clips": [{"name",
/// "duration", "frames", "contacts", "bind_contacts", "failed", "deepest", "fixed", "events": [{"regions",
/// "name", "first_frame", ... as CheckEvent, "over_threshold", "failed"}]}]}. Depths in model units and as
/// "depth_rel" (of the height).
nlohmann::json CheckReportJson(const CheckReport& report);

/// The report as JUnit XML (one `testsuite` "spherechain check", one `testcase` per clip, each failing
/// event a line of its `failure` text), the format CI reporters read.
std::string CheckReportJUnit(const CheckReport& report);

}  // namespace spherechain::evaluate
