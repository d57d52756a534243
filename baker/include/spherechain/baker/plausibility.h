// spherechain baker — "no silent wrong bake" (issue 11): plausibility checks on a segmentation and its
// fitted spheres, each finding with a stable code. Bake() refuses a body that fails one unless
// BakeConfig::force is set (then the asset is written and the report and the asset, Asset.forced_findings,
// carry the findings as errors).
#pragma once

#include <string>
#include <vector>

#include "spherechain/baker/coverage.h"
#include "spherechain/baker/segment.h"
#include "spherechain/baker/types.h"

namespace spherechain::baker {

/// One failed check. Codes (stable):
///   PLAUS-LIMB-PIECES    a limb region is not one connected piece (triangles joined through welded vertices;
///                        loose parts — pieces that share no vertex with any other region, a mesh component
///                        of their own such as a tail's tuft or an eye — are not counted)
///   PLAUS-LIMB-DETACHED  a limb region shares no (welded) vertex with the torso (a creature's trunk)
///   PLAUS-LIMB-BALANCE   left and right arm (or leg) differ too much in area or in length; a creature's
///                        limbs paired by name (RegionInfo::mirror: HindLeg_L and HindLeg_R)
///   PLAUS-HEAD-IN-LIMB   the top of the body above the torso's centre (the head) is mostly a limb region
///                        (the paper's layout only: a standing body)
///   PLAUS-TRUNK-AXIS     the torso region's principal axis is far from the up axis (a horizontal trunk;
///                        the paper's layout only — Bake() with segmentation auto then tries the
///                        any-skeleton path on a rigged body)
///   PLAUS-OUTSIDE        too much of the spheres' volume lies outside the body (coverage.h protrusion)
///   PLAUS-SEG-AGREE      rig and geometry segmentations disagree on too many triangles
struct PlausibilityFinding {
  std::string code;
  std::string message;  ///< what was measured against which bound, region names included
};

/// Bounds of the checks. Defaults pass the reference bodies (MakeHuman, CesiumMan, BCN_Epileptic,
/// human.zae, mrfixit.iqm) with margin and fail the constructed wrong segmentations of the tests.
struct PlausibilityLimits {
  double limb_area_balance = 0.4;     ///< [Limit: 0..1] min/max of left vs right area, below: BALANCE
  double limb_length_balance = 0.6;   ///< [Limit: 0..1] min/max of left vs right length (principal extent)
  double head_limb_share = 0.5;       ///< [Limit: 0..1] share of the head's area in limb regions, above: HEAD
  double head_radius_rel = 0.06;      ///< the head column's radius around the torso's centre / body height
  double head_depth_rel = 0.08;       ///< the head band: this far below the top of the body / body height
  double trunk_tilt_deg = 45.0;       ///< [Units: degrees] torso principal axis vs up, above: TRUNK-AXIS
  double max_protrusion = 0.35;       ///< [Limit: 0..1] CoverageStats::protrusion, above: OUTSIDE
  double min_agreement = 0.6;         ///< [Limit: 0..1] SegmentationAgreement::triangle_fraction, below: SEG-AGREE
};

/// Runs every check that applies: the limb/head/trunk checks on `seg` of `mesh` (valid, as after
/// Segment); OUTSIDE when `coverage` is given [opt]; SEG-AGREE when `agreement` is given [opt] (a rigged
/// body compared with its geometry segmentation). Empty = plausible. Units: relative to the body height
/// along Mesh::up_axis. Cost O(\#V + \#T) plus the welded graph (segment_internal.h); allocates; pure.
std::vector<PlausibilityFinding> CheckPlausibility(const Mesh& mesh, const Segmentation& seg,
                                                   const CoverageStats* coverage,
                                                   const SegmentationAgreement* agreement,
                                                   const PlausibilityLimits& limits = {});

/// PLAUS-OUTSIDE alone (the check CheckPlausibility runs when given `coverage`): appends the finding to
/// `out` when coverage.protrusion > limits.max_protrusion. Bake() runs the other checks right after
/// segmentation — a refused body costs no fit — and this one once the spheres' coverage is measured.
void CheckProtrusion(const CoverageStats& coverage, const PlausibilityLimits& limits,
                     std::vector<PlausibilityFinding>* out);

}  // namespace spherechain::baker
