// spherechain baker — sphere approximation of the regions (paper §3.1, §3.2), φ2 (Welzl 1991 via CGAL)
// and the accuracy measure F (§3.2).
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "spherechain/baker/segment.h"
#include "spherechain/baker/types.h"

namespace spherechain::baker {

/// Torso labels (Figure 6), a bitmask: a sphere may be both L and T.
enum TorsoLabel : uint8_t { kLabelL = 1, kLabelR = 2, kLabelT = 4, kLabelD = 8 };

/// How the regions are filled: "cover" (FitCover, the default) or "paper" (FitTubular + FitTorso, §3).
enum class FitMethod : uint8_t { kCover = 0, kPaper = 1 };
const char* FitMethodName(FitMethod m);

struct FitParams {
  FitMethod method = FitMethod::kCover;
  // --- cover fit (FitCover) ---
  int max_spheres = 128;              ///< sphere budget [Limit: 5..4096]
  double cover_voxel_rel = 1.0 / 200; ///< interior voxel edge / body height [Limit: 0.001..0.1]
  /// Budget of interior voxels for a creature (a segmentation whose RegionLayout is not the paper's): one
  /// with more at cover_voxel_rel (bulky along its longest extent, the voxels' scale: the Wuson, 267,000)
  /// is voxelised again with voxels larger by the cube root of the excess (× 1.02), so its fit costs what
  /// a human's does (MakeHuman 95,000 … mrfixit 132,000 interior voxels). The paper's bipeds, whose voxels
  /// scale with their height, get kBipedVoxelFactor times this budget: no standing body comes near it, a
  /// body lying down (its "height" its thickness: millions of voxels) does. 0: no budget for either.
  /// [Limit: >= 0] JSON "cover_max_voxels" (in the configuration hash only when not the default)
  int cover_max_voxels = 140'000;
  /// The paper's bipeds' voxel budget, in multiples of cover_max_voxels (see there).
  static constexpr int kBipedVoxelFactor = 4;
  double min_radius_rel = 0.003;      ///< smallest sphere radius / body height (fingers, toes: none)
  double min_gain = 0.0002;           ///< stop when the best sphere adds less than this (weighted share
                                      ///< of the body's volume, see region_balance) [Limit: 0..1]
  /// Gain of a voxel of region k: (V_k / V)^−balance / V, V_k its region's interior volume: 0 ranks
  /// spheres by the body volume they add, 1 by the share of their own region's. [Limit: 0..1]
  double region_balance = 0.5;
  int refine_sweeps = 4;              ///< optimisation sweeps (0: greedy only) [Limit: 0..64]
  double dilation_rel = 0.003;        ///< radii grown past the surface / body height [Limit: 0..0.05]
  /// Skin pass: spheres of the budget kept for the limb skin the volume cover leaves far from every
  /// sphere (hands, feet, elbows: little volume, much contact); kept only when the body has limbs.
  /// 0 turns it off. kSkinSpheresByLayout (the default): the layout's, SkinSpheres(). [Limit: −1..max_spheres−5]
  int skin_spheres = kSkinSpheresByLayout;
  /// skin_spheres' default: 16 for the paper's five regions and a creature's, 24 for a standing biped's extended
  /// regions, whose head, hands and feet bring more skin far from the volume cover (docs/design.md "Head, hands and
  /// feet": region recall on MakeHuman 160 frames / CesiumMan 94.5 → 97.6 % / 95.6 → 98.6 %).
  static constexpr int kSkinSpheresByLayout = -1;
  /// A limb vertex is uncovered when it lies more than this × body height outside every sphere of its
  /// region (radii with the dilation). [Limit: 0..0.2]
  double skin_tolerance_rel = 0.01;
  /// The skin pass stops when the best sphere would bring fewer uncovered vertices within tolerance.
  /// [Limit: 1..1e6]
  int skin_min_vertices = 8;
  /// Smallest medial ball the skin pass may take / body height. Its candidates include, behind each
  /// uncovered vertex, the ball centred halfway along the inward normal ray to the far skin (FitCover 6b),
  /// off the voxel grid — the spheres of fingers and toes a voxel or two thick. 1 (larger than any limb)
  /// leaves the voxel candidates alone. [Limit: 0.0001..1] JSON "medial_min_rel"
  double medial_min_rel = 0.001;
  // --- paper fit (FitTubular, FitTorso) ---
  int rays = 80;                    ///< N_r, rays of the torso disk [Limit: >= 8]
  int spheres_per_level = 2;        ///< N_s [Limit: 2]
  double disk_step = 0.0;           ///< δ [Units: source] ; 0 = disk_step_rel × height
  double disk_step_rel = 0.25 / 16.66;  ///< δ relative to the body height (0.25 on the 16.66-unit MakeHuman)
  double penetration_depth = 0.30;  ///< PD: neighbours overlap by PD·(r_a + r_b) [Limit: 0..0.9]
};

/// One fitted sphere ⊙ (bind pose, model space, source units).
struct FittedSphere {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< φ1' (adjusted; = φ1 for tubular regions)
  double radius = 0.0;
  Eigen::Vector3d center_phi1 = Eigen::Vector3d::Zero();  ///< φ1 before the adjustment
  double radius_phi1 = 0.0;
  /// φ2 (torso only): the minimum enclosing ball of `support_vertices` (Welzl 1991), for comparison;
  /// tubular regions: equal to φ1.
  Eigen::Vector3d center_phi2 = Eigen::Vector3d::Zero();
  double radius_phi2 = 0.0;
  Region region = Region::kTorso;
  uint8_t labels = 0;      ///< TorsoLabel bits (torso only)
  int sequence = 0;        ///< position along its region's sequence: limbs from the torso outwards,
                           ///< torso bottom-up by level (paper Figure 12)
  int level = -1;          ///< torso: ordinal of the chosen disk level, 0 = bottom; limbs: -1
  /// Cover fit, limbs: distance from the limb's root (where it joins the torso) to the centre, bind pose,
  /// source units — the key of `sequence`; 0 otherwise.
  double root_distance = 0.0;
  int column = -1;         ///< torso: 0 = character's left, 1 = right; limbs: -1
  /// Torso only: the disk's rays assigned to this sphere: ray index k (0..N_r-1), the disk centre and
  /// the surface hit distance along the ray (the paper's per-ray comparison, §6).
  Eigen::Vector3d disk_center = Eigen::Vector3d::Zero();
  std::vector<int> ray_ids;
  std::vector<Eigen::Vector3d> ray_dirs;
  std::vector<double> ray_hit;  ///< distance from disk_center to the ray's last exit from the torso
                                ///< surface [Units: source]; +inf: the ray missed
  /// Torso only: vertex indices of the triangles its rays hit (its part of the surrounding region,
  /// §3.2), sorted; the vertices over which F is measured for φ1, φ1' and φ2.
  std::vector<uint32_t> support_vertices;
};

struct FitResult {
  std::vector<FittedSphere> spheres;  ///< R0, R1, R2, R3 sequences, then the torso, in that order
  double body_height = 0.0;           ///< along the up axis, source units
  double disk_step = 0.0;             ///< δ actually used
};

/// Moving circumference (§3.1) for one tubular region: spheres centred in the limb's cross-section,
/// radius reaching the nearest surface of the region, neighbours overlapping by PD.
/// Base curve: graph-geodesic distance over the region's vertex graph from its root boundary (edges
/// shared with triangles outside the region, i.e. the torso; a free-standing region starts at one of
/// its boundary loops), level sets of width ~1.5 mean edges, each reduced to its largest connected
/// ring, centroids interpolated. A position fits when the sphere does not reach past the root or the
/// tip along the curve and its radius is above a quarter of the limb's median (skips the gaps between
/// fingers/toes). First sphere: the first fitting position; next: the first position whose centre
/// distance is ≥ (1 − PD)(r_prev + r); last: the last fitting position near the tip when not already
/// covered. Spheres ordered from the torso outwards; center = center_phi1 = center_phi2.
/// `region_triangles`: triangle indices of the region (mesh.indices / 3), bind pose, source units.
/// Errors: kFit (region empty, index out of range, PD outside [0, 0.9], degenerate region).
/// Cost: O(\#T log \#T) for the region plus a uniform-grid query a curve sample; allocates.
Result<std::vector<FittedSphere>> FitTubular(const Mesh& mesh, const std::vector<uint32_t>& region_triangles,
                                             Region region, const FitParams& params, Context* ctx = nullptr);

/// Disk of N_r rays moving up in steps of δ, N_s = 2 spheres per level, then the adjustment φ1' (§3.2),
/// and the L/R/T/D labels (Figure 6).
/// Frame: up = Mesh::up_axis; the character's left = centroid(R0) − centroid(R1) (else legs R2 − R3,
/// else +X for Y-up), horizontal; forward = left × up. Ray k points at θ = 2π(k + ½)/N_r from forward
/// towards left: rays 0..N_r/2−1 are the left half (column 0), the rest the right half (column 1).
/// Per level (heights hmin + δ/2 + kδ over the torso): disk centre = centre of the hits (iterated);
/// each ray records its last exit from the torso surface (inner surfaces such as the mouth do not
/// stop it); a half needs ≥ 40% of its rays to hit. φ1: centre = centroid of the half's hit points,
/// radius = distance to the nearest of the level's hit points and of the surrounding region (all
/// triangles any ray hit, 3-D) — inscribed. Levels are kept like FitTubular keeps positions (both
/// columns must clear (1 − PD)(r_prev + r)), first level at least ½ r above the bottom, last one
/// fitting under the top. φ1' (center/radius): centre moved from φ1 towards the disk centre by
/// t ∈ [0, 1], radius = median distance to support_vertices, t minimising mean |F| over them.
/// φ2 = MinimumEnclosingBall(support_vertices). Labels: L/R by column; T on levels between the lowest
/// and highest vertex shared by an arm and the torso (else the level nearest that band); D on the
/// bottom level. `seg` must match the mesh (\#T); it orients left/right and finds the shoulders.
/// Errors: kFit (empty torso, rays odd or < 8, N_s ≠ 2, PD outside [0, 0.9], δ ≤ 0, segmentation
/// size mismatch, no level with a closed cross-section). Cost: ~\#levels × N_r × \#triangles crossing a
/// level ray tests; allocates.
Result<std::vector<FittedSphere>> FitTorso(const Mesh& mesh, const std::vector<uint32_t>& torso_triangles,
                                           const Segmentation& seg, const FitParams& params,
                                           Context* ctx = nullptr);

/// The "cover" fit: spheres that fill each region, at most params.max_spheres in all.
/// Method (after Coverage Axis, Dou et al. 2022, and the coverage objective of variational sphere
/// sets, Wang et al. 2006):
/// 1. the body's interior as voxel centres of edge cover_voxel_rel × height (a creature's: coarser when
///    that gives more than cover_max_voxels interior voxels) (VoxelizeInterior: the
///    ray-parity test of MeasureCoverage, which tolerates open real meshes);
/// 2. for each interior voxel, the exact distance to the nearest triangle (CGAL AABB_tree) — the
///    radius of the largest ball centred there inside the surface — and the region of that triangle;
/// 3. candidates: voxels whose inscribed ball has radius ≥ min_radius_rel × height;
/// 4. lazy greedy set cover (Minoux 1978): repeatedly the candidate whose ball adds the largest share
///    of its own region's still-uncovered interior (so arms and legs are served like the torso), until
///    max_spheres or the best adds < min_gain; every region gets at least one sphere;
/// 5. optimisation: refine_sweeps passes of coordinate ascent — each sphere moves to the neighbouring
///    candidate voxel (26-neighbourhood, same region) whose ball adds most, while coverage grows;
/// 6. each centre pushed off the grid towards the medial axis while its inscribed radius grows;
/// 6b. skin pass (limbs, when skin_spheres > 0): the limb vertices more than skin_tolerance_rel × height
///    outside every sphere of their region are covered by lazy greedy set cover, each step the candidate
///    ball of their region that brings the most of them within tolerance (at least skin_min_vertices),
///    with the budget the volume cover left. Candidates: the interior voxels' balls within 3 % of the
///    height of an uncovered vertex, and the medial ball behind each uncovered vertex (at most 16,384,
///    strided): the ray along its inward normal (area-weighted face normals, oriented by the enclosed
///    volume's sign) to where it leaves the body through skin of the same region, its midpoint the centre,
///    the distance to the skin the radius, kept when ≥ medial_min_rel × height — the spheres of fingers
///    and toes a voxel or two thick, which hold no interior voxel (single-ray shape diameter, Shapira et
///    al. 2008; cf. Ma et al. 2012's medial points from normals). The extended layout's head gets at most
///    a quarter of the pass;
/// 6c. the budget the skin pass leaves goes back to the volume cover (4, the skin spheres counting as
///    cover);
/// 6d. redundant balls placed again: the coverage counts rebuilt from the final balls (off the grid), a
///    volume ball that covers less than min_gain on its own (two voxel centres that climbed to one
///    medial point in 6) gives its place back to the greedy, whose new ball stays on the grid when off it
///    it would land within a quarter radius of another; at most 4 rounds, a region's last ball kept, the
///    skin pass's balls kept; off when min_gain is 0.
/// Radii = distance to the surface + dilation_rel × height: the spheres touch the skin from inside, so
/// protrusion is only the dilation and the voxel sampling of the mesh. Order and labels: limbs from
/// the torso outwards (distance from the centroid of the vertices the limb shares with the torso);
/// torso bottom-up, then left to right, labelled L and/or R by the side of the torso's mid-plane
/// (within half a radius of it: both), T when the sphere spans a height of the arm–torso junction, D
/// when its bottom is below the top of the leg–torso junction (each label given to at least one
/// sphere); level = −1, column by side. center = center_phi1 = center_phi2.
/// `mesh`: bind pose, model space; `seg` must match it (\#T). Errors: kFit (parameters out of range,
/// segmentation size mismatch, a mesh that encloses almost no volume, a region with triangles but no
/// interior voxel or no sphere, a voxelisation error). A region without triangles gets no sphere. Cost: O(\#T log \#T + \#voxels + Σ candidate ball voxels
/// × lazy re-evaluations + \#uncovered limb vertices × (one ray and one closest-point query + the vertices
/// within a ball's reach)); allocates ~8 bytes a voxel of the bounding box. Adds "fit.cover.*" timings.
/// Deterministic on any number of cores (fixed chunks; the medial balls are computed per vertex).
/// The skin pass's budget FitCover uses: params.skin_spheres when >= 0, else (FitParams::kSkinSpheresByLayout)
/// 24 for a standing biped's extended regions (RegionLayout::paper, not the paper's five) and 16 otherwise.
int SkinSpheres(const FitParams& params, const RegionLayout& layout);

Result<std::vector<FittedSphere>> FitCover(const Mesh& mesh, const Segmentation& seg, const FitParams& params,
                                           Context* ctx = nullptr);

/// All five regions: with FitMethod::kCover, FitCover; with kPaper, FitTubular for R0..R3, then FitTorso; δ = params.disk_step, or disk_step_rel ×
/// the body height along Mesh::up_axis. Adds a "fit" timing to `ctx`. Errors: kFit (segmentation size
/// mismatch, a region's failure naming the region, an exception from CGAL turned into a message).
Result<FitResult> FitSpheres(const Mesh& mesh, const Segmentation& seg, const FitParams& params,
                             Context* ctx = nullptr);

/// φ2: the minimum enclosing ball of `points` (Welzl 1991, CGAL::Min_sphere_of_spheres_d). Exact up to
/// double rounding. Empty input gives radius 0 at the origin.
struct Ball {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 0.0;
};
Ball MinimumEnclosingBall(const std::vector<Eigen::Vector3d>& points);

/// F statistics (§3.2): F_i = r − ‖c − v_i‖ (positive: v_i inside the sphere).
struct AccuracyStats {
  double mean_abs_f = 0.0, rms_f = 0.0, min_f = 0.0, max_f = 0.0;
  size_t count = 0;
};
/// Adds the F values of `points` against sphere (c, r) to a running accumulation.
class AccuracyAccumulator {
 public:
  void Add(const Eigen::Vector3d& c, double r, const Eigen::Vector3d& v);
  AccuracyStats Stats() const;

 private:
  double sum_abs_ = 0, sum_sq_ = 0, min_ = 0, max_ = 0;
  size_t n_ = 0;
};

}  // namespace spherechain::baker
