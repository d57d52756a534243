// spherechain baker — the "cover" fit (fit.h FitCover): spheres that fill the body. Inner balls centred on
// the voxels of the body's interior, radius the exact distance to the surface, chosen by lazy greedy
// set cover of the interior (Coverage Axis, Dou et al. 2022; lazy evaluation, Minoux 1978) and then
// moved voxel by voxel while the covered volume grows (coordinate ascent on the coverage objective of
// variational sphere sets, Wang et al. 2006); then a skin pass, greedy set cover of the limb vertices
// the volume cover leaves beyond a tolerance (the surface-distance term of sphere-set fitting, e.g.
// MorphIt 2025, spent where the body is thin: hands, feet).
#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <limits>
#include <numeric>
#include <queue>
#include <unordered_map>
#include <string>

#include <Eigen/Eigenvalues>

#include "geometry.h"
#include "parallel.h"
#include "surface_tree.h"
#include "spherechain/baker/coverage.h"
#include "spherechain/baker/fit.h"

namespace spherechain::baker {
namespace {

using surface_detail::Point3;
using surface_detail::Tree;
using Eigen::Vector3d;

constexpr uint8_t kOutside = 0xFF;

using detail::ParallelFor;

// The interior as a dense grid: region label (kOutside outside), distance to the surface, and how many
// chosen spheres of the voxel's own region cover it.
struct Field {
  uint32_t n[3] = {0, 0, 0};
  size_t stride[3] = {1, 0, 0};
  double h = 0.0;
  Vector3d origin = Vector3d::Zero();
  std::vector<uint8_t> label;
  std::vector<float> dist;  // [Units: voxels]
  std::vector<uint16_t> count;
  float grow = 0.0f;  // dilation added to every ball [Units: voxels]
  int regions = kRegionCount;                 // region values below this (RegionLayout::count())
  std::array<double, kMaxRegions> volume{};   // voxels of each region
  std::array<double, kMaxRegions> weight{};   // gain per voxel of each region: volume^-balance

  void Coords(size_t v, int64_t* i, int64_t* j, int64_t* k) const {
    *i = int64_t(v % n[0]);
    *j = int64_t((v / n[0]) % n[1]);
    *k = int64_t(v / stride[2]);
  }
  Vector3d Centre(size_t v) const {
    int64_t i, j, k;
    Coords(v, &i, &j, &k);
    return origin + h * Vector3d(double(i) + 0.5, double(j) + 0.5, double(k) + 0.5);
  }

  // Calls fn(voxel) for every interior voxel whose centre lies within dist[c] + grow (voxel units) of
  // voxel c's centre.
  template <class Fn>
  void ForBall(size_t c, Fn&& fn) const {
    int64_t ci, cj, ck;
    Coords(c, &ci, &cj, &ck);
    const double r = double(dist[c]) + grow, r2 = r * r;
    const int64_t R = int64_t(std::floor(r));
    for (int64_t dk = -R; dk <= R; ++dk) {
      const int64_t k = ck + dk;
      if (k < 0 || k >= int64_t(n[2])) continue;
      for (int64_t dj = -R; dj <= R; ++dj) {
        const int64_t j = cj + dj;
        if (j < 0 || j >= int64_t(n[1])) continue;
        const double rest = r2 - double(dj * dj + dk * dk);
        if (rest < 0.0) continue;
        const int64_t half = int64_t(std::floor(std::sqrt(rest)));
        const int64_t i0 = std::max<int64_t>(0, ci - half), i1 = std::min<int64_t>(int64_t(n[0]) - 1, ci + half);
        const size_t row = size_t(j) * stride[1] + size_t(k) * stride[2];
        for (int64_t i = i0; i <= i1; ++i)
          if (label[row + size_t(i)] != kOutside) fn(row + size_t(i));
      }
    }
  }
  // What a sphere at c would add: the interior voxels it covers that no sphere covers yet, each
  // weighted by its region's weight.
  double Gain(size_t c) const {
    std::array<uint32_t, kMaxRegions> g{};
    ForBall(c, [&](size_t v) { g[label[v]] += count[v] == 0; });
    return Weighted(g);
  }
  // Voxel counts per region, each weighted by its region's weight.
  double Weighted(const std::array<uint32_t, kMaxRegions>& per_region) const {
    double sum = 0.0;
    for (int r = 0; r < regions; ++r) sum += per_region[r] * weight[r];
    return sum;
  }
  void Apply(size_t c, int delta) {
    ForBall(c, [&](size_t v) { count[v] = static_cast<uint16_t>(count[v] + delta); });
  }
  // Calls fn(voxel) for every interior voxel whose centre lies in a ball off the grid (centre [Units:
  // source], radius [Units: voxels], the dilation added).
  template <class Fn>
  void ForWorldBall(const Vector3d& centre, double radius, Fn&& fn) const {
    const Vector3d g = (centre - origin) / h - Vector3d::Constant(0.5);
    const double r = radius + grow, r2 = r * r;
    const int64_t lo[3] = {int64_t(std::ceil(g.x() - r)), int64_t(std::ceil(g.y() - r)), int64_t(std::ceil(g.z() - r))};
    const int64_t hi[3] = {int64_t(std::floor(g.x() + r)), int64_t(std::floor(g.y() + r)), int64_t(std::floor(g.z() + r))};
    for (int64_t k = std::max<int64_t>(0, lo[2]); k <= std::min<int64_t>(int64_t(n[2]) - 1, hi[2]); ++k)
      for (int64_t j = std::max<int64_t>(0, lo[1]); j <= std::min<int64_t>(int64_t(n[1]) - 1, hi[1]); ++j)
        for (int64_t i = std::max<int64_t>(0, lo[0]); i <= std::min<int64_t>(int64_t(n[0]) - 1, hi[0]); ++i) {
          const Vector3d d = Vector3d(double(i), double(j), double(k)) - g;
          const size_t v = size_t(i) + size_t(j) * stride[1] + size_t(k) * stride[2];
          if (d.squaredNorm() <= r2 && label[v] != kOutside) fn(v);
        }
  }
  // Counts a ball off the grid as covering the interior voxels whose centres it holds: the skin pass's
  // medial balls (6b) in 6c, every final ball in 6d.
  void ApplyBall(const Vector3d& centre, double radius, int delta) {
    ForWorldBall(centre, radius, [&](size_t v) { count[v] = static_cast<uint16_t>(count[v] + delta); });
  }
  // What removing a ball off the grid would lose: the interior voxels only it covers, weighted as in Gain.
  double LossBall(const Vector3d& centre, double radius) const {
    std::array<uint32_t, kMaxRegions> g{};
    ForWorldBall(centre, radius, [&](size_t v) { g[label[v]] += count[v] == 1; });
    return Weighted(g);
  }
};

// The medial ball behind skin point `p`: the ray from p along its inward unit normal `n` to where it leaves
// the body (the far side of a finger, a palm, a toe), its midpoint the centre, the distance from there to the
// skin the radius (inscribed by construction). The single-ray form of the shape diameter function (Shapira,
// Shamir & Cohen-Or 2008) and of ray-shooting medial approximations. Triangles with a corner at p are skipped;
// `exit` receives the primitive the ray leaves through. Returns the radius, 0 when the ray never leaves
// (n points out of a closed body) or leaves within `t_min`.
double MedialBallAlongNormal(const Tree& tree, const surface_detail::TriangleList& tris, const Vector3d& p,
                             const Vector3d& n, double t_min, Vector3d* centre, size_t* exit) {
  using Ray3 = surface_detail::K::Ray_3;
  const Point3 origin(p.x(), p.y(), p.z());
  const double eps2 = t_min * t_min * 1e-6;
  auto at_p = [&](surface_detail::TriangleList::const_iterator it) {
    for (int k = 0; k < 3; ++k)
      if (CGAL::squared_distance((*it)[k], origin) <= eps2) return true;
    return false;
  };
  const Ray3 ray(origin, surface_detail::K::Vector_3(n.x(), n.y(), n.z()));
  const auto hit = tree.first_intersected_primitive(ray, at_p);
  if (!hit) return 0.0;
  const surface_detail::Triangle3& tri = **hit;
  const Vector3d a(tri[0].x(), tri[0].y(), tri[0].z()), b(tri[1].x(), tri[1].y(), tri[1].z()),
      c(tri[2].x(), tri[2].y(), tri[2].z());
  const double t = fit_detail::RayTriangle(p, n, a, b, c);
  if (!(t > t_min) || !std::isfinite(t)) return 0.0;
  *centre = p + 0.5 * t * n;
  *exit = size_t(*hit - tris.cbegin());
  const Point3 q(centre->x(), centre->y(), centre->z());
  return std::sqrt(CGAL::squared_distance(q, tree.closest_point(q)));
}

// Per vertex: bit 0 when a triangle of one of `limbs` uses it, bit 1 when a triangle of `base` does (3: on
// the junction). `base`: the torso (trunk) by default; a limb's parent for its own junction (a hand's arm).
std::vector<uint8_t> JunctionMask(const Mesh& mesh, const Segmentation& seg, std::initializer_list<Region> limbs,
                                  int base = -1) {
  std::vector<uint8_t> mask(mesh.vertex_count(), 0);
  const uint8_t base_region = uint8_t(base >= 0 ? Region(base) : seg.layout.trunk());
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    const uint8_t r = seg.triangle_regions[t];
    uint8_t bit = r == base_region ? 2 : 0;
    for (Region l : limbs)
      if (r == uint8_t(l)) bit = 1;
    if (bit)
      for (int k = 0; k < 3; ++k) mask[mesh.indices[3 * t + k]] |= bit;
  }
  return mask;
}

// Mean of the vertices shared by region `reg`'s triangles and its parent's (the torso; a hand's arm, a
// foot's leg: RegionLayout::Parent) — its root —, or the region's vertex nearest the torso's centroid
// when the two do not touch.
Vector3d LimbRoot(const Mesh& mesh, const Segmentation& seg, Region reg, const Vector3d& torso_centroid) {
  const uint32_t V = mesh.vertex_count();
  const std::vector<uint8_t> mask = JunctionMask(mesh, seg, {reg}, int(seg.layout.Parent(reg)));
  Vector3d sum = Vector3d::Zero();
  size_t n = 0;
  double best = std::numeric_limits<double>::infinity();
  Vector3d nearest = torso_centroid;
  for (uint32_t v = 0; v < V; ++v) {
    if (mask[v] == 3) sum += fit_detail::Vertex(mesh, v), ++n;
    if (mask[v] & 1) {
      const double d = (fit_detail::Vertex(mesh, v) - torso_centroid).squaredNorm();
      if (d < best) best = d, nearest = fit_detail::Vertex(mesh, v);
    }
  }
  return n ? Vector3d(sum / double(n)) : nearest;
}

// Heights (along up) of the vertices shared by the torso and any of `limbs`: [lo, hi]; empty → lo > hi.
std::pair<double, double> JunctionBand(const Mesh& mesh, const Segmentation& seg, const Vector3d& up,
                                       std::initializer_list<Region> limbs) {
  const uint32_t V = mesh.vertex_count();
  const std::vector<uint8_t> mask = JunctionMask(mesh, seg, limbs);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (uint32_t v = 0; v < V; ++v)
    if (mask[v] == 3) {
      const double y = fit_detail::Vertex(mesh, v).dot(up);
      lo = std::min(lo, y), hi = std::max(hi, y);
    }
  return {lo, hi};
}

// The plane that separates limb `reg` from its parent (the torso; a hand's arm, a foot's leg):
// least-squares plane through the vertices the two share (the junction loop at the shoulder, hip, wrist
// or ankle), its normal pointing into the limb (towards the mean of the limb's vertices). Returns false
// when they share fewer than 3 vertices or the loop is too close to a line for a plane to be defined.
bool JunctionPlane(const Mesh& mesh, const Segmentation& seg, Region reg, Vector3d* origin, Vector3d* normal) {
  const uint32_t V = mesh.vertex_count();
  const std::vector<uint8_t> mask = JunctionMask(mesh, seg, {reg}, int(seg.layout.Parent(reg)));
  Vector3d sum = Vector3d::Zero(), limb = Vector3d::Zero();
  size_t n = 0, n_limb = 0;
  for (uint32_t v = 0; v < V; ++v) {
    if (mask[v] == 3) sum += fit_detail::Vertex(mesh, v), ++n;
    if (mask[v] == 1) limb += fit_detail::Vertex(mesh, v), ++n_limb;
  }
  if (n < 3 || n_limb == 0) return false;
  const Vector3d o = sum / double(n);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (uint32_t v = 0; v < V; ++v)
    if (mask[v] == 3) {
      const Vector3d d = fit_detail::Vertex(mesh, v) - o;
      cov += d * d.transpose();
    }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  const Eigen::Vector3d ev = es.eigenvalues();  // ascending
  if (!(ev[1] > 1e-3 * ev[2])) return false;   // collinear junction: no plane
  Vector3d nrm = es.eigenvectors().col(0);
  if (nrm.dot(limb / double(n_limb) - o) < 0.0) nrm = -nrm;
  *origin = o;
  *normal = nrm;
  return true;
}

// One entry per sphere of the fit: the voxel it grew from, and (from step 6 on) the ball it became.
struct CoverBall {
  static constexpr uint32_t kMedial = std::numeric_limits<uint32_t>::max();  // no voxel: a medial ball (6b)
  uint32_t voxel = kMedial;  ///< interior voxel index, or kMedial
  uint8_t region = kOutside;
  bool skin = false;         ///< placed by the skin pass (6b): it covers skin, not volume (6d keeps it)
  Vector3d centre = Vector3d::Zero();  ///< [Units: source] off the grid (6); before the dilation
  double radius = 0.0;                 ///< [Units: source] inscribed radius; before the dilation
};

}  // namespace

int SkinSpheres(const FitParams& params, const RegionLayout& layout) {
  if (params.skin_spheres >= 0) return params.skin_spheres;
  return layout.paper && !layout.IsPaperFive() ? 24 : 16;
}

Result<std::vector<FittedSphere>> FitCover(const Mesh& mesh, const Segmentation& seg, const FitParams& params,
                                           Context* ctx) {
  Context::Timer timer(ctx, "fit.cover");
  const uint32_t T = mesh.triangle_count();
  if (seg.triangle_regions.size() != T)
    return MakeError(Error::Code::kFit, "fit cover: segmentation does not match the mesh's triangle count");
  const RegionLayout& layout = seg.layout;
  const int nreg = layout.count();
  if (nreg < 2 || nreg > kMaxRegions)
    return MakeError(Error::Code::kFit, "fit cover: the layout has " + std::to_string(nreg) + " regions (2.." +
                                            std::to_string(kMaxRegions) + ")");
  if (params.max_spheres < std::max(kRegionCount, nreg) || params.max_spheres > 4096)
    return MakeError(Error::Code::kFit, "fit cover: max_spheres must be in [" + std::to_string(std::max(kRegionCount, nreg)) +
                                            ", 4096] (at least one sphere a region)");
  if (params.skin_spheres < FitParams::kSkinSpheresByLayout || params.skin_min_vertices < 1 ||
      !(params.skin_tolerance_rel >= 0.0 && params.skin_tolerance_rel <= 0.2))
    return MakeError(Error::Code::kFit, "fit cover: skin_spheres must be >= 0 (or -1: the layout's), skin_min_vertices >= 1, "
                                        "skin_tolerance_rel in [0, 0.2]");
  const int skin_spheres = SkinSpheres(params, layout);
  if (!(params.cover_voxel_rel >= 1e-3 && params.cover_voxel_rel <= 0.1))
    return MakeError(Error::Code::kFit, "fit cover: cover_voxel_rel must be in [0.001, 0.1]");
  if (params.cover_max_voxels < 0)
    return MakeError(Error::Code::kFit, "fit cover: cover_max_voxels must be >= 0 (0: no budget)");

  // 1. The interior.
  CoverageOptions vopt;
  vopt.voxel_rel = float(params.cover_voxel_rel);
  vopt.max_voxels = 16'000'000;
  auto vox = VoxelizeInterior(mesh.positions, mesh.indices, vopt, ctx);
  if (!vox.ok()) return MakeError(Error::Code::kFit, "fit cover: " + vox.error().message);
  // A creature lies along its longest extent, the voxels' scale: a bulky one (a quadruped's trunk and head)
  // has more interior at 1/200 of its length than the budget: coarser voxels, by the cube root of the excess
  // (2 % more, to land under it). The paper's bipeds are measured by their height, so a standing one has far
  // fewer (MakeHuman 95,000); their budget is FitParams::kBipedVoxelFactor times the creatures', which no standing body
  // reaches, so it only stops a body lying down (whose "height" is its thickness) from a fit of millions of
  // voxels.
  const size_t budget = params.cover_max_voxels == 0 ? 0
                        : layout.paper               ? size_t(params.cover_max_voxels) * FitParams::kBipedVoxelFactor
                                                     : size_t(params.cover_max_voxels);
  if (ctx) ctx->Debug("fit cover: " + std::to_string(vox->inside.size()) + " interior voxels");
  if (budget > 0 && vox->inside.size() > budget) {
    const double grow = 1.02 * std::cbrt(double(vox->inside.size()) / double(budget));
    if (ctx)
      ctx->Info("fit cover: " + std::to_string(vox->inside.size()) + " interior voxels, over the budget " +
                std::to_string(budget) + " (cover_max_voxels" + (layout.paper ? " × " + std::to_string(FitParams::kBipedVoxelFactor) : "") +
                "): voxels " + std::to_string(grow) + " times larger");
    vopt.voxel_rel = float(params.cover_voxel_rel * grow);
    Context::Timer t(ctx, "fit.cover.voxelize_coarser");  // its own name: the report keys timings by name
    vox = VoxelizeInterior(mesh.positions, mesh.indices, vopt, nullptr);
    if (!vox.ok()) return MakeError(Error::Code::kFit, "fit cover: " + vox.error().message);
  }
  const InteriorVoxels& iv = vox.value();
  const double height = iv.body_height;
  if (iv.inside.size() < 64)
    return MakeError(Error::Code::kFit, "fit cover: the mesh encloses almost no volume (" +
                                            std::to_string(iv.inside.size()) +
                                            " interior voxels): is it a closed surface?");

  Field F;
  for (int a = 0; a < 3; ++a) F.n[a] = iv.dims[a];
  F.stride[1] = F.n[0];
  F.stride[2] = size_t(F.n[0]) * F.n[1];
  F.h = iv.voxel_size;
  F.origin = iv.origin;
  const size_t total = F.stride[2] * F.n[2];
  F.regions = nreg;
  F.label.assign(total, kOutside);
  F.dist.assign(total, 0.0f);
  F.count.assign(total, 0);

  // 2. Distance to the surface and region (of the nearest triangle) of every interior voxel.
  const surface_detail::SurfaceTriangles surface = surface_detail::NonDegenerateTriangles(mesh.positions, mesh.indices);
  const surface_detail::TriangleList& tris = surface.triangles;
  const std::vector<uint32_t>& tri_ids = surface.ids;
  if (tris.empty()) return MakeError(Error::Code::kFit, "fit cover: every triangle is degenerate");
  Tree tree(tris.begin(), tris.end());
  {
    // Fixed chunks of consecutive interior voxels, each started without a hint and then hinted by the
    // previous voxel's closest point: the chunks, not the threads, decide the hints, so the labels (a
    // tie between two triangles may go either way with another hint) are the same on any thread count.
    Context::Timer t(ctx, "fit.cover.distance");
    tree.build();
    tree.accelerate_distance_queries();
    constexpr size_t kChunk = 4096;
    const size_t chunks = (iv.inside.size() + kChunk - 1) / kChunk;
    auto query_chunk = [&](size_t c) {
      const size_t end = std::min(iv.inside.size(), (c + 1) * kChunk);
      Point3 hint;
      size_t prev = SIZE_MAX;
      for (size_t i = c * kChunk; i < end; ++i) {
        const uint32_t v = iv.inside[i];
        const Vector3d p = iv.Centre(v);
        const Point3 q(p.x(), p.y(), p.z());
        const auto hit = prev + 1 == v ? tree.closest_point_and_primitive(q, std::make_pair(hint, tris.cbegin()))
                                       : tree.closest_point_and_primitive(q);
        hint = hit.first;
        prev = v;
        const uint8_t reg = seg.triangle_regions[tri_ids[size_t(hit.second - tris.cbegin())]];
        if (reg >= nreg) continue;
        F.label[v] = reg;
        F.dist[v] = float(std::sqrt(CGAL::squared_distance(q, hit.first)) / F.h);
      }
    };
    if (chunks > 0) query_chunk(0);  // the first query builds the search structures lazily: not in parallel
    ParallelFor(1, chunks, query_chunk);
    for (uint32_t v : iv.inside)
      if (F.label[v] < nreg) F.volume[F.label[v]] += 1.0;
  }
  // No limb sphere is centred behind its limb's junction plane (in the chest under a shoulder's skin,
  // in the pelvis under a hip's): the voxels there keep their region (a limb sphere may still reach
  // them), but a centre there follows the limb's skin out of the torso when the limb moves.
  std::vector<uint8_t> behind_junction(total, 0);
  {
    std::array<Vector3d, kMaxRegions> origin, normal;
    std::array<bool, kMaxRegions> has_plane{};
    for (int r = 0; r < nreg; ++r)
      if (layout.IsLimb(Region(r))) has_plane[r] = JunctionPlane(mesh, seg, Region(r), &origin[r], &normal[r]);
    for (uint32_t v : iv.inside) {
      const uint8_t reg = F.label[v];
      if (reg < nreg && has_plane[reg] && (iv.Centre(v) - origin[reg]).dot(normal[reg]) < 0.0)
        behind_junction[v] = 1;
    }
  }
  // Nor where the limb's skin does not enclose the centre: walking from the voxel along ±x, ±y, ±z to
  // the last interior voxel, at least 4 of the 6 walks must end at the limb's own skin. A hip under a
  // hanging arm's skin (nearest skin: the forearm lying against it) ends at the hip's and leg's skin
  // on most walks; a voxel inside the arm reaches arm skin on all but the walk along the arm.
  auto enclosed_by_own_skin = [&](size_t v) {
    int64_t c[3];
    F.Coords(v, &c[0], &c[1], &c[2]);
    int own = 0;
    for (int axis = 0; axis < 3; ++axis)
      for (int dir : {-1, 1}) {
        int64_t p[3] = {c[0], c[1], c[2]};
        size_t last = v;
        for (;;) {
          p[axis] += dir;
          if (p[axis] < 0 || p[axis] >= int64_t(F.n[axis])) break;
          const size_t w = size_t(p[0]) + size_t(p[1]) * F.stride[1] + size_t(p[2]) * F.stride[2];
          if (F.label[w] == kOutside) break;
          last = w;
        }
        own += F.label[last] == F.label[v];
      }
    return own >= 4;
  };
  std::array<bool, kMaxRegions> has_triangles{};
  for (uint8_t r : seg.triangle_regions)
    if (r < nreg) has_triangles[r] = true;
  for (int r = 0; r < nreg; ++r)
    if (has_triangles[r] && F.volume[r] < 1.0)
      return MakeError(Error::Code::kFit, std::string("fit cover: region ") + RegionSymbol(Region(r)) + " " + layout.Name(Region(r)) +
                                              " has no interior voxel (too thin for cover_voxel_rel " +
                                              std::to_string(params.cover_voxel_rel) + ")");

  double total_volume = 0.0;
  for (int r = 0; r < nreg; ++r) total_volume += F.volume[r];
  for (int r = 0; r < nreg; ++r)
    // A region cut out of another (the extended layout's head, hands and feet: RegionInfo::volume_group)
    // weighs its voxels by the share of the region it came from, so the volume cover spends the budget as
    // on the paper's five regions; the cut only decides which region each chosen sphere belongs to.
    if (F.volume[r] > 0.0) {
      const int g = layout.regions[size_t(r)].volume_group;
      double group_volume = 0.0;
      for (int q = 0; q < nreg; ++q)
        if (q == (g >= 0 ? g : r) || layout.regions[size_t(q)].volume_group == (g >= 0 ? g : r)) group_volume += F.volume[q];
      F.weight[r] = std::pow(group_volume / total_volume, -params.region_balance) / total_volume;
    } else {
      F.weight[r] = 0.0;
    }

  F.grow = float(params.dilation_rel * height / F.h);

  // 3. Candidates: interior voxels whose inscribed ball is at least min_radius (fingers and toes,
  //    thinner, are left to their neighbours' spheres) and at least one voxel.
  const float rmin = float(std::max(1.0, params.min_radius_rel * height / F.h));
  //    The greedy starts from every other voxel along each axis (an eighth of them: the set-cover
  //    gains are smooth at that scale) and the optimisation moves spheres over all of them.
  std::vector<uint32_t> cand, start;
  for (uint32_t v : iv.inside) {
    if (F.label[v] == kOutside || F.dist[v] < rmin) continue;
    if (behind_junction[v] || (F.label[v] != uint8_t(layout.trunk()) && !enclosed_by_own_skin(v))) continue;
    cand.push_back(v);
    int64_t i, j, k;
    F.Coords(v, &i, &j, &k);
    if (((i | j | k) & 1) == 0 || F.dist[v] < 2.0f) start.push_back(v);  // thin parts: every voxel
  }
  if (cand.empty()) return MakeError(Error::Code::kFit, "fit cover: no interior point is min_radius_rel from the surface");

  // 4. Lazy greedy set cover: the sphere that adds the largest share of its region's volume, until
  //    max_spheres or the best adds less than min_gain. Every region gets its first sphere before any
  //    region its second (a thin limb is never left without one).
  //    The same lazy greedy serves 6c (the budget the skin pass leaves): `greedy(budget)` adds spheres
  //    from `start` until `chosen` holds `budget` or the best adds less than min_gain.
  std::vector<CoverBall> chosen;
  std::array<int, kMaxRegions> per_region{};
  auto greedy = [&](int budget) {
    using Entry = std::pair<double, uint32_t>;  // gain, candidate voxel (ties: the larger index — fixed)
    std::vector<double> first_gain(start.size());  // every start's gain at once, on all cores
    ParallelFor(0, start.size(), [&](size_t i) { first_gain[i] = F.Gain(start[i]); });
    std::priority_queue<Entry> queue;
    for (size_t i = 0; i < start.size(); ++i) queue.emplace(first_gain[i], start[i]);
    while (!queue.empty() && int(chosen.size()) < budget) {
      auto [gain, c] = queue.top();
      queue.pop();
      const double now = F.Gain(c);
      if (!queue.empty() && now < queue.top().first) {
        queue.emplace(now, c);  // stale: re-queue with its current gain
        continue;
      }
      const bool first_of_region = per_region[F.label[c]] == 0;
      if (now < params.min_gain && !first_of_region) {
        // Below the threshold: only regions still without a sphere may take one.
        bool all_served = true;
        for (int r = 0; r < nreg; ++r) all_served = all_served && (per_region[r] > 0 || F.volume[r] == 0.0);
        if (all_served) break;
        continue;
      }
      F.Apply(c, +1);
      chosen.push_back({.voxel = c, .region = F.label[c]});
      ++per_region[F.label[c]];
    }
  };
  // The skin pass covers limb skin only: a body without limbs keeps the whole budget for its volume.
  bool has_limb = false;
  for (int r = 0; r < nreg; ++r) has_limb = has_limb || (layout.IsLimb(Region(r)) && F.volume[r] > 0.0);
  const int volume_budget =
      has_limb ? std::max(std::max(kRegionCount, nreg), params.max_spheres - skin_spheres) : params.max_spheres;
  {
    Context::Timer t(ctx, "fit.cover.greedy");
    greedy(volume_budget);
    for (int r = 0; r < nreg; ++r)
      if (per_region[r] == 0 && has_triangles[r])
        return MakeError(Error::Code::kFit, std::string("fit cover: no sphere fits region ") + RegionSymbol(Region(r)) + " " +
                                                layout.Name(Region(r)) +
                                                " (thinner than min_radius_rel, or max_spheres too small)");
  }
  const size_t volume_spheres = chosen.size();
  std::vector<uint8_t> is_cand(total, 0);  // 5 and 6b
  for (uint32_t c : cand) is_cand[c] = 1;

  // 5. Optimisation: move each sphere to the neighbouring voxel (26-neighbourhood, same region, a
  //    candidate) whose ball adds the most, while the covered volume grows.
  {
    Context::Timer t(ctx, "fit.cover.refine");
    for (int sweep = 0; sweep < params.refine_sweeps; ++sweep) {
      size_t moved = 0;
      for (CoverBall& ball : chosen) {
        uint32_t& c = ball.voxel;
        F.Apply(c, -1);
        const uint8_t reg = F.label[c];
        // The gains of c and of its 26 neighbours, computed on all cores, then compared in a fixed order.
        std::array<uint32_t, 27> site;
        std::array<double, 27> gain;
        size_t sites = 0;
        site[sites++] = c;
        int64_t ci, cj, ck;
        F.Coords(c, &ci, &cj, &ck);
        for (int dk = -1; dk <= 1; ++dk)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              const int64_t i = ci + di, j = cj + dj, k = ck + dk;
              if ((di | dj | dk) == 0 || i < 0 || j < 0 || k < 0 || i >= F.n[0] || j >= F.n[1] || k >= F.n[2]) continue;
              const size_t v = size_t(i) + size_t(j) * F.stride[1] + size_t(k) * F.stride[2];
              if (is_cand[v] && F.label[v] == reg) site[sites++] = uint32_t(v);
            }
        ParallelFor(0, sites, [&](size_t i) { gain[i] = F.Gain(site[i]); });
        double best = gain[0];
        uint32_t best_c = c;
        for (size_t i = 1; i < sites; ++i)
          if (gain[i] > best + 1e-12) best = gain[i], best_c = site[i];
        moved += best_c != c;
        c = best_c;
        F.Apply(c, +1);
      }
      if (moved == 0) break;
    }
  }

  // 6. Off the grid: each centre pushed away from its nearest surface point, half a voxel at a time
  //    while its inscribed radius grows (towards the medial axis: a voxel centre is up to half a voxel
  //    diagonal off it, which costs a thin limb a few % of its radius).
  auto off_grid = [&](uint32_t c) {  // → (centre, inscribed radius)
    Vector3d x = iv.Centre(c);
    Point3 q(x.x(), x.y(), x.z());
    Point3 near = tree.closest_point(q);
    double r = std::sqrt(CGAL::squared_distance(q, near));
    for (int it = 0; it < 8; ++it) {
      const Vector3d away = x - Vector3d(near.x(), near.y(), near.z());
      if (away.norm() <= 0.0) break;
      const Vector3d y = x + 0.5 * F.h * away.normalized();
      const Point3 qy(y.x(), y.y(), y.z());
      const Point3 ny = tree.closest_point(qy);
      const double ry = std::sqrt(CGAL::squared_distance(qy, ny));
      if (!(ry > r)) break;
      x = y, near = ny, r = ry;
    }
    return std::pair<Vector3d, double>(x, r);
  };
  auto place = [&](CoverBall& b) { std::tie(b.centre, b.radius) = off_grid(b.voxel); };
  for (CoverBall& b : chosen) place(b);

  // 6b. Skin pass: the limb vertices farther than skin_tolerance_rel outside every sphere of their
  //     region (a hand's fingers and palm, a foot: too little volume for the cover above) are covered
  //     greedily, each time by the candidate ball of their region that brings the most of them within
  //     tolerance (lazy greedy set cover of the surface), with the budget the volume cover left. The
  //     candidates: the interior voxels' balls, and the medial ball behind each uncovered vertex (off the
  //     voxel grid: a finger or a toe a few voxels thick has almost no interior voxel of its own, yet its
  //     medial balls are the spheres that follow it).
  const double dilation = params.dilation_rel * height;
  if (int skin_left = params.max_spheres - int(chosen.size()); skin_spheres > 0 && skin_left > 0) {
    Context::Timer t(ctx, "fit.cover.skin");
    const double tol = params.skin_tolerance_rel * height;
    const uint32_t V = mesh.vertex_count();
    std::vector<uint8_t> vreg(V, kOutside);
    for (uint32_t t = 0; t < T; ++t)
      for (int k = 0; k < 3; ++k) {
        // A vertex on a border between the trunk and a limb (or the head) is the limb's skin: the pass
        // leaves the trunk's own skin to the volume cover, not the rim of the parts cut from it
        // (BCN_Epileptic's chin, on the head's border with the neck, lay 2.9 % of the height outside).
        uint8_t& r = vreg[mesh.indices[3 * t + k]];
        if (r >= nreg || r == uint8_t(layout.trunk())) r = seg.triangle_regions[t];
      }
    // The head of the extended layout gets at most a quarter of the pass: a round part the volume cover
    // fills, whose face the pass would otherwise chase vertex by vertex (uncapped, CesiumMan's head ended with
    // 34 of its 128 spheres and each hand with 2–3); the face still gets some, for a hand laid on it.
    const int head = layout.paper && !layout.IsPaperFive() ? layout.Find("head") : -1;
    const int head_cap = std::max(1, skin_spheres / 4);
    int head_added = 0;
    std::vector<uint32_t> uncovered;
    std::vector<double> outside;
    for (uint32_t v = 0; v < V; ++v) {
      if (vreg[v] >= nreg || vreg[v] == uint8_t(layout.trunk())) continue;
      const Vector3d p = fit_detail::Vertex(mesh, v);
      double best = std::numeric_limits<double>::infinity();
      for (const CoverBall& b : chosen)
        if (b.region == vreg[v]) best = std::min(best, (p - b.centre).norm() - b.radius - dilation);
      if (best > tol) {
        uncovered.push_back(v);
        outside.push_back(best);
      }
    }
    // Which candidate balls bring which uncovered vertices within tolerance. Candidate keys: an interior
    // voxel's index (< total), or total + m for the medial ball m.
    std::unordered_map<uint32_t, std::vector<uint32_t>> reach;
    // (a) Interior voxels of the vertex's region in a cube of 3 % of the height around it.
    const int64_t K = int64_t(std::ceil(0.03 * height / F.h));
    for (uint32_t u = 0; u < uncovered.size(); ++u) {
      const Vector3d p = fit_detail::Vertex(mesh, uncovered[u]);
      const Vector3d g = (p - F.origin) / F.h;
      const int64_t ci = int64_t(std::floor(g.x())), cj = int64_t(std::floor(g.y())), ck = int64_t(std::floor(g.z()));
      for (int64_t k = std::max<int64_t>(0, ck - K); k <= std::min<int64_t>(int64_t(F.n[2]) - 1, ck + K); ++k)
        for (int64_t j = std::max<int64_t>(0, cj - K); j <= std::min<int64_t>(int64_t(F.n[1]) - 1, cj + K); ++j)
          for (int64_t i = std::max<int64_t>(0, ci - K); i <= std::min<int64_t>(int64_t(F.n[0]) - 1, ci + K); ++i) {
            const size_t v = size_t(i) + size_t(j) * F.stride[1] + size_t(k) * F.stride[2];
            if (!is_cand[v] || F.label[v] != vreg[uncovered[u]]) continue;
            if ((iv.Centre(v) - p).norm() <= double(F.dist[v]) * F.h + dilation + tol) reach[uint32_t(v)].push_back(u);
          }
    }
    // (b) Medial balls: at most kMaxMedial uncovered vertices (evenly strided), each with the medial ball
    //     behind it (MedialBallAlongNormal), kept when its radius is at least medial_min_rel of the height
    //     and its ray leaves the body through skin of the vertex's own region.
    std::vector<std::pair<Vector3d, double>> medial;
    std::vector<uint8_t> medial_region;
    if (!uncovered.empty()) {
      // Inward vertex normals: area-weighted face normals, turned by the sign of the enclosed volume.
      double volume6 = 0.0;
      std::vector<Vector3d> normal(V, Vector3d::Zero());
      for (uint32_t t = 0; t < T; ++t) {
        const Vector3d a = fit_detail::Vertex(mesh, mesh.indices[3 * t]), b = fit_detail::Vertex(mesh, mesh.indices[3 * t + 1]),
                       c = fit_detail::Vertex(mesh, mesh.indices[3 * t + 2]);
        const Vector3d nrm = (b - a).cross(c - a);
        volume6 += a.dot(b.cross(c));
        for (int k = 0; k < 3; ++k) normal[mesh.indices[3 * t + k]] += nrm;
      }
      const double inward = volume6 >= 0.0 ? -1.0 : 1.0;  // outward-wound faces: the normals point out
      constexpr size_t kMaxMedial = 16384;
      const size_t step = (uncovered.size() + kMaxMedial - 1) / kMaxMedial;
      std::vector<uint32_t> seeds;
      for (size_t u = 0; u < uncovered.size(); u += step) seeds.push_back(uint32_t(u));
      std::vector<std::pair<Vector3d, double>> ball(seeds.size(), {Vector3d::Zero(), 0.0});
      const double t_min = 1e-4 * height, rmin_medial = params.medial_min_rel * height;
      ParallelFor(0, seeds.size(), [&](size_t i) {
        const uint32_t v = uncovered[seeds[i]];
        const Vector3d nv = normal[v];
        if (!(nv.norm() > 0.0)) return;
        const Vector3d n = inward * nv.normalized();
        Vector3d c = Vector3d::Zero();
        size_t exit = 0;
        const double r = MedialBallAlongNormal(tree, tris, fit_detail::Vertex(mesh, v), n, t_min, &c, &exit);
        if (!(r >= rmin_medial)) return;  // too thin, or the ray never left the body (n points out of it)
        const surface_detail::Triangle3& tri = tris[exit];
        const Vector3d ta(tri[0].x(), tri[0].y(), tri[0].z()), tb(tri[1].x(), tri[1].y(), tri[1].z()),
            tc(tri[2].x(), tri[2].y(), tri[2].z());
        if (-inward * (tb - ta).cross(tc - ta).dot(n) <= 0.0) return;  // the ray entered the skin: n pointed out
        if (seg.triangle_regions[tri_ids[exit]] != vreg[v]) return;  // it leaves through another region
        ball[i] = {c, r};
      });
      // Uncovered vertices bucketed in cubes of 2 % of the height (from the voxel grid's corner, so the
      // cube coordinates are small and non-negative), for the balls' reach.
      const double cell = 0.02 * height;
      auto key = [&](int64_t i, int64_t j, int64_t k) {
        return (uint64_t(i + (1 << 20)) << 42) | (uint64_t(j + (1 << 20)) << 21) | uint64_t(k + (1 << 20));
      };
      std::unordered_map<uint64_t, std::vector<uint32_t>> bucket;
      for (uint32_t u = 0; u < uncovered.size(); ++u) {
        const Vector3d g = (fit_detail::Vertex(mesh, uncovered[u]) - F.origin) / cell;
        bucket[key(int64_t(std::floor(g.x())), int64_t(std::floor(g.y())), int64_t(std::floor(g.z())))].push_back(u);
      }
      for (size_t i = 0; i < seeds.size(); ++i) {
        if (ball[i].second <= 0.0) continue;
        const uint8_t reg = vreg[uncovered[seeds[i]]];
        const Vector3d& c = ball[i].first;
        const double R = ball[i].second + dilation + tol;
        const Vector3d lo = (c - Vector3d::Constant(R) - F.origin) / cell, hi = (c + Vector3d::Constant(R) - F.origin) / cell;
        std::vector<uint32_t> list;
        for (int64_t k = int64_t(std::floor(lo.z())); k <= int64_t(std::floor(hi.z())); ++k)
          for (int64_t j = int64_t(std::floor(lo.y())); j <= int64_t(std::floor(hi.y())); ++j)
            for (int64_t ii = int64_t(std::floor(lo.x())); ii <= int64_t(std::floor(hi.x())); ++ii) {
              const auto it = bucket.find(key(ii, j, k));
              if (it == bucket.end()) continue;
              for (uint32_t u : it->second)
                if (vreg[uncovered[u]] == reg && (fit_detail::Vertex(mesh, uncovered[u]) - c).norm() <= R) list.push_back(u);
            }
        if (list.empty()) continue;
        reach[uint32_t(total + medial.size())] = std::move(list);
        medial.push_back(ball[i]);
        medial_region.push_back(reg);
      }
    }
    std::vector<uint8_t> done(uncovered.size(), 0);
    // A candidate's gain: the uncovered vertices it brings within tolerance, each counting 1 — the head's
    // by how far outside it lies (in tolerances): its share of the pass is capped, so it goes where its
    // skin lies farthest out (a chin, a nose) before where it has the most vertices (the scalp).
    auto gain = [&](const std::vector<uint32_t>& list, size_t* count) {
      double g = 0.0;
      size_t c = 0;
      for (uint32_t u : list) {
        if (done[u]) continue;
        g += int(vreg[uncovered[u]]) == head ? outside[u] / tol : 1.0;
        ++c;
      }
      if (count) *count = c;
      return g;
    };
    using Entry = std::pair<double, uint32_t>;  // gain, candidate key (ties: the larger key)
    std::priority_queue<Entry> queue;
    for (const auto& [v, list] : reach) queue.emplace(gain(list, nullptr), v);
    int added = 0, added_medial = 0;
    while (!queue.empty() && added < skin_left) {
      const uint32_t v = queue.top().second;
      queue.pop();
      size_t count = 0;
      const double now = gain(reach[v], &count);
      if (!queue.empty() && now < queue.top().first) {
        queue.emplace(now, v);  // stale: re-queue with its current gain
        continue;
      }
      if (count < size_t(params.skin_min_vertices)) {
        if (head < 0) break;  // gains are counts: every candidate left brings fewer
        continue;             // a head's gain is no count: others may still bring enough
      }
      const bool is_medial = v >= total;
      const uint8_t reg = is_medial ? medial_region[v - total] : F.label[v];
      if (head >= 0 && int(reg) == head && head_added++ >= head_cap) continue;  // the head's share is spent
      for (uint32_t u : reach[v]) done[u] = 1;
      CoverBall b{.voxel = is_medial ? CoverBall::kMedial : v, .region = reg, .skin = true};
      if (is_medial)
        std::tie(b.centre, b.radius) = medial[v - total];
      else
        place(b);
      chosen.push_back(b);
      ++added;
      added_medial += is_medial;
    }
    if (ctx)
      ctx->Info("fit cover: skin pass: " + std::to_string(uncovered.size()) + " limb vertices beyond " +
                std::to_string(params.skin_tolerance_rel) + " of the height, " + std::to_string(added) + " spheres added (" +
                std::to_string(added_medial) + " medial balls of " + std::to_string(medial.size()) + " candidates)");
  }
  // 6c. The budget the skin pass left goes back to the volume cover, the skin spheres counting as cover
  //     (CesiumMan's hands needed 6 of the 16 held back: 10 more spheres for its torso and limbs).
  if (const size_t before = chosen.size(); volume_budget < params.max_spheres && int(before) < params.max_spheres) {
    Context::Timer t(ctx, "fit.cover.leftover");  // its own name: the report keys timings by name
    for (size_t k = volume_spheres; k < before; ++k) {
      if (chosen[k].voxel == CoverBall::kMedial)
        F.ApplyBall(chosen[k].centre, chosen[k].radius / F.h, +1);
      else
        F.Apply(chosen[k].voxel, +1);
    }
    greedy(params.max_spheres);
    for (size_t k = before; k < chosen.size(); ++k) place(chosen[k]);
  }

  // 6d. Off the grid, two volume balls may end where one would do: two voxel centres a voxel or two apart
  //     climb to the same medial point (CesiumMan's chest: two balls 0.6 % of a radius apart). The counts
  //     are rebuilt from the final balls; a volume ball that covers less than min_gain on its own (a
  //     region's last one excepted) gives its place back to the greedy, whose new balls stay on the grid
  //     when off it they would land within a quarter radius of another ball. At most 4 rounds.
  if (params.min_gain > 0.0) {
    Context::Timer t(ctx, "fit.cover.redundant");
    std::fill(F.count.begin(), F.count.end(), uint16_t{0});
    for (const CoverBall& b : chosen) F.ApplyBall(b.centre, b.radius / F.h, +1);
    size_t replaced = 0;
    for (int round = 0; round < 4; ++round) {
      std::vector<double> loss(chosen.size(), std::numeric_limits<double>::infinity());
      ParallelFor(0, chosen.size(), [&](size_t k) {
        if (!chosen[k].skin) loss[k] = F.LossBall(chosen[k].centre, chosen[k].radius / F.h);
      });
      // The least useful first; ties: the lower index. Each removal changes the others' losses: one at a time.
      std::vector<size_t> order(chosen.size());
      std::iota(order.begin(), order.end(), size_t{0});
      std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return loss[a] < loss[b]; });
      std::vector<uint8_t> drop(chosen.size(), 0);
      size_t dropped = 0;
      for (size_t k : order) {
        if (!(loss[k] < params.min_gain)) break;
        const CoverBall& b = chosen[k];
        if (per_region[b.region] <= 1) continue;
        if (F.LossBall(b.centre, b.radius / F.h) >= params.min_gain) continue;  // others went first
        F.ApplyBall(b.centre, b.radius / F.h, -1);
        --per_region[b.region];
        drop[k] = 1;
        ++dropped;
      }
      if (dropped == 0) break;
      size_t w = 0;
      for (size_t k = 0; k < chosen.size(); ++k)
        if (!drop[k]) chosen[w++] = chosen[k];
      chosen.resize(w);
      const size_t before = chosen.size();
      greedy(params.max_spheres);
      for (size_t k = before; k < chosen.size(); ++k) {
        // greedy() counted the voxel ball; count the ball where it ends instead.
        CoverBall& b = chosen[k];
        F.Apply(b.voxel, -1);
        place(b);
        for (size_t q = 0; q < k; ++q)
          if ((b.centre - chosen[q].centre).norm() < 0.25 * std::min(b.radius, chosen[q].radius)) {
            b.centre = iv.Centre(b.voxel), b.radius = double(F.dist[b.voxel]) * F.h;
            break;
          }
        F.ApplyBall(b.centre, b.radius / F.h, +1);
      }
      replaced += chosen.size() - before;
    }
    if (ctx && replaced) ctx->Info("fit cover: " + std::to_string(replaced) + " redundant ball(s) placed again");
  }

  // 7. Spheres, their order and labels.
  const Vector3d up = fit_detail::UpVector(mesh.up_axis);
  std::array<Vector3d, kMaxRegions> centroid;
  for (auto& c : centroid) c.setZero();
  for (uint32_t v : iv.inside)
    if (F.label[v] != kOutside) centroid[F.label[v]] += iv.Centre(v);
  for (int r = 0; r < nreg; ++r) centroid[r] /= std::max(1.0, F.volume[r]);  // volume: voxel counts
  Vector3d left = Vector3d::Zero();
  for (auto [l, r] : {std::pair{0, 1}, std::pair{2, 3}}) {
    left = centroid[l] - centroid[r];
    left -= left.dot(up) * up;
    if (left.norm() > 1e-9 * height) break;
  }
  if (left.norm() <= 1e-9 * height) left = up.unitOrthogonal();
  left.normalize();
  const int torso = int(layout.trunk());
  // A creature's trunk (RegionLayout::paper false) has no up: its spheres are ordered along its axis.
  const Vector3d trunk_axis(layout.trunk_axis[0], layout.trunk_axis[1], layout.trunk_axis[2]);
  // Plain variables, not structured bindings: lambdas below capture them (clang < 16, the fuzz preset's
  // compiler, cannot capture a structured binding).
  const std::pair<double, double> arm_band = JunctionBand(mesh, seg, up, {Region::kLeftArm, Region::kRightArm});
  const std::pair<double, double> leg_band = JunctionBand(mesh, seg, up, {Region::kLeftLeg, Region::kRightLeg});
  const double arm_lo = arm_band.first, arm_hi = arm_band.second, leg_lo = leg_band.first, leg_hi = leg_band.second;

  std::vector<FittedSphere> out;
  for (int r = 0; r < nreg; ++r) {
    std::vector<FittedSphere> group;
    const Vector3d root = r == torso ? Vector3d::Zero() : LimbRoot(mesh, seg, Region(r), centroid[torso]);
    for (const CoverBall& b : chosen) {
      if (b.region != r) continue;
      FittedSphere s;
      s.center = s.center_phi1 = s.center_phi2 = b.centre;
      s.radius = s.radius_phi1 = s.radius_phi2 = b.radius + dilation;
      s.region = Region(r);
      group.push_back(std::move(s));
    }
    if (r != torso) {
      // Limbs: from the torso outwards, by distance from the limb's root.
      for (FittedSphere& s : group) s.root_distance = (s.center - root).norm();
      std::stable_sort(group.begin(), group.end(),
                       [](const FittedSphere& a, const FittedSphere& b) { return a.root_distance < b.root_distance; });
    } else if (!layout.paper) {
      // A creature's trunk: along its axis (no torso labels, no columns).
      std::stable_sort(group.begin(), group.end(), [&](const FittedSphere& a, const FittedSphere& b) {
        return a.center.dot(trunk_axis) < b.center.dot(trunk_axis);
      });
    } else {
      // Torso: bottom-up, then from the character's left to its right; labels of Figure 6.
      std::stable_sort(group.begin(), group.end(), [&](const FittedSphere& a, const FittedSphere& b) {
        const double ha = a.center.dot(up), hb = b.center.dot(up);
        if (ha != hb) return ha < hb;
        return a.center.dot(left) > b.center.dot(left);
      });
      const double mid = centroid[torso].dot(left);
      for (FittedSphere& s : group) {
        const double side = s.center.dot(left) - mid, y = s.center.dot(up);
        // Within half a radius of the mid-plane: both sides (the belly, the head, the spine).
        if (side > -0.5 * s.radius) s.labels |= kLabelL;
        if (side < 0.5 * s.radius) s.labels |= kLabelR;
        s.column = side >= 0.0 ? 0 : 1;
        if (arm_lo <= arm_hi && y + s.radius >= arm_lo && y - s.radius <= arm_hi) s.labels |= kLabelT;
        if (leg_lo <= leg_hi && y - s.radius <= leg_hi) s.labels |= kLabelD;
      }
      // A chain member set must not be empty: the nearest sphere takes a label nobody has.
      auto ensure = [&](uint8_t label, auto distance) {
        if (std::any_of(group.begin(), group.end(), [&](const FittedSphere& s) { return s.labels & label; })) return;
        auto it = std::min_element(group.begin(), group.end(), [&](const FittedSphere& a, const FittedSphere& b) {
          return distance(a) < distance(b);
        });
        if (it != group.end()) it->labels |= label;
      };
      ensure(kLabelT, [&](const FittedSphere& s) { return std::abs(s.center.dot(up) - 0.5 * (arm_lo + arm_hi)); });
      ensure(kLabelD, [&](const FittedSphere& s) { return s.center.dot(up) - s.radius; });
    }
    for (size_t k = 0; k < group.size(); ++k) group[k].sequence = int(k);
    for (FittedSphere& s : group) out.push_back(std::move(s));
  }
  if (ctx)
    ctx->Info("fit cover: " + std::to_string(out.size()) + " spheres from " + std::to_string(cand.size()) +
              " candidates over " + std::to_string(iv.inside.size()) + " interior voxels");
  return out;
}

}  // namespace spherechain::baker
