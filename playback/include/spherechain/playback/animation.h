// spherechain playback — animation playback on the CPU: sample a Clip (or apply a Pose) to get every
// node's local TRS, compose node globals, build the skinning matrices and deform Mesh::positions by
// linear blend skinning into a caller buffer. This is the reference deformation the `play` command
// and the tests feed to the runtime (a game uses its own skinning; the runtime only sees positions).
//
// Conventions (glTF's): quaternions are (x, y, z, w), unit length; matrices are 4×4 column-major
// (element (row r, column c) at [c·4 + r]); a node's local matrix is T·R·S; Global(n) =
// Global(parent(n))·Local(n). Skinning matrix of joint j: M_j = Global(node_j)·inverse_bind_j, mapping
// assembled bind-pose model space (Mesh::positions) to posed model space. Posed vertex:
// v' = Σ_k w_k · M_{j_k} · v over the vertex's influences (Skin CSR rows); a vertex with no influence
// stays at its bind position.
//
// Nothing here prints or throws; user-data problems (a malformed clip, a buffer of the wrong size)
// come back as Error (kConfig / kFormat / kInvalidMesh). Functions taking a std::vector output resize
// it and then reuse its capacity: a loop over frames allocates only on its first call.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "spherechain/playback/types.h"

namespace spherechain::playback {

/// Unit quaternion (x, y, z, w).
using Quat = std::array<float, 4>;
/// 4×4 matrix, column-major (element (r, c) at [c·4 + r]).
using Matrix4 = std::array<float, 16>;

/// A node's local transform (translation in source units, rotation, scale).
struct Transform {
  std::array<float, 3> translation{0, 0, 0};
  Quat rotation{0, 0, 0, 1};
  std::array<float, 3> scale{1, 1, 1};
};

// ---- quaternion helpers ------------------------------------------------------------------------

/// Rotation of `degrees` about `axis` (any non-zero length; normalised here). A zero axis gives the
/// identity. Right-handed: positive degrees turn counter-clockwise looking down the axis.
Quat QuatFromAxisAngle(const std::array<float, 3>& axis, float degrees);
/// Hamilton product a·b (apply b first, then a).
Quat QuatMultiply(const Quat& a, const Quat& b);
/// Conjugate (the inverse of a unit quaternion).
Quat QuatConjugate(const Quat& q);
/// q scaled to unit length; the identity when |q| is 0 or not finite.
Quat QuatNormalize(const Quat& q);
/// Spherical linear interpolation a → b, u ∈ [0, 1], along the shorter arc (b is negated when
/// a·b < 0) — what clip playback uses between keys.
Quat QuatSlerp(const Quat& a, const Quat& b, float u);
/// Spherical linear interpolation along the great arc from a to b *as given* (no hemisphere flip), so
/// that slerp(1, q², u) = q^(2u) for rotations of up to 180°: the primitive of the morph's de Casteljau
/// evaluation (morph.h). Falls back to a normalised lerp when a ≈ ±b.
Quat QuatSlerpArc(const Quat& a, const Quat& b, float u);
/// Rotates vector v by unit quaternion q.
std::array<float, 3> QuatRotate(const Quat& q, const std::array<float, 3>& v);

// ---- poses and clips → local transforms -----------------------------------------------------------

/// Every node's rest (bind-time) local transform, in Skin::nodes order (\#nodes).
void RestLocals(const Skin& skin, std::vector<Transform>* locals);

/// A static pose: local rotations that replace the rest rotation of some nodes (translation and scale
/// stay at rest). Built from readable pose files by LoadPose (morph.h), or by hand.
struct Pose {
  struct Rotation {
    int32_t node = -1;  ///< index into Skin::nodes
    Quat rotation{0, 0, 0, 1};  ///< the node's new local rotation (parent space), unit
  };
  std::string name;         ///< short id, e.g. "arms_crossed"
  std::string description;  ///< [opt] what the pose shows
  std::vector<Rotation> rotations;
};

/// Locals of `pose`: rest locals with the pose's rotations applied. Errors: kConfig when a rotation
/// names a node out of range (the message names the pose and the index).
Status PoseLocals(const Skin& skin, const Pose& pose, std::vector<Transform>* locals);

/// Checks a clip against a skin: channel nodes in range, key times finite and non-decreasing, values
/// of 3 (translation, scale) or 4 (rotation) floats a key, finite. Errors: kFormat naming the clip and
/// channel.
Status ValidateClip(const Skin& skin, const Clip& clip);

/// Samples `clip` at `time_s` [Units: s]: rest locals, overwritten by each channel's value at that time.
/// Linear channels interpolate translation/scale linearly and rotation by QuatSlerp (shorter arc);
/// step channels hold the last key at or before `time_s`. Before the first key the first value holds,
/// after the last key the last value holds (no wrapping: pass fmod(t, duration) for a loop).
/// Errors: ValidateClip's. O(\#nodes + Σ log \#keys); allocation only to grow `locals`.
Status SampleClip(const Skin& skin, const Clip& clip, float time_s, std::vector<Transform>* locals);

// ---- local transforms → skinning matrices → deformed positions --------------------------------------

/// T·R·S of a local transform.
Matrix4 TransformMatrix(const Transform& t);
/// Matrix product a·b (column-major).
Matrix4 MatrixMultiply(const Matrix4& a, const Matrix4& b);

/// Node globals (model space): Global(n) = Global(parent)·Local(n), roots Local(n). Each product in double,
/// stored as float. Errors: kConfig when `locals.size()` != \#nodes or a parent index is not < n.
Status GlobalMatrices(const Skin& skin, const std::vector<Transform>& locals, std::vector<Matrix4>* globals);

/// Skinning matrices M_j = Global(node_j)·inverse_bind_j (\#joints), bind model space → posed model
/// space; the identity for every joint at the rest pose. Errors: kConfig when `globals.size()` !=
/// \#nodes or a joint's node is out of range.
Status SkinningMatrices(const Skin& skin, const std::vector<Matrix4>& globals, std::vector<Matrix4>* matrices);

/// Linear blend skinning of `mesh.positions` (bind pose, \#V×3, source units) by `matrices` (\#joints)
/// into `out` (\#V×3 floats, caller-owned, `out_floats` = 3·\#V; may not alias mesh.positions).
/// Errors: kConfig when the mesh has no skin, `out` is null or `out_floats` != 3·\#V, `matrices` has
/// the wrong length, or the skin's weight rows do not match \#V / reference a joint out of range.
/// Cost: O(Σ influences); no allocation; thread-safe.
Status SkinPositions(const Mesh& mesh, const std::vector<Matrix4>& matrices, float* out, size_t out_floats);

/// Reusable scratch of one character's playback (locals, globals, skinning matrices): keep one per
/// character so per-frame evaluation allocates nothing after the first frame. Not thread-safe.
struct SkinningScratch {
  std::vector<Transform> locals;
  std::vector<Matrix4> globals;
  std::vector<Matrix4> matrices;
};

/// `locals` → globals → skinning matrices → SkinPositions(out). Errors: those of the three steps.
Status SkinLocals(const Mesh& mesh, const std::vector<Transform>& locals, SkinningScratch* scratch, float* out,
                  size_t out_floats);

/// The whole chain for a clip: SampleClip(t) → SkinLocals into `out` (\#V×3). `mesh.skin` required
/// (kConfig otherwise). Errors: those of SampleClip and SkinLocals.
Status SkinClip(const Mesh& mesh, const Clip& clip, float time_s, SkinningScratch* scratch, float* out,
                size_t out_floats);

/// The whole chain for a static pose: PoseLocals → SkinLocals into `out` (\#V×3).
Status SkinPose(const Mesh& mesh, const Pose& pose, SkinningScratch* scratch, float* out, size_t out_floats);

/// Index of the node named `name` in `skin.nodes`, or -1.
int32_t FindNode(const Skin& skin, const std::string& name);

}  // namespace spherechain::playback
