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
#include "spherechain/import/file_io.h"
#include "spherechain/baker/types.h"

namespace spherechain::baker {

/// The baker's name and version, written into every asset (Asset.generator). Bump the version when the
/// baker's output for the same input changes: `spherechain check` keys its cache of bakes on it.
inline constexpr const char* kGenerator = "spherechain-baker 0.2.0";

/// Overall accuracy (schema Accuracy).
struct AccuracySummary {
  AccuracyStats phi1, phi1_adjusted, phi2;
};

/// Everything the asset holds, by reference. Spheres are written as float32.
struct AssetInputs {
  const Mesh* mesh = nullptr;
  const Segmentation* segmentation = nullptr;
  const FitResult* fit = nullptr;
  const std::vector<Ball>* phi2 = nullptr;  ///< \#S
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
  const std::vector<float>* bind_positions = nullptr;  ///< Asset.bind_positions (\#V×3); null: left out
  double crease = -1.0;                             ///< Asset.crease [Units: source]; <= 0: left out
  bool skin_weights = false;  ///< Asset.skin_* from mesh->skin (with the crease and centre_weights only)
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

}  // namespace spherechain::baker
