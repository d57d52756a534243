#include "spherechain/playback/character.h"

#include <cstdio>

#include "spherechain/import/import.h"
#include "spherechain/import/vertex_contract.h"

namespace spherechain::playback {

namespace {

std::string Hex(uint64_t v) {
  char b[24];
  std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(v));
  return b;
}

}  // namespace

Status CheckFingerprint(const runtime::AssetView& view, const Mesh& mesh, const std::string& asset_path,
                        const std::string& mesh_path) {
  const import::Fingerprint f = import::ComputeFingerprint(mesh);
  const auto* af = view.asset->fingerprint();
  const std::string pair = "mesh '" + mesh_path + "' does not match asset '" + asset_path + "': ";
  if (f.vertex_count != af->vertex_count())
    return MakeError(Error::Code::kInvalidMesh,
                     pair + "the mesh has " + std::to_string(f.vertex_count) + " vertices, the asset was baked from " +
                         std::to_string(af->vertex_count()) + " (" + import::DescribeVertexMismatch(view, f.vertex_count) + ")");
  if (f.triangle_count != af->triangle_count())
    return MakeError(Error::Code::kInvalidMesh, pair + "the mesh has " + std::to_string(f.triangle_count) +
                                                    " triangles, the asset was baked from " +
                                                    std::to_string(af->triangle_count()));
  if (f.positions_hash != af->positions_hash() || f.indices_hash != af->indices_hash())
    return MakeError(Error::Code::kInvalidMesh,
                     pair + "same counts but different content (positions hash " + Hex(f.positions_hash) + " vs " +
                         Hex(af->positions_hash()) + ", indices hash " + Hex(f.indices_hash) + " vs " +
                         Hex(af->indices_hash()) + "); re-bake the asset from this mesh");
  return Ok{};
}

Status ImportMeshForAsset(const runtime::AssetView& view, const std::string& asset_name, const std::string& mesh_path,
                          const std::string& rig_path, Mesh* mesh, import::Context* log) {
  import::ImportOptions opts;
  opts.rig_path = rig_path;
  opts.vertices = import::ContractForReimport(view, mesh_path);  // the buffer the asset was baked from
  auto imported = import::ImportMesh(mesh_path, opts, log);
  if (!imported.ok())
    return MakeError(imported.error().code, import::ToString(imported.error()));
  *mesh = std::move(imported).value();
  return CheckFingerprint(view, *mesh, asset_name, mesh_path);
}

Status OpenCharacter(const std::string& asset_path, const std::string& mesh_path, const std::string& rig_path,
                     import::LoadedAsset* asset, Mesh* mesh, import::Context* log) {
  if (auto s = import::LoadAssetFile(asset_path, asset); !s.ok()) return s;
  return ImportMeshForAsset(asset->view, asset_path, mesh_path, rig_path, mesh, log);
}

}  // namespace spherechain::playback
