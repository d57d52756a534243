// spherechain import — Wavefront OBJ reader (source vertex order kept) and the MakeHuman rig
// (default.mhskel + default_weights.mhw, data/README.md) that turns base.obj's group `body` into a
// skinned character.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "import_internal.h"

namespace spherechain::import::detail {
namespace {

namespace fs = std::filesystem;

/// The OBJ as read: every `v` of the file (file order) and the kept triangles (fan-triangulated
/// faces), indices into `all_positions`.
struct ObjData {
  std::vector<float> all_positions;  ///< #V_file×3, source units
  std::vector<uint32_t> triangles;   ///< #T×3 into all_positions
  bool has_group = false;            ///< the file has a `g` naming options.obj_group
  bool makehuman_header = false;     ///< a "# basemesh hm08"-style comment was seen
};

/// Reads `path` whole into `out`; records it in `ctx` (files_read) once read.
bool ReadWholeFile(const std::string& path, std::string& out, Context* ctx) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  out.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (in.bad()) return false;
  if (ctx) ctx->RecordFileRead(path);
  return true;
}

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

/// Splits on blanks.
std::vector<std::string_view> Tokens(std::string_view s) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r')) ++i;
    size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t' && s[j] != '\r') ++j;
    if (j > i) out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

/// A coordinate: read as a double (an exporter writing doubles may write 1e-50), then rounded to float — a
/// value below float's range becomes 0 or a denormal, one above it infinite (refused as non-finite later,
/// with the vertex named). false only when `t` is not a number.
bool ParseFloat(std::string_view t, float& out) {
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  double d = 0;
  const auto r = std::from_chars(t.data(), t.data() + t.size(), d);
  const bool out_of_double = r.ec == std::errc::result_out_of_range;  // 1e-400 (→ 0) or 1e400 (→ inf)
  if ((r.ec != std::errc() && !out_of_double) || r.ptr != t.data() + t.size()) return false;
  if (out_of_double) {
    const size_t e = t.find_first_of("eE");
    const bool tiny = e != std::string_view::npos && e + 1 < t.size() && t[e + 1] == '-';
    d = tiny ? 0.0 : (t.front() == '-' ? -HUGE_VAL : HUGE_VAL);
  }
  out = static_cast<float>(d);
  return true;
}

/// Two passes: the first finds whether the wanted group exists in a MakeHuman base mesh (a `# basemesh`
/// comment, or `makehuman_rig`: the caller gives a rig) — faces are kept only inside it then; any other OBJ
/// keeps every group —, the second reads vertices and faces. Face corners are `v`, `v/vt`, `v//vn`,
/// `v/vt/vn`, negative values relative to the vertices read so far.
Result<ObjData> ReadObj(const std::string& path, const std::string& text, const std::string& group, bool makehuman_rig) {
  ObjData d;
  auto for_lines = [&](auto&& fn) -> Status {
    size_t pos = 0;
    size_t line_no = 0;
    while (pos < text.size()) {
      size_t end = text.find('\n', pos);
      if (end == std::string::npos) end = text.size();
      ++line_no;
      Status s = fn(Trim(std::string_view(text).substr(pos, end - pos)), line_no);
      if (!s.ok()) return s;
      pos = end + 1;
    }
    return Ok{};
  };
  auto group_matches = [&](std::string_view line) {
    const auto tok = Tokens(line.substr(1));
    return std::any_of(tok.begin(), tok.end(), [&](std::string_view t) { return t == group; });
  };
  if (!group.empty()) {
    bool group_seen = false, header_seen = false;
    Status s = for_lines([&](std::string_view line, size_t) -> Status {
      if (line.size() > 1 && line[0] == 'g' && (line[1] == ' ' || line[1] == '\t') && group_matches(line))
        group_seen = true;
      if (!line.empty() && line[0] == '#' && line.find("basemesh") != std::string_view::npos) header_seen = true;
      return Ok{};
    });
    (void)s;
    d.has_group = group_seen && (header_seen || makehuman_rig);
  }

  bool in_group = !d.has_group;  // no such group: keep every face
  std::vector<int64_t> corners;
  int64_t max_corner = -1;  // the largest vertex a kept face references (0-based), and its line: checked at the end
  size_t max_corner_line = 0;  // (a face may reference a vertex the file gives later)
  Status s = for_lines([&](std::string_view line, size_t line_no) -> Status {
    if (line.empty()) return Ok{};
    if (line[0] == '#') {
      if (line.find("basemesh") != std::string_view::npos) d.makehuman_header = true;
      return Ok{};
    }
    const auto tok = Tokens(line);
    if (tok.empty()) return Ok{};
    const std::string where = "line " + std::to_string(line_no);
    if (tok[0] == "v") {
      if (tok.size() < 4) return FileError(Error::Code::kFormat, path, where + ": vertex needs 3 coordinates");
      for (int k = 1; k <= 3; ++k) {
        float f = 0.0f;
        if (!ParseFloat(tok[static_cast<size_t>(k)], f))
          return FileError(Error::Code::kFormat, path,
                           where + ": cannot parse coordinate '" + std::string(tok[static_cast<size_t>(k)]) + "'");
        d.all_positions.push_back(f);
      }
    } else if (tok[0] == "g") {
      if (d.has_group) in_group = group_matches(line);
    } else if (tok[0] == "f") {
      if (!in_group) return Ok{};
      if (tok.size() < 4) return FileError(Error::Code::kFormat, path, where + ": face needs at least 3 corners");
      const int64_t nv = static_cast<int64_t>(d.all_positions.size() / 3);
      corners.clear();
      for (size_t c = 1; c < tok.size(); ++c) {
        std::string_view v = tok[c].substr(0, tok[c].find('/'));
        int64_t idx = 0;
        const auto r = std::from_chars(v.data(), v.data() + v.size(), idx);
        if (r.ec != std::errc() || r.ptr != v.data() + v.size())
          return FileError(Error::Code::kFormat, path, where + ": cannot parse face corner '" + std::string(tok[c]) + "'");
        if (idx < 0) idx = nv + idx + 1;  // relative to the vertices read so far
        if (idx <= 0)
          return FileError(Error::Code::kInvalidMesh, path,
                           where + ": face references vertex " + std::string(v) + " (out of range)");
        corners.push_back(idx - 1);
        if (idx - 1 > max_corner) max_corner = idx - 1, max_corner_line = line_no;
      }
      for (size_t c = 1; c + 1 < corners.size(); ++c) {
        for (int64_t i : {corners[0], corners[c], corners[c + 1]}) {
          if (i > 0xFFFFFFFEll)
            return FileError(Error::Code::kInvalidMesh, path, where + ": face index " + std::to_string(i + 1) + " too large");
          d.triangles.push_back(static_cast<uint32_t>(i));
        }
      }
    }
    return Ok{};  // vt, vn, o, s, usemtl, mtllib, l, p: not geometry we keep
  });
  if (!s.ok()) return s.error();
  const size_t nv = d.all_positions.size() / 3;
  if (max_corner >= static_cast<int64_t>(nv))
    return FileError(Error::Code::kInvalidMesh, path,
                     "line " + std::to_string(max_corner_line) + ": face references vertex " +
                         std::to_string(max_corner + 1) + " (1-based) but the file has " + std::to_string(nv) +
                         " vertices");
  return d;
}

/// A JSON value from the file, for a message: a number, string (cut at 40 characters), boolean or null as
/// written; an array or object only by its size. Never the whole value: nlohmann's dump() recurses once per
/// level, and a rig of "[[[[…" 50,000 deep overflowed the stack printing it (found by fuzz_import_makehuman).
std::string Brief(const nlohmann::ordered_json& v) {
  if (v.is_array()) return "an array of " + std::to_string(v.size());
  if (v.is_object()) return "an object of " + std::to_string(v.size()) + " keys";
  const std::string text = v.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
  return text.size() <= 40 ? text : text.substr(0, 40) + "...";
}

/// Reads a JSON file; kIo when unreadable, kFormat when not JSON.
Result<nlohmann::ordered_json> ReadJson(const std::string& path, Context* ctx) {
  std::string text;
  if (!ReadWholeFile(path, text, ctx)) return FileError(Error::Code::kIo, path, "cannot read file");
  nlohmann::ordered_json j = nlohmann::ordered_json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return FileError(Error::Code::kFormat, path, "not valid JSON");
  return j;
}

/// MakeHuman rig → Skin. `all_positions` are all base.obj vertices (the mhskel's `joints` lists
/// index them, 0-based); `remap[v]` is v's index in the imported mesh or -1 when v is not kept.
/// Nodes: one per bone, parents-first (roots, then children depth-first, in file order); rest rotation
/// identity, translation = head − parent head (model space, dm). Joints: one per bone, inverse_bind =
/// translate(−head). Weights from the mhw, normalised per vertex.
Result<Skin> ReadMakeHumanRig(const std::string& skel_path, const std::string& weights_path_opt,
                              const std::vector<float>& all_positions, const std::vector<int64_t>& remap,
                              uint32_t vertex_count, Context* ctx) {
  Result<nlohmann::ordered_json> skel_r = ReadJson(skel_path, ctx);
  if (!skel_r.ok()) return skel_r.error();
  const nlohmann::ordered_json& skel = skel_r.value();
  if (!skel.is_object() || !skel.contains("bones") || !skel["bones"].is_object() || !skel.contains("joints") ||
      !skel["joints"].is_object())
    return FileError(Error::Code::kFormat, skel_path, "not a MakeHuman skeleton (needs 'bones' and 'joints')");

  std::string weights_path = weights_path_opt;
  if (weights_path.empty()) {
    // The skeleton's own `weights_file` is data, not the user's choice: like a glTF's buffers it may name only
    // a file in the skeleton's folder.
    const fs::path dir = fs::path(skel_path).parent_path();
    if (skel.contains("weights_file") && skel["weights_file"].is_string())
      weights_path = (dir / skel["weights_file"].get<std::string>()).string();
    else
      weights_path = (dir / "default_weights.mhw").string();
    if (!InsideFolder(dir.empty() ? "." : dir.string(), weights_path))
      return FileError(Error::Code::kFormat, skel_path,
                       "weights file " + weights_path + " is outside the skeleton's folder (a rig may only name files beside it)");
  }

  // Joint positions: mean of the listed base.obj vertices.
  const size_t nv_file = all_positions.size() / 3;
  std::unordered_map<std::string, Eigen::Vector3d> joint_pos;
  for (const auto& [name, verts] : skel["joints"].items()) {
    if (!verts.is_array() || verts.empty())
      return FileError(Error::Code::kFormat, skel_path, "joint '" + name + "' lists no vertices");
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const auto& v : verts) {
      if (!v.is_number_integer() || v.get<int64_t>() < 0 || static_cast<size_t>(v.get<int64_t>()) >= nv_file)
        return FileError(Error::Code::kFormat, skel_path,
                         "joint '" + name + "' lists vertex " + Brief(v) + ", the OBJ has " + std::to_string(nv_file));
      const size_t i = static_cast<size_t>(v.get<int64_t>());
      sum += Eigen::Vector3d(all_positions[i * 3], all_positions[i * 3 + 1], all_positions[i * 3 + 2]);
    }
    joint_pos[name] = sum / static_cast<double>(verts.size());
  }

  // Bones in file order; parents-first order by depth-first walk from the roots.
  struct BoneIn {
    std::string name, parent;
    Eigen::Vector3d head;
  };
  std::vector<BoneIn> bones;
  std::unordered_map<std::string, size_t> bone_index;
  for (const auto& [name, b] : skel["bones"].items()) {
    if (!b.is_object() || !b.contains("head") || !b["head"].is_string())
      return FileError(Error::Code::kFormat, skel_path, "bone '" + name + "' has no head joint");
    const std::string head = b["head"].get<std::string>();
    auto it = joint_pos.find(head);
    if (it == joint_pos.end())
      return FileError(Error::Code::kFormat, skel_path, "bone '" + name + "' names unknown joint '" + head + "'");
    std::string parent;
    if (b.contains("parent") && b["parent"].is_string()) parent = b["parent"].get<std::string>();
    bone_index[name] = bones.size();
    bones.push_back({name, parent, it->second});
  }
  std::vector<std::vector<size_t>> children(bones.size());
  std::vector<size_t> roots;
  for (size_t i = 0; i < bones.size(); ++i) {
    if (bones[i].parent.empty()) {
      roots.push_back(i);
      continue;
    }
    auto it = bone_index.find(bones[i].parent);
    if (it == bone_index.end())
      return FileError(Error::Code::kFormat, skel_path,
                       "bone '" + bones[i].name + "' has unknown parent '" + bones[i].parent + "'");
    children[it->second].push_back(i);
  }
  Skin skin;
  skin.source = "mhskel";
  std::vector<int32_t> node_of(bones.size(), -1);
  std::vector<std::pair<size_t, int32_t>> stack;  // (bone, parent node)
  for (auto r = roots.rbegin(); r != roots.rend(); ++r) stack.emplace_back(*r, -1);
  while (!stack.empty()) {
    const auto [b, parent_node] = stack.back();
    stack.pop_back();
    const int32_t n = static_cast<int32_t>(skin.nodes.size());
    node_of[b] = n;
    Node node;
    node.name = bones[b].name;
    node.parent = parent_node;
    const Eigen::Vector3d parent_head =
        parent_node < 0 ? Eigen::Vector3d::Zero() : bones[bone_index[bones[b].parent]].head;
    const Eigen::Vector3d t = bones[b].head - parent_head;
    node.translation = {static_cast<float>(t.x()), static_cast<float>(t.y()), static_cast<float>(t.z())};
    skin.nodes.push_back(node);
    for (auto c = children[b].rbegin(); c != children[b].rend(); ++c) stack.emplace_back(*c, n);
  }
  if (skin.nodes.size() != bones.size())
    return FileError(Error::Code::kFormat, skel_path, "bone hierarchy has a cycle");
  // One joint per node (same index), inverse bind = translate(−head world).
  skin.joints.resize(skin.nodes.size());
  std::vector<size_t> bone_of_node(bones.size());
  for (size_t b = 0; b < bones.size(); ++b) bone_of_node[static_cast<size_t>(node_of[b])] = b;
  for (size_t n = 0; n < skin.nodes.size(); ++n) {
    Eigen::Matrix4d ib = Eigen::Matrix4d::Identity();
    ib.block<3, 1>(0, 3) = -bones[bone_of_node[n]].head;
    skin.joints[n].node = static_cast<int32_t>(n);
    skin.joints[n].inverse_bind = ToColumnMajor(ib);
  }

  // Weights.
  Result<nlohmann::ordered_json> w_r = ReadJson(weights_path, ctx);
  if (!w_r.ok()) return w_r.error();
  const nlohmann::ordered_json& wj = w_r.value();
  if (!wj.is_object() || !wj.contains("weights") || !wj["weights"].is_object())
    return FileError(Error::Code::kFormat, weights_path, "not a MakeHuman weights file (needs 'weights')");
  std::vector<Influences> per_vertex(vertex_count);
  for (const auto& [bone, list] : wj["weights"].items()) {
    auto it = bone_index.find(bone);
    if (it == bone_index.end())
      return FileError(Error::Code::kFormat, weights_path, "weights for unknown bone '" + bone + "'");
    const uint32_t joint = static_cast<uint32_t>(node_of[it->second]);
    if (!list.is_array()) return FileError(Error::Code::kFormat, weights_path, "weights of '" + bone + "' not a list");
    for (const auto& pair : list) {
      if (!pair.is_array() || pair.size() != 2 || !pair[0].is_number_integer() || !pair[1].is_number())
        return FileError(Error::Code::kFormat, weights_path, "weights of '" + bone + "': entry " + Brief(pair) +
                                                                  " is not [vertex, weight]");
      const int64_t v = pair[0].get<int64_t>();
      if (v < 0 || static_cast<size_t>(v) >= remap.size())
        return FileError(Error::Code::kFormat, weights_path,
                         "weights of '" + bone + "' name vertex " + std::to_string(v) + ", the OBJ has " +
                             std::to_string(remap.size()));
      if (remap[static_cast<size_t>(v)] < 0) continue;  // helper geometry, not imported
      per_vertex[static_cast<size_t>(remap[static_cast<size_t>(v)])].emplace_back(joint, pair[1].get<float>());
    }
  }
  PackWeights(per_vertex, skin);
  if (ctx)
    ctx->Info("import: MakeHuman rig " + skel_path + ": " + std::to_string(skin.nodes.size()) + " bones, weights " +
              weights_path);
  return skin;
}

}  // namespace

Result<Mesh> ImportObj(const std::string& path, const ImportOptions& options, Context* ctx) {
  std::string text;
  if (!ReadWholeFile(path, text, ctx)) return FileError(Error::Code::kIo, path, "cannot read file");
  Result<ObjData> obj_r = ReadObj(path, text, options.obj_group, !options.rig_path.empty());
  if (!obj_r.ok()) return obj_r.error();
  ObjData& obj = obj_r.value();
  std::string().swap(text);

  Mesh mesh;
  mesh.source_format = "obj";
  mesh.up_axis = UpAxis::kY;  // OBJ has no axis metadata; +Y up is the convention (MakeHuman too)
  const size_t nv_file = obj.all_positions.size() / 3;
  std::vector<int64_t> remap(nv_file, -1);
  if (obj.has_group) {
    // Keep the vertices the group references, in file order.
    for (uint32_t i : obj.triangles) remap[i] = 0;
    int64_t next = 0;
    for (size_t v = 0; v < nv_file; ++v) {
      if (remap[v] < 0) continue;
      remap[v] = next++;
      mesh.positions.insert(mesh.positions.end(), obj.all_positions.begin() + static_cast<ptrdiff_t>(v * 3),
                            obj.all_positions.begin() + static_cast<ptrdiff_t>(v * 3 + 3));
    }
    mesh.indices.reserve(obj.triangles.size());
    for (uint32_t i : obj.triangles) mesh.indices.push_back(static_cast<uint32_t>(remap[i]));
  } else {
    for (size_t v = 0; v < nv_file; ++v) remap[v] = static_cast<int64_t>(v);
    mesh.positions = obj.all_positions;
    mesh.indices = obj.triangles;
  }
  MeshPart part;
  // Never the file's name: the asset would then differ with the name it was saved under (builds cache on it).
  part.name = obj.has_group ? options.obj_group : "mesh0";
  part.vertex_count = mesh.vertex_count();
  part.triangle_count = mesh.triangle_count();
  mesh.parts.push_back(part);
  if (ctx && obj.has_group)
    ctx->Info("import: " + path + ": kept group '" + options.obj_group + "' (" + std::to_string(mesh.vertex_count()) +
              " of " + std::to_string(nv_file) + " vertices)");

  // The MakeHuman rig: given explicitly, or found beside a base mesh that has the body group.
  std::string skel_path = options.rig_path;
  if (skel_path.empty() && obj.has_group) {
    const fs::path dir = fs::path(path).parent_path();
    const fs::path cand = dir / "default.mhskel";
    const bool weights_known =
        !options.weights_path.empty() || fs::exists(dir / "default_weights.mhw");
    if (fs::exists(cand) && weights_known) skel_path = cand.string();
  }
  if (!skel_path.empty()) {
    if (!fs::exists(skel_path)) return FileError(Error::Code::kIo, skel_path, "rig file not found");
    if (mesh.vertex_count() == 0) return FileError(Error::Code::kInvalidMesh, path, "no triangles");
    Result<Skin> skin = ReadMakeHumanRig(skel_path, options.weights_path, obj.all_positions, remap,
                                         mesh.vertex_count(), ctx);
    if (!skin.ok()) return skin.error();
    mesh.skin = std::move(skin.value());
  }
  if (obj.makehuman_header || mesh.skin) {
    mesh.units = "dm";  // MakeHuman base mesh: 1 unit = 1 decimetre (data/README.md)
    mesh.unit_scale_m = 0.1f;
  }
  return mesh;
}

}  // namespace spherechain::import::detail
