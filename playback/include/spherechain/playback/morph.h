// spherechain playback — the paper's morphing animation (§5.1: "Some poses are taken as basis of the
// frames and a quadric Bézier interpolation is applied between such poses"; §6: 40 frames).
//
// Design: the animation visits the key poses one after the other; each visit is an excursion
// rest → key → rest in rotation space, per bone, as ONE quadratic Bézier curve evaluated by de
// Casteljau with slerp, with end points P0 = P2 = rest and control point C = rest·δ², where
// δ = rest⁻¹·key is the bone's rotation away from rest. Then B(½) = key exactly and, in closed form,
// B(t) = rest·δ^(4t(1−t)): the bone eases out of rest, reaches the key at t = ½ with zero angular
// velocity, and eases back. Bones the key does not rotate stay at rest. (Works for key rotations of
// up to 180° away from rest.)
//
// Frame schedule: `frame_count` frames over `key_count` keys; key k gets n_k = frame_count / key_count
// frames (the first frame_count % key_count keys one more). Within its n_k frames, frame i samples
//   t = i / n_k          when n_k is even,
//   t = i / (n_k − 1)    when n_k is odd,
// so i = 0 is the rest pose (t = 0) and the mid frame i = n_k / 2 (integer division) samples t = ½,
// the key pose exactly. With the paper's 40 frames and 5 keys: 8 frames a key, keys at frames
// 4, 12, 20, 28, 36; rest at frames 0, 8, 16, 24, 32.
//
// Key poses are readable JSON files (data/poses/<character>/*.json):
//   {"name": "arms_crossed", "description": "...",
//    "rotations": {"upperarm01.L": {"axis": [x, y, z], "degrees": d}, ...}}
// Each entry rotates that bone by `degrees` about `axis`, expressed in the bone's parent frame at rest
// (for a MakeHuman rig, whose rest rotations are identity, that is the character's frame: +X the
// character's left, +Y up, +Z front), applied on top of the rest rotation: local = q(axis, deg)·rest.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "spherechain/playback/animation.h"
#include "spherechain/playback/types.h"

namespace spherechain::playback {

/// Where a frame of the morph lies: which key pose's excursion and the Bézier parameter in it.
struct MorphFrame {
  uint32_t key = 0;  ///< index into the key poses
  /// Bézier parameter: i/n for an excursion of an even number n of frames, i/(n − 1) for an odd one (so that
  /// its mid frame is ½, the key), whose last frame is then t = 1 — the rest pose, as the next excursion's
  /// first frame is. ½ at the key's mid frame.
  float t = 0.0f;
};

/// The schedule above. Errors: kConfig when key_count == 0, frame_count < 2·key_count (each
/// excursion needs its rest frame and its key frame) or frame >= frame_count.
Result<MorphFrame> MorphFrameAt(uint32_t frame, uint32_t frame_count, uint32_t key_count);

/// The frame at which key `key` is reached exactly (t = ½). Same limits as MorphFrameAt; returns
/// frame_count when they are not met.
uint32_t MorphKeyFrame(uint32_t key, uint32_t frame_count, uint32_t key_count);

/// Quadratic Bézier in rotation space, by de Casteljau with QuatSlerpArc:
/// B(t) = slerp(slerp(p0, c, t), slerp(c, p2, t), t). With p0 = p2 = 1 and c = q²: B(t) = q^(4t(1−t)).
Quat QuadraticBezierRotation(const Quat& p0, const Quat& c, const Quat& p2, float t);

/// Locals of the morph at parameter `t` of the excursion to `key`: for every node the key rotates,
/// B(t) with P0 = P2 = rest rotation and C = rest·δ² (δ = rest⁻¹·key); all other nodes at rest.
/// t = 0 gives the rest locals exactly, t = ½ the key's rotations (up to float rounding).
/// Errors: PoseLocals' (a rotation's node out of range).
Status MorphLocals(const Skin& skin, const Pose& key, float t, std::vector<Transform>* locals);

/// Frame `frame` of the morph through `keys` → deformed positions `out` (\#V×3, source units, model
/// space), via MorphFrameAt, MorphLocals and SkinLocals. Errors: those, and kConfig when `keys` is
/// empty or the mesh has no skin.
Status SkinMorphFrame(const Mesh& mesh, const std::vector<Pose>& keys, uint32_t frame, uint32_t frame_count,
                      SkinningScratch* scratch, float* out, size_t out_floats);

/// Parses a key pose (format above) against `skin`. `origin` names the source in messages (a path).
/// Errors (kConfig, the message names origin, bone and field): not JSON / not an object; "rotations"
/// missing or not an object; a bone not in the skin (the message suggests names that contain it);
/// "axis" not 3 numbers finite as 32-bit floats, or of zero length; "degrees" not a finite number or outside
/// [-180, 180]; "name" not a string. "name" defaults to `origin`'s stem.
Result<Pose> ParsePose(std::string_view json_text, const Skin& skin, const std::string& origin);

/// Reads and parses one pose file. Errors: kIo (unreadable), ParsePose's.
Result<Pose> LoadPose(const std::string& path, const Skin& skin);

/// Every `*.json` in `folder`, in file-name order, parsed against `skin`. Errors: kIo (not a folder),
/// kConfig (no pose files; the first file that fails to parse).
Result<std::vector<Pose>> LoadPoseFolder(const std::string& folder, const Skin& skin);

}  // namespace spherechain::playback
