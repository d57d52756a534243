// spherechain import — the vertex contract an asset was baked with (Asset.vertex_contract, import.h
// VertexContract): re-importing a character the way its asset expects, and saying which contract a
// game's mismatching vertex buffer looks like.
#pragma once

#include <cstdint>
#include <string>

#include "spherechain/import/import.h"
#include "spherechain/runtime/asset.h"

namespace spherechain::import {

/// The contract to re-import `mesh_path` with so that it gives the buffer `view` was baked from:
/// Asset.vertex_contract "joined" → kJoined, "source" → kSource, "file" → kAuto. An asset baked before the
/// field existed read assimp files as is: kSource when `mesh_path` is read through assimp
/// (ReadThroughAssimp), else kAuto. `view` must be valid. O(1), no allocation beyond the result.
VertexContract ContractForReimport(const runtime::AssetView& view, const std::string& mesh_path);

/// "joined", "source", "file", or "unrecorded" (an asset baked before Asset.vertex_contract).
std::string AssetVertexContractName(const runtime::AssetView& view);

/// One clause for a vertex buffer of `vertex_count` vertices that the asset `view` (valid) refuses, naming
/// the contract it looks like from the counts the asset records (Asset.source_vertex_count /
/// joined_vertex_count), e.g. "the buffer has 2,633 vertices: it looks like the joined contract; this
/// asset was baked with --vertices source (15,378 vertices)". When the count is neither contract's, it
/// says so and gives both; for glTF / OBJ assets and assets without the counts it gives the two counts.
/// Empty when `vertex_count` equals the asset's fingerprint count (the mismatch is not the count).
/// Allocates the string only.
std::string DescribeVertexMismatch(const runtime::AssetView& view, uint32_t vertex_count);

/// `n` with thousands separators: 15378 → "15,378".
std::string GroupThousands(uint64_t n);

}  // namespace spherechain::import
