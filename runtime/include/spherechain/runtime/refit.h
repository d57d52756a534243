// spherechain runtime — sphere refit from pivot polygons (paper §5.1).
#pragma once

#include <cmath>
#include <cstdint>

#include "spherechain/runtime/asset.h"
#include "spherechain/runtime/formulas.h"
#include "spherechain/runtime/model.h"
#include "spherechain/runtime/status.h"

namespace spherechain::runtime {

/// How a sphere follows its four pivot polygons (§5.1). Let p0..p3 be the current centroids of the
/// sphere's pivot triangles (Asset.pivot_vertices, \#S×4×3 vertex indices; centroid = mean of the 3
/// vertices) and m their mean. In both modes the radius is
///   r = (bind radius / PivotFrame.mean_distance) · mean_k ‖c − p_k‖
/// — the paper's "average of the distances from the centre to the pivot polygons", scaled so the
/// bind pose gives back the bind radius.
enum class RefitMode : uint8_t {
  /// Exactly the paper: c = bind centre + mean displacement of the 4 pivot centroids
  ///   = m + PivotFrame.centroid_offset. Follows translation exactly, not rotation (a rotating limb
  ///   drags its spheres off-centre by |centroid_offset|·angle).
  kPaper = 0,
  /// Variant (default): c = o + R · PivotFrame.local_center with (o, R) = BuildPivotFrame(p0..p3).
  /// Exact under any rigid motion of the mesh (every sphere moves rigidly, radius unchanged); equal
  /// to kPaper when the pivots only translate. Falls back to kPaper for a sphere whose pivots became
  /// degenerate (BuildPivotFrame returns false).
  kPivotFrame = 1,
};

/// An orthonormal frame in model space: origin plus three unit axes (right-handed).
struct PivotFrameBasis {
  float origin[3];   ///< mean of p0..p3
  float axes[3][3];  ///< axes[0] = x, axes[1] = y, axes[2] = z = x × y (unit, orthogonal)
};

/// Builds the pivot frame of four pivot-polygon centroids p[0..3] (model space, source units):
///   o = (p0 + p1 + p2 + p3) / 4
///   x = normalize(p1 − p0)
///   w = (p2 + p3)/2 − (p0 + p1)/2 ;  y = normalize(w − (w·x) x)      (Gram–Schmidt)
///   z = x × y
/// Returns false (frame undefined, `*out` holds o and unspecified axes) when |p1 − p0| or the
/// residual |w − (w·x)x| is <= 1e-6 · (1 + max |p_k − o|) (collinear / coincident pivots).
/// The baker MUST fill PivotFrame.local_center with PivotFrameToLocal(BuildPivotFrame(bind p), c)
/// so runtime and baker agree bit for bit. The formula is formulas::PivotFrameLanes (formulas.inl), the
/// one the SIMD kernels and CUDA evaluate. Cost: ~60 flops, inline, no allocation.
inline bool BuildPivotFrame(const float p[4][3], PivotFrameBasis* out) {
  const float px[4] = {p[0][0], p[1][0], p[2][0], p[3][0]};
  const float py[4] = {p[0][1], p[1][1], p[2][1], p[3][1]};
  const float pz[4] = {p[0][2], p[1][2], p[2][2], p[3][2]};
  const bool ok = formulas::PivotFrameLanes<formulas::ScalarOps>(px, py, pz, out->origin, out->axes);
  return ok;
}

/// Model-space point `c` → coordinates in frame `f` (local = Rᵀ (c − o)). Baker: local_center.
inline void PivotFrameToLocal(const PivotFrameBasis& f, const float c[3], float local[3]) {
  const float d[3] = {c[0] - f.origin[0], c[1] - f.origin[1], c[2] - f.origin[2]};
  for (int a = 0; a < 3; ++a) local[a] = d[0] * f.axes[a][0] + d[1] * f.axes[a][1] + d[2] * f.axes[a][2];
}

/// Frame coordinates → model space (c = o + R local). What kPivotFrame refit computes
/// (formulas::FrameToModelLane).
inline void PivotFrameToModel(const PivotFrameBasis& f, const float local[3], float c[3]) {
  for (int k = 0; k < 3; ++k)
    c[k] = formulas::FrameToModelLane<formulas::ScalarOps>(f.origin, f.axes, local[0], local[1], local[2], k);
}

/// Mean distance from `c` to p[0..3]. Baker: PivotFrame.mean_distance = PivotMeanDistance(bind p,
/// bind centre); centroid_offset = bind centre − mean(p). Runtime radius uses the same formula
/// (formulas::PivotMeanDistanceLanes).
inline float PivotMeanDistance(const float p[4][3], const float c[3]) {
  const float px[4] = {p[0][0], p[1][0], p[2][0], p[3][0]};
  const float py[4] = {p[0][1], p[1][1], p[2][1], p[3][1]};
  const float pz[4] = {p[0][2], p[1][2], p[2][2], p[3][2]};
  return formulas::PivotMeanDistanceLanes<formulas::ScalarOps>(px, py, pz, c[0], c[1], c[2]);
}

/// Centroid of triangle (a, b, c): (a + b + c) / 3, computed as the runtime does it.
inline void TriangleCentroid(const float a[3], const float b[3], const float c[3], float out[3]) {
  formulas::TriangleCentroid3(a, b, c, out);
}

/// ozz-style job: refits every sphere of one character (`workspace`) to its deformed `positions` (§5.1),
/// with the per-asset data of `model`. Per sphere: the centroids p0..p3 of its 4 pivot triangles, then
/// formulas::RefitLanes (centre per RefitMode, radius = radius_scale · mean distance to the p_k).
/// Inputs: positions (\#V vertices, strided), mode, parallel_for [opt]. Output: the workspace's spheres
/// (Workspace::spheres(), SoA, same space/units as positions).
/// Cost: O(\#S) — 12 vertex reads + ~120 flops per sphere (SSE2, AVX or AVX-512 — 4, 8 or 16 spheres an
/// iteration, picked at Model::Init — all bit-identical to the scalar formulas); no allocation, no exceptions. With parallel_for set, spheres are split into ranges
/// (`parallel_grain` spheres per task index). Thread safety: one job per workspace at a time; the model
/// is only read.
struct RefitJob {
  PositionsView positions;                    ///< deformed vertex positions (see PositionsView)
  RefitMode mode = RefitMode::kPivotFrame;    ///< see RefitMode
  const Model* model = nullptr;               ///< initialised; read only (shared across characters)
  Workspace* workspace = nullptr;             ///< made for `model`; its spheres are overwritten
  ParallelFor parallel_for;                   ///< [opt]
  uint32_t parallel_grain = 64;               ///< [Limit: > 0] spheres per parallel task index

  /// True when Run() would not fail on arguments (does not read the positions).
  bool Validate() const { return Check() == Status::kOk; }
  /// The status Run() would return for bad arguments, or kOk: kErrorNullArgument (model, workspace or
  /// positions.data null), kErrorInvalidJob (model or workspace not initialised, unknown mode, grain 0),
  /// kErrorWorkspaceModel (workspace made for another model), kErrorAlignment (positions.data not 4-byte
  /// aligned), kErrorStride, kErrorVertexCount.
  Status Check() const;
  /// Runs the refit. Returns Check()'s error (spheres untouched) or kOk. Non-finite positions give
  /// non-finite spheres (which then never overlap); they are not checked per frame.
  Status Run() const;
};

/// Floats per joint matrix JointRefitJob reads: a 3×4 row-major affine matrix (rows r0, r1, r2 of
/// the 4×4 skinning matrix, each [m_r0 m_r1 m_r2 t_r]), so p' = M · (p, 1).
inline constexpr uint32_t kJointMatrixFloats = 12;

/// Column-major 4×4 (glTF, ozz, glm: element (row r, column c) at [4c + r]) → the 3×4 row-major layout
/// JointRefitJob reads. The bottom row (0 0 0 1 for an affine matrix) is dropped. Cost: 12 copies.
inline void JointMatrixFromColumnMajor(const float m[16], float out[kJointMatrixFloats]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) out[4 * r + c] = m[4 * c + r];
}

/// Refit from joint matrices, for games that skin on the GPU and hold no deformed vertex buffer on the
/// CPU. Every sphere's centre is skinned like a vertex (linear blend skinning of its bind centre):
///   c = Σ_k w_k · M_{j_k} · (c_bind, 1),   k = 0..3,
/// with (j_k, w_k) = Asset.sphere_joints / sphere_joint_weights (schema v3: per sphere the mean skin
/// weights of its surrounding region's vertices, four largest kept, summing to 1) and c_bind =
/// Asset.spheres' centre. Radius rule: r = bind radius (a rig's joints are rigid; scale in the joint
/// matrices moves centres but does not resize spheres). Tracking against the vertex refit (RefitJob,
/// kPivotFrame) on the real clips: docs/evaluation.md, "Refit from joint matrices".
///
/// Inputs: `joint_matrices` \#J × kJointMatrixFloats floats, packed: the skinning matrices
/// M_j = (joint j's current model-space transform) · (its inverse bind matrix), in the skin's joint
/// order (Asset.joint_count = \#J; glTF skin.joints, assimp bones, .mhskel bones) — the same matrices
/// that deform the vertices. Units: the asset's source units; output spheres in that model space.
/// Borrowed for Run(). The joint weights and bind spheres are the model's (copied out of the asset at
/// Model::Init: the asset bytes are not read). Output: the workspace's spheres (SoA), overwritten.
/// Order of operations (the contract the kernels keep bit for bit, tests/runtime/kernels_test.cpp): the
/// blend runs over influence 0 and then influences 1, 2, 3 while their weight is not 0 (the first zero
/// weight ends it), M = ((w0·M_j0 + w1·M_j1) + w2·M_j2) + w3·M_j3 per element; each centre coordinate is
/// (m_r0·bx + m_r1·by) + (m_r2·bz + m_r3), no FMA.
/// Cost: O(\#J) to check the matrices + O(\#S · influences) — ≤ 4 × 12 multiply-adds per sphere (SSE2,
/// AVX or AVX-512: a row or a whole matrix per vector; the model groups the spheres by influence count,
/// so no branch per sphere); serial, no allocation, no exceptions. Thread safety: one job per workspace
/// at a time.
struct JointRefitJob {
  const Model* model = nullptr;           ///< initialised; its centre joint weights (schema v3) are read
  Workspace* workspace = nullptr;         ///< made for `model`; its spheres are overwritten
  const float* joint_matrices = nullptr;  ///< \#J × 12 floats [Limit: 4-byte aligned]
  uint32_t joint_count = 0;               ///< \#J [Limit: == Model::joint_count(), else kErrorJointCount]

  /// True when Run() would not fail on arguments (does not read the matrices).
  bool Validate() const { return Check() == Status::kOk; }
  /// The status Run() would return for bad arguments, or kOk: kErrorNullArgument (model, workspace or
  /// joint_matrices null), kErrorInvalidJob (model or workspace not initialised), kErrorWorkspaceModel
  /// (workspace made for another model), kErrorMissingField (the asset holds no joint weights: baked
  /// from a mesh without a skin, or schema v1/v2 — re-bake), kErrorJointCount, kErrorAlignment
  /// (joint_matrices not 4-byte aligned).
  Status Check() const;
  /// Runs the refit. Returns Check()'s error, or kErrorNonFiniteJoints when one of the \#J matrices
  /// holds a NaN or an infinity — in both cases the spheres are untouched — or kOk.
  Status Run() const;
};

}  // namespace spherechain::runtime
