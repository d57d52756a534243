// spherechain baker — segmentation into the paper's five regions (§3, Figure 1).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "spherechain/baker/types.h"

namespace spherechain::baker {

struct Segmentation {
  std::vector<uint8_t> triangle_regions;  ///< \#T, Region value per triangle (never kNoRegion on success)
  std::vector<uint8_t> vertex_regions;    ///< \#V, Region per vertex (kNoRegion for unreferenced vertices)
  std::string method;                     ///< "rig", "geometry", "map" or "skeleton"
  std::string notes;                      ///< human-readable diagnostics (pose found, cut heights, ...)
  /// What the region values mean: the paper's five (rig, geometry, a plain map) or a creature's limbs
  /// and trunk (skeleton; a map that names its regions).
  RegionLayout layout;
  /// The any-skeleton path: the region of each skin joint (\#joints, Skin::joints order; a bone of no limb
  /// is the trunk's); empty for the other methods. ChoosePivots (regions.h) puts a creature's pivots on
  /// skin its own region's bones move.
  std::vector<uint8_t> joint_regions;
};

/// kSkeleton: the any-skeleton path (SegmentBySkeleton), for rigged creatures that are not standing bipeds.
enum class SegmentMethod : uint8_t { kAuto, kRig, kGeometry, kSkeleton };

/// Segments from skin weights and bone-name rules (arm/hand/finger/clavicle → arm? see segment_rig.cpp;
/// side from `.L`/`_L`/`Left`/...; legs from thigh/leg/knee/foot/toe; everything else torso).
/// Each limb region is then reduced to its largest connected piece (the rest joins the torso).
/// Errors: kSegmentation when the mesh has no skin or a limb's bones cannot be found.
Result<Segmentation> SegmentByRig(const Mesh& mesh, Context* ctx = nullptr);

/// Segments a standing body (A-pose, T-pose or arms-down) with no rig, from geometry alone.
/// `up` is the standing direction. Errors: kSegmentation "not a standing body: ..." when two legs and
/// two arms cannot be found.
Result<Segmentation> SegmentByGeometry(const Mesh& mesh, Context* ctx = nullptr);

/// Bounds of the any-skeleton path.
struct SkeletonOptions {
  /// A branch of the bone tree is a limb when its bones move at least this share of the body's surface
  /// (skin weights × vertex area); smaller branches stay with the region they hang from. A junction is
  /// a bone where three such branches meet. [Limit: (0, 0.5)] Wuson: legs 7–10 %, tail 12 %, ears 1–2 %.
  double limb_min_share = 0.03;
};

/// The any-skeleton path (issue 11): segments a rigged creature that is not a standing biped
/// (quadrupeds, many-legged creatures, tails, necks, wings) from its bone tree and skin weights, into a
/// creature RegionLayout: limbs R0..R(n−2) (the branches off the trunk: legs, tail, neck and head...),
/// trunk R(n−1). Method (segment_skeleton.cpp): each bone's share of the surface (skin weights × vertex
/// area); junctions, bones where three branches of at least `limb_min_share` meet; the trunk, the
/// smallest subtree of bones joining the junctions; a limb per branch off the trunk of at least
/// `limb_min_share`, with everything below it; triangles by the region of largest summed weight over
/// their corners; each limb one connected piece (as SegmentByRig); limbs left without a triangle
/// dropped. Limbs are numbered in bone-tree order, named from their bones (common stem of the main
/// chain, else the bone moving the most surface: "HindLeg_L", "Tail", "Neck"; unique), paired left/right
/// by names that differ only in a side token; layout.trunk_axis is the trunk's principal axis.
/// Errors: kSegmentation "segment (skeleton): the mesh has no skin: ..." (no rig), "segment (skeleton): no
/// recognisable limbs: ..." (fewer than three weighted bones, no junction, more than kMaxRegions − 1
/// limbs, a trunk or fewer than two limbs left with triangles) — the message names the bones.
/// Cost O(\#V·influences + \#bones + \#T·\#regions) plus MakeLimbsConnected; allocates.
Result<Segmentation> SegmentBySkeleton(const Mesh& mesh, const SkeletonOptions& options = {}, Context* ctx = nullptr);

/// Reads a user region map: a JSON file {"triangle_regions": [r0, r1, ...]} with \#T values, or
/// {"vertex_regions": [...]} with \#V values (a triangle takes its vertices' majority). A value is a region
/// index, its symbol ("R2") or its name ("left_leg"); the regions are the paper's five, or with
/// "regions": ["Tail", "Leg_L", ..., "trunk"] (3..kMaxRegions unique names, the trunk last) a creature's
/// layout (limbs paired left/right by name, trunk_axis measured).
/// Errors: kIo, kConfig (wrong length, a value out of range or naming no region — the message lists the
/// map's regions —, a bad or repeated "regions" name).
Result<Segmentation> SegmentByMap(const Mesh& mesh, const std::string& map_path, Context* ctx = nullptr);

/// kAuto: rig when the mesh has a skin whose bones are recognised, else geometry.
Result<Segmentation> Segment(const Mesh& mesh, SegmentMethod method, Context* ctx = nullptr);

/// Head, hands and feet: the parts the paper keeps inside the torso, the arms and the legs (its stated
/// limitation), which `regions: extended` gives spheres and chains of their own.
enum class Extremity : uint8_t { kNone = 0, kHead = 1, kLeftHand = 2, kRightHand = 3, kLeftFoot = 4, kRightFoot = 5 };
inline constexpr int kExtremityCount = 5;
/// "head", "left_hand", "right_hand", "left_foot", "right_foot"; "none" otherwise.
const char* ExtremityName(Extremity e);

/// How SplitExtremities finds each part: by bone names where the rig has them (kAuto falls back to
/// geometry per kind of part), by geometry only, or by the rig only (parts it cannot name stay whole).
enum class ExtremityMethod : uint8_t { kAuto, kRig, kGeometry };

struct ExtremitySplit {
  std::vector<uint8_t> triangle_parts;  ///< \#T, Extremity per triangle (kNone: stays in its region)
  /// Per Extremity value (index 1..5): "rig", "geometry", or empty when the part was not found.
  std::array<std::string, kExtremityCount + 1> method;
  std::string notes;  ///< cut positions and triangle counts, for the report
};

/// Cuts head, hands and feet out of a five-region segmentation `seg` (bind pose, standing along
/// Mesh::up_axis; `seg` must match the mesh, \#T). A hand / foot is only ever cut from its own arm /
/// leg, the head from the torso.
/// - rig (kAuto, kRig; hands and feet): triangles whose corners' skin weights are more than half on
///   bones named like the part (hand, wrist, finger, thumb, metacarpal, palm / foot, toe, ankle, heel,
///   ball: segment_internal.h ExtremityOfBone), when both sides have such bones;
/// - geometry (kAuto, kGeometry; the head always): the narrowest cross-section — area-weighted RMS
///   radius of the welded vertices, binned (12–48 bins, ~6 vertices a bin) — where the part joins the
///   rest: the wrist along the arm's geodesic distance from its junction with the torso (55–92 % of
///   the way to the fingertips), the ankle along the up axis (the leg's lowest 3–30 %), the neck along
///   the up axis (5–60 % of the way from the top of the arms' junction to the top of the body). The
///   part must widen past the cut (by 1.2× for a palm, 1.3× for a foot or a head), else it is not
///   there (CesiumMan's mitten arms have no hands). A triangle is beyond the cut when two corners are.
/// Errors: kSegmentation when `seg` does not match the mesh. A part that cannot be found is left in
/// its region (ExtremitySplit::method empty; `notes` says why). Cost O(\#V log \#V + \#T); allocates.
Result<ExtremitySplit> SplitExtremities(const Mesh& mesh, const Segmentation& seg,
                                        ExtremityMethod method = ExtremityMethod::kAuto, Context* ctx = nullptr);

/// Turns a five-region segmentation into the extended layout (`regions: extended`, issue 11): the parts
/// `split` found become regions of their own — R0..R3 stay the arms and legs, then head, left_hand,
/// right_hand, left_foot, right_foot (those found, in that order), the torso last. RegionLayout::paper
/// stays true (a standing biped: Table 1's chains, extended by ExtendedChainDefs; torso labels); hands
/// and feet mirror each other and hang off their arm / leg (RegionInfo::parent), the head off the torso.
/// A part that was not found stays in its region. Segmentation::vertex_regions is recomputed and a
/// summary appended to `notes`. Errors: kSegmentation when `seg` is not the paper's five regions or
/// `split` does not match it (\#T). No-op (Ok) when nothing was found.
Status ApplyExtremities(const Mesh& mesh, const ExtremitySplit& split, Segmentation* seg);

/// Fraction of triangles (area-weighted) on which two segmentations agree, overall and per region
/// (IoU per region). Both must have the same triangle count.
struct SegmentationAgreement {
  double triangle_fraction = 0.0;            ///< agreeing triangles / \#T
  double area_fraction = 0.0;                ///< agreeing area / total area
  std::array<double, kRegionCount> iou{};    ///< per region: |A∩B| / |A∪B| by triangle count
};
SegmentationAgreement CompareSegmentations(const Mesh& mesh, const Segmentation& a, const Segmentation& b);

}  // namespace spherechain::baker
