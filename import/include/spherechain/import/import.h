// spherechain import — import a character (paper §3 input; DESIGN.md "Vertex and triangle order").
#pragma once

#include <string>

#include "spherechain/import/types.h"

namespace spherechain::import {

/// Input policy (docs/guide.md "Bad input"): the baker reads untrusted files, so it bounds what it reads.
/// Largest input file [bytes]; bigger files are refused (kFormat) before any parser sees them.
inline constexpr uint64_t kMaxInputBytes = uint64_t{512} << 20;
/// Most vertices / triangles an imported mesh may have (2^26); more is refused (kInvalidMesh).
inline constexpr uint32_t kMaxInputVertices = uint32_t{1} << 26;
inline constexpr uint32_t kMaxInputTriangles = uint32_t{1} << 26;
/// The formats the baker reads (lower-case extensions), and through what: gltf/glb → tinygltf,
/// obj → our own reader, fbx/dae/zae (Collada archive)/x/blend/3ds/ply/stl and the game-character
/// formats iqm/smd/md5mesh/ms3d/b3d → assimp with only those importers registered (content sniffing
/// can never reach another assimp importer) and reading files only inside the input's folder, each at
/// most kMaxInputBytes (a file a format refers to — an MD5 animation, a Collada archive's entries —
/// outside that folder, through ".." or a symbolic link, is refused). Everything else: kFormat.
inline constexpr const char* kSupportedExtensions[] = {"gltf", "glb",   "obj", "fbx",     "dae",  "zae",
                                                       "x",    "blend", "3ds", "ply",     "stl",  "iqm",
                                                       "smd",  "md5mesh", "ms3d", "b3d"};

/// Quality findings on an imported mesh that the baker keeps (they are legal input) but reports.
struct MeshIssues {
  /// Triangles with a repeated vertex index or zero area (cross product exactly 0). Kept: indices
  /// must stay the source's; pivot polygons never use them (regions.cpp skips negligible areas).
  uint32_t degenerate_triangles = 0;
  /// Undirected edges used by more than two triangles (non-manifold). Reported only.
  uint32_t non_manifold_edges = 0;
};

/// Counts the MeshIssues of a mesh that passed ValidateMesh. O(\#T log \#T), allocates.
MeshIssues InspectMesh(const Mesh& mesh);

/// Which vertex buffer an assimp-format character is read as (docs/guide.md "The vertex contract"); the asset's
/// indices refer to it and records it (Asset.vertex_contract), and the runtime must be fed that buffer.
/// - kJoined: what engines' importers give — assimp with aiProcess_Triangulate |
///   aiProcess_JoinIdenticalVertices (vertices whose every attribute assimp read — position, normal,
///   UVs, colours, bone weights — is identical become one; triangle order kept). The default.
/// - kSource: assimp with aiProcess_Triangulate only: the importer's own buffer (for `.x`, one vertex
///   per face corner).
/// - kAuto: kJoined for assimp formats; for glTF / OBJ the file's own buffer (nothing else applies).
/// glTF and OBJ buffers are already the engine's: kJoined / kSource are a no-op there (a warning through
/// the Context says so) and the mesh records "file".
enum class VertexContract : uint8_t { kAuto, kJoined, kSource };
/// "auto", "joined", "source".
const char* ToString(VertexContract c);

struct ImportOptions {
  /// Vertex contract for assimp formats (see VertexContract). [opt] default kAuto = joined.
  VertexContract vertices = VertexContract::kAuto;
  /// [opt] MakeHuman rig: a `.mhskel` path. Empty: for a MakeHuman `base.obj`, `default.mhskel` and
  /// `default_weights.mhw` beside the OBJ are used when present.
  std::string rig_path;
  /// [opt] `.mhw` weights path; empty: the `weights_file` named by the `.mhskel`, else
  /// `default_weights.mhw` beside it.
  std::string weights_path;
  /// OBJ group to keep when the file is a MakeHuman base mesh (a `# basemesh` comment, or `rig_path` given)
  /// and has a group of that name: "body" (MakeHuman's helper geometry is left out). Any other OBJ keeps
  /// every group. Empty keeps all.
  std::string obj_group = "body";
  /// Read animation clips (skins are always read when present).
  bool read_clips = true;
  /// Most vertices / triangles the imported mesh may have; more is refused (kInvalidMesh) while importing,
  /// before the memory for them is taken, however the file reaches them (a glTF mesh instanced by many nodes,
  /// an accessor without a bufferView, assimp's instanced meshes). Clips may hold at most 3 × max_vertices
  /// key values in all. [Limit: 1..kMaxInputVertices / kMaxInputTriangles] [opt] default: those caps.
  /// A pipeline (or a fuzzer) that wants a smaller bound sets it here.
  uint32_t max_vertices = kMaxInputVertices;
  uint32_t max_triangles = kMaxInputTriangles;
  /// assimp's parsers run in a child process (fork), so that one that crashes or never returns on a hostile
  /// file (fuzzing found a PLY that loops) fails the import with kFormat instead of ending or hanging the
  /// caller. The child gets `assimp_seconds` of wall-clock time [Units: s] [Limit: > 0] and then is killed,
  /// and `assimp_memory_bytes` of address space [Limit: 0 = none; not applied under AddressSanitizer].
  /// false: assimp runs in this process (a fork saved; its crash is then the caller's). Cost of true: a fork
  /// and one copy of the mesh through a pipe. Linux only: elsewhere assimp runs in this process whatever
  /// this says. [opt] default true, 120 s, 16 GiB.
  bool isolate_assimp = true;
  double assimp_seconds = 120.0;
  uint64_t assimp_memory_bytes = uint64_t{16} << 30;
};

/// Reads a character file.
/// - `.gltf` / `.glb`: tinygltf. Primitives of every mesh node in the default scene, visited
///   depth-first in node order, concatenated in (node, primitive) order; node global transforms are
///   applied so the bind pose is assembled, after the morph targets' POSITION at their default weights (the
///   node's, else the mesh's; animated morph weights are not read). Skin joints, inverse binds,
///   JOINTS_0/WEIGHTS_0 (and _1) and clips.
/// - every other extension: assimp, triangulated, and with `options.vertices` joined (the default)
///   aiProcess_JoinIdenticalVertices, nothing else that welds or reorders; meshes concatenated in
///   depth-first node order, then mesh order in the node. Mesh::source_vertex_count and
///   joined_vertex_count hold \#V under both contracts (one read, the join applied after counting).
///   Cost: the join is O(\#V log \#V) in assimp. Mesh::up_axis: +Y (assimp's convention) unless the
///   file declares another (assimp's "UpAxis" scene metadata, e.g. FBX); a `.blend` is +Z (Blender's
///   world axis, which assimp's Blender reader keeps).
/// - OBJ: every group, the file's vertices in file order. A MakeHuman base mesh (a `# basemesh` comment, or
///   `rig_path` given): only group `obj_group` ("body"); its vertices are the OBJ's vertices in file order
///   restricted to those the group references (for base.obj: the first 13,380, order kept).
///   The rig (mhskel + mhw) becomes Mesh::skin.
/// Policy: only kSupportedExtensions; files over kMaxInputBytes and meshes over options.max_vertices /
/// max_triangles (default kMaxInputVertices / kMaxInputTriangles) are refused; a glTF whose JSON nests
/// deeper than 64 levels is refused before it is parsed; glTF may read only files inside the input's own
/// folder (URIs with `..` or absolute paths that leave it are refused) and never decodes images; a MakeHuman
/// skeleton's `weights_file` must lie in the skeleton's folder; degenerate triangles and non-manifold edges
/// are kept and reported through `ctx` (InspectMesh).
/// Files: each file read — the input; glTF's external buffers and images; whatever assimp's importer opened;
/// the MakeHuman .mhskel and .mhw — is added to ctx->files_read once read (Context::RecordFileRead), also when
/// the import then fails.
/// Clips keep the file's names, made unique: a name the file repeats gets " #2", " #3"… (a warning through
/// `ctx` says so), so that a clip is found by its name.
/// Errors: kIo (missing / unreadable), kFormat (unsupported, too large or corrupt), kInvalidMesh (no
/// triangles, too many vertices / triangles, NaN/Inf coordinates, index out of range), kConfig (a MakeHuman
/// rig or weights path given for a file that is not an OBJ). Nothing is written.
Result<Mesh> ImportMesh(const std::string& path, const ImportOptions& options = {}, Context* ctx = nullptr);

/// True when ImportMesh reads `path` through assimp (a supported extension other than glTF, GLB, OBJ):
/// the files the vertex contract applies to. By extension only; the file is not opened.
bool ReadThroughAssimp(const std::string& path);

/// Checks a mesh the way every importer does: at least one triangle, finite coordinates, indices in
/// range. Returns kInvalidMesh with the first offending vertex / triangle named.
Status ValidateMesh(const Mesh& mesh);

}  // namespace spherechain::import
