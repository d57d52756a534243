// spherechain import — glTF 2.0 / GLB import through tinygltf (images are never decoded).
//
// Order (import.h): the default scene's nodes depth-first in node order; for each node with a mesh,
// its triangle primitives in primitive order. Positions are the assembled bind pose: node global ×
// POSITION for unskinned meshes; for skinned ones B × POSITION with B = Global(joint)·IBM(joint)
// (the same for all joints when rest = bind; skinning ignores the mesh node), else the node global. Skin::nodes is every node of the scene, parents-first (the depth-first
// order), with rest local TRS. For a skinned primitive on mesh node M with skin S, one SkinJoint per
// S.joints[k] with inverse_bind = IBM_k · B⁻¹, so that Σ w · Global(joint) · inverse_bind · p
// reproduces the assembled positions at rest. Unskinned primitives in a skinned file follow their
// own node rigidly (one joint on node M, inverse_bind = M⁻¹, weight 1).
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "import_internal.h"

namespace spherechain::import::detail {
namespace {

/// tinygltf image callback that decodes nothing: the baker needs geometry only.
bool SkipImage(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

// Filesystem callbacks (the Debian tinygltf build sets none by default). Reads only; never writes;
// confined to the input's own folder (`user_data`: its canonical path): a buffer URI with `..`, an
// absolute path or a symlink that leads outside it is refused, as is a file over kMaxInputBytes. Every file
// read (the .gltf/.glb itself, external buffers and images) is recorded in the Context (files_read).
struct FsRoot {
  std::filesystem::path root;  // canonical folder of the input file
  std::string refused;         // the first path refused for leaving it (for the error message)
  Context* ctx = nullptr;      // [opt] records the files read
};
bool InsideRoot(const std::string& filename, void* user_data) {
  auto* fs_root = static_cast<FsRoot*>(user_data);
  if (!fs_root) return false;
  std::error_code ec;
  const std::filesystem::path p = std::filesystem::weakly_canonical(filename, ec);
  bool inside = !ec;
  auto r = fs_root->root.begin(), q = p.begin();
  for (; inside && r != fs_root->root.end(); ++r, ++q)
    if (q == p.end() || *q != *r) inside = false;
  if (!inside && fs_root->refused.empty()) fs_root->refused = filename;
  return inside;
}
bool FsFileExists(const std::string& abs_filename, void* user_data) {
  std::error_code ec;
  return InsideRoot(abs_filename, user_data) && std::filesystem::is_regular_file(abs_filename, ec);
}
std::string FsExpandFilePath(const std::string& filepath, void*) { return filepath; }
bool FsReadWholeFile(std::vector<unsigned char>* out, std::string* err, const std::string& filepath, void* user_data) {
  if (!InsideRoot(filepath, user_data)) {
    if (err) *err += "refused to read " + filepath + ": outside the input file's folder\n";
    return false;
  }
  std::error_code ec;
  const uintmax_t bytes = std::filesystem::file_size(filepath, ec);
  if (!ec && bytes > kMaxInputBytes) {
    if (err) *err += "refused to read " + filepath + ": over the 512 MiB input limit\n";
    return false;
  }
  std::ifstream in(filepath, std::ios::binary);
  if (!in) {
    if (err) *err += "cannot open " + filepath + "\n";
    return false;
  }
  out->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (in.bad()) {
    if (err) *err += "cannot read " + filepath + "\n";
    return false;
  }
  if (auto* fs_root = static_cast<FsRoot*>(user_data); fs_root && fs_root->ctx) fs_root->ctx->RecordFileRead(filepath);
  return true;
}
bool FsWriteWholeFile(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "the importer never writes files\n";
  return false;
}

/// Deepest JSON nesting a glTF may have. tinygltf turns every "extras" value into its own Value type by
/// recursion, so a file of a few kilobytes of "[[[[…" would overflow the stack inside it (found by
/// fuzz_import_gltf; tinygltf is Debian's header, not ours to patch): such a file is refused before it is parsed.
/// A real glTF nests about six levels (root, meshes, a mesh, primitives, a primitive, attributes) plus its extras.
constexpr size_t kMaxJsonDepth = 64;

/// Deepest nesting of arrays and objects in `json` (brackets inside strings do not count); stops counting
/// past kMaxJsonDepth. Not a validator: broken JSON is left to the parser.
size_t JsonDepth(std::string_view json) {
  size_t depth = 0, deepest = 0;
  bool in_string = false;
  for (size_t i = 0; i < json.size() && deepest <= kMaxJsonDepth; ++i) {
    const char c = json[i];
    if (in_string) {
      if (c == '\\') ++i;  // the escaped character
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return deepest;
}

/// The JSON chunk of a GLB (glTF 2.0 §4.4: a 12-byte header, then chunk 0 = length, "JSON", data); empty when
/// the bytes are not laid out so (tinygltf then refuses them).
std::string_view GlbJsonChunk(const std::vector<unsigned char>& glb) {
  if (glb.size() < 20 || std::memcmp(glb.data() + 16, "JSON", 4) != 0) return {};
  uint32_t length = 0;
  std::memcpy(&length, glb.data() + 12, 4);
  return {reinterpret_cast<const char*>(glb.data()) + 20, std::min<size_t>(length, glb.size() - 20)};
}

int ComponentCount(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT4: return 16;
    default: return 0;
  }
}

int ComponentSize(int ct) {
  switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
  }
}

/// One component as double; normalised integers map to [0,1] / [-1,1] (glTF 2.0 §3.11).
double ReadComponent(const unsigned char* p, int ct, bool normalized) {
  switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
      float f;
      std::memcpy(&f, p, 4);
      return f;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      uint32_t v;
      std::memcpy(&v, p, 4);
      return normalized ? v / 4294967295.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      uint16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      int16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0 : p[0];
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      const auto v = static_cast<int8_t>(p[0]);
      return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    default: return 0.0;
  }
}

bool IsUnsignedInteger(int ct) {
  return ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE || ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
         ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
}

/// Reads accessor `index` as doubles, #count × components, honouring byteStride, normalisation and
/// sparse substitution. Every offset, length and count comes from the file, so each is checked, without
/// overflow, before anything is read or allocated: a view inside its buffer, every element inside its view,
/// sparse indices unsigned integers below count. An accessor without a bufferView (zeros, maybe with sparse
/// values over them) may hold at most `max_values` values: it takes memory the file does not pay for.
/// kFormat on any inconsistency.
Result<std::vector<double>> ReadAccessor(const tinygltf::Model& model, int index, const std::string& path,
                                         const std::string& what, size_t max_values) {
  auto fail = [&](const std::string& m) { return FileError(Error::Code::kFormat, path, what + ": " + m); };
  if (index < 0 || index >= static_cast<int>(model.accessors.size())) return fail("accessor index out of range");
  const tinygltf::Accessor& acc = model.accessors[static_cast<size_t>(index)];
  const size_t nc = static_cast<size_t>(ComponentCount(acc.type));
  const size_t cs = static_cast<size_t>(ComponentSize(acc.componentType));
  if (nc == 0 || cs == 0) return fail("unsupported accessor type");
  const size_t count = acc.count;
  const size_t elem = nc * cs;

  // Where n elements of `elem_bytes` at `offset` in view `view_index` start: checked against the view and its buffer.
  struct Span {
    const unsigned char* base = nullptr;
    size_t stride = 0;
  };
  auto locate = [&](int view_index, size_t offset, size_t n, size_t elem_bytes) -> Result<Span> {
    if (view_index < 0 || view_index >= static_cast<int>(model.bufferViews.size()))
      return fail("bufferView index out of range");
    const tinygltf::BufferView& view = model.bufferViews[static_cast<size_t>(view_index)];
    if (view.buffer < 0 || view.buffer >= static_cast<int>(model.buffers.size())) return fail("buffer index out of range");
    const std::vector<unsigned char>& data = model.buffers[static_cast<size_t>(view.buffer)].data;
    const size_t stride = view.byteStride ? view.byteStride : elem_bytes;
    if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
      return fail("bufferView runs past its buffer");
    if (n > 0 && (offset > view.byteLength || elem_bytes > view.byteLength - offset ||
                  n - 1 > (view.byteLength - offset - elem_bytes) / stride))
      return fail(std::to_string(n) + " elements run past their bufferView");
    return Span{data.data() + view.byteOffset + offset, stride};
  };

  Span dense;
  if (acc.bufferView >= 0) {
    Result<Span> at = locate(acc.bufferView, acc.byteOffset, count, elem);
    if (!at.ok()) return at.error();
    dense = at.value();
  } else if (count > max_values / nc) {
    return fail(std::to_string(count) + " elements without a bufferView, over the limit of " +
                std::to_string(max_values / nc));
  }
  std::vector<double> out(count * nc, 0.0);
  if (dense.base)
    for (size_t i = 0; i < count; ++i)
      for (size_t c = 0; c < nc; ++c)
        out[i * nc + c] = ReadComponent(dense.base + i * dense.stride + c * cs, acc.componentType, acc.normalized);

  if (acc.sparse.isSparse) {
    const auto& sp = acc.sparse;
    if (sp.count < 0 || static_cast<size_t>(sp.count) > count) return fail("sparse count out of range");
    if (sp.indices.byteOffset < 0 || sp.values.byteOffset < 0) return fail("negative sparse byteOffset");
    if (!IsUnsignedInteger(sp.indices.componentType)) return fail("sparse indices are not unsigned integers");
    const size_t n = static_cast<size_t>(sp.count);
    const size_t ics = static_cast<size_t>(ComponentSize(sp.indices.componentType));
    Result<Span> idx_at = locate(sp.indices.bufferView, static_cast<size_t>(sp.indices.byteOffset), n, ics);
    if (!idx_at.ok()) return idx_at.error();
    Result<Span> val_at = locate(sp.values.bufferView, static_cast<size_t>(sp.values.byteOffset), n, elem);
    if (!val_at.ok()) return val_at.error();
    for (size_t k = 0; k < n; ++k) {
      const double i = ReadComponent(idx_at->base + k * idx_at->stride, sp.indices.componentType, false);
      if (!(i < static_cast<double>(count))) return fail("sparse index out of range");
      for (size_t c = 0; c < nc; ++c)
        out[static_cast<size_t>(i) * nc + c] = ReadComponent(val_at->base + k * val_at->stride + c * cs, acc.componentType,
                                                             acc.normalized);
    }
  }
  return out;
}

/// Skin influence set `set` of `prim` (JOINTS_set and WEIGHTS_set, glTF 2.0 §3.7.3): false when either is
/// absent (the sets end there), else both read into `joints`, `weights` (ReadAccessor's errors, `what` naming
/// the primitive).
Result<bool> ReadInfluenceSet(const tinygltf::Model& model, const tinygltf::Primitive& prim, int set, const std::string& path,
                              const std::string& what, size_t max_values, std::vector<double>* joints,
                              std::vector<double>* weights) {
  const auto ji = prim.attributes.find("JOINTS_" + std::to_string(set));
  const auto wi = prim.attributes.find("WEIGHTS_" + std::to_string(set));
  if (ji == prim.attributes.end() || wi == prim.attributes.end()) return false;
  Result<std::vector<double>> jr = ReadAccessor(model, ji->second, path, what + " JOINTS_" + std::to_string(set), max_values);
  if (!jr.ok()) return jr.error();
  Result<std::vector<double>> wr = ReadAccessor(model, wi->second, path, what + " WEIGHTS_" + std::to_string(set), max_values);
  if (!wr.ok()) return wr.error();
  *joints = std::move(jr).value();
  *weights = std::move(wr).value();
  return true;
}

/// `d` as a vertex or joint number below `limit`: false when it is not a whole number in [0, limit) (NaN
/// included), so that converting it is defined.
bool AsIndex(double d, double limit, uint32_t* out) {
  if (!(d >= 0.0 && d < limit && d == std::floor(d))) return false;
  *out = static_cast<uint32_t>(d);
  return true;
}

/// A number read from the file, for a message (any double, NaN and infinities included).
std::string NumberText(double d) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", d);
  return buf;
}

Eigen::Matrix4d LocalMatrix(const tinygltf::Node& n) {
  if (n.matrix.size() == 16) {
    Eigen::Matrix4d m;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m(r, c) = n.matrix[static_cast<size_t>(c * 4 + r)];
    return m;
  }
  Eigen::Affine3d a = Eigen::Affine3d::Identity();
  if (n.translation.size() == 3) a.translate(Eigen::Vector3d(n.translation[0], n.translation[1], n.translation[2]));
  if (n.rotation.size() == 4)
    a.rotate(Eigen::Quaterniond(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]).normalized());
  if (n.scale.size() == 3) a.scale(Eigen::Vector3d(n.scale[0], n.scale[1], n.scale[2]));
  return a.matrix();
}

}  // namespace

Result<Mesh> ImportGltf(const std::string& path, const ImportOptions& options, Context* ctx) {
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&SkipImage, nullptr);
  std::error_code ec;
  FsRoot root;
  root.ctx = ctx;
  root.root = std::filesystem::weakly_canonical(std::filesystem::absolute(path, ec).parent_path(), ec);
  if (ec) return FileError(Error::Code::kIo, path, "cannot resolve the file's folder: " + ec.message());
  loader.SetFsCallbacks(
      tinygltf::FsCallbacks{&FsFileExists, &FsExpandFilePath, &FsReadWholeFile, &FsWriteWholeFile, &root});
  tinygltf::Model model;
  std::string err, warn;
  const bool binary = LowerExtension(path) == "glb";
  // Read here (as tinygltf's LoadASCIIFromFile / LoadBinaryFromFile would) so that the JSON's nesting is
  // checked before tinygltf sees it.
  std::vector<unsigned char> bytes;
  if (!FsReadWholeFile(&bytes, &err, path, &root)) return FileError(Error::Code::kIo, path, "cannot read file: " + err);
  if (bytes.empty()) return FileError(Error::Code::kFormat, path, "not a readable glTF file: empty file");
  const size_t depth = JsonDepth(binary ? GlbJsonChunk(bytes) : std::string_view(reinterpret_cast<const char*>(bytes.data()),
                                                                                  bytes.size()));
  if (depth > kMaxJsonDepth)
    return FileError(Error::Code::kFormat, path,
                     "not a readable glTF file: its JSON nests deeper than " + std::to_string(kMaxJsonDepth) + " levels");
  const size_t slash = path.find_last_of("/\\");
  const std::string base_dir = slash == std::string::npos ? std::string() : path.substr(0, slash);  // as tinygltf's GetBaseDir
  const bool ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(),
                                                       static_cast<unsigned int>(bytes.size()), base_dir)
                         : loader.LoadASCIIFromString(&model, &err, &warn, reinterpret_cast<const char*>(bytes.data()),
                                                      static_cast<unsigned int>(bytes.size()), base_dir);
  if (!warn.empty() && ctx) ctx->Warn("import: " + path + ": tinygltf: " + warn);
  if (!ok) {
    while (!err.empty() && (err.back() == '\n' || err.back() == '\r')) err.pop_back();
    if (!root.refused.empty())
      err += " (refused " + root.refused + ": a glTF may only reference files inside its own folder)";
    return FileError(Error::Code::kFormat, path, "not a readable glTF file: " + (err.empty() ? "unknown error" : err));
  }

  // Scene roots: the default scene, else scene 0, else every parentless node.
  std::vector<int> roots;
  if (!model.scenes.empty()) {
    const int s = (model.defaultScene >= 0 && model.defaultScene < static_cast<int>(model.scenes.size())) ? model.defaultScene : 0;
    roots = model.scenes[static_cast<size_t>(s)].nodes;
  } else {
    std::vector<bool> has_parent(model.nodes.size(), false);
    for (const auto& n : model.nodes)
      for (int c : n.children)
        if (c >= 0 && c < static_cast<int>(model.nodes.size())) has_parent[static_cast<size_t>(c)] = true;
    for (size_t i = 0; i < model.nodes.size(); ++i)
      if (!has_parent[i]) roots.push_back(static_cast<int>(i));
  }

  // Depth-first walk: parents-first node table with globals.
  const size_t n_nodes = model.nodes.size();
  std::vector<int32_t> node_slot(n_nodes, -1);  // glTF node → Skin::nodes index
  std::vector<int> order;                       // Skin::nodes index → glTF node
  std::vector<Eigen::Matrix4d> global;
  std::vector<Node> nodes;
  std::vector<std::pair<int, int32_t>> stack;
  for (auto r = roots.rbegin(); r != roots.rend(); ++r) stack.emplace_back(*r, -1);
  while (!stack.empty()) {
    const auto [gi, parent] = stack.back();
    stack.pop_back();
    if (gi < 0 || gi >= static_cast<int>(n_nodes)) return FileError(Error::Code::kFormat, path, "node index out of range");
    if (node_slot[static_cast<size_t>(gi)] >= 0)
      return FileError(Error::Code::kFormat, path, "node " + std::to_string(gi) + " is reached twice (not a tree)");
    const tinygltf::Node& gn = model.nodes[static_cast<size_t>(gi)];
    const int32_t slot = static_cast<int32_t>(nodes.size());
    node_slot[static_cast<size_t>(gi)] = slot;
    order.push_back(gi);
    const Eigen::Matrix4d local = LocalMatrix(gn);
    global.push_back(parent < 0 ? local : Eigen::Matrix4d(global[static_cast<size_t>(parent)] * local));
    Node node;
    node.name = gn.name.empty() ? "node" + std::to_string(gi) : gn.name;
    node.parent = parent;
    if (gn.matrix.size() == 16) {
      SetNodeTrs(local, node);
    } else {
      if (gn.translation.size() == 3)
        node.translation = {static_cast<float>(gn.translation[0]), static_cast<float>(gn.translation[1]),
                            static_cast<float>(gn.translation[2])};
      if (gn.rotation.size() == 4)
        node.rotation = {static_cast<float>(gn.rotation[0]), static_cast<float>(gn.rotation[1]),
                         static_cast<float>(gn.rotation[2]), static_cast<float>(gn.rotation[3])};
      if (gn.scale.size() == 3)
        node.scale = {static_cast<float>(gn.scale[0]), static_cast<float>(gn.scale[1]), static_cast<float>(gn.scale[2])};
    }
    nodes.push_back(node);
    for (auto c = gn.children.rbegin(); c != gn.children.rend(); ++c) stack.emplace_back(*c, slot);
  }

  Mesh mesh;
  mesh.source_format = binary ? "glb" : "gltf";
  mesh.units = "m";  // glTF 2.0 §3.4: metres, +Y up
  mesh.unit_scale_m = 1.0f;
  mesh.up_axis = UpAxis::kY;

  // Values an accessor without a bufferView may hold, and key values all clips may hold (import.h max_vertices).
  const size_t max_values = 3 * size_t{std::max(std::min(options.max_vertices, kMaxInputVertices),
                                                std::min(options.max_triangles, kMaxInputTriangles))};
  bool any_skin = false;
  for (int gi : order) {
    const auto& gn = model.nodes[static_cast<size_t>(gi)];
    if (gn.mesh >= 0 && gn.skin >= 0) any_skin = true;
  }
  Skin skin;
  skin.source = "gltf";
  std::vector<Influences> influences;
  std::map<std::pair<int, int>, uint32_t> joint_base;  // (skin, mesh node) → first SkinJoint
  std::map<int, uint32_t> rigid_joint;                 // mesh node → its rigid SkinJoint

  for (size_t slot = 0; slot < order.size(); ++slot) {
    const tinygltf::Node& gn = model.nodes[static_cast<size_t>(order[slot])];
    if (gn.mesh < 0) continue;
    if (gn.mesh >= static_cast<int>(model.meshes.size())) return FileError(Error::Code::kFormat, path, "mesh index out of range");
    const tinygltf::Mesh& gm = model.meshes[static_cast<size_t>(gn.mesh)];
    // Names in messages; an unnamed mesh or skin by its index.
    const std::string mesh_label = gm.name.empty() ? "mesh " + std::to_string(gn.mesh) : "mesh '" + gm.name + "'";
    // A skinned mesh is placed where its joints put it at rest (glTF 2.0: skinning ignores the mesh
    // node's transform), B = Global(joint)·IBM(joint) when all joints agree; otherwise its node global.
    Eigen::Matrix4d M = global[slot];
    std::vector<double> ibm;  // inverse bind matrices of gn.skin, 16 per joint, column-major
    if (gn.skin >= 0) {
      if (gn.skin >= static_cast<int>(model.skins.size())) return FileError(Error::Code::kFormat, path, "skin index out of range");
      const tinygltf::Skin& gs = model.skins[static_cast<size_t>(gn.skin)];
      const std::string skin_label = gs.name.empty() ? "skin " + std::to_string(gn.skin) : "skin '" + gs.name + "'";
      if (gs.inverseBindMatrices >= 0) {
        Result<std::vector<double>> r = ReadAccessor(model, gs.inverseBindMatrices, path, skin_label + " inverseBindMatrices",
                                                     max_values);
        if (!r.ok()) return r.error();
        ibm = std::move(r.value());
        if (ibm.size() < gs.joints.size() * 16)
          return FileError(Error::Code::kFormat, path, skin_label + " has fewer inverse binds than joints");
      }
      // The joints this mesh's vertices weight (SkinnedMeshBind reads only those: an unweighted helper or
      // root joint whose inverse bind does not match its rest pose must not move the mesh); all of them
      // when no vertex carries a weight.
      std::vector<char> weighted(gs.joints.size(), 0);
      bool any_weighted = false;
      std::vector<double> set_joints, set_weights;
      for (const tinygltf::Primitive& prim : gm.primitives)
        for (int set = 0; set < 2; ++set) {
          Result<bool> read = ReadInfluenceSet(model, prim, set, path, mesh_label, max_values, &set_joints, &set_weights);
          if (!read.ok()) return read.error();
          if (!read.value()) break;
          for (size_t i = 0; i < std::min(set_joints.size(), set_weights.size()); ++i) {
            uint32_t joint = 0;
            if (set_weights[i] > 0.0 && AsIndex(set_joints[i], static_cast<double>(gs.joints.size()), &joint)) {
              weighted[joint] = 1;
              any_weighted = true;
            }
          }
        }
      std::vector<Eigen::Matrix4d> joint_binds;
      for (size_t k = 0; k < gs.joints.size(); ++k) {
        const int jn = gs.joints[k];
        if (jn < 0 || jn >= static_cast<int>(n_nodes) || node_slot[static_cast<size_t>(jn)] < 0)
          return FileError(Error::Code::kFormat, path,
                           skin_label + " joint " + std::to_string(k) + " is not a node of the scene");
        if (any_weighted && !weighted[k]) continue;
        Eigen::Matrix4d ib = Eigen::Matrix4d::Identity();
        if (!ibm.empty())
          for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) ib(r, c) = ibm[k * 16 + static_cast<size_t>(c * 4 + r)];
        joint_binds.push_back(global[static_cast<size_t>(node_slot[static_cast<size_t>(jn)])] * ib);
      }
      bool consistent = false;
      M = SkinnedMeshBind(joint_binds, global[slot], &consistent);
      if (!consistent && ctx)
        ctx->Warn("import: " + path + ": " + skin_label + ": rest pose differs from the bind pose; mesh placed by its node");
    }
    const Eigen::Matrix4d M_inv = M.inverse();
    for (size_t pi = 0; pi < gm.primitives.size(); ++pi) {
      const tinygltf::Primitive& prim = gm.primitives[pi];
      const std::string what = mesh_label + " primitive " + std::to_string(pi);
      const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
      if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN) {
        if (ctx) ctx->Info("import: " + path + ": " + what + " skipped (not triangles)");
        continue;
      }
      auto pos_it = prim.attributes.find("POSITION");
      if (pos_it == prim.attributes.end()) return FileError(Error::Code::kFormat, path, what + " has no POSITION");
      Result<std::vector<double>> pos = ReadAccessor(model, pos_it->second, path, what + " POSITION", max_values);
      if (!pos.ok()) return pos.error();
      if (model.accessors[static_cast<size_t>(pos_it->second)].type != TINYGLTF_TYPE_VEC3)
        return FileError(Error::Code::kFormat, path, what + " POSITION is not VEC3");
      // Morph targets at their default weights (the node's, else the mesh's; glTF 2.0 §3.7.2.2): the shape a
      // viewer shows with no animation playing is the bind pose.
      const std::vector<double>& morph_weights = !gn.weights.empty() ? gn.weights : gm.weights;
      for (size_t ti = 0; ti < prim.targets.size() && ti < morph_weights.size(); ++ti) {
        const double w = morph_weights[ti];
        if (!std::isfinite(w))
          return FileError(Error::Code::kFormat, path, what + ": morph target " + std::to_string(ti) + "'s weight is not finite");
        const auto target_it = prim.targets[ti].find("POSITION");
        if (w == 0.0 || target_it == prim.targets[ti].end()) continue;
        const std::string target = what + " morph target " + std::to_string(ti) + " POSITION";
        Result<std::vector<double>> delta = ReadAccessor(model, target_it->second, path, target, max_values);
        if (!delta.ok()) return delta.error();
        if (delta->size() != pos->size())
          return FileError(Error::Code::kFormat, path, target + " has " + std::to_string(delta->size() / 3) +
                                                           " values, POSITION " + std::to_string(pos->size() / 3));
        for (size_t i = 0; i < pos->size(); ++i) pos.value()[i] += w * delta.value()[i];
      }
      const size_t nv = pos->size() / 3;
      std::vector<uint32_t> idx;
      if (prim.indices >= 0) {
        Result<std::vector<double>> ir = ReadAccessor(model, prim.indices, path, what + " indices", max_values);
        if (!ir.ok()) return ir.error();
        idx.resize(ir->size());
        for (size_t i = 0; i < idx.size(); ++i)
          if (!AsIndex(ir.value()[i], 4294967296.0, &idx[i]))
            return FileError(Error::Code::kFormat, path, what + " indices: index " + std::to_string(i) + " is " +
                                                             NumberText(ir.value()[i]) + ", not a vertex number");
      } else {
        idx.resize(nv);
        for (size_t i = 0; i < nv; ++i) idx[i] = static_cast<uint32_t>(i);
      }
      std::vector<uint32_t> tris;
      if (mode == TINYGLTF_MODE_TRIANGLES) {
        tris.assign(idx.begin(), idx.begin() + static_cast<ptrdiff_t>(idx.size() / 3 * 3));
      } else {
        for (size_t i = 2; i < idx.size(); ++i) {
          if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
            if (i % 2 == 0) tris.insert(tris.end(), {idx[i - 2], idx[i - 1], idx[i]});
            else tris.insert(tris.end(), {idx[i - 1], idx[i - 2], idx[i]});
          } else {
            tris.insert(tris.end(), {idx[0], idx[i - 1], idx[i]});
          }
        }
      }
      for (size_t t = 0; t < tris.size(); ++t) {
        if (tris[t] >= nv)
          return FileError(Error::Code::kInvalidMesh, path,
                           what + ": triangle " + std::to_string(t / 3) + " references vertex " + std::to_string(tris[t]) +
                               " of " + std::to_string(nv));
      }

      if (Status s = CheckMeshBudget(path, uint64_t{mesh.vertex_count()} + nv, uint64_t{mesh.triangle_count()} + tris.size() / 3,
                                     options);
          !s.ok())
        return s.error();
      MeshPart part;
      part.name = gm.name.empty() ? "mesh" + std::to_string(gn.mesh) : gm.name;
      if (gm.primitives.size() > 1) part.name += "#" + std::to_string(pi);
      part.first_vertex = mesh.vertex_count();
      part.vertex_count = static_cast<uint32_t>(nv);
      part.first_triangle = mesh.triangle_count();
      part.triangle_count = static_cast<uint32_t>(tris.size() / 3);
      for (size_t v = 0; v < nv; ++v) {
        const Eigen::Vector4d p = M * Eigen::Vector4d(pos.value()[v * 3], pos.value()[v * 3 + 1], pos.value()[v * 3 + 2], 1.0);
        mesh.positions.insert(mesh.positions.end(),
                              {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())});
      }
      for (uint32_t i : tris) mesh.indices.push_back(part.first_vertex + i);
      mesh.parts.push_back(part);

      if (!any_skin) continue;
      influences.resize(mesh.vertex_count());
      if (gn.skin >= 0) {
        const tinygltf::Skin& gs = model.skins[static_cast<size_t>(gn.skin)];
        auto key = std::make_pair(gn.skin, order[slot]);
        auto base_it = joint_base.find(key);
        if (base_it == joint_base.end()) {
          const uint32_t base = static_cast<uint32_t>(skin.joints.size());
          for (size_t k = 0; k < gs.joints.size(); ++k) {
            const int jn = gs.joints[k];
            Eigen::Matrix4d ib = Eigen::Matrix4d::Identity();
            if (!ibm.empty())
              for (int c = 0; c < 4; ++c)
                for (int r = 0; r < 4; ++r) ib(r, c) = ibm[k * 16 + static_cast<size_t>(c * 4 + r)];
            SkinJoint j;
            j.node = node_slot[static_cast<size_t>(jn)];
            j.inverse_bind = ToColumnMajor(ib * M_inv);
            skin.joints.push_back(j);
          }
          base_it = joint_base.emplace(key, base).first;
        }
        const uint32_t base = base_it->second;
        for (int set = 0; set < 2; ++set) {
          std::vector<double> jr, wr;
          Result<bool> read = ReadInfluenceSet(model, prim, set, path, what, max_values, &jr, &wr);
          if (!read.ok()) return read.error();
          if (!read.value()) break;
          if (jr.size() != nv * 4 || wr.size() != nv * 4)
            return FileError(Error::Code::kFormat, path, what + ": JOINTS/WEIGHTS are not VEC4 per vertex");
          for (size_t v = 0; v < nv; ++v) {
            for (int k = 0; k < 4; ++k) {
              const double w = wr[v * 4 + static_cast<size_t>(k)];
              if (!(w > 0.0)) continue;
              const double j = jr[v * 4 + static_cast<size_t>(k)];
              uint32_t joint = 0;
              if (!AsIndex(j, static_cast<double>(gs.joints.size()), &joint))
                return FileError(Error::Code::kInvalidMesh, path,
                                 what + ": vertex " + std::to_string(v) + " names joint " + NumberText(j) + " of " +
                                     std::to_string(gs.joints.size()));
              influences[part.first_vertex + v].emplace_back(base + joint, static_cast<float>(w));
            }
          }
        }
      } else {
        // Unskinned part of a skinned character: rigid on its own node.
        auto it = rigid_joint.find(order[slot]);
        if (it == rigid_joint.end()) {
          SkinJoint j;
          j.node = static_cast<int32_t>(slot);
          j.inverse_bind = ToColumnMajor(M_inv);
          it = rigid_joint.emplace(order[slot], static_cast<uint32_t>(skin.joints.size())).first;
          skin.joints.push_back(j);
        }
        for (size_t v = 0; v < nv; ++v) influences[part.first_vertex + v].emplace_back(it->second, 1.0f);
      }
    }
  }
  if (mesh.indices.empty()) return FileError(Error::Code::kInvalidMesh, path, "no triangles");

  if (any_skin) {
    influences.resize(mesh.vertex_count());
    skin.nodes = nodes;
    PackWeights(influences, skin);
    mesh.skin = std::move(skin);
  }

  if (options.read_clips && mesh.skin) {
    size_t clip_values = 0;
    for (size_t ai = 0; ai < model.animations.size(); ++ai) {
      const tinygltf::Animation& ga = model.animations[ai];
      Clip clip;
      clip.name = ga.name.empty() ? "animation" + std::to_string(ai) : ga.name;
      for (size_t ci = 0; ci < ga.channels.size(); ++ci) {
        const tinygltf::AnimationChannel& gc = ga.channels[ci];
        const std::string what = "animation '" + clip.name + "' channel " + std::to_string(ci);
        Channel ch;
        if (gc.target_path == "translation") ch.path = Channel::Path::kTranslation;
        else if (gc.target_path == "rotation") ch.path = Channel::Path::kRotation;
        else if (gc.target_path == "scale") ch.path = Channel::Path::kScale;
        else continue;  // morph weights: not skeletal
        if (gc.target_node < 0 || gc.target_node >= static_cast<int>(n_nodes) ||
            node_slot[static_cast<size_t>(gc.target_node)] < 0)
          continue;  // a node outside the scene
        ch.node = node_slot[static_cast<size_t>(gc.target_node)];
        if (gc.sampler < 0 || gc.sampler >= static_cast<int>(ga.samplers.size()))
          return FileError(Error::Code::kFormat, path, what + ": sampler index out of range");
        const tinygltf::AnimationSampler& gsamp = ga.samplers[static_cast<size_t>(gc.sampler)];
        Result<std::vector<double>> t = ReadAccessor(model, gsamp.input, path, what + " input", max_values);
        if (!t.ok()) return t.error();
        Result<std::vector<double>> v = ReadAccessor(model, gsamp.output, path, what + " output", max_values);
        if (!v.ok()) return v.error();
        const size_t width = ch.path == Channel::Path::kRotation ? 4 : 3;
        const size_t nk = t->size();
        const bool cubic = gsamp.interpolation == "CUBICSPLINE";
        if (v->size() != nk * width * (cubic ? 3 : 1))
          return FileError(Error::Code::kFormat, path, what + ": output count does not match input count");
        clip_values += nk * (width + 1);  // channels may share one accessor: the copies are what costs
        if (clip_values > max_values)
          return FileError(Error::Code::kFormat, path,
                           what + ": the clips hold more than " + std::to_string(max_values) + " key values");
        ch.interpolation = gsamp.interpolation == "STEP" ? Channel::Interpolation::kStep : Channel::Interpolation::kLinear;
        if (cubic && ctx) ctx->Warn("import: " + path + ": " + what + ": CUBICSPLINE sampled as LINEAR through its keys");
        for (size_t k = 0; k < nk; ++k) {
          ch.times.push_back(static_cast<float>(t.value()[k]));
          clip.duration_s = std::max(clip.duration_s, static_cast<float>(t.value()[k]));
          const size_t at = cubic ? (k * 3 + 1) * width : k * width;  // cubic: (in-tangent, value, out-tangent)
          for (size_t c = 0; c < width; ++c) ch.values.push_back(static_cast<float>(v.value()[at + c]));
        }
        clip.channels.push_back(std::move(ch));
      }
      if (!clip.channels.empty()) mesh.clips.push_back(std::move(clip));
    }
  }
  return mesh;
}

}  // namespace spherechain::import::detail
