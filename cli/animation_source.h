// spherechain CLI — the animation a command plays (a skinned clip or the paper's morph through key
// poses), shared by `play` and `evaluate`, and the mesh ↔ asset fingerprint check.
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "spherechain/import/file_io.h"
#include "spherechain/playback/animation_source.h"
#include "spherechain/runtime/asset.h"

namespace spherechain::cli {

/// A .sphc file in aligned memory with its verified view (import::LoadedAsset).
using import::LoadedAsset;

/// Reads and verifies `path` (import::LoadAssetFile). On failure `*error` says what and where (file, status).
bool LoadAssetFile(const std::string& path, LoadedAsset* out, std::string* error);

/// What the user asked for on the command line.
struct AnimationArgs {
  std::string mesh;                ///< the character file (for messages and the poses folder's name)
  std::string clip;                ///< --clip NAME (empty: the first clip, or the morph when none)
  std::vector<std::string> morph;  ///< --morph POSES... (files, names in the poses folder, folders)
  std::string poses_dir;           ///< --poses-dir
  uint32_t frames = 40;            ///< --frames
  CLI::Option* morph_option = nullptr;  ///< set by AddAnimationOptions: `--morph` given (with or without poses)

  /// True when --morph was given, also bare (the default key poses even when the mesh has clips).
  bool morph_requested() const { return !morph.empty() || (morph_option && morph_option->count() > 0); }
};

/// The files in the default key-pose folders a run on `mesh` may read (FindPosesDir), for OutputsClash. Before
/// the import the character is not known, so both folders it may name: `makehuman` (a MakeHuman rig) and the
/// file's stem. Lists folders; reads no file.
std::vector<std::string> DefaultPoseFiles(const std::string& mesh);

/// The files the animation may read besides the mesh, for OutputsClash: the --morph arguments, every file in
/// those that are folders, and every file in --poses-dir, or without it in the default folders
/// (DefaultPoseFiles), where pose names, a bare --morph and a mesh without clips look.
std::vector<std::string> PoseInputs(const AnimationArgs& a);

/// Registers the options every animating command shares on `sub` — ASSET (positional, an existing
/// file), --mesh (required, existing), --clip, --morph, --poses-dir, --frames and --rig — into `asset`,
/// `rig` and `anim` (--mesh fills anim->mesh). The pointers must outlive the parse.
void AddAnimationOptions(CLI::App* sub, std::string* asset, std::string* rig, AnimationArgs* anim);

/// Folder of the character's default key poses, the first that exists of: `explicit_dir` (--poses-dir); the
/// installed data, <executable's folder>/SPHERECHAIN_BIN_TO_DATA/poses/<character> (bin/ → share/spherechain/);
/// the source tree's data/poses/<character> (a build tree, compiled-in path); data/poses/<character> walking up
/// from the current directory. Empty when none exists.
std::string FindPosesDir(const std::string& character, const std::string& explicit_dir);

/// The chosen animation (playback::Animation: a clip sampled uniformly, or the Bézier morph through key poses).
using AnimationSource = playback::Animation;

/// The playback request of the command line's options: --clip, --morph (a bare --morph: the default poses),
/// --frames, and the poses folder (--poses-dir, else the character's default key poses found by FindPosesDir).
playback::AnimationRequest MakeAnimationRequest(const import::Mesh& mesh, const AnimationArgs& args);

/// Picks the animation (playback::OpenAnimation, with the default poses folder found by FindPosesDir):
/// unknown clip, missing poses, too few frames: false with `*error` saying what. `mesh` must have a skin.
bool OpenAnimation(const import::Mesh& mesh, const AnimationArgs& args, AnimationSource* out, std::string* error);

/// Loads the asset (verified) and imports the character it was baked from (`rig`: MakeHuman .mhskel,
/// empty = default), then checks their fingerprints (playback::OpenCharacter). False with `*error`.
bool OpenAssetAndMesh(const std::string& asset_path, const std::string& mesh_path, const std::string& rig,
                      LoadedAsset* asset, import::Mesh* mesh, std::string* error);

}  // namespace spherechain::cli
