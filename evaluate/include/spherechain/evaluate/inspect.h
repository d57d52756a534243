// spherechain evaluate — what an asset holds, as JSON: what `spherechain inspect --json` prints and Python's
// Asset.info() returns.
#pragma once

#include <nlohmann/json.hpp>

#include "spherechain/runtime/asset.h"

namespace spherechain::evaluate {

/// The asset `view` describes (a loaded, verified view; borrowed for the call) as JSON: schema version,
/// generator, counts (vertices, triangles, spheres), vertex contract, units, up axis, fingerprint (hex), parts,
/// regions (triangles and spheres per region; a creature's symbol, kind, bone, mirror), chains, excluded
/// pairs, joint refit, unassigned triangles, reach, bake parameters, φ1/φ1'/φ2 accuracy (schema
/// AccuracyStats), fit, contact and fold margins, bind coverage, forced plausibility findings. Fields an
/// older schema lacks are absent or null. Cost O(\#T + \#S); allocates the JSON.
nlohmann::json DescribeAsset(const runtime::AssetView& view);

}  // namespace spherechain::evaluate
