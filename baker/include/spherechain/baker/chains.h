// spherechain baker — chain construction (paper §4, Table 1) and the adjacent (excluded) pairs (§5.2).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "spherechain/baker/fit.h"
#include "spherechain/baker/types.h"

namespace spherechain::baker {

/// A chain definition: a name and the sphere sets it unites. Member tokens:
/// "R0".."R3" (a whole tubular region), "R4" (the whole torso), "R4L", "R4R", "R4T", "R4D" (torso
/// spheres carrying that label, Figure 6). A creature's layout (RegionLayout::paper false): "R0".."R<n−1>"
/// or a region's name ("Tail", "trunk"); no labels.
struct ChainDef {
  std::string name;
  std::vector<std::string> members;
};

/// Table 1: ζ0 = R0 ∪ R4L ∪ R2, ζ1 = R1 ∪ R4R ∪ R3, ζ2 = R0 ∪ R4T ∪ R1, ζ3 = R2 ∪ R4D ∪ R3,
/// ζ4 = R0 ∪ R4T ∪ R4R ∪ R3, ζ5 = R1 ∪ R4T ∪ R4L ∪ R2.
std::vector<ChainDef> DefaultChainDefs();

/// Table 1 on the extended layout (head, hands and feet: segment.h ApplyExtremities): the same six chains,
/// each limb with the parts hanging off it (ζ0 = R0 ∪ left hand ∪ R4L ∪ R2 ∪ left foot, …; the torso's
/// labelled sets are the trunk's), and the head in ζ0, ζ1 and ζ2 — so a hand meets the face (ζ0, ζ1: its
/// own side's; ζ2: either), a hand the other arm and hand (ζ2, ζ4, ζ5), a foot the other leg and foot (ζ3).
/// Tokens are R<k> of `layout`. On the paper's five regions it returns DefaultChainDefs() unchanged.
std::vector<ChainDef> ExtendedChainDefs(const RegionLayout& layout);

/// A creature's chains (the any-skeleton path, whose limbs Table 1 does not know): one chain per pair of
/// limbs, "A+B" = R_a ∪ R_b, then one per limb with the trunk, "A+trunk" = R_a ∪ R_trunk — L(L+1)/2
/// chains for L ≤ 7 limbs; more limbs go in 7 groups of consecutive limbs (bone-tree order: a spider's
/// neighbouring legs together), chains pairing the groups, 28 in all (runtime::kMaxChains is 32). Every
/// pair of regions (and of spheres) shares at least one chain, so M1 tests every pair M2 tests (a limb's
/// own pairs and the trunk's in several chains; M1 reports them once per chain). Built from `layout`'s
/// names and symbols; Bake() uses them when the configuration keeps the default chains.
std::vector<ChainDef> CreatureChainDefs(const RegionLayout& layout);

/// A built chain ζ_i: sphere indices into the fitted sphere list, ascending, unique.
struct Chain {
  std::string name;
  std::vector<uint16_t> spheres;
};

/// Builds the chains; tokens name regions of `layout` (the paper's five by default). Errors: kConfig for an
/// unknown member token (a region the layout does not have; a torso label outside the paper's layout), a
/// chain with fewer than two spheres, more than 65,535 spheres, or no chain at all.
Result<std::vector<Chain>> BuildChains(const std::vector<FittedSphere>& spheres, const std::vector<ChainDef>& defs,
                                       const RegionLayout& layout = RegionLayout());

/// A pair of sphere indices, a < b.
using SpherePair = std::pair<uint16_t, uint16_t>;

/// Adjacent pairs, never reported by detection (§5.2 "two spheres collide when they are not adjacent"):
/// neighbours in a region's sequence (limbs: consecutive spheres; torso: the two spheres of a level and
/// consecutive levels of a column and across columns), and every pair that overlaps at the bind pose
/// (‖cA − cB‖ < rA + rB — the limb roots and the torso spheres they join, among others).
/// Sorted by (a, b), unique. `cross_region_bind_overlaps` [opt, out] receives the bind-overlapping
/// pairs whose regions are not a limb and the torso (e.g. a hand resting on a thigh), which the report
/// flags because such contacts are then never reported.
std::vector<SpherePair> ExcludedPairs(const std::vector<FittedSphere>& spheres,
                                      std::vector<SpherePair>* cross_region_bind_overlaps = nullptr);

/// Why BindExcludedPairs excluded its pairs (each pair counted once, under the first reason that holds).
struct ExclusionReasons {
  size_t limb_neighbour = 0;  ///< consecutive spheres of a limb's sequence
  size_t limb_side_by_side = 0;  ///< same limb, |root_distance_A − root_distance_B| < rA + rB: two spheres of
                                 ///< one stretch of the tube (their skins face away from each other; a
                                 ///< flexing joint moves them together without any fold of skin on skin)
  size_t torso_side_by_side = 0;  ///< two torso spheres whose heights (along the up axis) differ by less than
                                  ///< the larger radius: one level of the torso, side by side (a bending
                                  ///< spine folds one level onto another, not a level onto itself; the
                                  ///< skin between them moves them together at the hips and armpits)
  size_t bind_overlap = 0;    ///< ‖cA − cB‖ < rA + rB at bind pose
  size_t bind_near = 0;       ///< ‖cA − cB‖ < rA + rB + near at bind pose (they nearly touch)
  size_t junction = 0;        ///< a limb sphere and a sphere of the region it hangs off (the torso; in the
                              ///< extended layout a hand's arm, a foot's leg: RegionInfo::parent) with
                              ///< ‖cA − cB‖ < 1.25 (rA + rB) + near: the crease of the hip, armpit, wrist or
                              ///< ankle, where flexing folds skin on skin
  size_t trunk_fold = 0;      ///< two trunk spheres with ‖cA − cB‖ < 1.25 (rA + rB) + near when the head is a
                              ///< region of its own (the extended layout): the belly or the small of the
                              ///< back, which a bending spine folds skin on skin (MakeHuman's hip-level and
                              ///< belly spheres, 1.4–2.6 % of the height apart at bind, overlap by up to
                              ///< 1.2 % bent over the thighs with no skin meeting; BCN_Epileptic's belly
                              ///< likewise). With the head in the torso (the paper's five) the chin meets
                              ///< the chest through such pairs, so there they stay tested
  size_t sibling_crease = 0;  ///< spheres of two limbs hanging off the same region (both legs off the torso),
                              ///< each within rA + rB of its limb's root (FittedSphere::root_distance), with
                              ///< ‖cA − cB‖ < 1.25 (rA + rB) + near: the crotch, where closing the legs
                              ///< presses the inner thighs' skin (MakeHuman's thigh-top spheres, 1.56 % of the
                              ///< height apart at bind, met with nothing of the legs within 1 % as they crossed)
};

/// Adjacent pairs from bind-pose geometry and the limb sequences (the "cover" fit's rule): consecutive
/// spheres of a tubular region's sequence, limb spheres side by side along the limb
/// (FittedSphere::root_distance within rA + rB), torso spheres side by side on one level (heights along
/// `up` within the larger radius: on CesiumMan's walk the hip-level torso spheres, 1.5–1.8 % of the
/// height apart at bind, met in 5 of 40 frames with no skin within 1 %), the junction and sibling creases
/// (ExclusionReasons), the trunk's folds where the head is a region of its own, and every pair whose spheres overlap or come within `near`
/// (source units, ≥ 0) of each other at the bind pose — at those places the skin folds onto itself
/// when the joint bends, without anything meeting. No fixed ±k window: spheres of one region that are
/// apart at bind pose are tested (a bending spine, an elbow folding the forearm onto the upper arm).
/// Sorted by (a, b), unique. `reasons` [opt, out] counts them by reason; `cross_region_bind_overlaps`
/// [opt, out] as ExcludedPairs (bind-overlapping pairs of two different regions other than a limb and
/// the torso). `layout` [opt]: the regions' meaning (nullptr: the paper's five, torso R4 along `up`); a
/// creature's layout makes its trunk the torso and RegionLayout::trunk_axis its up. Cost: O(\#S²).
std::vector<SpherePair> BindExcludedPairs(const std::vector<FittedSphere>& spheres, double near,
                                          ExclusionReasons* reasons = nullptr,
                                          std::vector<SpherePair>* cross_region_bind_overlaps = nullptr,
                                          UpAxis up = UpAxis::kY, const RegionLayout* layout = nullptr);

}  // namespace spherechain::baker
