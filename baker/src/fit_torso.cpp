// spherechain baker — the torso (non-tubular region, paper §3.2): a disk of N_r rays moves up the torso
// in steps of δ; at each level the rays' nearest hits are split by the sagittal plane into the
// character's left and right halves, each approximated by a sphere (φ1, N_s = 2). Levels are kept like
// the moving circumference keeps positions (neighbours overlap by PD). Each sphere is then adjusted
// towards the disk centre (φ1', Figures 4–5) and labelled L/R/T/D (Figure 6).
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "geometry.h"
#include "spherechain/baker/fit.h"

namespace spherechain::baker {

namespace {

using Eigen::Vector3d;
using fit_detail::Vertex;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;

Vector3d RegionCentroid(const Mesh& mesh, const Segmentation& seg, Region r, size_t* count) {
  Vector3d c = Vector3d::Zero();
  size_t n = 0;
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t)
    if (seg.triangle_regions[t] == static_cast<uint8_t>(r))
      for (int k = 0; k < 3; ++k, ++n) c += Vertex(mesh, mesh.indices[3 * t + k]);
  *count = n;
  return n ? Vector3d(c / static_cast<double>(n)) : c;
}

/// One half (column) of one disk level.
struct HalfFit {
  bool valid = false;
  Vector3d c = Vector3d::Zero();  // φ1 centre
  double r = 0.0;                 // φ1 radius
  double r_spacing = 0.0;         // radius used to space levels: the half's nearest hit from the disk
                                  // centre, about the size φ1' reaches once moved towards that centre
  std::vector<int> rays;          // ray ids of this half
  std::vector<uint32_t> hit_tris;
};

struct Level {
  double h = 0.0;                   // height along up
  Vector3d disk_center = Vector3d::Zero();
  std::vector<double> hit;          // N_r distances (+inf = miss)
  std::vector<uint32_t> hit_tri;    // N_r triangle slots (grid order) or UINT32_MAX
  HalfFit half[2];
  bool valid = false;
};

/// φ1' for a sphere (§3.2, Figures 4–5): centre c(t) = c1 + t (disk − c1), t ∈ [0, 1], moving in the
/// disk plane towards the disk centre; radius = the nearest point's distance, so the sphere still only
/// touches the surface and stays inside the body (a collision proxy must not bulge out: an arm hanging
/// beside the torso would otherwise overlap it at the bind pose and its contacts be excluded forever);
/// t minimises mean |F| under that constraint (grid, then golden section). t = 0 is φ1's centre, so
/// mean |F| of φ1' never exceeds that of φ1 measured the same way.
void Adjust(const Vector3d& c1, const Vector3d& disk, const std::vector<Vector3d>& pts, Vector3d* c_out,
            double* r_out) {
  std::vector<double> d(pts.size());
  auto eval = [&](double t, double* radius) {
    const Vector3d c = c1 + t * (disk - c1);
    for (size_t i = 0; i < pts.size(); ++i) d[i] = (pts[i] - c).norm();
    const double r = *std::min_element(d.begin(), d.end());
    double s = 0.0;
    for (double x : d) s += std::abs(r - x);
    if (radius) *radius = r;
    return s / static_cast<double>(d.size());
  };
  constexpr int kSteps = 40;
  int best = 0;
  double best_cost = kInf;
  for (int i = 0; i <= kSteps; ++i) {
    const double cost = eval(static_cast<double>(i) / kSteps, nullptr);
    if (cost < best_cost) best_cost = cost, best = i;
  }
  double lo = std::max(0.0, (best - 1.0) / kSteps), hi = std::min(1.0, (best + 1.0) / kSteps);
  double best_t = static_cast<double>(best) / kSteps;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  for (int it = 0; it < 30; ++it) {
    const double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
    const double fa = eval(a, nullptr), fb = eval(b, nullptr);
    if (fa < best_cost) best_cost = fa, best_t = a;
    if (fb < best_cost) best_cost = fb, best_t = b;
    if (fa < fb) hi = b; else lo = a;
  }
  double r = 0.0;
  eval(best_t, &r);
  *c_out = c1 + best_t * (disk - c1);
  *r_out = r;
}

}  // namespace

Result<std::vector<FittedSphere>> FitTorso(const Mesh& mesh, const std::vector<uint32_t>& torso_triangles,
                                           const Segmentation& seg, const FitParams& params, Context* ctx) {
  if (torso_triangles.empty()) return MakeError(Error::Code::kFit, "fit torso: region has no triangles");
  if (params.rays < 8 || params.rays % 2 != 0)
    return MakeError(Error::Code::kFit, "fit torso: rays must be an even number >= 8");
  if (params.spheres_per_level != 2)
    return MakeError(Error::Code::kFit, "fit torso: only 2 spheres per level are supported");
  if (!(params.penetration_depth >= 0.0 && params.penetration_depth <= 0.9))
    return MakeError(Error::Code::kFit, "fit: penetration_depth must be in [0, 0.9]");
  const uint32_t tcount = mesh.triangle_count();
  if (seg.triangle_regions.size() != tcount)
    return MakeError(Error::Code::kFit, "fit torso: segmentation does not match the mesh's triangle count");
  for (uint32_t t : torso_triangles)
    if (t >= tcount) return MakeError(Error::Code::kFit, "fit torso: triangle index out of range");
  const double delta = fit_detail::DiskStep(mesh, params);
  if (!(delta > 0.0)) return MakeError(Error::Code::kFit, "fit torso: disk step δ is not positive");

  // Frame: up, the character's left (from the arms, else the legs), forward = left × up.
  const Vector3d up = fit_detail::UpVector(mesh.up_axis);
  Vector3d left = Vector3d::Zero();
  for (auto [l, r] : {std::pair{Region::kLeftArm, Region::kRightArm}, std::pair{Region::kLeftLeg, Region::kRightLeg}}) {
    size_t nl = 0, nr = 0;
    const Vector3d cl = RegionCentroid(mesh, seg, l, &nl), cr = RegionCentroid(mesh, seg, r, &nr);
    if (nl && nr) {
      left = cl - cr;
      left -= left.dot(up) * up;
      if (left.norm() > 1e-9) break;
    }
  }
  if (left.norm() <= 1e-9) {
    left = up.cross(Vector3d::UnitZ());
    if (left.norm() < 0.5) left = Vector3d::UnitX();
    left = up.cross(left).cross(up);
    if (ctx) ctx->Warn("fit torso: no left/right limbs to orient by; the character's left is assumed");
  }
  left.normalize();
  const Vector3d fwd = left.cross(up).normalized();

  // Torso triangles and their height spans.
  const fit_detail::TriangleGrid grid(mesh, torso_triangles);
  const size_t nt = grid.size();
  std::vector<double> tlo(nt), thi(nt);
  double hmin = kInf, hmax = -kInf;
  for (size_t i = 0; i < nt; ++i) {
    const double ha = grid.a(i).dot(up), hb = grid.b(i).dot(up), hc = grid.c(i).dot(up);
    tlo[i] = std::min({ha, hb, hc});
    thi[i] = std::max({ha, hb, hc});
    hmin = std::min(hmin, tlo[i]);
    hmax = std::max(hmax, thi[i]);
  }
  std::vector<size_t> by_lo(nt);
  std::iota(by_lo.begin(), by_lo.end(), 0);
  std::sort(by_lo.begin(), by_lo.end(), [&](size_t a, size_t b) { return tlo[a] < tlo[b]; });

  // Ray directions: θ_k = 2π(k + ½)/N_r from forward towards the left; rays 0..N_r/2−1 are the
  // character's left half (column 0), the rest the right half (column 1).
  const int nr = params.rays;
  std::vector<Vector3d> dirs(nr);
  for (int k = 0; k < nr; ++k) {
    const double th = 2.0 * kPi * (k + 0.5) / nr;
    dirs[k] = std::cos(th) * fwd + std::sin(th) * left;
  }

  // Sweep the disk.
  std::vector<Level> levels;
  std::vector<size_t> cand;
  for (double h = hmin + 0.5 * delta; h < hmax; h += delta) {
    Level L;
    L.h = h;
    cand.clear();
    for (size_t idx : by_lo) {
      if (tlo[idx] > h) break;
      if (thi[idx] >= h) cand.push_back(idx);
    }
    if (cand.empty()) {
      levels.push_back(std::move(L));
      continue;
    }
    Vector3d c = Vector3d::Zero();
    for (size_t idx : cand) c += (grid.a(idx) + grid.b(idx) + grid.c(idx)) / 3.0;
    c /= static_cast<double>(cand.size());
    c += (h - c.dot(up)) * up;
    L.hit.assign(nr, kInf);
    L.hit_tri.assign(nr, UINT32_MAX);
    for (int iter = 0; iter < 4; ++iter) {
      Vector3d sum = Vector3d::Zero();
      int nh = 0;
      for (int k = 0; k < nr; ++k) {
        double best = kInf;
        uint32_t bt = UINT32_MAX;
        for (size_t idx : cand) {
          const double t = fit_detail::RayTriangle(c, dirs[k], grid.a(idx), grid.b(idx), grid.c(idx));
          // The ray's last exit from the torso surface: inner surfaces (mouth, eye sockets) do not
          // stop it; the outer skin does.
          if (t < kInf && (best == kInf || t > best)) best = t, bt = static_cast<uint32_t>(idx);
        }
        L.hit[k] = best;
        L.hit_tri[k] = bt;
        if (best < kInf) sum += c + best * dirs[k], ++nh;
      }
      if (nh == 0) break;
      const Vector3d nc = sum / nh;
      if ((nc - c).norm() < 1e-4 * delta || iter == 3) break;
      c = nc;  // iterate: the centre of the hits
    }
    L.disk_center = c;
    bool all = true;
    for (int col = 0; col < 2; ++col) {
      HalfFit& hf = L.half[col];
      Vector3d sum = Vector3d::Zero();
      int nh = 0;
      for (int k = col * nr / 2; k < (col + 1) * nr / 2; ++k) {
        hf.rays.push_back(k);
        if (L.hit[k] < kInf) {
          sum += c + L.hit[k] * dirs[k];
          ++nh;
          hf.hit_tris.push_back(L.hit_tri[k]);
        }
      }
      // A half needs most of its rays to hit (rays may leave through the arm openings at the
      // shoulders).
      if (nh < (nr / 2) * 2 / 5) {
        all = false;
        continue;
      }
      hf.c = sum / nh;
      hf.r_spacing = kInf;
      for (int k = col * nr / 2; k < (col + 1) * nr / 2; ++k) hf.r_spacing = std::min(hf.r_spacing, L.hit[k]);
      hf.valid = true;
    }
    L.valid = all;
    levels.push_back(std::move(L));
  }

  // φ1 radius: the sphere collides with the surface — the nearest of the level's hit points (in the
  // disk plane) and of the surrounding region (every triangle some ray hit, in 3-D, so the sphere
  // stays inside the torso above and below its level too).
  std::vector<uint32_t> surrounding;
  for (const Level& L : levels)
    for (uint32_t slot : L.hit_tri)
      if (slot != UINT32_MAX) surrounding.push_back(torso_triangles[slot]);
  std::sort(surrounding.begin(), surrounding.end());
  surrounding.erase(std::unique(surrounding.begin(), surrounding.end()), surrounding.end());
  const fit_detail::TriangleGrid skin(mesh, surrounding);
  for (Level& L : levels) {
    if (!L.valid) continue;
    for (HalfFit& hf : L.half) {
      double r = kInf;
      for (int k = 0; k < nr; ++k)
        if (L.hit[k] < kInf) r = std::min(r, (L.disk_center + L.hit[k] * dirs[k] - hf.c).norm());
      r = std::min(r, skin.NearestDistance(hf.c));
      hf.r = r;
      hf.valid = r > 0.0;
      L.valid = L.valid && hf.valid;
    }
  }

  // Keep levels like the moving circumference: the first that fits above the bottom, then the first
  // whose pair overlaps the previous pair by no more than PD, then one near the top of the head.
  const double keep = 1.0 - params.penetration_depth;
  auto fits = [&](size_t i) {
    const Level& L = levels[i];
    if (!L.valid) return false;
    const double rmax = std::max(L.half[0].r, L.half[1].r);
    return L.h - hmin >= 0.5 * rmax && hmax - L.h >= rmax;
  };
  auto far_enough = [&](size_t p, size_t j, double factor) {
    for (int col = 0; col < 2; ++col) {
      // Spaced by the size the spheres will have after the adjustment (§3.2), not φ1's: φ1 is small
      // where the cross-section is round (neck, head) and would stack levels there.
      const HalfFit &a = levels[p].half[col], &b = levels[j].half[col];
      const double ra = std::max(a.r, a.r_spacing), rb = std::max(b.r, b.r_spacing);
      if ((a.c - b.c).norm() < factor * keep * (ra + rb)) return false;
    }
    return true;
  };
  std::vector<size_t> chosen;
  for (size_t i = 0; i < levels.size(); ++i) {
    if (!fits(i)) continue;
    if (chosen.empty() || far_enough(chosen.back(), i, 1.0)) chosen.push_back(i);
  }
  if (chosen.empty()) return MakeError(Error::Code::kFit, "fit torso: no disk level has a closed cross-section");
  for (size_t j = levels.size(); j-- > chosen.back() + 1;) {
    if (!fits(j)) continue;
    if (far_enough(chosen.back(), j, 0.5)) chosen.push_back(j);
    break;
  }

  // Shoulder band (T): heights where the arms' triangles touch the torso's.
  double t_lo = kInf, t_hi = -kInf;
  {
    std::vector<uint8_t> vmask(mesh.vertex_count(), 0);  // bit 0: arm, bit 1: torso
    for (uint32_t t = 0; t < tcount; ++t) {
      const uint8_t r = seg.triangle_regions[t];
      const uint8_t bit = (r == static_cast<uint8_t>(Region::kLeftArm) || r == static_cast<uint8_t>(Region::kRightArm))
                              ? 1
                              : (r == static_cast<uint8_t>(Region::kTorso) ? 2 : 0);
      for (int k = 0; k < 3; ++k) vmask[mesh.indices[3 * t + k]] |= bit;
    }
    for (uint32_t v = 0; v < mesh.vertex_count(); ++v)
      if (vmask[v] == 3) {
        const double h = Vertex(mesh, v).dot(up);
        t_lo = std::min(t_lo, h);
        t_hi = std::max(t_hi, h);
      }
  }
  std::vector<uint8_t> is_t(chosen.size(), 0);
  if (t_lo <= t_hi) {
    bool any = false;
    for (size_t i = 0; i < chosen.size(); ++i)
      if (levels[chosen[i]].h >= t_lo && levels[chosen[i]].h <= t_hi) is_t[i] = 1, any = true;
    if (!any) {
      size_t best = 0;
      const double mid = 0.5 * (t_lo + t_hi);
      for (size_t i = 1; i < chosen.size(); ++i)
        if (std::abs(levels[chosen[i]].h - mid) < std::abs(levels[chosen[best]].h - mid)) best = i;
      is_t[best] = 1;
    }
  } else if (ctx) {
    ctx->Warn("fit torso: the arms do not touch the torso; no T label");
  }

  std::vector<FittedSphere> out;
  for (size_t li = 0; li < chosen.size(); ++li) {
    const Level& L = levels[chosen[li]];
    for (int col = 0; col < 2; ++col) {
      const HalfFit& hf = L.half[col];
      FittedSphere s;
      s.region = Region::kTorso;
      s.level = static_cast<int>(li);
      s.column = col;
      s.sequence = static_cast<int>(2 * li + col);
      s.labels = col == 0 ? kLabelL : kLabelR;
      if (is_t[li]) s.labels |= kLabelT;
      if (li == 0) s.labels |= kLabelD;
      s.center_phi1 = hf.c;
      s.radius_phi1 = hf.r;
      s.disk_center = L.disk_center;
      for (int k : hf.rays) {
        s.ray_ids.push_back(k);
        s.ray_dirs.push_back(dirs[k]);
        s.ray_hit.push_back(L.hit[k]);
      }
      for (uint32_t slot : hf.hit_tris) {
        const uint32_t t = torso_triangles[slot];
        for (int k = 0; k < 3; ++k) s.support_vertices.push_back(mesh.indices[3 * t + k]);
      }
      std::sort(s.support_vertices.begin(), s.support_vertices.end());
      s.support_vertices.erase(std::unique(s.support_vertices.begin(), s.support_vertices.end()),
                               s.support_vertices.end());
      std::vector<Vector3d> pts;
      pts.reserve(s.support_vertices.size());
      for (uint32_t v : s.support_vertices) pts.push_back(Vertex(mesh, v));
      Adjust(s.center_phi1, L.disk_center, pts, &s.center, &s.radius);
      const Ball b = MinimumEnclosingBall(pts);
      s.center_phi2 = b.center;
      s.radius_phi2 = b.radius;
      out.push_back(std::move(s));
    }
  }
  if (ctx)
    ctx->Debug("fit torso: " + std::to_string(levels.size()) + " disk levels (δ = " + std::to_string(delta) +
               "), " + std::to_string(chosen.size()) + " kept, " + std::to_string(out.size()) + " spheres");
  return out;
}

}  // namespace spherechain::baker
