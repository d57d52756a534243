// spherechain baker — random poses of a rigged mesh, for choosing what follows the skin best.
#pragma once

#include <cstdint>
#include <vector>

#include "spherechain/baker/types.h"

namespace spherechain::baker {

/// How SampleTrainingPoses bends the skeleton.
struct TrainingPoseOptions {
  /// Number of poses [Limit: 0..256]; 0 gives none.
  uint32_t count = 24;
  /// Each skin joint's node turns about a random axis by an angle uniform in [0, max_angle_deg] in its
  /// own frame, on top of its rest rotation [Units: degrees] [Limit: [0, 90]].
  float max_angle_deg = 30.0f;
  /// Seed of the generator (SplitMix64): same seed, same poses, on every platform.
  uint64_t seed = 0x5eedc4a1;
};

/// Deformed copies of the bind positions under random poses of the mesh's own skeleton: every node that
/// a skin joint follows turns by a random rotation about its rest pivot (children follow), and the
/// vertices are skinned by linear blend skinning with the mesh's weights and inverse binds
/// (Σ_j w_j · G'(node_j) · inverse_bind_j · v, G' the posed global transforms). A vertex without
/// influence stays where it is. The poses are no animation of the character: they are a spread of the
/// bends its rig allows, for the baker to prefer what tracks the skin under any of them (ChoosePivots).
/// Returns \#poses buffers of \#V×3 floats (model space, source units). An unskinned mesh, or a skin whose
/// weight rows do not match the vertices, gives none (no error: the callers then keep the geometric
/// choice). Cost: O(count · (\#nodes + Σ influences)), count × \#V × 12 bytes. Deterministic.
std::vector<std::vector<float>> SampleTrainingPoses(const Mesh& mesh, const TrainingPoseOptions& options = {});

}  // namespace spherechain::baker
