// spherechain baker — import a character (paper §3 input; DESIGN.md "Vertex and triangle order").
#pragma once

#include <string>

#include "spherechain/baker/types.h"

namespace spherechain::baker {

struct ImportOptions {
  /// [opt] MakeHuman rig: a `.mhskel` path. Empty: for a MakeHuman `base.obj`, `default.mhskel` and
  /// `default_weights.mhw` beside the OBJ are used when present.
  std::string rig_path;
  /// [opt] `.mhw` weights path; empty: the `weights_file` named by the `.mhskel`, else
  /// `default_weights.mhw` beside it.
  std::string weights_path;
  /// OBJ group to keep when the file has groups named `body` (MakeHuman): "body". Empty keeps all.
  std::string obj_group = "body";
  /// Read animation clips (skins are always read when present).
  bool read_clips = true;
};

/// Reads a character file.
/// - `.gltf` / `.glb`: tinygltf. Primitives of every mesh node in the default scene, visited
///   depth-first in node order, concatenated in (node, primitive) order; node global transforms are
///   applied so the bind pose is assembled. Skin joints, inverse binds, JOINTS_0/WEIGHTS_0 and clips.
/// - every other extension: assimp, with no post-process that welds or reorders vertices
///   (triangulation only); meshes concatenated in depth-first node order, then mesh order in the node.
/// - MakeHuman `base.obj`: only group `obj_group` ("body"); its vertices are the OBJ's vertices in file
///   order restricted to those the group references (for base.obj: the first 13,380, order kept).
///   The rig (mhskel + mhw) becomes Mesh::skin.
/// Errors: kIo (missing / unreadable), kFormat (unsupported or corrupt), kInvalidMesh (no triangles,
/// NaN/Inf coordinates, index out of range). Nothing is written.
Result<Mesh> ImportMesh(const std::string& path, const ImportOptions& options = {}, Context* ctx = nullptr);

/// Checks a mesh the way every importer does: at least one triangle, finite coordinates, indices in
/// range. Returns kInvalidMesh with the first offending vertex / triangle named.
Status ValidateMesh(const Mesh& mesh);

}  // namespace spherechain::baker
