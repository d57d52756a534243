// spherechain baker — segmentation of an unrigged standing body from geometry alone (paper §3 regions).
//
// 1. Axes: up = Mesh::up_axis; lateral = the main axis of the area-weighted horizontal spread (arms and
//    shoulders make the body wider than deep in A-pose, T-pose and arms-down); forward = the way the
//    feet point (toes ahead of the ankles); the character's left = up × forward.
// 2. Height sweep (a merge tree of the welded vertex graph, elder rule): pieces are born at local
//    minima of height and merge at saddles. The two large pieces born at the bottom are the legs; they
//    merge at the crotch. Hanging arms (A-pose, arms-down) are large pieces born higher up (finger tips)
//    that merge with the body at the armpits.
// 3. T-pose (no hanging arms): a sweep inwards along the lateral axis from each side; the arm is the
//    piece born at the finger tips, the armpit the saddle where the torso's flank joins it.
// 4. Each limb = its sweep piece plus the vertices beyond the plane through the armpit / crotch normal
//    to the limb axis (principal axis of the limb's part near the cut), kept connected to the limb's
//    tip. Triangles take their vertices' majority; each limb is then made one connected piece.
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <deque>
#include <numeric>
#include <sstream>

#include "segment_internal.h"

namespace spherechain::baker {

using namespace segment_detail;

namespace {

Error NotABody(const std::string& why) {
  return MakeError(Error::Code::kSegmentation, "segment (geometry): not a standing body: " + why);
}

/// A piece that died in a sweep: born at `birth`, merged into the piece born at `survivor_birth` when
/// vertex `merge` was reached.
struct Death {
  uint32_t birth = 0, survivor_birth = 0, merge = 0;
  double area = 0, survivor_area = 0;
};

/// Sweep over the welded graph in the order of `order` (representatives only). Returns rank per vertex
/// (UINT32_MAX for non-representatives) and the deaths of pieces whose area reached `min_area`.
struct Sweep {
  std::vector<uint32_t> rank;
  std::vector<Death> deaths;
};

Sweep RunSweep(const WeldedGraph& g, const std::vector<uint32_t>& order, double min_area) {
  const size_t nv = g.rep.size();
  Sweep s;
  s.rank.assign(nv, UINT32_MAX);
  for (uint32_t i = 0; i < order.size(); ++i) s.rank[order[i]] = i;
  std::vector<uint32_t> parent(nv), birth(nv);
  std::vector<double> area(nv, 0.0);
  auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (uint32_t v : order) {
    parent[v] = v;
    birth[v] = v;
    area[v] = g.area[v];
    for (uint32_t k = g.offsets[v]; k < g.offsets[v + 1]; ++k) {
      const uint32_t n = g.adj[k];
      if (s.rank[n] >= s.rank[v]) continue;  // not active yet
      uint32_t a = find(v), b = find(n);
      if (a == b) continue;
      if (s.rank[birth[a]] > s.rank[birth[b]]) std::swap(a, b);  // a is elder
      if (area[b] >= min_area) s.deaths.push_back({birth[b], birth[a], v, area[b], area[a]});
      parent[b] = a;
      area[a] += area[b];
    }
  }
  return s;
}

/// Vertices reachable from `seed` through vertices for which `allowed` holds.
template <class F>
std::vector<uint8_t> Flood(const WeldedGraph& g, uint32_t seed, F allowed) {
  std::vector<uint8_t> in(g.rep.size(), 0);
  std::deque<uint32_t> q{seed};
  in[seed] = 1;
  while (!q.empty()) {
    const uint32_t v = q.front();
    q.pop_front();
    for (uint32_t k = g.offsets[v]; k < g.offsets[v + 1]; ++k) {
      const uint32_t n = g.adj[k];
      if (!in[n] && allowed(n)) in[n] = 1, q.push_back(n);
    }
  }
  return in;
}

std::vector<uint8_t> RankBelow(const std::vector<uint32_t>& rank, uint32_t cut_rank) {
  std::vector<uint8_t> m(rank.size());
  for (size_t v = 0; v < rank.size(); ++v) m[v] = rank[v] < cut_rank;
  return m;
}

struct Limb {
  uint32_t tip = 0;    ///< birth vertex (finger or toe tip)
  Eigen::Vector3d cut = Eigen::Vector3d::Zero();  ///< armpit / crotch point
  std::vector<uint8_t> before;  ///< vertices the sweep had reached when it found the cut
  std::vector<uint8_t> piece;   ///< the limb's sweep piece when the cut was found
  std::vector<uint8_t> region;  ///< final vertex set
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();  ///< from the cut towards the tip
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
};

/// Axis of the limb part near the cut (within half the limb's reach), oriented towards the tip side,
/// then the limb's vertex set: the piece plus what lies beyond the plane through the cut.
void GrowLimb(const Mesh& mesh, const WeldedGraph& g, Limb& limb) {
  const Eigen::Vector3d c = limb.cut;
  double reach = 0, wsum = 0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (uint32_t v = 0; v < g.rep.size(); ++v) {
    if (!limb.piece[v]) continue;
    reach = std::max(reach, (Position(mesh, v) - c).norm());
    centroid += g.area[v] * Position(mesh, v);
    wsum += g.area[v];
  }
  centroid /= std::max(wsum, 1e-300);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  double w = 0;
  for (uint32_t v = 0; v < g.rep.size(); ++v) {
    const double r = (Position(mesh, v) - c).norm();
    if (limb.piece[v] && r > 0.1 * reach && r < 0.5 * reach) mean += g.area[v] * Position(mesh, v), w += g.area[v];
  }
  mean /= std::max(w, 1e-300);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (uint32_t v = 0; v < g.rep.size(); ++v) {
    const double r = (Position(mesh, v) - c).norm();
    if (!limb.piece[v] || r <= 0.1 * reach || r >= 0.5 * reach) continue;
    const Eigen::Vector3d d = Position(mesh, v) - mean;
    cov += g.area[v] * d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  Eigen::Vector3d axis = es.eigenvectors().col(2);
  if ((centroid - c).dot(axis) < 0) axis = -axis;
  limb.axis = axis;
  limb.region = Flood(g, limb.tip, [&](uint32_t v) {
    if (limb.piece[v]) return true;
    return !limb.before[v] && (Position(mesh, v) - c).dot(axis) >= 0.0;
  });
  limb.centroid = centroid;
}

}  // namespace

Result<Segmentation> SegmentByGeometry(const Mesh& mesh, Context* ctx) {
  Context::Timer timer(ctx, "segment.geometry");
  if (Status s = CheckMeshForSegmentation(mesh); !s) return s.error();
  const WeldedGraph g = BuildWeldedGraph(mesh);
  const uint32_t nv = mesh.vertex_count();
  std::vector<uint32_t> reps;
  double total_area = 0;
  for (uint32_t v = 0; v < nv; ++v)
    if (g.rep[v] == v && g.used[v]) reps.push_back(v), total_area += g.area[v];
  if (total_area <= 0) return NotABody("the mesh has no area");

  // 1. Axes.
  const Eigen::Vector3d up = UpVector(mesh.up_axis);
  double hmin = 1e300, hmax = -1e300;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (uint32_t v : reps) {
    const Eigen::Vector3d p = Position(mesh, v);
    hmin = std::min(hmin, p.dot(up));
    hmax = std::max(hmax, p.dot(up));
    mean += g.area[v] * p;
  }
  mean /= total_area;
  const double height = hmax - hmin;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (uint32_t v : reps) {
    Eigen::Vector3d d = Position(mesh, v) - mean;
    d -= d.dot(up) * up;
    cov += g.area[v] * d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  Eigen::Vector3d lateral = es.eigenvectors().col(2);
  lateral = (lateral - lateral.dot(up) * up).normalized();
  auto h = [&](uint32_t v) { return Position(mesh, v).dot(up); };
  auto x = [&](uint32_t v) { return Position(mesh, v).dot(lateral); };

  // 2. Height sweep: legs, then hanging arms.
  std::vector<uint32_t> order = reps;
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    const double ha = h(a), hb = h(b);
    return ha < hb || (ha == hb && a < b);
  });
  Sweep vertical = RunSweep(g, order, 0.003 * total_area);
  const double foot_level = hmin + 0.1 * height;
  const Death* legs = nullptr;
  for (const Death& d : vertical.deaths) {
    if (h(d.birth) < foot_level && h(d.survivor_birth) < foot_level && d.area >= 0.05 * total_area &&
        d.survivor_area >= 0.05 * total_area) {
      legs = &d;
      break;
    }
  }
  if (!legs || h(legs->merge) - hmin < 0.2 * height)
    return NotABody("the bottom of the mesh does not split into two legs");
  std::ostringstream notes;
  notes << "height " << height << ", crotch at " << (h(legs->merge) - hmin) / height << " of height; ";

  Limb leg[2];
  leg[0].tip = legs->survivor_birth;
  leg[1].tip = legs->birth;
  for (Limb& l : leg) {
    l.cut = Position(mesh, legs->merge);
    l.before = RankBelow(vertical.rank, vertical.rank[legs->merge]);
    l.piece = Flood(g, l.tip, [&](uint32_t v) { return l.before[v] != 0; });
    GrowLimb(mesh, g, l);
  }
  const double center_x = x(legs->merge);

  // Hanging arms: the two largest pieces not born at the feet that die above the crotch.
  std::vector<const Death*> hanging;
  for (const Death& d : vertical.deaths) {
    if (&d == legs || h(d.birth) < foot_level || d.area < 0.02 * total_area) continue;
    if (vertical.rank[d.merge] <= vertical.rank[legs->merge]) continue;
    hanging.push_back(&d);
  }
  // The two arms: pieces on opposite sides, the most alike in area (ties: the larger pair).
  {
    double best = -1;
    std::pair<const Death*, const Death*> pick{nullptr, nullptr};
    for (const Death* a : hanging)
      for (const Death* b : hanging) {
        if (a >= b || (x(a->birth) - center_x) * (x(b->birth) - center_x) >= 0) continue;
        const double score = std::min(a->area, b->area) / std::max(a->area, b->area) + 1e-3 * (a->area + b->area) / total_area;
        if (score > best) best = score, pick = {a, b};
      }
    hanging.clear();
    if (pick.first) hanging = {pick.first, pick.second};
  }
  Limb arm[2];
  bool have_arms = false;
  if (hanging.size() >= 2 && (x(hanging[0]->birth) - center_x) * (x(hanging[1]->birth) - center_x) < 0) {
    for (int i = 0; i < 2; ++i) {
      arm[i].tip = hanging[i]->birth;
      arm[i].cut = Position(mesh, hanging[i]->merge);
      arm[i].before = RankBelow(vertical.rank, vertical.rank[hanging[i]->merge]);
      arm[i].piece = Flood(g, arm[i].tip, [&](uint32_t v) { return arm[i].before[v] != 0; });
    }
    have_arms = true;
    notes << "pose: arms hanging (A-pose / arms down), armpits at " << (arm[0].cut.dot(up) - hmin) / height << ", "
          << (arm[1].cut.dot(up) - hmin) / height << " of height; ";
  } else {
    // 3. T-pose: walk inwards from each side in slabs across the lateral axis; the arm's slabs are thin
    //    (their extent along `up` is the arm's thickness); the armpit is the first slab where the
    //    extent jumps (the torso's flank begins).
    have_arms = true;
    const double slab = 0.01 * height;
    for (int i = 0; i < 2 && have_arms; ++i) {
      const double side = i == 0 ? 1.0 : -1.0;
      uint32_t tip = reps.front();
      for (uint32_t v : reps)
        if (side * x(v) > side * x(tip)) tip = v;
      const double span = side * (x(tip) - center_x);
      // An arm reaches 0.3 to about 0.5 of the height from the centre; one reaching more than 5 heights is no
      // arm. The bound also keeps the slab count small: a mesh 8e9 times wider than tall asked for more slabs
      // than an int holds (found by fuzz_import_gltf).
      if (span < 0.3 * height || span > 5.0 * height) {
        have_arms = false;
        break;
      }
      const int nslab = int(std::ceil(span / slab));
      std::vector<double> lo(size_t(nslab), 1e300), hi(size_t(nslab), -1e300);
      for (uint32_t v : reps) {
        const double slab_of_v = (side * (x(tip) - x(v))) / slab;  // the other side may lie any distance away
        if (!(slab_of_v >= 0.0 && slab_of_v < nslab)) continue;
        const int k = int(slab_of_v);
        lo[size_t(k)] = std::min(lo[size_t(k)], h(v));
        hi[size_t(k)] = std::max(hi[size_t(k)], h(v));
      }
      int pit = -1;
      std::vector<double> seen;
      for (int k = 0; k < nslab; ++k) {
        if (hi[size_t(k)] < lo[size_t(k)]) continue;
        const double extent = hi[size_t(k)] - lo[size_t(k)];
        if (seen.size() >= 8) {
          std::vector<double> tmp = seen;
          std::nth_element(tmp.begin(), tmp.begin() + long(tmp.size() / 2), tmp.end());
          if (extent > 2.5 * tmp[tmp.size() / 2]) {
            pit = k;
            break;
          }
        }
        seen.push_back(extent);
      }
      if (pit < 0 || pit * slab < 0.15 * height) {
        have_arms = false;
        break;
      }
      const double x_pit = x(tip) - side * pit * slab;
      arm[i].tip = tip;
      arm[i].before.assign(nv, 0);
      for (uint32_t v : reps) arm[i].before[v] = side * (x(v) - x_pit) > 0;
      arm[i].piece = Flood(g, tip, [&](uint32_t v) { return arm[i].before[v] != 0; });
      // Cut point: the centre of the piece's vertices in the last slab before the flank.
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      double n = 0;
      for (uint32_t v : reps)
        if (arm[i].piece[v] && side * (x(v) - x_pit) < 2 * slab) sum += Position(mesh, v), n += 1;
      if (n == 0) {
        have_arms = false;
        break;
      }
      arm[i].cut = sum / n;
      arm[i].cut += (x_pit - arm[i].cut.dot(lateral)) * lateral;
    }
    if (have_arms) {
      notes << "pose: arms raised (T-pose), armpits at " << std::abs(arm[0].cut.dot(lateral) - center_x) / height
            << ", " << std::abs(arm[1].cut.dot(lateral) - center_x) / height << " of height from the centre; ";
    }
  }
  if (!have_arms) return NotABody("two arms were not found (neither hanging nor raised to the sides)");
  for (Limb& a : arm) GrowLimb(mesh, g, a);

  // Forward: the feet point forwards (toes ahead of the ankles).
  const Eigen::Vector3d depth = up.cross(lateral).normalized();
  double toe_lead = 0;
  for (const Limb& l : leg) {
    Eigen::Vector3d foot = Eigen::Vector3d::Zero(), ankle = Eigen::Vector3d::Zero();
    double wf = 0, wa = 0;
    for (uint32_t v : reps) {
      if (!l.piece[v]) continue;
      const double rel = (h(v) - hmin) / height;
      if (rel < 0.03) foot += g.area[v] * Position(mesh, v), wf += g.area[v];
      else if (rel > 0.06 && rel < 0.10) ankle += g.area[v] * Position(mesh, v), wa += g.area[v];
    }
    if (wf > 0 && wa > 0) toe_lead += (foot / wf - ankle / wa).dot(depth);
  }
  Eigen::Vector3d forward;
  if (std::abs(toe_lead) > 0.01 * height) {
    forward = toe_lead > 0 ? depth : Eigen::Vector3d(-depth);
    notes << "facing from the feet; ";
  } else {
    // No usable feet: the usual convention (+Z for Y-up, -Y for Z-up, +Z for X-up).
    const Eigen::Vector3d conv = mesh.up_axis == UpAxis::kZ ? Eigen::Vector3d(-Eigen::Vector3d::UnitY())
                                                            : Eigen::Vector3d(Eigen::Vector3d::UnitZ());
    forward = conv.dot(depth) >= 0 ? depth : Eigen::Vector3d(-depth);
    notes << "facing not found from the feet, assumed the axis convention; ";
    if (ctx) ctx->Warn("segment (geometry): the feet do not show which way the body faces; assumed the convention");
  }
  const Eigen::Vector3d left = up.cross(forward).normalized();
  notes << "forward (" << forward.x() << ", " << forward.y() << ", " << forward.z() << "); ";
  const Eigen::Vector3d centre = Position(mesh, legs->merge);
  auto is_left = [&](const Limb& l) { return (l.centroid - centre).dot(left) > 0; };
  if (is_left(arm[0]) == is_left(arm[1])) return NotABody("both arms are on the same side");
  if (is_left(leg[0]) == is_left(leg[1])) return NotABody("both legs are on the same side");

  // 4. Vertex labels (arms first, then legs), triangles by majority.
  std::vector<uint8_t> vlabel(nv, static_cast<uint8_t>(Region::kTorso));
  auto paint = [&](const Limb& l, Region r) {
    for (uint32_t v : reps)
      if (l.region[v] && vlabel[v] == static_cast<uint8_t>(Region::kTorso)) vlabel[v] = static_cast<uint8_t>(r);
  };
  for (const Limb& a : arm) paint(a, is_left(a) ? Region::kLeftArm : Region::kRightArm);
  for (const Limb& l : leg) paint(l, is_left(l) ? Region::kLeftLeg : Region::kRightLeg);

  Segmentation seg;
  seg.method = "geometry";
  const uint32_t nt = mesh.triangle_count();
  seg.triangle_regions.resize(nt);
  for (uint32_t t = 0; t < nt; ++t) {
    const uint8_t a = vlabel[g.rep[mesh.indices[3 * t]]], b = vlabel[g.rep[mesh.indices[3 * t + 1]]],
                  c = vlabel[g.rep[mesh.indices[3 * t + 2]]];
    seg.triangle_regions[t] = (a == b || a == c) ? a : (b == c ? b : static_cast<uint8_t>(Region::kTorso));
  }
  seg.notes = notes.str();
  MakeLimbsConnected(mesh, seg.triangle_regions, seg.notes);
  for (int r = 0; r < kRegionCount - 1; ++r) {
    if (std::find(seg.triangle_regions.begin(), seg.triangle_regions.end(), r) == seg.triangle_regions.end())
      return NotABody(std::string("no triangles left for ") + RegionName(static_cast<Region>(r)));
  }
  ComputeVertexRegions(mesh, seg);
  seg.notes += RegionCounts(seg.triangle_regions);
  if (ctx) ctx->Info("segment (geometry): " + seg.notes);
  return seg;
}

}  // namespace spherechain::baker
