// spherechain import — internals shared by the importers (import.cpp dispatches to them).
//
// Not installed; include only from import/src/import*.cpp.
#pragma once

#include <Eigen/Geometry>

#include <signal.h>

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "spherechain/import/import.h"
#include "spherechain/import/types.h"

namespace spherechain::import::detail {

/// The signals that end a process by request (Ctrl-C, a kill, a closed terminal, Ctrl-\): the CLI removes its
/// output temporaries on them (RemoveTemporariesOnSignal), OutputFiles blocks them while it changes its list, and
/// the assimp child is forked with them blocked.
inline constexpr int kEndingSignals[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT};
/// kEndingSignals as a signal set.
sigset_t EndingSignalSet();

/// glTF / GLB through tinygltf. `path` exists and is a regular file (checked by ImportMesh).
/// Errors: kIo (unreadable), kFormat (not glTF, broken accessors, ...), kInvalidMesh (no triangles).
Result<Mesh> ImportGltf(const std::string& path, const ImportOptions& options, Context* ctx);

/// Every other extension assimp knows, triangulation only (no weld, no reorder).
/// Errors: kFormat (unsupported or corrupt), kInvalidMesh.
Result<Mesh> ImportAssimp(const std::string& path, const ImportOptions& options, Context* ctx);

/// Wavefront OBJ through our own line reader, keeping the file's `v` order (assimp splits OBJ
/// vertices per face corner, which would break the vertex-order contract). Keeps only group
/// `options.obj_group` when the file has such a group; reads the MakeHuman rig (mhskel + mhw) when
/// one is given or found beside a MakeHuman base mesh.
/// Errors: kIo, kFormat (unparsable line, broken rig JSON), kInvalidMesh (index 0 / out of range).
Result<Mesh> ImportObj(const std::string& path, const ImportOptions& options, Context* ctx);

/// An importer ImportInChild can run: ImportAssimp.
using ChildImporter = Result<Mesh> (*)(const std::string& path, const ImportOptions& options, Context* ctx);

/// Runs `import(path, options, …)` in a child process (fork) and returns its result, its log lines and files
/// read replayed into `ctx` (import_child.cpp). The child gets options.assimp_seconds of wall-clock time (then
/// it is killed) and, unless built with AddressSanitizer, options.assimp_memory_bytes of address space. A
/// child that is killed, crashes or exits without an answer is kFormat ("assimp did not finish reading it
/// within 120 s", "the assimp importer's process died reading it (signal 11 …)"); kInternal only when no
/// process can be started. Cost: a fork, and the mesh copied once through a pipe.
Result<Mesh> ImportInChild(const std::string& path, const ImportOptions& options, Context* ctx, ChildImporter import);

/// In the child of ImportInChild, says what the importer does now ('R': the third-party parser reads,
/// 'C': our code converts its scene), so a death is reported as the one or the other; a no-op elsewhere.
void ChildPhase(char phase);

/// True when `file` (relative paths: to the current directory, as fopen reads them), with "..",
/// "." and symbolic links resolved, lies inside `folder` (resolved the same way). What the assimp
/// importers may open besides the input itself (import.h kSupportedExtensions).
bool InsideFolder(const std::string& folder, const std::string& file);

/// "path: message" — every importer error names the file first.
inline Error FileError(Error::Code code, const std::string& path, const std::string& message) {
  return MakeError(code, path + ": " + message);
}

/// kInvalidMesh naming the limit when a mesh of `vertices` / `triangles` would exceed options.max_vertices /
/// max_triangles (and never more than kMaxInputVertices / kMaxInputTriangles). The importers call it before
/// they grow the mesh, so a small file that multiplies its data (instances, zero accessors) is refused
/// before the memory is taken.
Status CheckMeshBudget(const std::string& path, uint64_t vertices, uint64_t triangles, const ImportOptions& options);

/// Column-major float copy of a 4×4 affine matrix (SkinJoint::inverse_bind layout).
inline std::array<float, 16> ToColumnMajor(const Eigen::Matrix4d& m) {
  std::array<float, 16> out{};
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) out[static_cast<size_t>(c * 4 + r)] = static_cast<float>(m(r, c));
  return out;
}

/// Local matrix T·R·S of a Node's rest transform.
inline Eigen::Matrix4d NodeLocalMatrix(const Node& n) {
  Eigen::Affine3d a = Eigen::Affine3d::Identity();
  a.translate(Eigen::Vector3d(n.translation[0], n.translation[1], n.translation[2]));
  a.rotate(Eigen::Quaterniond(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]).normalized());
  a.scale(Eigen::Vector3d(n.scale[0], n.scale[1], n.scale[2]));
  return a.matrix();
}

/// Decomposes an affine matrix (no shear expected) into the Node's translation, rotation
/// (unit quaternion x, y, z, w) and scale. A negative determinant flips the X scale.
inline void SetNodeTrs(const Eigen::Matrix4d& m, Node& n) {
  const Eigen::Matrix3d l = m.topLeftCorner<3, 3>();
  Eigen::Vector3d s(l.col(0).norm(), l.col(1).norm(), l.col(2).norm());
  if (l.determinant() < 0) s.x() = -s.x();
  Eigen::Matrix3d r = l;
  for (int i = 0; i < 3; ++i)
    if (s[i] != 0.0) r.col(i) /= s[i];
  Eigen::Quaterniond q(r);
  q.normalize();
  n.translation = {static_cast<float>(m(0, 3)), static_cast<float>(m(1, 3)), static_cast<float>(m(2, 3))};
  n.rotation = {static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()),
                static_cast<float>(q.w())};
  n.scale = {static_cast<float>(s.x()), static_cast<float>(s.y()), static_cast<float>(s.z())};
}

/// One vertex's influences while importing: (joint index into Skin::joints, raw weight).
using Influences = std::vector<std::pair<uint32_t, float>>;

/// Fills skin.weight_offsets / weight_joints / weights from per-vertex influence lists (#V lists):
/// weights of the same joint are summed, non-positive / non-finite ones dropped, the rest sorted by
/// joint index and normalised to sum 1. A vertex with no influence keeps an empty row.
void PackWeights(std::vector<Influences>& per_vertex, Skin& skin);

/// The bind transform B of a skinned mesh: the matrix that places its vertices in assembled model
/// space at bind time. Skinning ignores the mesh node's own transform (glTF 2.0 §3.7.3.3; DirectX
/// `.x` frames of skinned meshes likewise), so B is read from the bones: B = Global_rest(joint) ·
/// inverse_bind_source(joint), which is the same matrix for every joint when the rest pose is the
/// bind pose. `joint_binds` holds that product per joint that carries weight. When they agree (within
/// 1e-4 relative) their first is returned and `*consistent` is true; otherwise (rest pose ≠ bind
/// pose, or no weighted joint) `node_global` is returned and `*consistent` is false.
Eigen::Matrix4d SkinnedMeshBind(const std::vector<Eigen::Matrix4d>& joint_binds, const Eigen::Matrix4d& node_global,
                                bool* consistent);

/// Lower-case extension without the dot ("gltf", "obj"); empty when there is none.
std::string LowerExtension(const std::string& path);

}  // namespace spherechain::import::detail
