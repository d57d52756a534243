// spherechain import — import entry point: dispatch by extension, shared checks (ValidateMesh).
#include "spherechain/import/import.h"

#include <algorithm>
#include <set>
#include <cctype>
#include <cmath>
#include <exception>
#include <iterator>
#include <vector>
#include <filesystem>
#include <new>
#include <string>
#include <system_error>

#include "import_internal.h"

namespace spherechain::import {
namespace detail {

std::string LowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

Eigen::Matrix4d SkinnedMeshBind(const std::vector<Eigen::Matrix4d>& joint_binds, const Eigen::Matrix4d& node_global,
                                bool* consistent) {
  *consistent = false;
  if (joint_binds.empty()) return node_global;
  const Eigen::Matrix4d& b0 = joint_binds.front();
  const double scale = std::max(1.0, b0.cwiseAbs().maxCoeff());
  for (const Eigen::Matrix4d& b : joint_binds)
    if ((b - b0).cwiseAbs().maxCoeff() > 1e-4 * scale) return node_global;
  *consistent = true;
  return b0;
}

void PackWeights(std::vector<Influences>& per_vertex, Skin& skin) {
  skin.weight_offsets.assign(1, 0u);
  skin.weight_offsets.reserve(per_vertex.size() + 1);
  skin.weight_joints.clear();
  skin.weights.clear();
  for (Influences& inf : per_vertex) {
    std::sort(inf.begin(), inf.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    // Merge duplicates (a bone listed twice for a vertex) and drop unusable weights.
    Influences merged;
    for (const auto& [j, w] : inf) {
      if (!std::isfinite(w) || w <= 0.0f) continue;
      if (!merged.empty() && merged.back().first == j)
        merged.back().second += w;
      else
        merged.emplace_back(j, w);
    }
    double sum = 0.0;
    for (const auto& jw : merged) sum += jw.second;
    for (const auto& [j, w] : merged) {
      skin.weight_joints.push_back(j);
      skin.weights.push_back(static_cast<float>(w / sum));
    }
    skin.weight_offsets.push_back(static_cast<uint32_t>(skin.weights.size()));
    Influences().swap(inf);
  }
}

Status CheckMeshBudget(const std::string& path, uint64_t vertices, uint64_t triangles, const ImportOptions& options) {
  const uint64_t max_v = std::min(options.max_vertices, kMaxInputVertices);
  const uint64_t max_t = std::min(options.max_triangles, kMaxInputTriangles);
  if (vertices > max_v)
    return FileError(Error::Code::kInvalidMesh, path,
                     std::to_string(vertices) + " vertices, over the limit of " + std::to_string(max_v));
  if (triangles > max_t)
    return FileError(Error::Code::kInvalidMesh, path,
                     std::to_string(triangles) + " triangles, over the limit of " + std::to_string(max_t));
  return Ok{};
}

}  // namespace detail

Status ValidateMesh(const Mesh& mesh) {
  const std::string where = mesh.source_path.empty() ? std::string("mesh") : mesh.source_path;
  auto fail = [&](const std::string& m) -> Status {
    return MakeError(Error::Code::kInvalidMesh, where + ": " + m);
  };
  if (mesh.positions.size() % 3 != 0) return fail("positions size is not a multiple of 3");
  if (mesh.indices.size() % 3 != 0) return fail("indices size is not a multiple of 3");
  if (mesh.indices.empty()) return fail("no triangles");
  const uint32_t nv = mesh.vertex_count();
  for (uint32_t v = 0; v < nv; ++v) {
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(mesh.positions[static_cast<size_t>(v) * 3 + k]))
        return fail("vertex " + std::to_string(v) + " has a non-finite coordinate");
    }
  }
  const uint32_t nt = mesh.triangle_count();
  for (uint32_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = mesh.indices[static_cast<size_t>(t) * 3 + k];
      if (i >= nv)
        return fail("triangle " + std::to_string(t) + " references vertex " + std::to_string(i) + " of " +
                    std::to_string(nv));
    }
  }
  for (size_t p = 0; p < mesh.parts.size(); ++p) {
    const MeshPart& part = mesh.parts[p];
    if (uint64_t{part.first_vertex} + part.vertex_count > nv ||
        uint64_t{part.first_triangle} + part.triangle_count > nt)
      return fail("part " + std::to_string(p) + " ('" + part.name + "') exceeds the mesh");
  }
  if (mesh.skin) {
    const Skin& s = *mesh.skin;
    for (size_t n = 0; n < s.nodes.size(); ++n) {
      if (s.nodes[n].parent >= static_cast<int32_t>(n) || s.nodes[n].parent < -1)
        return fail("skin node " + std::to_string(n) + " is not stored after its parent");
    }
    for (size_t j = 0; j < s.joints.size(); ++j) {
      if (s.joints[j].node < 0 || s.joints[j].node >= static_cast<int32_t>(s.nodes.size()))
        return fail("skin joint " + std::to_string(j) + " references node " + std::to_string(s.joints[j].node));
    }
    if (s.weight_offsets.size() != size_t{nv} + 1 || s.weight_offsets.back() != s.weights.size() ||
        s.weight_joints.size() != s.weights.size())
      return fail("skin weight table does not match the vertex count");
    for (size_t w = 0; w < s.weight_joints.size(); ++w) {
      if (s.weight_joints[w] >= s.joints.size())
        return fail("skin weight " + std::to_string(w) + " references joint " + std::to_string(s.weight_joints[w]));
    }
  }
  return Ok{};
}

MeshIssues InspectMesh(const Mesh& mesh) {
  MeshIssues issues;
  const uint32_t nt = mesh.triangle_count();
  std::vector<uint64_t> edges;
  edges.reserve(size_t{nt} * 3);
  for (uint32_t t = 0; t < nt; ++t) {
    const uint32_t* i = mesh.indices.data() + size_t{t} * 3;
    if (i[0] == i[1] || i[1] == i[2] || i[0] == i[2]) {
      ++issues.degenerate_triangles;
      continue;
    }
    const float* a = mesh.positions.data() + size_t{i[0]} * 3;
    const float* b = mesh.positions.data() + size_t{i[1]} * 3;
    const float* c = mesh.positions.data() + size_t{i[2]} * 3;
    const double u[3] = {double{b[0]} - a[0], double{b[1]} - a[1], double{b[2]} - a[2]};
    const double v[3] = {double{c[0]} - a[0], double{c[1]} - a[1], double{c[2]} - a[2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    if (n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0) ++issues.degenerate_triangles;
    for (int k = 0; k < 3; ++k) {
      const uint32_t p = i[k], q = i[(k + 1) % 3];
      edges.push_back(p < q ? (uint64_t{p} << 32 | q) : (uint64_t{q} << 32 | p));
    }
  }
  std::sort(edges.begin(), edges.end());
  for (size_t e = 0; e < edges.size();) {
    size_t f = e;
    while (f < edges.size() && edges[f] == edges[e]) ++f;
    if (f - e > 2) ++issues.non_manifold_edges;
    e = f;
  }
  return issues;
}

const char* ToString(VertexContract c) {
  switch (c) {
    case VertexContract::kJoined: return "joined";
    case VertexContract::kSource: return "source";
    case VertexContract::kAuto: break;
  }
  return "auto";
}

Result<Mesh> ImportMesh(const std::string& path, const ImportOptions& options, Context* ctx) {
  Context::Timer timer(ctx, "import");
  try {
    std::error_code ec;
    const std::filesystem::file_status st = std::filesystem::status(path, ec);
    if (ec || !std::filesystem::exists(st)) return detail::FileError(Error::Code::kIo, path, "file not found");
    if (!std::filesystem::is_regular_file(st)) return detail::FileError(Error::Code::kIo, path, "not a regular file");

    const std::string ext = detail::LowerExtension(path);
    if (std::find(std::begin(kSupportedExtensions), std::end(kSupportedExtensions), ext) ==
        std::end(kSupportedExtensions))
      return detail::FileError(Error::Code::kFormat, path,
                               "unsupported format '" + (ext.empty() ? std::string("(no extension)") : "." + ext) +
                                   "': the baker reads glTF/GLB, FBX, DAE/ZAE, X, OBJ, BLEND, 3DS, PLY, STL, IQM, SMD, MD5MESH, "
                                   "MS3D and B3D");
    const uintmax_t bytes = std::filesystem::file_size(path, ec);
    if (ec) return detail::FileError(Error::Code::kIo, path, "cannot stat file: " + ec.message());
    if (bytes > kMaxInputBytes)
      return detail::FileError(Error::Code::kFormat, path,
                               "file is " + std::to_string(bytes) + " bytes, over the input limit of " +
                                   std::to_string(kMaxInputBytes) + " bytes (512 MiB)");
    if ((!options.rig_path.empty() || !options.weights_path.empty()) && ext != "obj")
      return detail::FileError(Error::Code::kConfig, path,
                               "a MakeHuman rig (--rig, or the config's \"rig\") applies to an OBJ mesh; a ." + ext +
                                   " file carries its own skeleton, if any");
    Result<Mesh> mesh = MakeError(Error::Code::kInternal, path + ": not imported");
    if (ext == "gltf" || ext == "glb") {
      mesh = detail::ImportGltf(path, options, ctx);
    } else if (ext == "obj") {
      mesh = detail::ImportObj(path, options, ctx);
    } else {
      mesh = options.isolate_assimp ? detail::ImportInChild(path, options, ctx, &detail::ImportAssimp)
                                    : detail::ImportAssimp(path, options, ctx);
    }
    if (!mesh.ok()) return mesh;
    if (mesh->vertex_contract == "file" && options.vertices != VertexContract::kAuto && ctx)
      ctx->Warn("import: " + path + ": --vertices " + ToString(options.vertices) +
                " applies to assimp formats only; a ." + ext +
                " file's vertex buffer is already the one engines upload (read as is)");
    mesh->source_path = path;
    if (mesh->source_format.empty()) mesh->source_format = ext;
    // Clips are chosen by name (--clip, check's report, a baseline): a name the file repeats gets " #2", " #3"….
    std::set<std::string> clip_names;
    for (Clip& clip : mesh->clips) {
      std::string name = clip.name;
      for (int k = 2; clip_names.count(name); ++k) name = clip.name + " #" + std::to_string(k);
      if (name != clip.name && ctx)
        ctx->Warn("import: " + path + ": a second clip named '" + clip.name + "' is called '" + name + "'");
      clip.name = name;
      clip_names.insert(name);
    }
    if (Status s = detail::CheckMeshBudget(path, mesh->positions.size() / 3, mesh->indices.size() / 3, options); !s.ok())
      return s.error();
    Status valid = ValidateMesh(mesh.value());
    if (!valid.ok()) return valid.error();
    const MeshIssues issues = InspectMesh(mesh.value());
    if (ctx && issues.degenerate_triangles)
      ctx->Warn("import: " + path + ": " + std::to_string(issues.degenerate_triangles) +
                " degenerate triangle(s) (repeated index or zero area): kept, never used as pivots");
    if (ctx && issues.non_manifold_edges)
      ctx->Warn("import: " + path + ": " + std::to_string(issues.non_manifold_edges) +
                " non-manifold edge(s) (shared by more than two triangles): kept");
    if (ctx) {
      ctx->Info("import: " + path + ": " + std::to_string(mesh->vertex_count()) + " vertices, " +
                std::to_string(mesh->triangle_count()) + " triangles, " + std::to_string(mesh->parts.size()) +
                " part(s), " + (mesh->skin ? std::to_string(mesh->skin->joints.size()) + " joints" : "no skin") +
                ", " + std::to_string(mesh->clips.size()) + " clip(s)");
    }
    return mesh;
  } catch (const std::bad_alloc&) {
    return detail::FileError(Error::Code::kInternal, path, "out of memory while importing");
  } catch (const std::exception& e) {
    return detail::FileError(Error::Code::kFormat, path, std::string("import failed: ") + e.what());
  } catch (...) {
    return detail::FileError(Error::Code::kFormat, path, "import failed: unknown exception");
  }
}

}  // namespace spherechain::import
