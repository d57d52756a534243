// spherechain baker — head, hands and feet (segment.h SplitExtremities): the parts the paper leaves in
// the torso, the arms and the legs (its stated limitation), cut off so that they get spheres and
// chains of their own. Two ways, per part:
// - rig (hands, feet): the bones named like a hand / foot (ExtremityOfBone), when both sides have them:
//   a triangle goes to the part whose bones hold most of its corners' weight;
// - geometry: the narrowest cross-section where the part joins the rest — the wrist along the arm's
//   geodesic distance from its junction with the torso, the ankle and the neck along the up axis —
//   provided the part widens beyond it. The head is always found so: rigs name the skull's bone
//   inconsistently (BCN_Epileptic's skull follows B_Neck; only its face bones say "eye", "lip").
#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "segment_internal.h"

namespace spherechain::baker {

const char* ExtremityName(Extremity e) {
  switch (e) {
    case Extremity::kHead: return "head";
    case Extremity::kLeftHand: return "left_hand";
    case Extremity::kRightHand: return "right_hand";
    case Extremity::kLeftFoot: return "left_foot";
    case Extremity::kRightFoot: return "right_foot";
    default: return "none";
  }
}

namespace {

using segment_detail::Position;
using segment_detail::WeldedGraph;
using Eigen::Vector3d;

constexpr uint8_t kNone = uint8_t(Extremity::kNone);

// The limb region each extremity is cut from.
Region ParentRegion(Extremity e) {
  switch (e) {
    case Extremity::kLeftHand: return Region::kLeftArm;
    case Extremity::kRightHand: return Region::kRightArm;
    case Extremity::kLeftFoot: return Region::kLeftLeg;
    case Extremity::kRightFoot: return Region::kRightLeg;
    default: return Region::kTorso;
  }
}

// Geodesic distance (along the welded edges of `region`'s triangles) of every representative vertex
// from the vertices the region shares with the torso; +inf where unreachable or outside the region.
std::vector<double> DistanceFromRoot(const Mesh& mesh, const Segmentation& seg, const WeldedGraph& g, Region region) {
  const uint32_t V = mesh.vertex_count(), T = mesh.triangle_count();
  std::vector<uint8_t> mask(V, 0);  // bit 0: in the region, bit 1: in the torso (on representatives)
  for (uint32_t t = 0; t < T; ++t) {
    const uint8_t r = seg.triangle_regions[t];
    const uint8_t bit = r == uint8_t(region) ? 1 : r == uint8_t(Region::kTorso) ? 2 : 0;
    if (bit)
      for (int k = 0; k < 3; ++k) mask[g.rep[mesh.indices[3 * t + k]]] |= bit;
  }
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> dist(V, inf);
  using Entry = std::pair<double, uint32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  for (uint32_t v = 0; v < V; ++v)
    if (mask[v] == 3) dist[v] = 0.0, queue.emplace(0.0, v);
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > dist[v]) continue;
    for (uint32_t k = g.offsets[v]; k < g.offsets[v + 1]; ++k) {
      const uint32_t w = g.adj[k];
      if (!(mask[w] & 1)) continue;
      const double nd = d + (Position(mesh, v) - Position(mesh, w)).norm();
      if (nd < dist[w]) dist[w] = nd, queue.emplace(nd, w);
    }
  }
  return dist;
}

constexpr int kLevels = 64;  // contour levels along a part

// The cross-section profile of a part of the mesh along a scalar field s (on welded representatives:
// geodesic distance or height): at kLevels evenly spaced values strictly between s_min and s_max
// (level l at s_min + (l + 1)·(s_max − s_min)/(kLevels + 1)), the level set's contour — the points where
// the edges of `triangles` cross the value — and its RMS distance from its centroid (measured across
// `axis` when `axis` is non-zero), smoothed by a median of three. NaN where a contour has < 3 points.
std::vector<double> ContourProfile(const Mesh& mesh, const WeldedGraph& g, const std::vector<uint32_t>& triangles,
                                   const std::vector<double>& s, double s_min, double s_max, const Vector3d& axis) {
  const double step = (s_max - s_min) / (kLevels + 1);
  std::vector<double> m(kLevels, std::nan(""));
  if (!(step > 0.0)) return m;
  std::vector<std::vector<Vector3d>> points(kLevels);
  for (uint32_t t : triangles)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = g.rep[mesh.indices[3 * t + k]], b = g.rep[mesh.indices[3 * t + (k + 1) % 3]];
      const double sa = s[a], sb = s[b];
      if (!std::isfinite(sa) || !std::isfinite(sb) || sa == sb) continue;
      const double lo_s = std::min(sa, sb), hi_s = std::max(sa, sb);
      for (int l = std::max(0, int(std::ceil((lo_s - s_min) / step)) - 1); l < kLevels; ++l) {
        const double level = s_min + (l + 1) * step;
        if (level > hi_s) break;
        if (level < lo_s) continue;
        const double u = (level - sa) / (sb - sa);
        points[l].push_back(Position(mesh, a) + u * (Position(mesh, b) - Position(mesh, a)));
      }
    }
  std::vector<double> r(kLevels, std::nan(""));
  for (int l = 0; l < kLevels; ++l) {
    if (points[l].size() < 3) continue;
    Vector3d c = Vector3d::Zero();
    for (const Vector3d& p : points[l]) c += p;
    c /= double(points[l].size());
    double r2 = 0.0;
    for (const Vector3d& p : points[l]) {
      Vector3d d = p - c;
      if (axis.squaredNorm() > 0.0) d -= d.dot(axis) * axis;
      r2 += d.squaredNorm();
    }
    r[l] = std::sqrt(r2 / double(points[l].size()));
  }
  for (int l = 1; l + 1 < kLevels; ++l) {  // median of three
    std::array<double, 3> v{r[l - 1], r[l], r[l + 1]};
    if (std::isnan(v[0]) || std::isnan(v[1]) || std::isnan(v[2])) continue;
    std::sort(v.begin(), v.end());
    m[l] = v[1];
  }
  return m;
}

// The level of the narrowest contour at a fraction [lo, hi] of the range beyond which the part gets
// `min_ratio` times wider (above it with `part_above`, else below): a palm past the wrist, a foot below
// the ankle, a head above the neck. Fingertips narrow again: the widening marks the wrist, not the
// global minimum; a limb that only tapers (a mitten, a stump) has no such level: -1.
int ChooseCut(const std::vector<double>& m, double lo, double hi, bool part_above, double min_ratio) {
  double best = std::numeric_limits<double>::infinity();
  int best_l = -1;
  for (int l = 0; l < kLevels; ++l) {
    const double f = double(l + 1) / (kLevels + 1);
    if (f < lo || f > hi || std::isnan(m[l]) || !(m[l] < best)) continue;
    double widest = 0.0;
    for (int k = part_above ? l + 1 : 0; k < (part_above ? kLevels : l); ++k)
      if (!std::isnan(m[k])) widest = std::max(widest, m[k]);
    if (widest >= min_ratio * m[l]) best = m[l], best_l = l;
  }
  return best_l;
}

}  // namespace

namespace segment_detail {

Extremity ExtremityOfBone(std::string_view bone_name) {
  const std::optional<Region> region = RegionOfBone(bone_name);
  std::string lower;
  for (char ch : bone_name) lower.push_back(char(std::tolower(static_cast<unsigned char>(ch))));
  auto has = [&](std::initializer_list<const char*> words) {
    for (const char* w : words)
      if (lower.find(w) != std::string::npos) return true;
    return false;
  };
  if (region == Region::kLeftArm || region == Region::kRightArm) {
    if (has({"hand", "finger", "thumb", "index", "middle", "ring", "pinky", "metacarpal", "palm", "wrist"}))
      return region == Region::kLeftArm ? Extremity::kLeftHand : Extremity::kRightHand;
  } else if (region == Region::kLeftLeg || region == Region::kRightLeg) {
    if (has({"foot", "toe", "ankle", "heel", "ball"}))
      return region == Region::kLeftLeg ? Extremity::kLeftFoot : Extremity::kRightFoot;
  }
  return Extremity::kNone;
}

}  // namespace segment_detail

Result<ExtremitySplit> SplitExtremities(const Mesh& mesh, const Segmentation& seg, ExtremityMethod method,
                                        Context* ctx) {
  Context::Timer timer(ctx, "segment.extremities");
  const uint32_t V = mesh.vertex_count(), T = mesh.triangle_count();
  if (seg.triangle_regions.size() != T)
    return MakeError(Error::Code::kSegmentation, "extremities: segmentation does not match the mesh's triangle count");
  if (!seg.layout.IsPaperFive())
    return MakeError(Error::Code::kSegmentation, "extremities: head, hands and feet are cut from the paper's five regions "
                                                 "(a standing biped), not from a creature's layout");
  ExtremitySplit out;
  out.triangle_parts.assign(T, kNone);
  std::ostringstream notes;
  const WeldedGraph g = segment_detail::BuildWeldedGraph(mesh);

  // ---- rig: parts named by their bones --------------------------------------------------------------
  std::array<bool, kExtremityCount + 1> by_rig{};
  if (method != ExtremityMethod::kGeometry && mesh.skin && mesh.skin->weight_offsets.size() == size_t(V) + 1) {
    const Skin& skin = *mesh.skin;
    std::vector<uint8_t> joint_part(skin.joints.size(), kNone);
    for (size_t j = 0; j < skin.joints.size(); ++j) {
      const int32_t node = skin.joints[j].node;
      if (node >= 0 && size_t(node) < skin.nodes.size())
        joint_part[j] = uint8_t(segment_detail::ExtremityOfBone(skin.nodes[size_t(node)].name));
    }
    // Per triangle: the weight of each part's bones summed over its corners; the part wins when it
    // holds more than half of the corners' total weight and the triangle lies in the parent region.
    std::vector<std::array<float, kExtremityCount + 1>> tw(T);
    std::array<size_t, kExtremityCount + 1> count{};
    for (uint32_t t = 0; t < T; ++t) {
      std::array<float, kExtremityCount + 1> sum{};
      float total = 0.0f;
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = mesh.indices[3 * t + k];
        for (uint32_t i = skin.weight_offsets[v]; i < skin.weight_offsets[v + 1]; ++i) {
          const uint32_t j = skin.weight_joints[i];
          if (j >= joint_part.size()) continue;
          sum[joint_part[j]] += skin.weights[i];
          total += skin.weights[i];
        }
      }
      for (int e = 1; e <= kExtremityCount; ++e)
        if (sum[e] > 0.5f * total && seg.triangle_regions[t] == uint8_t(ParentRegion(Extremity(e)))) {
          tw[t] = sum;
          ++count[e];
        }
    }
    // Both hands (or both feet) must be found for the rig to decide that kind of part.
    auto found = [&](Extremity e) { return count[size_t(e)] > 0; };
    by_rig[size_t(Extremity::kLeftHand)] = by_rig[size_t(Extremity::kRightHand)] =
        found(Extremity::kLeftHand) && found(Extremity::kRightHand);
    by_rig[size_t(Extremity::kLeftFoot)] = by_rig[size_t(Extremity::kRightFoot)] =
        found(Extremity::kLeftFoot) && found(Extremity::kRightFoot);
    for (uint32_t t = 0; t < T; ++t)
      for (int e = 1; e <= kExtremityCount; ++e)
        if (by_rig[e] && tw[t][e] > 0.0f && seg.triangle_regions[t] == uint8_t(ParentRegion(Extremity(e)))) {
          float total = 0.0f;
          for (float x : tw[t]) total += x;
          if (tw[t][e] > 0.5f * total) out.triangle_parts[t] = uint8_t(e);
        }
  }

  // ---- geometry: the narrowest cross-section -----------------------------------------------------
  const Vector3d up = segment_detail::UpVector(mesh.up_axis);
  // Hands: along the geodesic distance from the shoulder's junction, the wrist at 55–92 % of the way to
  // the fingertips. Feet: along the up axis from the sole, the ankle in the leg's lowest 3–30 % (a foot
  // lies flat: geodesic level sets across the ankle run slanted through the heel). Left and right share
  // one cut (the mean of their two profiles, each over its own range): a body's two hands are found
  // together, at the same fraction of their limbs, or not at all.
  for (auto [left, right] : {std::pair{Extremity::kLeftHand, Extremity::kRightHand},
                             std::pair{Extremity::kLeftFoot, Extremity::kRightFoot}}) {
    if (by_rig[size_t(left)]) {
      out.method[size_t(left)] = out.method[size_t(right)] = "rig";
      continue;
    }
    if (method == ExtremityMethod::kRig) continue;
    const bool hand = left == Extremity::kLeftHand;
    struct Side {
      Extremity part;
      Region parent;
      std::vector<double> s;
      double s_min = std::numeric_limits<double>::infinity(), s_max = -std::numeric_limits<double>::infinity();
      std::vector<uint32_t> triangles;
      std::vector<double> profile;
    };
    std::array<Side, 2> sides{Side{left, ParentRegion(left), {}, 0, 0, {}, {}}, Side{right, ParentRegion(right), {}, 0, 0, {}, {}}};
    bool usable = true;
    for (Side& side : sides) {
      side.s = hand ? DistanceFromRoot(mesh, seg, g, side.parent) : std::vector<double>(V, 0.0);
      side.s_min = std::numeric_limits<double>::infinity(), side.s_max = -side.s_min;
      size_t n = 0;
      for (uint32_t t = 0; t < T; ++t)
        if (seg.triangle_regions[t] == uint8_t(side.parent)) side.triangles.push_back(t);
      std::vector<uint8_t> seen(V, 0);
      for (uint32_t t : side.triangles)
        for (int k = 0; k < 3; ++k) {
          const uint32_t v = g.rep[mesh.indices[3 * t + k]];
          if (seen[v]) continue;
          seen[v] = 1;
          if (!hand) side.s[v] = Position(mesh, v).dot(up);
          if (!std::isfinite(side.s[v])) continue;
          ++n, side.s_min = std::min(side.s_min, side.s[v]), side.s_max = std::max(side.s_max, side.s[v]);
        }
      usable = usable && n >= 16 && side.s_max > side.s_min;
      if (usable) side.profile = ContourProfile(mesh, g, side.triangles, side.s, side.s_min, side.s_max, hand ? Vector3d::Zero() : up);
    }
    const char* what = hand ? "hands" : "feet";
    if (!usable) {
      notes << what << ": a limb too small to profile; ";
      continue;
    }
    std::vector<double> mean(kLevels);
    for (int l = 0; l < kLevels; ++l) mean[l] = 0.5 * (sides[0].profile[l] + sides[1].profile[l]);
    const int cut_level = hand ? ChooseCut(mean, 0.55, 0.92, true, 1.2) : ChooseCut(mean, 0.03, 0.30, false, 1.3);
    if (cut_level < 0) {
      notes << what << ": none (the limbs do not widen past their narrowest section); ";
      continue;
    }
    const double f = double(cut_level + 1) / (kLevels + 1);
    for (Side& side : sides) {
      const double cut = side.s_min + f * (side.s_max - side.s_min);
      for (uint32_t t : side.triangles) {
        int beyond = 0;
        for (int k = 0; k < 3; ++k) {
          const double x = side.s[g.rep[mesh.indices[3 * t + k]]];
          beyond += hand ? x > cut : x < cut;
        }
        if (beyond >= 2) out.triangle_parts[t] = uint8_t(side.part);
      }
      out.method[size_t(side.part)] = "geometry";
    }
    notes << what << ": cut at " << int(100.0 * f + 0.5)
          << (hand ? " % of the arms' geodesic length; " : " % of the legs' height; ");
  }
  if (method != ExtremityMethod::kRig) {
    // The neck: the narrowest horizontal section of the torso between the top of the arms' junction
    // and the top of the body.
    double shoulder = -std::numeric_limits<double>::infinity(), top = shoulder;
    std::vector<uint8_t> torso_v(V, 0), arm_v(V, 0);
    for (uint32_t t = 0; t < T; ++t) {
      const uint8_t r = seg.triangle_regions[t];
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = g.rep[mesh.indices[3 * t + k]];
        if (r == uint8_t(Region::kTorso)) torso_v[v] = 1;
        if (r == uint8_t(Region::kLeftArm) || r == uint8_t(Region::kRightArm)) arm_v[v] = 1;
      }
    }
    std::vector<double> height(V, 0.0);
    std::vector<uint32_t> verts;
    for (uint32_t v = 0; v < V; ++v) {
      if (g.rep[v] != v || !torso_v[v]) continue;
      height[v] = Position(mesh, v).dot(up);
      top = std::max(top, height[v]);
      if (arm_v[v]) shoulder = std::max(shoulder, height[v]);
    }
    for (uint32_t v = 0; v < V; ++v)
      if (g.rep[v] == v && torso_v[v] && height[v] >= shoulder) verts.push_back(v);
    if (std::isfinite(shoulder) && top > shoulder && verts.size() >= 32) {
      std::vector<uint32_t> torso_tris;
      for (uint32_t t = 0; t < T; ++t)
        if (seg.triangle_regions[t] == uint8_t(Region::kTorso)) torso_tris.push_back(t);
      const int cut_level = ChooseCut(ContourProfile(mesh, g, torso_tris, height, shoulder, top, up), 0.05, 0.6, true, 1.15);
      if (cut_level >= 0) {
        const double cut = shoulder + double(cut_level + 1) / (kLevels + 1) * (top - shoulder);
        size_t n = 0;
        for (uint32_t t = 0; t < T; ++t) {
          if (seg.triangle_regions[t] != uint8_t(Region::kTorso)) continue;
          int above = 0;
          for (int k = 0; k < 3; ++k) above += height[g.rep[mesh.indices[3 * t + k]]] > cut;
          if (above >= 2) out.triangle_parts[t] = uint8_t(Extremity::kHead), ++n;
        }
        if (n > 0) out.method[size_t(Extremity::kHead)] = "geometry";
        notes << "head: neck cut at " << int(100.0 * (cut - shoulder) / (top - shoulder) + 0.5)
              << " % of the way from the shoulders to the top; ";
      } else {
        notes << "head: none (the torso does not widen above its narrowest section over the shoulders); ";
      }
    }
  }
  std::array<size_t, kExtremityCount + 1> tri_count{};
  for (uint8_t p : out.triangle_parts) ++tri_count[p];
  for (int e = 1; e <= kExtremityCount; ++e) {
    notes << ExtremityName(Extremity(e)) << " " << tri_count[e] << " tri ("
          << (out.method[e].empty() ? std::string("not found") : out.method[e]) << ")"
          << (e < kExtremityCount ? ", " : "");
  }
  out.notes = notes.str();
  if (ctx) ctx->Info("segment (extremities): " + out.notes);
  return out;
}

Status ApplyExtremities(const Mesh& mesh, const ExtremitySplit& split, Segmentation* seg) {
  const uint32_t T = mesh.triangle_count();
  if (!seg->layout.IsPaperFive())
    return MakeError(Error::Code::kSegmentation, "extremities: the extended layout starts from the paper's five regions");
  if (split.triangle_parts.size() != T || seg->triangle_regions.size() != T)
    return MakeError(Error::Code::kSegmentation, "extremities: the split does not match the mesh's triangle count");
  std::array<bool, kExtremityCount + 1> found{};
  for (uint8_t p : split.triangle_parts)
    if (p >= 1 && p <= kExtremityCount) found[p] = true;
  bool any = false;
  for (bool f : found) any = any || f;
  if (!any) return Ok{};
  RegionLayout layout;  // the paper's five, the torso (R4) moved to the end below
  RegionInfo torso = layout.regions.back();
  layout.regions.pop_back();
  std::array<int, kExtremityCount + 1> index{};
  index.fill(-1);
  for (int e = 1; e <= kExtremityCount; ++e) {
    if (!found[size_t(e)]) continue;
    RegionInfo info;
    info.name = ExtremityName(Extremity(e));
    const Extremity ex = Extremity(e);
    info.parent = ex == Extremity::kLeftHand ? int(Region::kLeftArm) : ex == Extremity::kRightHand ? int(Region::kRightArm)
                : ex == Extremity::kLeftFoot ? int(Region::kLeftLeg) : ex == Extremity::kRightFoot ? int(Region::kRightLeg) : -1;
    info.volume_group = info.parent >= 0 ? info.parent : int(Region::kTorso);  // remapped below for the torso
    index[size_t(e)] = int(layout.regions.size());
    layout.regions.push_back(std::move(info));
  }
  for (auto [l, r] : {std::pair{Extremity::kLeftHand, Extremity::kRightHand}, std::pair{Extremity::kLeftFoot, Extremity::kRightFoot}})
    if (index[size_t(l)] >= 0 && index[size_t(r)] >= 0) {
      layout.regions[size_t(index[size_t(l)])].mirror = index[size_t(r)];
      layout.regions[size_t(index[size_t(r)])].mirror = index[size_t(l)];
    }
  const uint8_t new_torso = uint8_t(layout.regions.size());
  layout.regions.push_back(std::move(torso));
  for (RegionInfo& info : layout.regions)
    if (info.volume_group == int(Region::kTorso)) info.volume_group = new_torso;
  layout.paper = true;
  for (uint32_t t = 0; t < T; ++t) {
    const uint8_t p = split.triangle_parts[t];
    if (p >= 1 && p <= kExtremityCount && index[p] >= 0) seg->triangle_regions[t] = uint8_t(index[p]);
    else if (seg->triangle_regions[t] == uint8_t(Region::kTorso)) seg->triangle_regions[t] = new_torso;
  }
  seg->layout = std::move(layout);
  segment_detail::ComputeVertexRegions(mesh, *seg);
  seg->notes += "; extended (head, hands, feet): " + split.notes + "; " +
                segment_detail::RegionCounts(seg->triangle_regions, seg->layout);
  return Ok{};
}

}  // namespace spherechain::baker
