// spherechain baker — the whole preprocessing stage (paper §3, §4, §5.1) in one call, its
// configuration and its readable report.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "spherechain/baker/chains.h"
#include "spherechain/baker/contacts.h"
#include "spherechain/baker/coverage.h"
#include "spherechain/baker/fit.h"
#include "spherechain/import/import.h"
#include "spherechain/baker/plausibility.h"
#include "spherechain/baker/regions.h"
#include "spherechain/baker/segment.h"
#include "spherechain/baker/write.h"

namespace spherechain::baker {

/// Bake configuration. JSON form (every key optional):
/// { "fit": "cover"|"paper", "max_spheres": 128, "cover_voxel_rel": 0.005, "cover_max_voxels": 140000,
///   "min_radius_rel": 0.003,
///   "min_gain": 0.0002, "region_balance": 0.5, "refine_sweeps": 4, "dilation_rel": 0.003,
///   "skin_spheres": (layout default: 16, extended 24), "skin_tolerance_rel": 0.01, "skin_min_vertices": 8, "medial_min_rel": 0.001,
///   "contact_margin_rel": 0.004, "fold_margin_rel": (layout default; -1 = none),
///   "near_rel": 0.005, "reach_rel": 0.003, "pivot_poses": 0, "pivot_pose_angle": 30,
///   "segmentation": "auto"|"rig"|"geometry"|"skeleton"|"map", "region_map": "map.json", "rig": "x.mhskel",
///   "regions": "extended"|"paper",
///   "rays": 80, "spheres_per_level": 2, "disk_step": 0.25, "disk_step_rel": 0.015,
///   "penetration_depth": 0.3, "chains": [{"name": "zeta0", "members": ["R0", "R4L", "R2"]}, ...] }
/// Which regions a standing biped gets: the paper's five, or those plus head, hands and feet as regions
/// of their own (segment.h SplitExtremities / ApplyExtremities; chains.h ExtendedChainDefs).
enum class RegionSet : uint8_t { kPaper, kExtended };

struct BakeConfig {
  SegmentMethod segmentation = SegmentMethod::kAuto;
  /// "regions": "extended" (default since 2026-11-24) or "paper" (the paper's five; CLI `bake --regions`).
  /// Extended applies to the cover fit of a standing biped (the paper fit and a creature keep their regions);
  /// parts a body lacks (HUMAN.blend's stump hands) stay in their limb. It comes with a fold margin
  /// (fold_margin_rel), which keeps an elbow's or a knee's spheres from crying wolf before the skin in the
  /// joint's pit meets, and a skin pass of 24 spheres instead of 16 (FitParams::skin_spheres' layout default).
  /// Against the paper layout on MakeHuman 40 / 160 frames, CesiumMan, BCN_Epileptic: region recall M2 100 / 97.6 /
  /// 98.6 / 96.0 % (paper 100 / 96.8 / 95.5 / 97.9), false-alarm frames 0 / 2 / 1 / 1 (0 / 2 / 5 / 0), bind
  /// coverage 89.6 / 88.7 / 90.1 % (90.1 / 88.7 / 90.4) (docs/evaluation.md "Default against the paper layout").
  RegionSet regions = RegionSet::kExtended;
  std::string region_map;  ///< [opt] with segmentation "map" (or set alone: implies "map")
  ImportOptions import;
  FitParams fit;
  std::vector<ChainDef> chains = DefaultChainDefs();
  bool compare_segmentations = true;  ///< rigged mesh: also segment by geometry and report agreement
  /// Contact margin stored in the asset (schema Asset.contact_margin), relative to the body height:
  /// detection tests spheres with radii grown by it (physics engines' contact offset / skin width).
  double contact_margin_rel = 0.004;
  /// Fold margin stored in the asset (Asset.fold_margin, runtime DetectJob::fold_margin), relative to the body
  /// height: a pair of spheres of one region is reported within 2 × this instead of 2 × contact_margin_rel.
  /// Unset: the layout's default — 0.0015 for a standing biped's extended regions (their elbows' and knees'
  /// spheres meet before the skin in the joint's pit: false-alarm frames 2 / 22 / 5 / 0 → 0 / 2 / 1 / 0 on
  /// MakeHuman 40 / 160 frames, CesiumMan, BCN_Epileptic, with the 16-sphere skin pass; docs/design.md
  /// "The fold margin"), none for the paper's five and creatures (where a limb region holds its hand or foot,
  /// and BCN_Epileptic's knee folds are found through those pairs). Negative: none (every pair on
  /// contact_margin_rel). [Limit: < 0, or [0, 0.05]]
  std::optional<double> fold_margin_rel;
  /// The crease (Asset.crease, runtime crease.h), relative to the body height: two triangles that intersect
  /// are a fold of the skin, not a self-contact, when their corners lie within crease_rel × body height of
  /// each other along the welded bind surface's edges, or within two triangle rings. Written with the bind
  /// positions (Asset.bind_positions) so the runtime applies it with no geodesics per frame.
  /// [Limit: (0, 0.5]; config key "crease_rel"]
  double crease_rel = 0.03;
  /// Write the skin weights per vertex (Asset.skin_counts / skin_joints / skin_weights: 3 bytes an
  /// influence, +134 KB for MakeHuman's 40,156) beside the crease rule, for the narrow phase's joint-matrix
  /// cull (runtime NarrowPhaseJob::joint_matrices). A rigged mesh only (none: nothing written).
  /// [config key "skin_weights"; CLI bake --skin-weights] Default off.
  bool skin_weights = false;
  /// Exclusions (cover fit): pairs whose spheres come within (near_rel + 2·contact_margin_rel) × body
  /// height of each other at bind pose are adjacent (chains.h BindExcludedPairs) — so nothing the
  /// margin reaches at bind pose is ever reported.
  double near_rel = 0.005;
  /// Reach regions (regions.h AddReachRegions, Asset.reach_offsets / reach_triangles): a triangle is
  /// behind every sphere of its region whose surface one of its corners lies within reach_rel × body
  /// height of at bind pose, besides its owner's. [Limit: 0..0.05; 0: corners inside the sphere]
  /// 0.003 (0.3 % of the height): docs/design.md "Reach regions" gives what it adds.
  double reach_rel = 0.003;
  /// Pivot choice refined against random poses of the rig (regions.h PivotTraining, training_poses.h):
  /// how many poses ("pivot_poses" [Limit: 0..256]; 0, the default, keeps the geometric choice alone;
  /// ignored without a skin; 24 is what docs/design.md "Pivots trained on poses" measures) and how far each joint
  /// turns ("pivot_pose_angle" [Units: degrees] [Limit: [0, 90]]). Opt-in: on the reference animations it
  /// trades sphere-pair recall for fewer false alarms on some bodies and not on others (measured there).
  uint32_t pivot_poses = 0;
  double pivot_pose_angle = 30.0;
  /// Write the asset even when a plausibility check fails (plausibility.h, issue 11 "no silent wrong
  /// bake"): the findings then go to BakeResult::plausibility, the report (errors with their codes) and
  /// the asset (schema Asset.forced_findings, which `spherechain validate` reports as errors). CLI
  /// `bake --force`. Not a configuration key and not in the configuration hash: it changes nothing the
  /// bake computes.
  bool force = false;
  PlausibilityLimits plausibility;  ///< bounds of the checks (plausibility.h defaults; not a JSON key)
};

/// Parses a JSON configuration file; records it in `ctx` (Context::files_read) once read. Errors: kIo,
/// kConfig (unknown key, wrong type, value out of range, a fraction for a whole-number key, a segmentation
/// method beside "region_map" — the message names the key).
Result<BakeConfig> LoadBakeConfig(const std::string& path, Context* ctx = nullptr);
/// Parses JSON text (as LoadBakeConfig) — `where` names the source in messages.
Result<BakeConfig> ParseBakeConfig(const std::string& json_text, const std::string& where);

/// The options a bake takes besides its configuration: `spherechain bake`'s command-line options and the
/// keywords of Python's `spherechain.bake(path, config, **options)`. Each one that is set overrides the
/// configuration's key of the same meaning (ApplyBakeOptions); empty strings and 0 leave it as configured.
struct BakeOptions {
  std::string regions;       ///< [opt] "extended" or "paper" (config "regions"; CLI --regions)
  /// [opt] "auto", "rig", "geometry", "skeleton" or "map" (config "segmentation"); a method overrides the
  /// configuration's region map too, and is refused beside `region_map`
  std::string segmentation;
  std::string region_map;    ///< [opt] JSON region map path (config "region_map"; implies "map")
  std::string vertices;      ///< [opt] "joined" or "source" (config "vertices"; assimp formats)
  std::string rig;           ///< [opt] MakeHuman .mhskel path (config "rig")
  double disk_step = 0.0;    ///< [opt] torso disk step δ [Units: source] [Limit: 0 (unset) or > 0, finite]
  bool force = false;        ///< write the asset although a plausibility check fails (BakeConfig::force)
  bool skin_weights = false;  ///< [opt] true: BakeConfig::skin_weights on (false leaves it as configured)
};

/// Applies `options` over `*config` (the configuration file's, or the defaults). Errors: kConfig, naming the
/// option: a value outside its choices, a disk step that is negative or not finite, segmentation "map" with
/// no region map in either, a segmentation method and `region_map` both given. `*config` is unspecified
/// after an error. The one place the CLI and Python turn options into a BakeConfig, so both bake the same
/// bytes from the same input and options.
Status ApplyBakeOptions(const BakeOptions& options, BakeConfig* config);

/// The canonical JSON of a configuration (stable key order), hashed into the asset. With `layout`, the
/// defaults that depend on it are written resolved (skin_spheres: SkinSpheres); without, as configured.
std::string CanonicalConfig(const BakeConfig& config, const RegionLayout* layout = nullptr);

/// Accuracy F of one sphere over its surrounding region's vertices for φ1, φ1', φ2.
struct SphereAccuracy {
  AccuracyStats phi1, phi1_adjusted, phi2;
};

/// Everything a bake produced.
struct BakeResult {
  Mesh mesh;
  uint32_t crease_components = 0;  ///< connected pieces of the welded bind surface (runtime CreaseGraph)
  Segmentation segmentation;
  std::optional<Segmentation> other_segmentation;      ///< the method not chosen, when compared
  std::optional<SegmentationAgreement> agreement;      ///< chosen vs other
  std::string other_segmentation_error;                ///< why the comparison could not run
  FitResult fit;
  std::vector<Ball> phi2;                              ///< \#S, minimum enclosing balls
  std::vector<Chain> chains;
  std::vector<SpherePair> excluded;
  std::vector<SpherePair> cross_region_bind_overlaps;
  ExclusionReasons exclusion_reasons;                  ///< cover fit: why pairs were excluded
  /// A creature's (the any-skeleton path): sphere pairs excluded because triangles of their surrounding
  /// regions already intersect at bind pose (horns, eyes, a tail's tuft modelled through the skin: the
  /// model's own interpenetration, never a collision), added to `excluded`.
  size_t bind_contact_exclusions = 0;
  /// A creature's: pairs of spheres of two limbs whose regions share skin (the neck and a fore leg at the
  /// chest), within 1.25 (rA + rB) + near at bind — the crease where they leave the trunk side by side.
  size_t limb_crease_exclusions = 0;
  std::optional<CoverageStats> coverage;               ///< bind-pose coverage of φ1' (absent: not measurable)
  CoverageOptions coverage_options;                    ///< what it was measured with
  SurroundingRegions surrounding;
  Pivots pivots;
  std::optional<CentreWeights> centre_weights;         ///< rigged mesh: the joint refit's (schema v3)
  std::vector<SphereAccuracy> sphere_accuracy;         ///< \#S
  AccuracySummary accuracy;
  std::vector<uint8_t> asset;                          ///< the .sphc bytes
  uint32_t unassigned_triangles = 0;
  MeshIssues mesh_issues;                              ///< degenerate triangles, non-manifold edges (kept)
  /// Failed plausibility checks, in the order they ran: empty unless BakeConfig::force let a failing
  /// body through (then also in the asset, Asset.forced_findings).
  std::vector<PlausibilityFinding> plausibility;
};

/// Runs import → segment → plausibility checks → fit → chains → surrounding regions → pivots → φ2 +
/// accuracy → coverage → PLAUS-OUTSIDE → asset (plausibility.h: CheckPlausibility on the chosen
/// segmentation and, for a rigged body, the rig/geometry agreement the bake measures anyway, before the
/// fit; CheckProtrusion once the coverage is measured). Nothing is written to disk. Stage timings go to
/// ctx->timings_ms ("plausibility" for the checks). Errors: those of each stage; kImplausible when a
/// check fails and config.force is not set — "INPUT: the bake looks wrong, refused (nothing written):
/// CODE: what and where; CODE: ...", every failed check of that point named. With config.force the bake
/// succeeds, the findings are in BakeResult::plausibility and the asset, and each is logged as a warning
/// on `ctx`.
/// Files: every file the bake read is added to ctx->files_read (the character file, glTF buffers and
/// images, whatever assimp opened, the MakeHuman rig and weights, the region map; LoadBakeConfig adds the
/// configuration when given the same Context): the inputs a build system's depfile names.
/// Threads: independent bakes may run at once on different threads, each with its own Context; the result
/// is the same bytes as a bake run alone (no global state; the parallel loops work in fixed chunks).
Result<BakeResult> Bake(const std::string& input_path, const BakeConfig& config, Context* ctx = nullptr);

/// The JSON bake report: vertices, triangles, spheres, regions{name: {triangles, spheres}}, chains[{name,
/// spheres}], unassigned_triangles, mesh_issues{degenerate_triangles, non_manifold_edges},
/// accuracy{phi1, phi1_adjusted, phi2: {mean_abs_F, rms_F, min_F,
/// max_F}}, per-sphere table, segmentation (method, agreement), plausibility{passed, forced, errors[{code,
/// severity "error", message}]} (errors non-empty only in a forced bake), timings_ms.
nlohmann::json MakeBakeReport(const BakeResult& result, const BakeConfig& config, const Context& ctx);

/// The paper's per-ray comparison (§6) for the torso spheres as CSV: for each torso sphere and each
/// of its rays, the distance from the disk centre to the surface hit and to where the ray leaves the
/// sphere for φ1, φ1' and φ2 (empty when the ray misses that sphere, or for the surface when the ray
/// leaves through an opening).
std::string TorsoRayCsv(const BakeResult& result);

}  // namespace spherechain::baker
