// spherechain playback — the animation a tool plays over a character: one of its skinned clips sampled
// uniformly, or the paper's Bézier morph through key poses (morph.h, §5.1/§6). What `play`, `evaluate`,
// `view`, `export-debug --clip/--morph` and Play() (play.h) step through, frame by frame.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "spherechain/playback/animation.h"
#include "spherechain/playback/morph.h"
#include "spherechain/playback/types.h"

namespace spherechain::playback {

/// What to play (the CLI's --clip / --morph / --poses-dir / --frames).
/// The most frames an animation plays (AnimationRequest::frames; the CLI's --frames, Python's `frames`): an hour
/// at 277 fps. Each frame keeps a row in the reports (evaluate's holds its spheres and contact sets), so a
/// mistyped count ends here instead of in an allocation failure.
inline constexpr uint32_t kMaxFrames = 1'000'000;

struct AnimationRequest {
  std::string mesh_name;           ///< the character file, for messages
  std::string clip;                ///< [opt] clip name; empty: the first clip, or the morph when there is none
  std::vector<std::string> morph;  ///< [opt] key poses: .json files, names of poses in `poses_dir`, or folders
  bool use_morph = false;          ///< play the morph even when the mesh has clips (`morph` empty: every pose in `poses_dir`)
  std::string poses_dir;           ///< [opt] folder of the character's default key poses (see DefaultPoseCharacter)
  uint32_t frames = 40;            ///< [Limit: 1..kMaxFrames; >= 2 × \#keys for the morph] frames to play
  std::string frames_option = "--frames";  ///< how the caller's users set `frames`, for its errors
};

/// The folder name a character's default key poses live under (`data/poses/<name>`): "makehuman" for a
/// MakeHuman rig (Skin::source "mhskel"), else the stem of `mesh_name`.
std::string DefaultPoseCharacter(const Mesh& mesh, const std::string& mesh_name);

/// The folder of `character`'s default key poses: the first `<d>/poses/<character>` of `data_dirs` (each a
/// data folder — the installed share/spherechain/, the source tree's data/, a Python package's data/ — in
/// the caller's order of preference) that is a folder, lexically normalised; empty when none is.
/// Cost: one stat per candidate.
std::string FindPosesDir(const std::string& character, const std::vector<std::string>& data_dirs);

/// The files a morph may read besides the mesh, for import::OutputsClash: each of `morph` (pose files, names,
/// folders), every file in those that are folders, and every file in `poses_dir` (where pose names and the
/// default key poses are looked up). Lists folders; reads no file.
std::vector<std::string> PoseInputFiles(const std::vector<std::string>& morph, const std::string& poses_dir);

/// The chosen animation. Frame f (< frames) of a clip samples t = duration · f / frames [s] (no wrap:
/// the last frame is one step before the end), or times[f] when `times` is given; the morph's frames follow
/// MorphFrameAt.
/// Holds a pointer into the mesh's clips: the Mesh passed to OpenAnimation must outlive it (and not
/// move). Copyable; every method is const and thread-safe given distinct scratch.
struct Animation {
  const Clip* clip = nullptr;  ///< points into Mesh::clips when playing a clip, else null
  std::vector<Pose> poses;     ///< the morph's key poses (empty for a clip)
  std::string poses_from;      ///< the folder they came from, or "--morph"
  uint32_t frames = 0;         ///< frames to play (> 0)
  /// [opt] A clip's own sample times [Units: s] (ascending, in [0, duration]; `frames` == times.size()):
  /// frame f samples times[f] (`check --key-times`: a clip at its key times). Empty: uniform sampling.
  std::vector<float> times;

  /// Frame rate the morph's frames are shown at in timed outputs (animated glTF) [Units: frames/s].
  static constexpr float kMorphFps = 20.0f;

  /// One line: "clip 'Walk' (2.0 s)" or "morph through 8 key poses from DIR".
  std::string Describe() const;
  /// When frame `f` plays [Units: s]: the clip's sample time (times[f] when given), or f / kMorphFps for
  /// the morph. Strictly increasing in f (for a clip of duration > 0).
  float FrameTime(uint32_t f) const;
  /// Frame `f`'s label: "t=0.533s" (clip) or "arms_crossed t=0.500" (morph key and Bézier parameter).
  std::string FrameLabel(uint32_t f) const;
  /// Every node's local transform at frame `f` (\#nodes of `skin`): SampleClip, or MorphLocals of the
  /// frame's key. Errors: those of SampleClip / MorphFrameAt / MorphLocals. Allocates only to grow `locals`.
  Status FrameLocals(const Skin& skin, uint32_t f, std::vector<Transform>* locals) const;
  /// Deforms frame `f` of `mesh` (bind \#V×3 → posed \#V×3, model space, source units) into `out`
  /// (resized to 3·\#V) by linear blend skinning (SkinClip / SkinMorphFrame; `scratch->matrices` then hold
  /// the frame's skinning matrices), and names it in `label` [opt]. Errors: those of the skinning.
  Status Frame(const Mesh& mesh, uint32_t f, SkinningScratch* scratch, std::vector<float>* out,
               std::string* label = nullptr) const;
};

/// Picks the animation `request` asks for on `mesh` [Limit: mesh.skin present]: the named clip (checked
/// by ValidateClip), else (no `morph`, not `use_morph`) the first clip, else the morph through the poses of
/// `request.morph` (each a file, a pose name in `poses_dir`, or a folder of *.json), or through every
/// pose in `poses_dir`. Errors (kConfig unless the pose loader says otherwise; the messages name the
/// CLI's options): clip and morph both given, no skin, unknown clip (the message lists the clips), no
/// clips and no poses folder, a pose file that does not parse (LoadPose / LoadPoseFolder), frames outside
/// [1, kMaxFrames], frames < 2 × \#keys for the morph. Cost: reads the pose files.
Result<Animation> OpenAnimation(const Mesh& mesh, const AnimationRequest& request);

}  // namespace spherechain::playback
