// spherechain baker — surrounding regions and pivot polygons (paper §5.1, Figure 9).
#pragma once

#include <array>
#include <vector>

#include "spherechain/baker/fit.h"
#include "spherechain/baker/segment.h"
#include "spherechain/baker/types.h"

namespace spherechain::baker {

/// The surrounding region of each sphere: the triangles assigned to it (§5.1: Δ_i ∈ ⊙_j iff ⊙_j's
/// centre is the nearest to Δ_i). Here the nearest is taken among the spheres of the triangle's own
/// region (so an arm triangle never belongs to a torso sphere), measuring from the centre (or the
/// surface, Ownership) to the triangle's centroid; a region without spheres falls back to all spheres.
/// A sphere may own no triangle (deep inside, another sphere always nearer): its pivots then come from
/// its neighbourhood (ChoosePivots).
struct SurroundingRegions {
  std::vector<uint16_t> triangle_spheres;  ///< \#T, owning sphere per triangle
  std::vector<uint32_t> offsets;           ///< \#S+1 into `triangles`
  std::vector<uint32_t> triangles;         ///< triangle indices grouped by sphere, ascending in a group
  /// Vertex indices of sphere s's surrounding region (unique, ascending), for accuracy and φ2.
  std::vector<uint32_t> Vertices(const Mesh& mesh, size_t sphere) const;
  /// Reach regions (AddReachRegions; empty when not built): per sphere, its surrounding region and every
  /// other triangle of its region with a corner within the reach of its surface at bind pose — the
  /// triangles behind the sphere when the proxy reports it (Asset.reach_offsets / reach_triangles: a
  /// narrow phase restricted to the proxy's pairs tests them). They overlap: a triangle near two spheres
  /// is behind both; `triangle_spheres` still names its one owner.
  std::vector<uint32_t> reach_offsets;    ///< \#S+1 into `reach_triangles`
  std::vector<uint32_t> reach_triangles;  ///< triangle indices grouped by sphere, ascending in a group
};

/// Which sphere of its region a triangle belongs to: the nearest centre (the paper, §5.1) or the
/// nearest sphere surface, ‖c − p‖ − r (the cover fit, whose spheres of very different sizes all
/// reach the skin: the sphere that reaches the triangle owns it).
enum class Ownership : uint8_t { kNearestCentre, kNearestSurface };

/// Assigns every triangle to a sphere. Cost: O(\#T · spheres per region). Errors: kFit when there is no
/// sphere at all.
Result<SurroundingRegions> BuildSurroundingRegions(const Mesh& mesh, const Segmentation& seg,
                                                   const std::vector<FittedSphere>& spheres,
                                                   Ownership ownership = Ownership::kNearestCentre);

/// Fills `regions->reach_offsets / reach_triangles`: sphere s's reach region is its surrounding region
/// plus the triangles of the same segmentation region with a corner v where ‖v − c_s‖ − r_s <= `reach`
/// [Units: source, >= 0] at bind pose (the bake's reach_rel × body height). On a coarse mesh a triangle
/// several centimetres across touches the skin of two or three spheres; owned by the one nearest its
/// centroid, its contact is behind that sphere only, while another of them is the one that overlaps
/// (CesiumMan's arms against the flank). Spheres with no region (kNoRegion) keep their surrounding
/// region. Cost: O(\#T · spheres per region). Deterministic.
void AddReachRegions(const Mesh& mesh, const Segmentation& seg, const std::vector<FittedSphere>& spheres, double reach,
                     SurroundingRegions* regions);

/// Four pivot polygons per sphere (§5.1, Figure 9 right) and their bind-pose frame data.
struct Pivots {
  std::vector<uint32_t> triangles;  ///< \#S×4 triangle indices
  std::vector<uint32_t> vertices;   ///< \#S×4×3 vertex indices of those triangles
  struct Frame {
    std::array<float, 3> local_center{};     ///< centre in the pivot frame (runtime BuildPivotFrame)
    std::array<float, 3> centroid_offset{};  ///< centre − mean of the pivot centroids
    float mean_distance = 0.0f;              ///< mean ‖c − p_k‖ over the four pivot centroids
  };
  std::vector<Frame> frames;  ///< \#S
  /// What the refinement against training poses did (ChoosePivots `training`; zeros without it).
  struct Training {
    uint32_t poses = 0;            ///< poses the choice was weighed against
    uint32_t spheres_changed = 0;  ///< spheres whose pivots differ from the geometric choice
    double error_before = 0.0;     ///< mean over spheres of the tracking error E, geometric choice [Units: source]
    double error_after = 0.0;      ///< the same after refinement (≤ error_before)
  } training;
};

/// What ChoosePivots weighs its choice against: random poses of the character's own rig
/// (SampleTrainingPoses), over which a choice should keep the sphere where the skin around it goes.
struct PivotTraining {
  /// \#P buffers of \#V×3 (model space, source units); not owned, read during ChoosePivots only. Any buffer of
  /// another size, or none, leaves the geometric choice as it is (Pivots::training stays zero).
  const std::vector<std::vector<float>>* poses = nullptr;
  /// The skin a sphere answers for: the vertices within `witness_reach` of its bind surface
  /// (|c − v| − r ≤ reach) [Units: source] [Limit: > 0]; the bake uses 2 % of the body height.
  double witness_reach = 0.0;
};

/// Chooses four pivot polygons per sphere, spread around it: in the plane perpendicular to the
/// sphere's axis (limbs: towards the next sphere of the sequence; torso: up; a creature's trunk:
/// RegionLayout::trunk_axis of `segmentation`'s layout) the four triangles of its
/// surrounding region whose centroids lie nearest the directions +u, +v, −u, −v and closest to the
/// sphere's level, each of non-negligible area. The frame they span is never degenerate: a choice
/// whose frame is ill-conditioned is replaced by the best-spread triangles of the sphere's
/// neighbourhood. Errors: kFit naming the sphere when no non-degenerate choice exists.
/// `segmentation` [opt]: its layout (null: the paper's five); when it carries joint regions (the
/// any-skeleton path, Segmentation::joint_regions) each sphere first looks for pivots among the triangles
/// whose corners have ≥ 90 % of their skin weight on its own region's bones — the skin that moves with it
/// (a trunk sphere at the hip otherwise follows the leg's skin there) — and takes any triangle only when
/// no well-spread four are found so.
/// `training` [opt]: with poses, each sphere's choice is then refined against them — coordinate descent
/// over the 8 best-placed triangles per direction (its surrounding region's and its own region's within
/// 1.5 r), keeping a change only when it lowers the tracking error E, the mean over the poses of
/// mean_i |ΔF_i| + max(0, max_i ΔF_i), with F_i = r − ‖c − v_i‖ over the sphere's witness vertices
/// (the paper's accuracy measure F, §3.2, bind vs refit pose) and the refit exactly as the runtime's
/// kPivotFrame (refit.h). Our method (no published source); the error is the paper's F. Cost:
/// O(\#S · 64 · \#P · witnesses ≤ 192), on all cores; deterministic.
Result<Pivots> ChoosePivots(const Mesh& mesh, const std::vector<FittedSphere>& spheres,
                            const SurroundingRegions& surrounding, const Segmentation* segmentation = nullptr,
                            const PivotTraining* training = nullptr);

/// Skin weights of every sphere's centre, for the refit from joint matrices (schema v3
/// Asset.joint_count / sphere_joints / sphere_joint_weights; runtime JointRefitJob).
struct CentreWeights {
  uint32_t joint_count = 0;    ///< \#J, the skin's joints
  std::vector<uint16_t> joints;  ///< \#S×4 joint indices, by descending weight (ties: lower index)
  std::vector<float> weights;    ///< \#S×4, >= 0, each sphere's four summing to 1; unused: joint 0, 0
};

/// Derivation: the mean of the skin weights (Skin rows) over the distinct vertices of sphere s's
/// surrounding region — the blend under which the region's average point moves —, the four largest
/// kept and renormalised to sum 1 (what a game's four-influence skinning keeps too). A sphere with an
/// empty surrounding region (or none of whose vertices has an influence) takes the mean over its 12
/// pivot vertices (`pivots`, chosen from its neighbourhood then); failing that, joint 0 with weight 1
/// (counted in `*unweighted`; the caller warns). Cost O(Σ region vertices · influences), deterministic. Errors: kConfig when the
/// mesh has no skin, its rows do not match its vertices, or it has more than 65,535 joints.
Result<CentreWeights> CentreSkinWeights(const Mesh& mesh, const SurroundingRegions& surrounding,
                                        const Pivots& pivots, uint32_t* unweighted = nullptr);

}  // namespace spherechain::baker
