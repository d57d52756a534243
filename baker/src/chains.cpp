#include "spherechain/baker/chains.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>

#include "geometry.h"

namespace spherechain::baker {

std::vector<ChainDef> DefaultChainDefs() {
  return {
      {"zeta0", {"R0", "R4L", "R2"}},
      {"zeta1", {"R1", "R4R", "R3"}},
      {"zeta2", {"R0", "R4T", "R1"}},
      {"zeta3", {"R2", "R4D", "R3"}},
      {"zeta4", {"R0", "R4T", "R4R", "R3"}},
      {"zeta5", {"R1", "R4T", "R4L", "R2"}},
  };
}

std::vector<ChainDef> ExtendedChainDefs(const RegionLayout& layout) {
  // Each limb token of Table 1 brings the parts hanging off it (an arm its hand, a leg its foot); the
  // torso's labelled sets are the trunk's; the head joins the chains of both sides and the arms' chain.
  const int trunk = int(layout.trunk());
  auto limb = [&](int paper_region) {
    std::vector<std::string> m{RegionSymbol(Region(paper_region))};
    for (int k = 0; k < layout.count(); ++k)
      if (layout.regions[size_t(k)].parent == paper_region) m.push_back(RegionSymbol(Region(k)));
    return m;
  };
  auto torso = [&](char label) { return std::string(RegionSymbol(Region(trunk))) + label; };
  const int head = layout.Find("head");
  std::vector<ChainDef> defs;
  for (const ChainDef& d : DefaultChainDefs()) {
    ChainDef e{d.name, {}};
    for (const std::string& token : d.members) {
      if (token.size() == 2 && token[1] >= '0' && token[1] <= '3') {
        for (const std::string& m : limb(token[1] - '0')) e.members.push_back(m);
      } else {
        e.members.push_back(torso(token.back()));
      }
    }
    // ζ0 (left side), ζ1 (right side), ζ2 (both arms): a hand meets the face.
    if (head >= 0 && (d.name == "zeta0" || d.name == "zeta1" || d.name == "zeta2"))
      e.members.push_back(RegionSymbol(Region(head)));
    defs.push_back(std::move(e));
  }
  return defs;
}

std::vector<ChainDef> CreatureChainDefs(const RegionLayout& layout) {
  // Limbs in groups of consecutive limbs (one limb a group up to 7 limbs: 28 chains), so the chains stay
  // within the runtime's 32 (runtime::kMaxChains): g groups give g(g + 1)/2 chains.
  const int limbs = layout.count() - 1;
  const int groups = std::min(limbs, 7);
  std::vector<std::vector<int>> group(size_t(std::max(groups, 0)));
  for (int l = 0; l < limbs; ++l) group[size_t(l * groups / limbs)].push_back(l);
  auto members = [&](const std::vector<int>& g, std::string* name) {
    std::vector<std::string> m;
    for (int l : g) {
      m.push_back(RegionSymbol(Region(l)));
      *name += (name->empty() ? "" : "+") + layout.regions[size_t(l)].name;
    }
    return m;
  };
  std::vector<ChainDef> defs;
  for (int a = 0; a < groups; ++a)
    for (int b = a + 1; b < groups; ++b) {
      ChainDef d;
      d.members = members(group[size_t(a)], &d.name);
      for (const std::string& m : members(group[size_t(b)], &d.name)) d.members.push_back(m);
      defs.push_back(std::move(d));
    }
  for (int a = 0; a < groups; ++a) {
    ChainDef d;
    d.members = members(group[size_t(a)], &d.name);
    d.name += "+" + layout.regions.back().name;
    d.members.push_back(RegionSymbol(layout.trunk()));
    defs.push_back(std::move(d));
  }
  return defs;
}

namespace {

// The region a chain token names: "R<k>" (k < layout.count()) or a region's name; -1 otherwise.
// `label` receives the torso label of "R<trunk>L/R/T/D" (the paper's layout only), else 0.
int TokenRegion(const std::string& token, const RegionLayout& layout, uint8_t* label) {
  *label = 0;
  size_t digits = 0;
  while (1 + digits < token.size() && std::isdigit(static_cast<unsigned char>(token[1 + digits]))) ++digits;
  if (token.size() >= 2 && token[0] == 'R' && digits > 0 && digits <= 2 && (token.size() == 1 + digits || token.size() == 2 + digits)) {
    const int k = std::stoi(token.substr(1, digits));
    if (k >= layout.count()) return -1;
    if (token.size() == 1 + digits) return k;
    if (!layout.paper || !layout.IsTrunk(Region(k))) return -1;
    switch (token.back()) {
      case 'L': *label = kLabelL; return k;
      case 'R': *label = kLabelR; return k;
      case 'T': *label = kLabelT; return k;
      case 'D': *label = kLabelD; return k;
      default: return -1;
    }
  }
  for (int k = 0; k < layout.count(); ++k)
    if (token == layout.regions[size_t(k)].name) return k;
  return -1;
}

}  // namespace

Result<std::vector<Chain>> BuildChains(const std::vector<FittedSphere>& spheres, const std::vector<ChainDef>& defs,
                                       const RegionLayout& layout) {
  if (defs.empty()) return MakeError(Error::Code::kConfig, "no chain is defined");
  if (spheres.size() > 0xFFFF) return MakeError(Error::Code::kConfig, "more than 65,535 spheres");
  std::vector<Chain> chains;
  for (const ChainDef& def : defs) {
    Chain chain{def.name, {}};
    for (const std::string& token : def.members) {
      uint8_t label = 0;
      const int region = TokenRegion(token, layout, &label);
      if (region < 0) {
        const std::string last = std::to_string(layout.count() - 1);
        const std::string trunk = layout.paper ? RegionSymbol(layout.trunk()) : std::string();  // its labels
        return MakeError(Error::Code::kConfig,
                         "chain '" + def.name + "': unknown member '" + token + "' (expected R0..R" + last +
                             (layout.paper ? ", " + trunk + "L, " + trunk + "R, " + trunk + "T or " + trunk + "D"
                                           : " or a region name of the layout") + ")");
      }
      for (size_t i = 0; i < spheres.size(); ++i)
        if (static_cast<int>(spheres[i].region) == region && (label == 0 || (spheres[i].labels & label) != 0))
          chain.spheres.push_back(static_cast<uint16_t>(i));
    }
    std::sort(chain.spheres.begin(), chain.spheres.end());
    chain.spheres.erase(std::unique(chain.spheres.begin(), chain.spheres.end()), chain.spheres.end());
    if (chain.spheres.size() < 2)
      return MakeError(Error::Code::kConfig, "chain '" + def.name + "' has fewer than two spheres");
    chains.push_back(std::move(chain));
  }
  return chains;
}

std::vector<SpherePair> ExcludedPairs(const std::vector<FittedSphere>& spheres,
                                      std::vector<SpherePair>* cross_region_bind_overlaps) {
  std::set<SpherePair> pairs;
  const size_t n = spheres.size();
  auto add = [&](size_t a, size_t b) {
    if (a == b) return;
    if (a > b) std::swap(a, b);
    pairs.emplace(static_cast<uint16_t>(a), static_cast<uint16_t>(b));
  };
  for (size_t a = 0; a < n; ++a) {
    for (size_t b = a + 1; b < n; ++b) {
      const FittedSphere& A = spheres[a];
      const FittedSphere& B = spheres[b];
      const bool same_region = A.region == B.region;
      // Sequence neighbours, and the next-but-one: spheres around a joint (elbow, knee, wrist) are
      // small and dense, and folding the joint makes i and i+2 meet though no surface interpenetrates.
      if (same_region && IsTubular(A.region) && std::abs(A.sequence - B.sequence) <= 2) add(a, b);
      // Torso: the same level, and levels up to two apart (a bending spine folds the torso onto itself).
      if (same_region && A.region == Region::kTorso && A.level >= 0 && B.level >= 0 &&
          std::abs(A.level - B.level) <= 2)
        add(a, b);
      // Overlap at the bind pose — and, across a limb's junction with the torso, near-overlap: a limb
      // root and the torso spheres around the hip or shoulder come within half their radii sum at the
      // bind pose and touch as soon as the joint flexes, with no surface interpenetrating.
      const double d = (A.center - B.center).norm();
      const bool limb_torso_pair = (A.region == Region::kTorso) != (B.region == Region::kTorso);
      const double junction_margin = limb_torso_pair ? 0.5 * (A.radius + B.radius) : 0.0;
      if (limb_torso_pair && d < A.radius + B.radius + junction_margin) add(a, b);
      if (d < A.radius + B.radius) {
        add(a, b);
        const bool limb_torso = (A.region == Region::kTorso) != (B.region == Region::kTorso);
        if (!same_region && !limb_torso && cross_region_bind_overlaps)
          cross_region_bind_overlaps->emplace_back(static_cast<uint16_t>(a), static_cast<uint16_t>(b));
      }
    }
  }
  return {pairs.begin(), pairs.end()};
}

std::vector<SpherePair> BindExcludedPairs(const std::vector<FittedSphere>& spheres, double near,
                                          ExclusionReasons* reasons,
                                          std::vector<SpherePair>* cross_region_bind_overlaps, UpAxis up_axis,
                                          const RegionLayout* layout) {
  std::vector<SpherePair> pairs;
  ExclusionReasons why;
  // The torso (a creature's trunk, whose axis stands for up) and its axis.
  const Region torso = layout ? layout->trunk() : Region::kTorso;
  const Eigen::Vector3d up = layout && !layout->paper
                                 ? Eigen::Vector3d(layout->trunk_axis[0], layout->trunk_axis[1], layout->trunk_axis[2])
                                 : fit_detail::UpVector(up_axis);
  // Two regions joined at a junction: a limb and the region it hangs off (the torso; a hand's arm, a foot's
  // leg in the extended layout).
  auto parent_of = [&](Region r) { return layout ? layout->Parent(r) : torso; };
  auto joined = [&](Region a, Region b) {
    return a != b && ((a != torso && parent_of(a) == b) || (b != torso && parent_of(b) == a));
  };
  // Two limbs hanging off the same region (both legs off the torso at the crotch, both arms off it).
  auto siblings = [&](Region a, Region b) {
    return a != b && a != torso && b != torso && parent_of(a) == parent_of(b);
  };
  // The head a region of its own (the extended layout): the trunk's levels meet only where it folds.
  const bool head_apart = layout && layout->paper && !layout->IsPaperFive() && layout->Find("head") >= 0;
  const size_t n = spheres.size();
  for (size_t a = 0; a < n; ++a) {
    for (size_t b = a + 1; b < n; ++b) {
      const FittedSphere& A = spheres[a];
      const FittedSphere& B = spheres[b];
      const bool same_region = A.region == B.region;
      const double d = (A.center - B.center).norm(), rr = A.radius + B.radius;
      const SpherePair p{static_cast<uint16_t>(a), static_cast<uint16_t>(b)};
      if (same_region && A.region != torso && std::abs(A.sequence - B.sequence) == 1) {
        ++why.limb_neighbour;
      } else if (same_region && A.region != torso && std::abs(A.root_distance - B.root_distance) < rr) {
        ++why.limb_side_by_side;  // one cross-section of the tube: no fold brings their skins together
      } else if (same_region && A.region == torso &&
                 std::abs(A.center.dot(up) - B.center.dot(up)) < std::max(A.radius, B.radius)) {
        ++why.torso_side_by_side;  // one level of the torso: a bending spine folds levels, not a level
      } else if (d < rr) {
        ++why.bind_overlap;
        if (!same_region && !joined(A.region, B.region) && cross_region_bind_overlaps) cross_region_bind_overlaps->push_back(p);
      } else if (d < rr + near) {
        ++why.bind_near;
      } else if (joined(A.region, B.region) && d < 1.25 * rr + near) {
        ++why.junction;  // a limb's root and what it hangs off, where the skin creases (hip, armpit, wrist)
      } else if (siblings(A.region, B.region) && d < 1.25 * rr + near && A.root_distance < rr &&
                 B.root_distance < rr) {
        // The roots of two limbs leaving one region side by side (the thighs either side of the crotch):
        // closing the limbs presses the skin between them, as at a junction. Only spheres within rA + rB
        // of their limb's root: further down, two legs standing close are two limbs, not a crease.
        ++why.sibling_crease;
      } else if (same_region && A.region == torso && head_apart && d < 1.25 * rr + near) {
        // Two levels of a trunk that does not carry the head: the belly or the small of the back, which a
        // bending spine folds skin on skin (the crease rule of a junction, within the trunk).
        ++why.trunk_fold;
      } else {
        continue;
      }
      pairs.push_back(p);  // (a, b) visited in ascending order: sorted and unique
    }
  }
  if (reasons) *reasons = why;
  return pairs;
}

}  // namespace spherechain::baker
