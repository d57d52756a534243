// Plausibility checks after segmentation and fitting (plausibility.h).
#include "spherechain/baker/plausibility.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

#include "segment_internal.h"

namespace spherechain::baker {

namespace {

using segment_detail::Position;

struct RegionShape {
  double area = 0.0;
  double length = 0.0;  ///< extent of its vertices along their principal axis
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
};

RegionShape Shape(const Mesh& mesh, const Segmentation& seg, const std::vector<double>& tri_area, int region) {
  RegionShape s;
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    if (seg.triangle_regions[t] != region) continue;
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) c += Position(mesh, mesh.indices[3 * t + k]) / 3.0;
    s.area += tri_area[t];
    s.centroid += tri_area[t] * c;
    second += tri_area[t] * c * c.transpose();
  }
  if (s.area <= 0) return s;
  s.centroid /= s.area;
  const Eigen::Matrix3d cov = second / s.area - s.centroid * s.centroid.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  s.axis = es.eigenvectors().col(2);
  double lo = 1e300, hi = -1e300;
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    if (seg.triangle_regions[t] != region) continue;
    for (int k = 0; k < 3; ++k) {
      const double x = Position(mesh, mesh.indices[3 * t + k]).dot(s.axis);
      lo = std::min(lo, x), hi = std::max(hi, x);
    }
  }
  s.length = hi - lo;
  return s;
}

std::string Fixed(double v, int digits = 2) {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(digits);
  o << v;
  return o.str();
}

}  // namespace

void CheckProtrusion(const CoverageStats& coverage, const PlausibilityLimits& limits,
                     std::vector<PlausibilityFinding>* out) {
  if (coverage.protrusion > limits.max_protrusion)
    out->push_back({"PLAUS-OUTSIDE", Fixed(100.0 * coverage.protrusion, 1) +
                                         " % of the spheres' volume is outside the body (bound " +
                                         Fixed(100.0 * limits.max_protrusion, 0) + " %)"});
}

std::vector<PlausibilityFinding> CheckPlausibility(const Mesh& mesh, const Segmentation& seg,
                                                   const CoverageStats* coverage,
                                                   const SegmentationAgreement* agreement,
                                                   const PlausibilityLimits& limits) {
  std::vector<PlausibilityFinding> out;
  auto add = [&](const char* code, std::string message) { out.push_back({code, std::move(message)}); };
  const uint32_t nv = mesh.vertex_count(), nt = mesh.triangle_count();
  if (nt == 0 || seg.triangle_regions.size() != nt) return out;
  const segment_detail::WeldedGraph g = segment_detail::BuildWeldedGraph(mesh);
  const std::vector<double> tri_area = segment_detail::TriangleAreas(mesh);
  const Eigen::Vector3d up = segment_detail::UpVector(mesh.up_axis);
  double hmin = 1e300, hmax = -1e300;
  for (uint32_t v = 0; v < nv; ++v)
    if (g.used[v]) hmin = std::min(hmin, Position(mesh, v).dot(up)), hmax = std::max(hmax, Position(mesh, v).dot(up));
  const double height = std::max(hmax - hmin, 1e-12);
  // The torso: R4 of the paper's five regions, a creature's trunk (the any-skeleton path) otherwise.
  const RegionLayout& layout = seg.layout;
  const int kTorso = static_cast<int>(layout.trunk());
  const char* torso_word = layout.paper ? "torso" : "trunk";

  // Each limb: one piece, attached to the torso (triangles joined through welded vertices).
  std::vector<uint8_t> in_region(nv);
  std::vector<uint32_t> parent(nv);
  auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::vector<uint8_t> touches_torso(nv, 0);
  for (uint32_t t = 0; t < nt; ++t)
    if (seg.triangle_regions[t] == kTorso)
      for (int k = 0; k < 3; ++k) touches_torso[g.rep[mesh.indices[3 * t + k]]] = 1;
  // Welded vertices used by triangles of two or more regions: a limb piece without one is a loose part
  // (a mesh component of its own — a tail's tuft, an eye, a claw), no sign of a limb cut in two.
  std::vector<uint8_t> first_region(nv, kNoRegion), shared(nv, 0);
  for (uint32_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = g.rep[mesh.indices[3 * t + k]];
      if (first_region[v] == kNoRegion) first_region[v] = seg.triangle_regions[t];
      else if (first_region[v] != seg.triangle_regions[t]) shared[v] = 1;
    }
  for (int r = 0; r < kTorso; ++r) {
    std::iota(parent.begin(), parent.end(), 0u);
    std::fill(in_region.begin(), in_region.end(), 0);
    bool attached = false, any = false;
    for (uint32_t t = 0; t < nt; ++t) {
      if (seg.triangle_regions[t] != r) continue;
      any = true;
      uint32_t a = g.rep[mesh.indices[3 * t]];
      for (int k = 0; k < 3; ++k) {
        const uint32_t b = g.rep[mesh.indices[3 * t + k]];
        in_region[b] = 1;
        attached = attached || touches_torso[b];
        const uint32_t ra = find(a), rb = find(b);
        if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
        a = b;
      }
    }
    const char* name = layout.Name(static_cast<Region>(r));
    if (!any) continue;  // an empty limb is the segmentation's error, not ours
    std::vector<uint8_t> joined(nv, 0);  // per piece (its root): touches another region
    for (uint32_t v = 0; v < nv; ++v)
      if (in_region[v] && shared[v]) joined[find(v)] = 1;
    uint32_t pieces = 0;
    for (uint32_t v = 0; v < nv; ++v) pieces += in_region[v] && find(v) == v && joined[v];
    if (pieces > 1)
      add("PLAUS-LIMB-PIECES", std::string(name) + " is " + std::to_string(pieces) + " separate pieces, not one");
    if (!attached) add("PLAUS-LIMB-DETACHED", std::string(name) + " shares no vertex with the " + torso_word);
  }

  // Left/right balance (area and principal length): the paper's arms and legs, a creature's limbs
  // paired by their names (RegionInfo::mirror).
  std::vector<RegionShape> shape(size_t(layout.count()));
  for (int r = 0; r < layout.count(); ++r) shape[size_t(r)] = Shape(mesh, seg, tri_area, r);
  std::vector<std::pair<int, int>> pairs;
  for (int r = 0; r < kTorso; ++r)
    if (const int m = layout.regions[size_t(r)].mirror; m > r && m < kTorso) pairs.emplace_back(r, m);
  for (const auto& [left, right] : pairs) {
    const RegionShape& l = shape[size_t(left)];
    const RegionShape& rr = shape[size_t(right)];
    const std::string what = layout.paper ? (left == 0 ? "arms" : "legs")
                                          : std::string("limbs (") + layout.Name(Region(left)) + ", " +
                                                layout.Name(Region(right)) + ")";
    if (l.area <= 0 || rr.area <= 0) continue;
    const double area_ratio = std::min(l.area, rr.area) / std::max(l.area, rr.area);
    const double length_ratio = std::min(l.length, rr.length) / std::max(std::max(l.length, rr.length), 1e-300);
    if (area_ratio < limits.limb_area_balance)
      add("PLAUS-LIMB-BALANCE", std::string("left and right ") + what + " differ in area: ratio " + Fixed(area_ratio) +
                                    " < " + Fixed(limits.limb_area_balance) + " (left " + Fixed(l.area, 4) + ", right " +
                                    Fixed(rr.area, 4) + " square units)");
    else if (length_ratio < limits.limb_length_balance)
      add("PLAUS-LIMB-BALANCE", std::string("left and right ") + what + " differ in length: ratio " +
                                    Fixed(length_ratio) + " < " + Fixed(limits.limb_length_balance) + " (left " +
                                    Fixed(l.length / height) + ", right " + Fixed(rr.length / height) + " of the height)");
  }

  // The head: the top band of the body within a column around the torso's centre (a standing body only:
  // a creature's head is wherever its neck leads).
  if (layout.paper && shape[kTorso].area > 0) {
    const Eigen::Vector3d c = shape[kTorso].centroid;
    double head = 0, in_limb = 0;
    for (uint32_t t = 0; t < nt; ++t) {
      Eigen::Vector3d p = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) p += Position(mesh, mesh.indices[3 * t + k]) / 3.0;
      if (p.dot(up) < hmax - limits.head_depth_rel * height) continue;
      Eigen::Vector3d d = p - c;
      d -= d.dot(up) * up;
      if (d.norm() > limits.head_radius_rel * height) continue;
      head += tri_area[t];
      if (seg.triangle_regions[t] != kTorso) in_limb += tri_area[t];
    }
    if (head > 0 && in_limb / head > limits.head_limb_share)
      add("PLAUS-HEAD-IN-LIMB", "the top of the body above the torso (the head) is " + Fixed(100.0 * in_limb / head, 0) +
                                    " % limb regions (bound " + Fixed(100.0 * limits.head_limb_share, 0) + " %)");
  }

  // The trunk stands along the up axis (biped path; a creature's trunk lies as it lies).
  if (layout.paper && shape[kTorso].area > 0) {
    const double tilt = std::acos(std::min(1.0, std::abs(shape[kTorso].axis.dot(up)))) * 180.0 / M_PI;
    if (tilt > limits.trunk_tilt_deg)
      add("PLAUS-TRUNK-AXIS", "the torso's principal axis is " + Fixed(tilt, 0) + " degrees from the up axis (bound " +
                                  Fixed(limits.trunk_tilt_deg, 0) + "): a horizontal trunk is not a standing body");
  }

  if (coverage) CheckProtrusion(*coverage, limits, &out);
  if (agreement && agreement->triangle_fraction < limits.min_agreement)
    add("PLAUS-SEG-AGREE", "rig and geometry segmentations agree on " + Fixed(100.0 * agreement->triangle_fraction, 1) +
                               " % of the triangles (bound " + Fixed(100.0 * limits.min_agreement, 0) + " %)");
  return out;
}

}  // namespace spherechain::baker
