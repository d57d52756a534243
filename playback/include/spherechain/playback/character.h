// spherechain playback — opening a character for playback: its baked asset (verified) and the mesh it was
// baked from (imported under the asset's vertex contract), checked to belong together by fingerprint
// (DESIGN.md: a mismatched pairing is an error, never a silent wrong answer).
#pragma once

#include <string>

#include "spherechain/import/file_io.h"
#include "spherechain/playback/types.h"
#include "spherechain/runtime/asset.h"

namespace spherechain::playback {

/// The mesh must be the one the asset was baked from (schema Fingerprint): counts, then the XXH3 hashes of
/// positions and indices. Errors: kInvalidMesh "mesh '<mesh_path>' does not match asset '<asset_path>': …"
/// (which count differs, with the vertex contract the count looks like, or both hashes).
Status CheckFingerprint(const runtime::AssetView& view, const Mesh& mesh, const std::string& asset_path,
                        const std::string& mesh_path);

/// Imports `mesh_path` (`rig_path`: a MakeHuman .mhskel for an OBJ, empty = default.mhskel beside it) with the
/// vertex contract the loaded asset `view` records (import::ContractForReimport) into `mesh`, and checks their
/// fingerprints (`asset_name` names the asset in messages). Errors: the importer's, with its code in the message
/// ("format: …"); CheckFingerprint's. `log` [opt] receives the importer's log lines. Cost: one import.
Status ImportMeshForAsset(const runtime::AssetView& view, const std::string& asset_name, const std::string& mesh_path,
                          const std::string& rig_path, Mesh* mesh, import::Context* log = nullptr);

/// Loads the asset at `asset_path` (import::LoadAssetFile: read, aligned, verified) into `asset`, imports
/// `mesh_path` (`rig_path`: a MakeHuman .mhskel for an OBJ, empty = default.mhskel beside it) with the vertex
/// contract the asset records (import::ContractForReimport) into `mesh`, and checks their fingerprints.
/// Errors: those of LoadAssetFile (kIo, kFormat); the importer's, with its code in the message
/// ("format: …"); CheckFingerprint's (ImportMeshForAsset). `log` [opt] receives the importer's log lines.
/// Cost: one asset read, one import.
Status OpenCharacter(const std::string& asset_path, const std::string& mesh_path, const std::string& rig_path,
                     import::LoadedAsset* asset, Mesh* mesh, import::Context* log = nullptr);

}  // namespace spherechain::playback
