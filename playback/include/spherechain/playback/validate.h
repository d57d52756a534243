// spherechain playback — asset validation for C++ callers (a game's asset CI): is this .sphc loadable,
// is it consistent, does it belong to this mesh, is its bind pose free of self-collision? Returns
// findings (stable code, severity, location, message); `spherechain validate` prints exactly these.
//
// Codes (stable; new ones may be added):
//   SPHC-LOAD       error    the bytes are not a loadable asset (unreadable file, runtime::LoadAsset's
//                            status); for a semantic rejection the location names the offending sphere,
//                            chain or field where it can be found
//   PLAUS-*         error    the bake failed this plausibility check and was written with --force
//                            (Asset.forced_findings; the code is the check's, baker plausibility.h:
//                            PLAUS-LIMB-PIECES, -LIMB-DETACHED, -LIMB-BALANCE, -HEAD-IN-LIMB,
//                            -TRUNK-AXIS, -OUTSIDE, -SEG-AGREE); location field "forced_findings"
//   SPHERE-NO-CHAIN warning  a sphere in no chain: M1 (§5.2) never tests it (M2 does)
//   SPHERE-NO-REGION warning a sphere whose surrounding region (§5.1) is empty: the narrow phase can
//                            never confirm a contact of it
//   MESH-IMPORT     error    the mesh file could not be imported
//   FP-COUNTS       error    mesh vertex/triangle counts differ from the asset's fingerprint (a vertex
//                            count says which vertex contract, joined or source, the buffer looks like)
//   FP-INDICES      error    same counts, different triangle indices (re-bake)
//   FP-POSITIONS    error    same counts and indices, different bind positions (moved vertices; play,
//                            evaluate, view and check refuse the pair)
//   RUNTIME         error    the runtime refused the bind-pose refit/detect (status in the message)
//   BIND-COLLISION  error    two spheres overlap at the bind pose (M2, the asset's contact margin): a
//                            correct proxy reports nothing for the undeformed character
// The hash and bind-pose checks run only when the counts match.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "spherechain/import/import.h"
#include "spherechain/import/types.h"
#include "spherechain/runtime/asset.h"

namespace spherechain::playback {

/// How bad a finding is: an error makes the asset invalid (the CLI exits 1), a warning does not.
enum class Severity : uint8_t { kWarning, kError };
/// "warning" / "error".
const char* ToString(Severity s);

/// Where a finding is. Every member is optional (-1 / empty = not applicable).
struct FindingLocation {
  std::string file;          ///< the asset or mesh path (or the name the caller gave the bytes)
  int32_t sphere = -1;       ///< sphere index (Asset.spheres)
  int32_t other_sphere = -1; ///< the second sphere of a pair (BIND-COLLISION), > sphere
  int32_t chain = -1;        ///< chain index (Asset.chains)
  std::string field;         ///< schema field, e.g. "spheres.radius", "chains.spheres"
  /// One line for people: "spheres 3,11" for a pair, else the file followed by " sphere 3",
  /// " chain 2", " field spheres.radius" as present (the file alone when nothing else is set).
  std::string ToString() const;
};

/// One finding.
struct Finding {
  std::string code;                     ///< stable code (table above)
  Severity severity = Severity::kError;
  FindingLocation location;
  std::string message;                  ///< what is wrong and, where known, what to do
};

/// Names used in locations and messages (paths, or anything the caller calls its bytes).
struct ValidateNames {
  std::string asset = "asset";
  std::string mesh = "mesh";
};

/// Validates a loaded, verified asset (`view` from runtime::LoadAsset; [Limit: view.valid()], else one
/// SPHC-LOAD finding) and, when `mesh` is given [opt], that it belongs to that mesh (fingerprint) and
/// that its bind pose (mesh->positions, refit then M2 detect at the asset's contact margin) reports no
/// sphere pair. Findings in a fixed order: the asset's own (forced bake findings, then by sphere, then chain), then the mesh's,
/// then bind collisions in the runtime's documented pair order; empty = valid, no warnings.
/// Ownership: reads `view` and `mesh` during the call only. Cost: O(\#S + \#chains·\#S + Σ region sizes)
/// plus, with a mesh, one fingerprint hash (O(\#V + \#T)), one runtime Model + Workspace Init and one refit/detect
/// (allocates; thread-safe for distinct arguments). Never throws except std::bad_alloc.
std::vector<Finding> ValidateAsset(const runtime::AssetView& view, const import::Mesh* mesh,
                                   const ValidateNames& names = {});

/// As above from raw asset bytes (any alignment: copied into aligned storage): a LoadAsset failure is
/// one SPHC-LOAD finding "'<names.asset>' is not a loadable .sphc asset: <status>", located, for a
/// semantic rejection (status 0x8000'02xx, the buffer itself verified), at the first offending sphere,
/// chain or field found by re-checking the arrays (kErrorRadius, kErrorNonFinite of a sphere,
/// kErrorChainOrder, kErrorIndexOutOfRange in a chain, kErrorContactMargin, kErrorMissingField,
/// kErrorCountMismatch name what they can). `bytes` may be null only with `size` 0.
std::vector<Finding> ValidateAssetBytes(const uint8_t* bytes, size_t size, const import::Mesh* mesh,
                                        const ValidateNames& names = {});

/// What `spherechain validate` does: reads `asset_path` (SPHC-LOAD with the reader's message when it
/// cannot), and with a non-empty `mesh_path` imports it (`rig_path`: MakeHuman .mhskel, empty =
/// default; MESH-IMPORT on failure, no clips read) and validates against it. `log` [opt] receives the
/// importer's log lines. `vertices` [opt]: the vertex contract to import an assimp-format mesh with
/// (the buffer the game feeds); kAuto = the one the asset records (baker vertex_contract.h
/// ContractForReimport). A buffer of the other contract is an FP-COUNTS error saying so.
std::vector<Finding> ValidateAssetFile(const std::string& asset_path, const std::string& mesh_path = {},
                                       const std::string& rig_path = {}, import::Context* log = nullptr,
                                       import::VertexContract vertices = import::VertexContract::kAuto);

/// Number of findings of severity kError (the asset is valid when 0).
size_t CountErrors(const std::vector<Finding>& findings);

}  // namespace spherechain::playback
