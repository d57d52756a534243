// spherechain import — import of every non-glTF, non-OBJ format through assimp.
//
// Post-processing: aiProcess_Triangulate, then with the joined vertex contract (the default, import.h
// VertexContract) aiProcess_JoinIdenticalVertices — the buffer a game importing the file with those
// flags gets; with the source contract nothing welds, splits or sorts. Order (import.h): nodes depth-first from the root, children in file order;
// for each node its meshes in node order (a mesh referenced by several nodes appears once per
// instance). Positions are the assembled bind pose (node global × vertex). Skin::nodes is the whole
// node hierarchy, parents-first, with rest local TRS decomposed from aiNode::mTransformation.
// One SkinJoint per (mesh instance, aiBone): node = the bone's node, inverse_bind = mOffsetMatrix · B⁻¹
// (B: the mesh's bind transform above), so Σ w · Global_rest(node) · inverse_bind · p = p at rest. Meshes without bones in a skinned scene follow their node rigidly.
// Clips: aiAnimation, times ticks / mTicksPerSecond (25 when 0).
#include <assimp/BaseImporter.h>
#include <assimp/DefaultIOSystem.h>
#include <assimp/Importer.hpp>
#include <assimp/importerdesc.h>
#include <assimp/anim.h>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include "import_internal.h"

namespace spherechain::import::detail {
namespace {

Eigen::Matrix4d ToEigen(const aiMatrix4x4& m) {
  Eigen::Matrix4d e;
  e << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
  return e;
}

std::string NodeName(const aiNode* n, size_t slot) {
  return n->mName.length ? std::string(n->mName.C_Str()) : "node" + std::to_string(slot);
}

/// Leaves registered in `importer` only the assimp importers of the formats the baker allows through
/// assimp (kSupportedExtensions minus glTF and OBJ, which have their own readers), so that assimp's
/// content sniffing can never hand a file to any other of its ~60 parsers. The removed importers are
/// deleted here (Importer only deletes those still registered).
void KeepAllowedImporters(Assimp::Importer& importer) {
  static constexpr const char* kAssimpFormats[] = {"fbx", "dae", "zae",     "x",    "blend", "3ds", "ply",
                                                   "stl", "iqm", "smd", "md5mesh", "ms3d", "b3d"};
  std::vector<Assimp::BaseImporter*> drop;
  for (size_t i = 0; i < importer.GetImporterCount(); ++i) {
    const aiImporterDesc* desc = importer.GetImporterInfo(i);
    bool keep = false;
    if (desc && desc->mFileExtensions) {
      std::istringstream words(desc->mFileExtensions);
      for (std::string w; words >> w;)
        for (const char* f : kAssimpFormats) keep = keep || w == f;
    }
    if (!keep) drop.push_back(importer.GetImporter(i));
  }
  for (Assimp::BaseImporter* imp : drop) {
    if (imp && importer.UnregisterLoader(imp) == aiReturn_SUCCESS) delete imp;
  }
}

/// assimp's file access confined to the input's folder: every Open / Exists of a file outside it
/// (after resolving "..", "." and symbolic links), or of a file over kMaxInputBytes, or for writing,
/// fails and is recorded, so the import either goes on without it or fails with the reason. Every file
/// it does open (the input, and what its format refers to: an MD5 animation, a texture, ...) is recorded
/// in the Context (files_read).
class ConfinedIOSystem : public Assimp::DefaultIOSystem {
 public:
  ConfinedIOSystem(std::string folder, Context* ctx) : folder_(std::move(folder)), ctx_(ctx) {}
  bool Exists(const char* file) const override { return file && Allowed(file, nullptr) && DefaultIOSystem::Exists(file); }
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    if (!file) return nullptr;
    std::string why;
    if (mode && std::string(mode).find_first_of("wa+") != std::string::npos) why = "opened for writing";
    if (!why.empty() || !Allowed(file, &why)) {
      refused_.push_back(std::string(file) + " (" + why + ")");
      return nullptr;
    }
    Assimp::IOStream* stream = DefaultIOSystem::Open(file, mode);
    if (stream && ctx_) ctx_->RecordFileRead(file);
    return stream;
  }
  const std::vector<std::string>& refused() const { return refused_; }

 private:
  bool Allowed(const std::string& file, std::string* why) const {
    if (!InsideFolder(folder_, file)) {
      if (why) *why = "outside the input's folder " + folder_;
      return false;
    }
    std::error_code ec;
    const uintmax_t bytes = std::filesystem::file_size(file, ec);
    if (!ec && bytes > kMaxInputBytes) {
      if (why) *why = std::to_string(bytes) + " bytes, over the input limit";
      return false;
    }
    return true;
  }
  std::string folder_;
  Context* ctx_;  // [opt]
  std::vector<std::string> refused_;
};

/// #V (and, in `faces`, the faces) of the concatenated mesh: every mesh instance of every node (a mesh
/// referenced by several nodes counts once per instance), as ImportAssimp concatenates them.
uint64_t InstancedVertexCount(const aiScene* scene, uint64_t* faces = nullptr) {
  uint64_t n = 0, f = 0;
  std::vector<const aiNode*> stack{scene->mRootNode};
  while (!stack.empty()) {
    const aiNode* an = stack.back();
    stack.pop_back();
    for (unsigned k = 0; k < an->mNumMeshes; ++k) {
      if (an->mMeshes[k] >= scene->mNumMeshes) continue;
      n += scene->mMeshes[an->mMeshes[k]]->mNumVertices;
      f += scene->mMeshes[an->mMeshes[k]]->mNumFaces;
    }
    for (unsigned c = 0; c < an->mNumChildren; ++c) stack.push_back(an->mChildren[c]);
  }
  if (faces) *faces = f;
  return n;
}

}  // namespace

bool InsideFolder(const std::string& folder, const std::string& file) {
  std::error_code ec;
  const std::filesystem::path f = std::filesystem::weakly_canonical(std::filesystem::absolute(file, ec), ec);
  if (ec) return false;
  const std::filesystem::path d = std::filesystem::weakly_canonical(std::filesystem::absolute(folder, ec), ec);
  if (ec) return false;
  auto fi = f.begin();
  for (auto di = d.begin(); di != d.end(); ++di, ++fi) {
    if (di->empty()) continue;  // a trailing separator
    if (fi == f.end() || *fi != *di) return false;
  }
  return true;
}

Result<Mesh> ImportAssimp(const std::string& path, const ImportOptions& options, Context* ctx) {
  Assimp::Importer importer;
  KeepAllowedImporters(importer);
  const std::string ext = LowerExtension(path);
  if (ext.empty() || !importer.IsExtensionSupported("." + ext))
    return FileError(Error::Code::kFormat, path,
                     "unsupported file extension '" + ext +
                         "' (the baker reads glTF/GLB, FBX, DAE/ZAE, X, OBJ, BLEND, 3DS, PLY, STL, IQM, SMD, MD5MESH, "
                         "MS3D and B3D)");
  // No skeleton placeholder meshes (BVH etc.): only real geometry is imported.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_NO_SKELETON_MESHES, true);
  std::error_code ec;
  auto* io = new ConfinedIOSystem(std::filesystem::weakly_canonical(std::filesystem::absolute(path, ec), ec)
                                      .parent_path()
                                      .string(),
                                  ctx);
  importer.SetIOHandler(io);  // the importer owns it from here
  const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate);
  std::string refused;
  for (const std::string& r : io->refused()) refused += (refused.empty() ? "" : "; ") + r;
  if (!scene || !scene->mRootNode)
    return FileError(Error::Code::kFormat, path,
                     std::string("assimp cannot read it: ") + importer.GetErrorString() +
                         (refused.empty() ? "" : " (refused to read: " + refused + ")"));
  if (!refused.empty() && ctx) ctx->Warn("import: " + path + ": refused to read " + refused);
  if (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)
    return FileError(Error::Code::kFormat, path, "assimp read an incomplete scene");
  // The vertex contract (import.h VertexContract): #V is counted before the join and after it, so the
  // asset can tell a game which contract a mismatching buffer looks like.
  const bool join = options.vertices != VertexContract::kSource;
  uint64_t source_faces = 0;
  const uint64_t source_vertices = InstancedVertexCount(scene, &source_faces);
  // Nodes may instance a mesh many times: the concatenated mesh is checked against the limits before it is built.
  if (Status s = CheckMeshBudget(path, source_vertices, source_faces, options); !s.ok()) return s.error();
  if (join) {
    scene = importer.ApplyPostProcessing(aiProcess_JoinIdenticalVertices);
    if (!scene || !scene->mRootNode)
      return FileError(Error::Code::kFormat, path,
                       std::string("assimp cannot join identical vertices: ") + importer.GetErrorString());
  }
  ChildPhase('C');  // assimp is done reading: our conversion of its scene

  Mesh mesh;
  mesh.source_format = ext;
  mesh.vertex_contract = join ? "joined" : "source";
  mesh.source_vertex_count = static_cast<uint32_t>(std::min<uint64_t>(source_vertices, UINT32_MAX));
  // assimp's convention is +Y up; overridden below when the file says otherwise. Blender's world is +Z
  // up and assimp's Blender reader keeps its coordinates (no "UpAxis" metadata): a standing body in a
  // .blend file stands along +Z (assimp-testmodels' BLEND/HUMAN.blend).
  mesh.up_axis = ext == "blend" ? UpAxis::kZ : UpAxis::kY;
  if (scene->mMetaData) {
    int32_t up = -1, sign = 1;
    if (scene->mMetaData->Get("UpAxis", up)) {
      scene->mMetaData->Get("UpAxisSign", sign);
      if (up == 0) mesh.up_axis = UpAxis::kX;
      if (up == 1) mesh.up_axis = UpAxis::kY;
      if (up == 2) mesh.up_axis = UpAxis::kZ;
      if (sign < 0 && ctx) ctx->Warn("import: " + path + ": file declares a negative up axis");
    }
    // FBX: centimetres per unit (assimp stores it as float; some writers as double).
    double scale_cm = 0.0;
    float scale_cm_f = 0.0f;
    if (scene->mMetaData->Get("UnitScaleFactor", scale_cm_f)) scale_cm = scale_cm_f;
    else scene->mMetaData->Get("UnitScaleFactor", scale_cm);
    if (std::isfinite(scale_cm) && scale_cm > 0.0) {
      mesh.unit_scale_m = static_cast<float>(scale_cm * 0.01);
      mesh.units = scale_cm == 1.0 ? "cm" : scale_cm == 100.0 ? "m" : scale_cm == 10.0 ? "dm" : "unknown";
    }
  }

  // Node table, parents-first (depth-first, children in file order), with globals.
  std::vector<const aiNode*> order;
  std::vector<Eigen::Matrix4d> global;
  std::vector<Node> nodes;
  std::unordered_map<std::string, int32_t> by_name;
  std::vector<std::pair<const aiNode*, int32_t>> stack{{scene->mRootNode, -1}};
  while (!stack.empty()) {
    const auto [an, parent] = stack.back();
    stack.pop_back();
    const int32_t slot = static_cast<int32_t>(nodes.size());
    const Eigen::Matrix4d local = ToEigen(an->mTransformation);
    global.push_back(parent < 0 ? local : Eigen::Matrix4d(global[static_cast<size_t>(parent)] * local));
    Node node;
    node.name = NodeName(an, static_cast<size_t>(slot));
    node.parent = parent;
    SetNodeTrs(local, node);
    by_name.emplace(node.name, slot);  // first wins on duplicate names
    nodes.push_back(node);
    order.push_back(an);
    for (unsigned c = an->mNumChildren; c-- > 0;) stack.emplace_back(an->mChildren[c], slot);
  }

  bool any_bones = false;
  for (const aiNode* an : order)
    for (unsigned k = 0; k < an->mNumMeshes; ++k)
      if (an->mMeshes[k] < scene->mNumMeshes && scene->mMeshes[an->mMeshes[k]]->HasBones()) any_bones = true;

  Skin skin;
  skin.source = "assimp";
  std::vector<Influences> influences;
  for (size_t slot = 0; slot < order.size(); ++slot) {
    const aiNode* an = order[slot];
    for (unsigned k = 0; k < an->mNumMeshes; ++k) {
      if (an->mMeshes[k] >= scene->mNumMeshes) return FileError(Error::Code::kFormat, path, "node references a missing mesh");
      const aiMesh* am = scene->mMeshes[an->mMeshes[k]];
      const std::string mname = am->mName.length ? std::string(am->mName.C_Str()) : NodeName(an, slot);
      // Bones first: a skinned mesh is placed by its bones (B), an unskinned one by its node (M).
      std::vector<int32_t> bone_node(am->mNumBones, -1);
      std::vector<Eigen::Matrix4d> joint_binds;
      for (unsigned b = 0; b < am->mNumBones; ++b) {
        const aiBone* bone = am->mBones[b];
        auto it = by_name.find(bone->mName.C_Str());
        if (it == by_name.end())
          return FileError(Error::Code::kFormat, path, "mesh '" + mname + "' bone '" + bone->mName.C_Str() + "' has no node");
        bone_node[b] = it->second;
        if (bone->mNumWeights > 0)
          joint_binds.push_back(global[static_cast<size_t>(it->second)] * ToEigen(bone->mOffsetMatrix));
      }
      Eigen::Matrix4d M = global[slot];
      if (am->HasBones()) {
        bool consistent = false;
        M = SkinnedMeshBind(joint_binds, global[slot], &consistent);
        if (!consistent && ctx)
          ctx->Warn("import: " + path + ": mesh '" + mname +
                    "': rest pose differs from the bind pose; placed by its node transform");
      }
      const Eigen::Matrix4d M_inv = M.inverse();
      MeshPart part;
      part.name = mname;
      part.first_vertex = mesh.vertex_count();
      part.vertex_count = am->mNumVertices;
      part.first_triangle = mesh.triangle_count();
      for (unsigned v = 0; v < am->mNumVertices; ++v) {
        const aiVector3D& q = am->mVertices[v];
        const Eigen::Vector4d p = M * Eigen::Vector4d(q.x, q.y, q.z, 1.0);
        mesh.positions.insert(mesh.positions.end(),
                              {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())});
      }
      unsigned skipped = 0;
      for (unsigned f = 0; f < am->mNumFaces; ++f) {
        const aiFace& face = am->mFaces[f];
        if (face.mNumIndices != 3) {
          ++skipped;  // points and lines
          continue;
        }
        for (unsigned c = 0; c < 3; ++c) {
          if (face.mIndices[c] >= am->mNumVertices)
            return FileError(Error::Code::kInvalidMesh, path,
                             "mesh '" + mname + "' face " + std::to_string(f) + " references vertex " +
                                 std::to_string(face.mIndices[c]) + " of " + std::to_string(am->mNumVertices));
          mesh.indices.push_back(part.first_vertex + face.mIndices[c]);
        }
      }
      if (skipped && ctx) ctx->Info("import: " + path + ": mesh '" + mname + "': " + std::to_string(skipped) + " non-triangle faces skipped");
      part.triangle_count = mesh.triangle_count() - part.first_triangle;
      mesh.parts.push_back(part);

      if (!any_bones) continue;
      influences.resize(mesh.vertex_count());
      if (am->HasBones()) {
        for (unsigned b = 0; b < am->mNumBones; ++b) {
          const aiBone* bone = am->mBones[b];
          SkinJoint j;
          j.node = bone_node[b];
          j.inverse_bind = ToColumnMajor(ToEigen(bone->mOffsetMatrix) * M_inv);
          const uint32_t ji = static_cast<uint32_t>(skin.joints.size());
          skin.joints.push_back(j);
          for (unsigned w = 0; w < bone->mNumWeights; ++w) {
            const aiVertexWeight& vw = bone->mWeights[w];
            if (vw.mVertexId >= am->mNumVertices)
              return FileError(Error::Code::kInvalidMesh, path,
                               "bone '" + std::string(bone->mName.C_Str()) + "' weights vertex " +
                                   std::to_string(vw.mVertexId) + " of " + std::to_string(am->mNumVertices));
            influences[part.first_vertex + vw.mVertexId].emplace_back(ji, vw.mWeight);
          }
        }
      } else {
        SkinJoint j;  // rigid part: follows its own node
        j.node = static_cast<int32_t>(slot);
        j.inverse_bind = ToColumnMajor(M_inv);
        const uint32_t ji = static_cast<uint32_t>(skin.joints.size());
        skin.joints.push_back(j);
        for (unsigned v = 0; v < am->mNumVertices; ++v) influences[part.first_vertex + v].emplace_back(ji, 1.0f);
      }
    }
  }
  if (mesh.indices.empty()) return FileError(Error::Code::kInvalidMesh, path, "no triangles");
  if (any_bones) {
    influences.resize(mesh.vertex_count());
    skin.nodes = nodes;
    PackWeights(influences, skin);
    mesh.skin = std::move(skin);
  }

  if (options.read_clips && mesh.skin) {
    for (unsigned a = 0; a < scene->mNumAnimations; ++a) {
      const aiAnimation* aa = scene->mAnimations[a];
      const double tps = aa->mTicksPerSecond > 0.0 ? aa->mTicksPerSecond : 25.0;
      Clip clip;
      clip.name = aa->mName.length ? std::string(aa->mName.C_Str()) : "animation" + std::to_string(a);
      clip.duration_s = static_cast<float>(aa->mDuration / tps);
      for (unsigned c = 0; c < aa->mNumChannels; ++c) {
        const aiNodeAnim* na = aa->mChannels[c];
        auto it = by_name.find(na->mNodeName.C_Str());
        if (it == by_name.end()) {
          if (ctx) ctx->Warn("import: " + path + ": clip '" + clip.name + "' animates unknown node '" + na->mNodeName.C_Str() + "'");
          continue;
        }
        if (na->mNumPositionKeys) {
          Channel ch;
          ch.node = it->second;
          ch.path = Channel::Path::kTranslation;
          for (unsigned k = 0; k < na->mNumPositionKeys; ++k) {
            const aiVectorKey& key = na->mPositionKeys[k];
            ch.times.push_back(static_cast<float>(key.mTime / tps));
            ch.values.insert(ch.values.end(), {key.mValue.x, key.mValue.y, key.mValue.z});
          }
          clip.channels.push_back(std::move(ch));
        }
        if (na->mNumRotationKeys) {
          Channel ch;
          ch.node = it->second;
          ch.path = Channel::Path::kRotation;
          for (unsigned k = 0; k < na->mNumRotationKeys; ++k) {
            const aiQuatKey& key = na->mRotationKeys[k];
            ch.times.push_back(static_cast<float>(key.mTime / tps));
            ch.values.insert(ch.values.end(), {key.mValue.x, key.mValue.y, key.mValue.z, key.mValue.w});
          }
          clip.channels.push_back(std::move(ch));
        }
        if (na->mNumScalingKeys) {
          Channel ch;
          ch.node = it->second;
          ch.path = Channel::Path::kScale;
          for (unsigned k = 0; k < na->mNumScalingKeys; ++k) {
            const aiVectorKey& key = na->mScalingKeys[k];
            ch.times.push_back(static_cast<float>(key.mTime / tps));
            ch.values.insert(ch.values.end(), {key.mValue.x, key.mValue.y, key.mValue.z});
          }
          clip.channels.push_back(std::move(ch));
        }
      }
      for (const Channel& ch : clip.channels)
        if (!ch.times.empty()) clip.duration_s = std::max(clip.duration_s, ch.times.back());
      mesh.clips.push_back(std::move(clip));
    }
  }
  if (join) {
    mesh.joined_vertex_count = mesh.vertex_count();
  } else {  // the clips are read: joining the scene now only counts what the joined contract gives
    ChildPhase('R');
    scene = importer.ApplyPostProcessing(aiProcess_JoinIdenticalVertices);
    ChildPhase('C');
    mesh.joined_vertex_count =
        scene ? static_cast<uint32_t>(std::min<uint64_t>(InstancedVertexCount(scene), UINT32_MAX)) : 0;
  }
  return mesh;
}

}  // namespace spherechain::import::detail
