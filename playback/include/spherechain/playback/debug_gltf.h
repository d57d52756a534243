// spherechain playback — the animated debug glTF: the character and its refit spheres moving through an
// animation, playable in any glTF 2.0 viewer (three.js editor, Blender, gltf-viewer, Babylon sandbox).
//
// Layout of the file (.gltf, buffers embedded as data URIs):
//   nodes 0..#N−1   the skeleton, Skin::nodes in order (same names, parents, rest TRS);
//   node  #N        "static": an identity joint that vertices without skin influence follow;
//   node  #N+1      "mesh": the character at its bind pose (Mesh::positions), coloured by region (COLOR_0,
//                   the static export's colours), skinned by skin 0 (joints = Skin::joints' nodes + "static",
//                   inverse binds = SkinJoint::inverse_bind; JOINTS_k/WEIGHTS_k, k = 0..⌈max influences / 4⌉ − 1,
//                   every influence, largest first: a viewer reading only JOINTS_0 (three.js) gets the 4 strongest) — glTF skinning Σ w·Global(joint)·IBM·v is exactly
//                   the reference deformation of animation.h, so a viewer shows the frames play() measures;
//   node  #N+2      "spheres", children #N+3.. "sphere_<s>": one per asset sphere, a unit sphere mesh of its
//                   region's colour (35 % opaque) with translation = centre and scale = radius.
//   animation 0     named after the clip (or "morph"): one shared input of the frame times (s, strictly
//                   increasing: Animation::FrameTime, or f / Animation::kMorphFps for a clip of zero length),
//                   LINEAR samplers; channels translation/rotation/scale for every skeleton node (its sampled
//                   locals: exact at the frames, slerp between), then translation and scale for every sphere
//                   (the runtime refit of that frame's skinned positions: what Play() reports).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "spherechain/playback/animation_source.h"
#include "spherechain/playback/types.h"
#include "spherechain/runtime/asset.h"
#include "spherechain/runtime/refit.h"

namespace spherechain::playback {

/// What ExportAnimatedGltf wrote.
struct AnimatedGltfStats {
  uint32_t frames = 0;            ///< keyframes per channel (= Animation::frames)
  uint32_t skeleton_nodes = 0;    ///< \#N (3 channels each)
  uint32_t spheres = 0;           ///< \#S (2 channels each)
  uint32_t channels = 0;          ///< 3·\#N + 2·\#S
  uint32_t max_influences = 0;    ///< most joints on one vertex (> 4: JOINTS_1/WEIGHTS_1 ... written)
  size_t bytes = 0;               ///< size of the file written
  std::vector<float> first_frame_spheres;  ///< frame 0's refit spheres, \#S×4 (x, y, z, r), source units
};

/// Writes the animated debug glTF above to `out_path` (.glb: binary, GltfBinary), atomically (nothing is left there on failure).
/// `mesh`: the character the asset was baked from [Limit: vertex/triangle counts equal the asset's,
/// mesh.skin present]; `asset`: a loaded view; `animation`: from OpenAnimation on this mesh;
/// `refit`: the runtime refit mode for the spheres (kPivotFrame is play's default).
/// Errors: kConfig (counts differ, no skin, a joint node out of range), kFormat / kConfig from the
/// animation's frames, kInternal (runtime refit failed: the status is named; a non-finite sphere),
/// kIo (folder missing, write failed). Cost: one skinning + refit per frame, O(frames·(\#V + \#N + \#S))
/// memory for the file; allocates; thread-safe for distinct outputs.
Status ExportAnimatedGltf(const Mesh& mesh, const runtime::AssetView& asset, const Animation& animation,
                          const std::string& out_path, runtime::RefitMode refit = runtime::RefitMode::kPivotFrame,
                          AnimatedGltfStats* stats = nullptr);

}  // namespace spherechain::playback
