#include "spherechain/runtime/status.h"

namespace spherechain::runtime {

const char* ToString(Status s) {
  switch (s) {
    case Status::kOk: return "kOk";
    case Status::kOkTruncated: return "kOkTruncated: success, but the output buffer was too small";
    case Status::kErrorNullArgument: return "kErrorNullArgument: a required pointer is null";
    case Status::kErrorAlignment: return "kErrorAlignment: a pointer below its documented alignment (asset bytes 8, positions and joint matrices 4, "
                                         "caller memory of InitInPlace 16)";
    case Status::kErrorInvalidJob: return "kErrorInvalidJob: job fields inconsistent (model or workspace not initialised, bad mode)";
    case Status::kErrorVertexCount: return "kErrorVertexCount: positions count differs from the asset's vertex count";
    case Status::kErrorStride: return "kErrorStride: positions stride must be >= 12 and a multiple of 4";
    case Status::kErrorOutOfMemory: return "kErrorOutOfMemory: model or workspace allocation failed";
    case Status::kErrorNonFinitePositions: return "kErrorNonFinitePositions: a deformed vertex position is NaN or infinite";
    case Status::kErrorAssetTooSmall: return "kErrorAssetTooSmall: asset truncated (smaller than a FlatBuffer header)";
    case Status::kErrorAssetTooLarge: return "kErrorAssetTooLarge: asset larger than kMaxAssetBytes";
    case Status::kErrorIdentifier: return "kErrorIdentifier: not a .sphc asset (file_identifier is not SPHC)";
    case Status::kErrorVersionTooOld: return "kErrorVersionTooOld: asset schema_version is older than this SDK reads (re-bake)";
    case Status::kErrorVersionTooNew: return "kErrorVersionTooNew: asset schema_version is newer than this SDK";
    case Status::kErrorCorrupt: return "kErrorCorrupt: FlatBuffers verification failed (truncated or corrupted)";
    case Status::kErrorMissingField: return "kErrorMissingField: a required asset field is absent";
    case Status::kErrorNoSpheres: return "kErrorNoSpheres: the asset has no spheres";
    case Status::kErrorTooManySpheres: return "kErrorTooManySpheres: more than kMaxSpheres spheres";
    case Status::kErrorTooManyChains: return "kErrorTooManyChains: more than kMaxChains chains, or more than kMaxChainPairs candidate pairs in them";
    case Status::kErrorCountMismatch: return "kErrorCountMismatch: array lengths disagree (#S, #T, 4#S, 12#S)";
    case Status::kErrorIndexOutOfRange: return "kErrorIndexOutOfRange: a sphere, triangle or vertex index is out of range";
    case Status::kErrorOffsets: return "kErrorOffsets: surrounding_offsets or reach_offsets malformed";
    case Status::kErrorNonFinite: return "kErrorNonFinite: NaN or infinite value in the asset";
    case Status::kErrorRadius: return "kErrorRadius: a sphere radius is <= 0";
    case Status::kErrorPivotFrame: return "kErrorPivotFrame: PivotFrame.mean_distance is <= 0, or so small that radius / mean_distance overflows";
    case Status::kErrorChainOrder: return "kErrorChainOrder: chain spheres not strictly ascending";
    case Status::kErrorContactMargin: return "kErrorContactMargin: Asset.contact_margin is negative";
    case Status::kErrorSkinWeights:
      return "kErrorSkinWeights: a sphere's joint weights are negative, not finite, nonzero after a zero or do not sum to 1, or a vertex's skin weights do not sum to 1";
    case Status::kErrorBindPoseTangled:
      return "kErrorBindPoseTangled: the bind pose passes through itself beyond the narrow phase's budget (a broken mesh)";
    case Status::kErrorCreaseTooWide:
      return "kErrorCreaseTooWide: the crease reaches too much of the bind surface from each vertex (a bind pose "
             "collapsed onto a few points, a mesh far denser than its crease, or a vertex shared by thousands of triangles)";
    case Status::kErrorRegions:
      return "kErrorRegions: Asset.regions malformed (count, one trunk last, or a region value past them)";
    case Status::kErrorJointCount:
      return "kErrorJointCount: the joint matrix count differs from the asset's Asset.joint_count";
    case Status::kErrorNonFiniteJoints: return "kErrorNonFiniteJoints: a joint matrix holds a NaN or an infinity";
    case Status::kErrorWorkspaceModel:
      return "kErrorWorkspaceModel: the workspace was made for another model (nothing written)";
    case Status::kErrorBufferTooSmall: return "kErrorBufferTooSmall: caller memory smaller than RequiredBytes()";
    case Status::kErrorFrameTangled:
      return "kErrorFrameTangled: the frame's skin passes through itself beyond the narrow phase's budget (positions "
             "that are no pose of this character: uninitialised, collapsed or scrambled)";
    case Status::kErrorExcludedPairs: return "kErrorExcludedPairs: excluded pairs not a < b or not strictly ascending";
  }
  return "unknown status";
}

}  // namespace spherechain::runtime
