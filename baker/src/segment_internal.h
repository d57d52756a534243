// spherechain baker — helpers shared by the segmentation files (segment.cpp, segment_rig.cpp,
// segment_geometry.cpp). Not installed.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <string>
#include <vector>

#include "spherechain/baker/segment.h"
#include "spherechain/baker/types.h"

namespace spherechain::baker::segment_detail {

/// Vertex `v` as a double vector (model space, source units).
inline Eigen::Vector3d Position(const Mesh& mesh, uint32_t v) {
  return {mesh.positions[3 * v + 0], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]};
}

/// Unit vector of Mesh::up_axis.
Eigen::Vector3d UpVector(UpAxis axis);

/// Indices in range and at least one triangle; kInvalidMesh otherwise.
Status CheckMeshForSegmentation(const Mesh& mesh);

/// Vertex adjacency for *analysis only*: vertices at the same position (UV / normal seams, split glTF
/// primitives, mirrored halves, triangle soups such as `.x` read with --vertices source) are welded to
/// one representative (the lowest index): positions within 1e-6 of the bounding-box diagonal of each
/// other (per coordinate), transitively; edges come from the triangles. So parts meeting at coincident
/// positions are one body for segmentation. Nothing in the mesh is changed (the asset keeps the
/// source's indices). Cost O(#V log #V) (sorted grid of 64 eps cells), O(#T) for the edges plus sorting each
/// vertex's short row.
struct WeldedGraph {
  std::vector<uint32_t> rep;      ///< #V: representative vertex of each vertex (rep[rep[v]] == rep[v])
  std::vector<uint32_t> offsets;  ///< #V+1 CSR over representatives (rows of non-representatives empty)
  std::vector<uint32_t> adj;      ///< neighbour representatives
  std::vector<uint8_t> used;      ///< #V: 1 when a representative is referenced by a triangle
  std::vector<double> area;       ///< #V: a third of the incident triangles' area, on representatives
};
WeldedGraph BuildWeldedGraph(const Mesh& mesh);

/// Area of each triangle (source units²).
std::vector<double> TriangleAreas(const Mesh& mesh);

/// Connected-component cleanup so that each limb region is one connected piece (triangles connected
/// through shared welded vertices): for each limb region every piece but the largest (by area) moves to
/// the region it touches most (the torso when it touches nothing); then every torso piece but the
/// largest that touches a single limb only (an island enclosed by that limb) joins that limb.
/// Appends what it did to `notes`. `layout` says which region is the trunk and how many there are (the
/// paper's five by default; region values must be below layout.count()). `keep_loose_parts`: a limb
/// piece that touches no other region at all (a mesh component of its own: a tail's tuft, an eye, a
/// claw) keeps its region instead of going to the torso (the any-skeleton path, where such parts are
/// skinned to the limb they belong to).
void MakeLimbsConnected(const Mesh& mesh, std::vector<uint8_t>& triangle_regions, std::string& notes,
                        const RegionLayout& layout = RegionLayout(), bool keep_loose_parts = false);

/// Fills Segmentation::vertex_regions from triangle_regions: a vertex takes the majority region of its
/// incident triangles (ties go to the lowest region value); kNoRegion when unreferenced. Regions of
/// seg.layout.
void ComputeVertexRegions(const Mesh& mesh, Segmentation& seg);

/// Bone-name rules (segment_rig.cpp): the region a bone's weights go to, or nullopt for a limb bone
/// with no side in its name. Tokens split at non-alphanumerics, case and digit changes; side tokens
/// l/left, r/right; clavicle / collar / shoulder / scapula / breast / pelvis → torso (the arm is cut at
/// the armpit, as the geometric method does); arm/elbow/wrist/hand/finger/thumb/metacarpal → arm;
/// leg/thigh/knee/calf/shin/foot/ankle/toe/heel and a *sided* hip → leg; anything else → torso.
std::optional<Region> RegionOfBone(std::string_view bone_name);

/// The extremity a bone skins (SplitExtremities' rig rule): a sided arm bone named like a hand
/// (hand, wrist, finger, thumb, index, middle, ring, pinky, metacarpal, palm), a sided leg bone named
/// like a foot (foot, toe, ankle, heel, ball); kNone otherwise (the head is found by geometry).
Extremity ExtremityOfBone(std::string_view bone_name);

/// "R0 left_arm 1234, R1 ..." summary for notes and logs (names from `layout`).
std::string RegionCounts(const std::vector<uint8_t>& triangle_regions, const RegionLayout& layout = RegionLayout());

/// Lower-case alphanumeric tokens of a bone or region name, split at other characters, lower→upper case
/// changes and letter↔digit changes ("HindLeg_L_01" → hind, leg, l, 01).
std::vector<std::string> NameTokens(std::string_view name);

/// Sets RegionInfo::mirror of a layout's limbs: two limbs whose names differ only by a side token
/// (l/left/lft against r/right/rgt) are a pair ("HindLeg_L" and "HindLeg_R"); first match in order.
void PairMirrorLimbs(RegionLayout& layout);

/// The principal axis (unit, largest component positive) of the corners of the triangles of region
/// `trunk`, area-weighted; Mesh::up_axis when the region is empty. Bind pose, model space.
std::array<double, 3> TrunkAxis(const Mesh& mesh, const std::vector<uint8_t>& triangle_regions, Region trunk);

}  // namespace spherechain::baker::segment_detail
