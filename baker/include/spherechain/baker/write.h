// spherechain baker — the .sphc asset (schemas/spherechain.fbs) and atomic file output.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "spherechain/baker/chains.h"
#include "spherechain/baker/coverage.h"
#include "spherechain/baker/fit.h"
#include "spherechain/baker/plausibility.h"
#include "spherechain/baker/regions.h"
#include "spherechain/baker/segment.h"
#include "spherechain/baker/types.h"

namespace spherechain::baker {

/// Source fingerprint (schema Fingerprint): counts and XXH3-64 of the bind positions (#V×3 float32)
/// and indices (#T×3 uint32) as read.
struct Fingerprint {
  uint32_t vertex_count = 0;
  uint32_t triangle_count = 0;
  uint64_t positions_hash = 0;
  uint64_t indices_hash = 0;
};
Fingerprint ComputeFingerprint(const Mesh& mesh);

/// Weld ids (schema Asset.weld_ids) of bind positions `positions` (#V×3): for every vertex the lowest
/// vertex index whose position compares equal (==, so +0 and −0 weld) — UV seams and triangle soups
/// get the adjacency a narrow phase needs to skip triangles that share a corner. Nothing is merged:
/// the index buffer keeps the source's vertices. Cost O(#V log #V), deterministic.
std::vector<uint32_t> ComputeWeldIds(const std::vector<float>& positions);

/// XXH3-64 of arbitrary bytes (the canonical bake configuration, ...).
uint64_t Hash64(const void* data, size_t size);

/// Overall accuracy (schema Accuracy).
struct AccuracySummary {
  AccuracyStats phi1, phi1_adjusted, phi2;
};

/// Everything the asset holds, by reference. Spheres are written as float32.
struct AssetInputs {
  const Mesh* mesh = nullptr;
  const Segmentation* segmentation = nullptr;
  const FitResult* fit = nullptr;
  const std::vector<Ball>* phi2 = nullptr;  ///< #S
  const std::vector<Chain>* chains = nullptr;
  const std::vector<SpherePair>* excluded = nullptr;
  const SurroundingRegions* surrounding = nullptr;
  const Pivots* pivots = nullptr;
  const CentreWeights* centre_weights = nullptr;  ///< [opt] Asset.joint_count / sphere_joints / _weights
  AccuracySummary accuracy;
  FitParams params;
  uint64_t config_hash = 0;
  double contact_margin = 0.0;                      ///< Asset.contact_margin [Units: source]
  double fold_margin = -1.0;                        ///< Asset.fold_margin [Units: source]; < 0: left out
  const CoverageStats* coverage = nullptr;          ///< [opt] Asset.coverage
  float coverage_voxel_rel = 0.0f;                  ///< the voxel edge it was measured with / height
  /// [opt] Asset.forced_findings: plausibility checks the bake failed and was forced past (bake --force).
  /// Null or empty: the field is left out (the asset is byte-identical to one baked before the field).
  const std::vector<PlausibilityFinding>* forced_findings = nullptr;
};

/// Serialises the asset. Deterministic: the same inputs give the same bytes (no timestamps, no
/// pointers, no unordered containers). The buffer is FlatBuffers-aligned from its start. Schema version:
/// runtime::kPaperSchemaVersion (3) for a segmentation of the paper's five regions; for a creature's
/// layout (RegionLayout::paper false) runtime::kSchemaVersion (4) with Asset.regions from
/// Segmentation::layout (names, kinds, mirrors, first bones).
std::vector<uint8_t> BuildAsset(const AssetInputs& in);

/// Writes `bytes` to `path` atomically: a temporary file in the same folder, flushed, then renamed over
/// `path`. On any failure the temporary is removed and `path` is untouched. Errors: kIo.
Status WriteFileAtomic(const std::string& path, const void* bytes, size_t size);
inline Status WriteFileAtomic(const std::string& path, const std::string& text) {
  return WriteFileAtomic(path, text.data(), text.size());
}

/// Reads a whole file. Errors: kIo. `max_size` caps what is read (kIo "file too large").
Result<std::vector<uint8_t>> ReadFileBytes(const std::string& path, size_t max_size = size_t(1) << 31);

}  // namespace spherechain::baker
