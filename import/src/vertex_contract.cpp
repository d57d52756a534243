// The vertex contract an asset was baked with (vertex_contract.h).
#include "spherechain/import/vertex_contract.h"

#include "import_internal.h"
#include "spherechain/runtime/schema/spherechain_generated.h"

namespace spherechain::import {

namespace {

std::string ContractOf(const runtime::AssetView& view) {
  const auto* c = view.asset->vertex_contract();
  return c ? c->str() : std::string();
}

}  // namespace

bool ReadThroughAssimp(const std::string& path) {
  const std::string ext = detail::LowerExtension(path);
  if (ext == "gltf" || ext == "glb" || ext == "obj") return false;
  for (const char* e : kSupportedExtensions)
    if (ext == e) return true;
  return false;
}

VertexContract ContractForReimport(const runtime::AssetView& view, const std::string& mesh_path) {
  const std::string c = ContractOf(view);
  if (c == "joined") return VertexContract::kJoined;
  if (c == "source") return VertexContract::kSource;
  if (c.empty() && ReadThroughAssimp(mesh_path)) return VertexContract::kSource;
  return VertexContract::kAuto;
}

std::string AssetVertexContractName(const runtime::AssetView& view) {
  const std::string c = ContractOf(view);
  return c.empty() ? "unrecorded" : c;
}

std::string GroupThousands(uint64_t n) {
  std::string digits = std::to_string(n), out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

std::string DescribeVertexMismatch(const runtime::AssetView& view, uint32_t vertex_count) {
  const uint32_t baked = view.vertex_count;
  if (vertex_count == baked) return {};
  const std::string c = ContractOf(view);
  const uint32_t source = view.asset->source_vertex_count();
  const uint32_t joined = view.asset->joined_vertex_count();
  const std::string has = "the buffer has " + GroupThousands(vertex_count) + " vertices";
  if ((c == "joined" || c == "source") && source && joined) {
    const std::string other = c == "joined" ? "source" : "joined";
    const uint32_t other_count = c == "joined" ? source : joined;
    if (vertex_count == other_count)
      return has + ": it looks like the " + other + " contract; this asset was baked with --vertices " + c + " (" +
             GroupThousands(baked) + " vertices): feed the " + c + " buffer" +
             (c == "joined" ? " (assimp: aiProcess_Triangulate | aiProcess_JoinIdenticalVertices)"
                            : " (assimp: aiProcess_Triangulate only)") +
             " or re-bake with --vertices " + other;
    return has + ": neither contract of this asset's mesh (joined " + GroupThousands(joined) + ", source " +
           GroupThousands(source) + " vertices; baked with --vertices " + c + "): a different mesh?";
  }
  return has + ", the asset's mesh " + GroupThousands(baked) + " (vertex contract " +
         (c.empty() ? std::string("unrecorded") : c) + ")";
}

}  // namespace spherechain::import
