#include "spherechain/baker/chains.h"

#include <algorithm>
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

namespace {

// True when sphere `s` belongs to the set named by `token`; false with *known=false for a bad token.
bool InSet(const FittedSphere& s, const std::string& token, bool* known) {
  *known = true;
  if (token.size() == 2 && token[0] == 'R' && token[1] >= '0' && token[1] <= '4')
    return static_cast<int>(s.region) == token[1] - '0';
  if (token.size() == 3 && token.rfind("R4", 0) == 0) {
    if (s.region != Region::kTorso) return false;
    switch (token[2]) {
      case 'L': return (s.labels & kLabelL) != 0;
      case 'R': return (s.labels & kLabelR) != 0;
      case 'T': return (s.labels & kLabelT) != 0;
      case 'D': return (s.labels & kLabelD) != 0;
      default: break;
    }
  }
  *known = false;
  return false;
}

}  // namespace

Result<std::vector<Chain>> BuildChains(const std::vector<FittedSphere>& spheres, const std::vector<ChainDef>& defs) {
  if (defs.empty()) return MakeError(Error::Code::kConfig, "no chain is defined");
  if (spheres.size() > 0xFFFF) return MakeError(Error::Code::kConfig, "more than 65,535 spheres");
  std::vector<Chain> chains;
  for (const ChainDef& def : defs) {
    Chain chain{def.name, {}};
    for (const std::string& token : def.members) {
      bool known = true;
      for (size_t i = 0; i < spheres.size(); ++i) {
        if (InSet(spheres[i], token, &known)) chain.spheres.push_back(static_cast<uint16_t>(i));
        if (!known) break;
      }
      if (!known)
        return MakeError(Error::Code::kConfig, "chain '" + def.name + "': unknown member '" + token +
                                                   "' (expected R0..R4, R4L, R4R, R4T or R4D)");
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
                                          std::vector<SpherePair>* cross_region_bind_overlaps, UpAxis up_axis) {
  std::vector<SpherePair> pairs;
  ExclusionReasons why;
  const Eigen::Vector3d up = fit_detail::UpVector(up_axis);
  const size_t n = spheres.size();
  for (size_t a = 0; a < n; ++a) {
    for (size_t b = a + 1; b < n; ++b) {
      const FittedSphere& A = spheres[a];
      const FittedSphere& B = spheres[b];
      const bool same_region = A.region == B.region;
      const double d = (A.center - B.center).norm(), rr = A.radius + B.radius;
      const SpherePair p{static_cast<uint16_t>(a), static_cast<uint16_t>(b)};
      if (same_region && IsTubular(A.region) && std::abs(A.sequence - B.sequence) == 1) {
        ++why.limb_neighbour;
      } else if (same_region && IsTubular(A.region) && std::abs(A.root_distance - B.root_distance) < rr) {
        ++why.limb_side_by_side;  // one cross-section of the tube: no fold brings their skins together
      } else if (same_region && A.region == Region::kTorso &&
                 std::abs(A.center.dot(up) - B.center.dot(up)) < std::max(A.radius, B.radius)) {
        ++why.torso_side_by_side;  // one level of the torso: a bending spine folds levels, not a level
      } else if (d < rr) {
        ++why.bind_overlap;
        const bool limb_torso = (A.region == Region::kTorso) != (B.region == Region::kTorso);
        if (!same_region && !limb_torso && cross_region_bind_overlaps) cross_region_bind_overlaps->push_back(p);
      } else if (d < rr + near) {
        ++why.bind_near;
      } else if ((A.region == Region::kTorso) != (B.region == Region::kTorso) && d < 1.25 * rr + near) {
        ++why.junction;  // a limb's root and the torso where the skin creases (hip, armpit)
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
