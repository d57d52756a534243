#include "spherechain/baker/regions.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>

#include <Eigen/Geometry>

#include "parallel.h"
#include "spherechain/runtime/refit.h"

namespace spherechain::baker {

namespace {

Eigen::Vector3d Vertex(const Mesh& mesh, uint32_t v) {
  return {mesh.positions[3 * v + 0], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]};
}

Eigen::Vector3d Centroid(const Mesh& mesh, uint32_t t) {
  return (Vertex(mesh, mesh.indices[3 * t]) + Vertex(mesh, mesh.indices[3 * t + 1]) +
          Vertex(mesh, mesh.indices[3 * t + 2])) /
         3.0;
}

// The spheres of each region, ascending (spheres of no region in none).
std::array<std::vector<uint32_t>, kMaxRegions> SpheresByRegion(const std::vector<FittedSphere>& spheres) {
  std::array<std::vector<uint32_t>, kMaxRegions> by_region;
  for (size_t s = 0; s < spheres.size(); ++s)
    if (static_cast<int>(spheres[s].region) < kMaxRegions) by_region[static_cast<int>(spheres[s].region)].push_back(uint32_t(s));
  return by_region;
}

double Area(const Mesh& mesh, uint32_t t) {
  const Eigen::Vector3d a = Vertex(mesh, mesh.indices[3 * t]);
  return 0.5 * (Vertex(mesh, mesh.indices[3 * t + 1]) - a).cross(Vertex(mesh, mesh.indices[3 * t + 2]) - a).norm();
}

Eigen::Vector3d UpVector(UpAxis up) {
  switch (up) {
    case UpAxis::kZ: return Eigen::Vector3d::UnitZ();
    case UpAxis::kX: return Eigen::Vector3d::UnitX();
    case UpAxis::kY: break;
  }
  return Eigen::Vector3d::UnitY();
}

// The sphere's axis: along its region's sequence for limbs, up for the torso (a creature's trunk: its axis).
Eigen::Vector3d SphereAxis(const Mesh& mesh, const std::vector<FittedSphere>& spheres, size_t s,
                           const RegionLayout& layout) {
  const FittedSphere& S = spheres[s];
  if (layout.IsTrunk(S.region)) {
    const Eigen::Vector3d axis(layout.trunk_axis[0], layout.trunk_axis[1], layout.trunk_axis[2]);
    return layout.paper || axis.norm() < 0.5 ? UpVector(mesh.up_axis) : axis;
  }
  const FittedSphere* prev = nullptr;
  const FittedSphere* next = nullptr;
  for (const FittedSphere& o : spheres) {
    if (o.region != S.region) continue;
    if (o.sequence == S.sequence - 1) prev = &o;
    if (o.sequence == S.sequence + 1) next = &o;
  }
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  if (prev && next) a = next->center - prev->center;
  else if (next) a = next->center - S.center;
  else if (prev) a = S.center - prev->center;
  if (a.norm() < 1e-12) a = UpVector(mesh.up_axis);
  return a.normalized();
}

// Pivots ordered +u, +v, −u, −v: both diagonals longer than `min_length` and at least 15° apart, so
// the runtime's BuildPivotFrame (refit.h) is stable under float noise and the pivots surround the centre.
bool PivotsWellConditioned(const float p[4][3], float min_length) {
  const Eigen::Vector3f a(p[0][0] - p[2][0], p[0][1] - p[2][1], p[0][2] - p[2][2]);
  const Eigen::Vector3f b(p[1][0] - p[3][0], p[1][1] - p[3][1], p[1][2] - p[3][2]);
  const float na = a.norm(), nb = b.norm();
  if (!(na > min_length) || !(nb > min_length)) return false;
  runtime::PivotFrameBasis basis;
  return a.cross(b).norm() / (na * nb) > 0.25f && runtime::BuildPivotFrame(p, &basis);
}

// The refit of one sphere on one set of positions, exactly as the runtime's kPivotFrame computes it
// (refit.h): frame from the four pivot centroids, the bind centre's frame coordinates, radius scaled by
// the mean pivot distance; a degenerate frame falls back to the mean centroid + offset (kPaper).
struct PivotBind {
  float local[3], offset[3], radius_scale;
};

void PivotCentroids(const float* positions, const Mesh& mesh, const std::array<uint32_t, 4>& tris, float p[4][3]) {
  for (int k = 0; k < 4; ++k) {
    const uint32_t* tri = &mesh.indices[3 * size_t(tris[k])];
    runtime::TriangleCentroid(&positions[3 * size_t(tri[0])], &positions[3 * size_t(tri[1])],
                              &positions[3 * size_t(tri[2])], p[k]);
  }
}

bool BindPivots(const Mesh& mesh, const std::array<uint32_t, 4>& tris, const FittedSphere& S, PivotBind* out) {
  float p[4][3];
  PivotCentroids(mesh.positions.data(), mesh, tris, p);
  runtime::PivotFrameBasis basis;
  if (!runtime::BuildPivotFrame(p, &basis)) return false;
  const float c[3] = {float(S.center.x()), float(S.center.y()), float(S.center.z())};
  runtime::PivotFrameToLocal(basis, c, out->local);
  for (int k = 0; k < 3; ++k) out->offset[k] = c[k] - basis.origin[k];
  const float md = runtime::PivotMeanDistance(p, c);
  if (!(md > 0.0f)) return false;
  out->radius_scale = float(S.radius) / md;
  return true;
}

void RefitOne(const float* positions, const Mesh& mesh, const std::array<uint32_t, 4>& tris, const PivotBind& b,
              float c[3], float* r) {
  float p[4][3];
  PivotCentroids(positions, mesh, tris, p);
  runtime::PivotFrameBasis basis;
  if (runtime::BuildPivotFrame(p, &basis)) {
    runtime::PivotFrameToModel(basis, b.local, c);
  } else {
    for (int k = 0; k < 3; ++k) c[k] = basis.origin[k] + b.offset[k];
  }
  *r = b.radius_scale * runtime::PivotMeanDistance(p, c);
}

// ChoosePivots' refinement against the training poses (regions.h PivotTraining): per sphere, coordinate
// descent over the best-placed triangles per direction, each change kept only when it lowers the
// tracking error of the sphere's witness vertices. Spheres are independent: on all cores, same result.
void RefinePivotsOnPoses(const Mesh& mesh, const std::vector<FittedSphere>& spheres,
                         const SurroundingRegions& surrounding, const RegionLayout& layout,
                         const std::vector<double>& areas, double min_area, const PivotTraining& training,
                         std::vector<std::array<uint32_t, 4>>* picks, Pivots::Training* stats) {
  const std::vector<std::vector<float>>& poses = *training.poses;
  const uint32_t V = mesh.vertex_count(), T = mesh.triangle_count();
  for (const std::vector<float>& pose : poses)
    if (pose.size() != size_t(V) * 3) return;
  constexpr size_t kMaxWitnesses = 192, kPerDirection = 8;
  std::vector<double> before(spheres.size(), 0.0), after(spheres.size(), 0.0);
  std::vector<uint8_t> changed_any(spheres.size(), 0);
  std::vector<uint8_t> triangle_region(T);
  for (uint32_t t = 0; t < T; ++t) triangle_region[t] = uint8_t(spheres[surrounding.triangle_spheres[t]].region);

  detail::ParallelFor(0, spheres.size(), [&](size_t s) {
    const FittedSphere& S = spheres[s];
    const Eigen::Vector3f c0 = S.center.cast<float>();
    const float r0 = float(S.radius);
    // Witnesses: the skin near the sphere's surface, every k-th when there are many.
    std::vector<uint32_t> witnesses;
    for (uint32_t v = 0; v < V; ++v) {
      const Eigen::Vector3f x(mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]);
      if ((x - c0).norm() - r0 <= training.witness_reach) witnesses.push_back(v);
    }
    if (witnesses.empty()) return;
    if (witnesses.size() > kMaxWitnesses) {
      std::vector<uint32_t> kept;
      for (size_t i = 0; i < kMaxWitnesses; ++i) kept.push_back(witnesses[i * witnesses.size() / kMaxWitnesses]);
      witnesses.swap(kept);
    }
    std::vector<float> bind_f(witnesses.size());
    for (size_t i = 0; i < witnesses.size(); ++i) {
      const float* x = &mesh.positions[3 * size_t(witnesses[i])];
      bind_f[i] = r0 - Eigen::Vector3f(x[0] - c0.x(), x[1] - c0.y(), x[2] - c0.z()).norm();
    }
    auto error = [&](const std::array<uint32_t, 4>& tris) {
      PivotBind b;
      if (!BindPivots(mesh, tris, S, &b)) return std::numeric_limits<double>::infinity();
      double sum = 0.0;
      for (const std::vector<float>& pose : poses) {
        float c[3], r;
        RefitOne(pose.data(), mesh, tris, b, c, &r);
        double mean_abs = 0.0, worst = 0.0;
        for (size_t i = 0; i < witnesses.size(); ++i) {
          const float* x = &pose[3 * size_t(witnesses[i])];
          const float dx = x[0] - c[0], dy = x[1] - c[1], dz = x[2] - c[2];
          const double df = double(r - std::sqrt(dx * dx + dy * dy + dz * dz)) - bind_f[i];
          mean_abs += std::abs(df);
          worst = std::max(worst, df);
        }
        sum += mean_abs / double(witnesses.size()) + worst;
      }
      return std::isfinite(sum) ? sum / double(poses.size()) : std::numeric_limits<double>::infinity();
    };

    // Candidates per direction (+u, +v, −u, −v, as ChoosePivots places them): the surrounding region's
    // triangles and the sphere's own region's within 1.5 r, ranked as the geometric choice ranks them.
    const Eigen::Vector3d a = SphereAxis(mesh, spheres, s, layout);
    const Eigen::Vector3d ref = std::abs(a.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d u = (ref - ref.dot(a) * a).normalized(), v = a.cross(u);
    const Eigen::Vector3d targets[4] = {u, v, -u, -v};
    std::vector<uint32_t> pool;
    for (uint32_t k = surrounding.offsets[s]; k < surrounding.offsets[s + 1]; ++k)
      if (areas[surrounding.triangles[k]] > min_area) pool.push_back(surrounding.triangles[k]);
    for (uint32_t t = 0; t < T; ++t)
      if (surrounding.triangle_spheres[t] != s && triangle_region[t] == uint8_t(S.region) && areas[t] > min_area &&
          (Centroid(mesh, t) - S.center).norm() < 1.5 * S.radius)
        pool.push_back(t);
    std::array<std::vector<uint32_t>, 4> ranked;
    for (int k = 0; k < 4; ++k) {
      std::vector<std::pair<double, uint32_t>> scored;
      for (uint32_t t : pool) {
        const Eigen::Vector3d d = Centroid(mesh, t) - S.center;
        const double axial = d.dot(a);
        const Eigen::Vector3d radial = d - axial * a;
        const double rn = radial.norm();
        if (rn < 1e-12) continue;
        const double score = radial.dot(targets[k]) / rn - 0.5 * std::abs(axial) / std::max(S.radius, 1e-12);
        if (score > 0.0) scored.emplace_back(-score, t);
      }
      const size_t n = std::min(kPerDirection, scored.size());
      std::partial_sort(scored.begin(), scored.begin() + n, scored.end());
      for (size_t i = 0; i < n; ++i) ranked[k].push_back(scored[i].second);
    }

    // A change must gain more than float noise: 1e-4 of the radius (E is a length).
    const double min_gain = 1e-4 * S.radius;
    std::array<uint32_t, 4> best = (*picks)[s];
    double best_error = error(best);
    before[s] = best_error;
    for (int sweep = 0; sweep < 2; ++sweep) {
      bool changed = false;
      for (int k = 0; k < 4; ++k)
        for (uint32_t t : ranked[k]) {
          if (std::find(best.begin(), best.end(), t) != best.end()) continue;
          std::array<uint32_t, 4> trial = best;
          trial[k] = t;
          float p[4][3];
          PivotCentroids(mesh.positions.data(), mesh, trial, p);
          if (!PivotsWellConditioned(p, float(0.05 * S.radius))) continue;
          const double e = error(trial);
          if (e < best_error - min_gain) best_error = e, best = trial, changed = true;
        }
      if (!changed) break;
    }
    after[s] = best_error;
    changed_any[s] = best != (*picks)[s];
    (*picks)[s] = best;
  });
  stats->poses = uint32_t(poses.size());
  for (size_t s = 0; s < spheres.size(); ++s) {
    stats->spheres_changed += changed_any[s];
    if (std::isfinite(before[s]) && std::isfinite(after[s]))
      stats->error_before += before[s] / double(spheres.size()), stats->error_after += after[s] / double(spheres.size());
  }
}

}  // namespace

std::vector<uint32_t> SurroundingRegions::Vertices(const Mesh& mesh, size_t sphere) const {
  std::vector<uint32_t> v;
  for (uint32_t k = offsets[sphere]; k < offsets[sphere + 1]; ++k) {
    const uint32_t t = triangles[k];
    v.insert(v.end(), {mesh.indices[3 * t], mesh.indices[3 * t + 1], mesh.indices[3 * t + 2]});
  }
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

Result<SurroundingRegions> BuildSurroundingRegions(const Mesh& mesh, const Segmentation& seg,
                                                   const std::vector<FittedSphere>& spheres, Ownership ownership) {
  if (spheres.empty()) return MakeError(Error::Code::kFit, "no sphere to assign triangles to");
  const uint32_t T = mesh.triangle_count();
  const std::array<std::vector<uint32_t>, kMaxRegions> by_region = SpheresByRegion(spheres);
  std::vector<uint32_t> all(spheres.size());
  std::iota(all.begin(), all.end(), 0u);

  SurroundingRegions out;
  out.triangle_spheres.resize(T);
  for (uint32_t t = 0; t < T; ++t) {
    const uint8_t r = t < seg.triangle_regions.size() ? seg.triangle_regions[t] : kNoRegion;
    const std::vector<uint32_t>& candidates = (r < kMaxRegions && !by_region[r].empty()) ? by_region[r] : all;
    const Eigen::Vector3d c = Centroid(mesh, t);
    double best = std::numeric_limits<double>::infinity();
    uint32_t best_s = candidates.front();
    for (uint32_t s : candidates) {
      const double d = ownership == Ownership::kNearestCentre ? (spheres[s].center - c).squaredNorm()
                                                              : (spheres[s].center - c).norm() - spheres[s].radius;
      if (d < best) { best = d; best_s = s; }  // ties keep the lower index: deterministic
    }
    out.triangle_spheres[t] = static_cast<uint16_t>(best_s);
  }
  out.offsets.assign(spheres.size() + 1, 0);
  for (uint32_t t = 0; t < T; ++t) ++out.offsets[out.triangle_spheres[t] + 1];
  for (size_t s = 0; s < spheres.size(); ++s) out.offsets[s + 1] += out.offsets[s];
  out.triangles.resize(T);
  std::vector<uint32_t> cursor(out.offsets.begin(), out.offsets.end() - 1);
  for (uint32_t t = 0; t < T; ++t) out.triangles[cursor[out.triangle_spheres[t]]++] = t;
  return out;
}

void AddReachRegions(const Mesh& mesh, const Segmentation& seg, const std::vector<FittedSphere>& spheres, double reach,
                     SurroundingRegions* regions) {
  const uint32_t T = mesh.triangle_count();
  const size_t S = spheres.size();
  const std::array<std::vector<uint32_t>, kMaxRegions> by_region = SpheresByRegion(spheres);
  std::vector<std::vector<uint32_t>> lists(S);
  for (size_t s = 0; s < S; ++s)
    for (uint32_t k = regions->offsets[s]; k < regions->offsets[s + 1]; ++k) lists[s].push_back(regions->triangles[k]);
  for (uint32_t t = 0; t < T; ++t) {
    const uint8_t r = t < seg.triangle_regions.size() ? seg.triangle_regions[t] : kNoRegion;
    if (r >= kMaxRegions) continue;
    const uint16_t own = regions->triangle_spheres[t];
    const Eigen::Vector3d corner[3] = {Vertex(mesh, mesh.indices[3 * t]), Vertex(mesh, mesh.indices[3 * t + 1]),
                                       Vertex(mesh, mesh.indices[3 * t + 2])};
    for (uint32_t s : by_region[r]) {
      if (s == own) continue;
      for (const Eigen::Vector3d& p : corner)
        if ((p - spheres[s].center).norm() - spheres[s].radius <= reach) {
          lists[s].push_back(t);
          break;
        }
    }
  }
  regions->reach_offsets.assign(1, 0);
  regions->reach_triangles.clear();
  for (size_t s = 0; s < S; ++s) {
    std::sort(lists[s].begin(), lists[s].end());
    regions->reach_triangles.insert(regions->reach_triangles.end(), lists[s].begin(), lists[s].end());
    regions->reach_offsets.push_back(static_cast<uint32_t>(regions->reach_triangles.size()));
  }
}

Result<Pivots> ChoosePivots(const Mesh& mesh, const std::vector<FittedSphere>& spheres,
                            const SurroundingRegions& surrounding, const Segmentation* segmentation,
                            const PivotTraining* training) {
  const RegionLayout paper;
  const RegionLayout& layout = segmentation ? segmentation->layout : paper;
  const uint32_t T = mesh.triangle_count();
  // A creature (joint regions known): per vertex, the share of its skin weight on each region's bones, so
  // a sphere's pivots can sit on skin its own bones move (a hip's trunk sphere must not follow the leg).
  const int nreg = layout.count();
  std::vector<float> bone_share;  // #V × nreg
  if (segmentation && !segmentation->joint_regions.empty() && mesh.skin &&
      mesh.skin->weight_offsets.size() == size_t(mesh.vertex_count()) + 1) {
    const Skin& skin = *mesh.skin;
    bone_share.assign(size_t(mesh.vertex_count()) * size_t(nreg), 0.0f);
    for (uint32_t v = 0; v < mesh.vertex_count(); ++v)
      for (uint32_t k = skin.weight_offsets[v]; k < skin.weight_offsets[v + 1]; ++k) {
        const uint32_t j = skin.weight_joints[k];
        if (j < segmentation->joint_regions.size() && segmentation->joint_regions[j] < nreg)
          bone_share[size_t(v) * nreg + segmentation->joint_regions[j]] += skin.weights[k];
      }
  }
  auto anchored = [&](uint32_t t, Region r) {  // ≥ 90 % of the corners' weight on region r's bones
    float sum = 0.0f;
    for (int k = 0; k < 3; ++k) sum += bone_share[size_t(mesh.indices[3 * t + k]) * nreg + size_t(r)];
    return sum >= 0.9f * 3.0f;
  };
  std::vector<double> areas(T);
  for (uint32_t t = 0; t < T; ++t) areas[t] = Area(mesh, t);
  std::vector<double> sorted = areas;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double min_area = 0.05 * sorted[sorted.size() / 2];

  std::vector<std::array<uint32_t, 4>> picks(spheres.size());
  for (size_t s = 0; s < spheres.size(); ++s) {
    const FittedSphere& S = spheres[s];
    const Eigen::Vector3d a = SphereAxis(mesh, spheres, s, layout);
    // u: a fixed world direction projected off the axis (deterministic), v = a × u.
    Eigen::Vector3d ref = std::abs(a.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d u = (ref - ref.dot(a) * a).normalized();
    const Eigen::Vector3d v = a.cross(u);
    const Eigen::Vector3d targets[4] = {u, v, -u, -v};

    // Candidates: the surrounding region's triangles of non-negligible area; when too few, the
    // triangles of the same region nearest the centre. A creature's sphere first tries the triangles its
    // own region's bones move (`allowed`), then any.
    std::function<bool(uint32_t)> allowed = [](uint32_t) { return true; };
    std::vector<uint32_t> candidates;
    auto gather = [&] {
      candidates.clear();
      for (uint32_t k = surrounding.offsets[s]; k < surrounding.offsets[s + 1]; ++k)
        if (areas[surrounding.triangles[k]] > min_area && allowed(surrounding.triangles[k]))
          candidates.push_back(surrounding.triangles[k]);
    };

    auto choose = [&](const std::vector<uint32_t>& cand, double axial_weight, std::array<uint32_t, 4>* pick) {
      for (int k = 0; k < 4; ++k) {
        double best = -std::numeric_limits<double>::infinity();
        uint32_t best_t = UINT32_MAX;
        for (uint32_t t : cand) {
          if (std::find(pick->begin(), pick->begin() + k, t) != pick->begin() + k) continue;
          const Eigen::Vector3d d = Centroid(mesh, t) - S.center;
          const double axial = d.dot(a);
          const Eigen::Vector3d radial = d - axial * a;
          const double rn = radial.norm();
          if (rn < 1e-12) continue;
          const double score = radial.dot(targets[k]) / rn - axial_weight * std::abs(axial) / std::max(S.radius, 1e-12);
          if (score > best) { best = score; best_t = t; }
        }
        if (best_t == UINT32_MAX) return false;
        (*pick)[k] = best_t;
      }
      return true;
    };
    auto well_conditioned = [&](const std::array<uint32_t, 4>& pick) {
      float p[4][3];
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector3d c = Centroid(mesh, pick[k]);
        p[k][0] = float(c.x()); p[k][1] = float(c.y()); p[k][2] = float(c.z());
      }
      return PivotsWellConditioned(p, float(0.05 * S.radius));
    };

    std::array<uint32_t, 4> pick{};
    bool ok = false;
    for (int pass = bone_share.empty() ? 1 : 0; pass < 2 && !ok; ++pass) {
      if (pass == 0) allowed = [&](uint32_t t) { return anchored(t, S.region); };
      else allowed = [](uint32_t) { return true; };
      gather();
      ok = candidates.size() >= 4 && choose(candidates, 0.5, &pick) && well_conditioned(pick);
      if (ok) break;
      // Widen to the neighbourhood: triangles within k·r of the centre (k = 2.5, 4, 8), with a relaxed
      // level constraint each time, until a well-spread choice appears.
      for (double reach : {2.5, 4.0, 8.0}) {
        std::vector<uint32_t> wide;
        // Triangles of the sphere's own region first (an interior sphere must not follow another
        // region's skin); any region when its own has too few.
        for (bool own : {true, false}) {
          wide.clear();
          for (uint32_t t = 0; t < T; ++t)
            if (areas[t] > 0.0 && (!own || spheres[surrounding.triangle_spheres[t]].region == S.region) &&
                allowed(t) && (Centroid(mesh, t) - S.center).norm() < reach * S.radius)
              wide.push_back(t);
          if (wide.size() >= 4) break;
        }
        for (double w : {0.5, 0.2, 0.0}) {
          pick = {};
          if (wide.size() >= 4 && choose(wide, w, &pick) && well_conditioned(pick)) { ok = true; break; }
        }
        if (ok) break;
      }
    }
    if (!ok)
      return MakeError(Error::Code::kFit, "sphere " + std::to_string(s) + " (" + RegionSymbol(S.region) +
                                              "): no four non-degenerate pivot polygons around it");
    picks[s] = pick;
  }

  Pivots out;
  if (training && training->poses && !training->poses->empty())
    RefinePivotsOnPoses(mesh, spheres, surrounding, layout, areas, min_area, *training, &picks, &out.training);

  out.triangles.reserve(spheres.size() * 4);
  out.vertices.reserve(spheres.size() * 12);
  out.frames.resize(spheres.size());
  for (size_t s = 0; s < spheres.size(); ++s) {
    const FittedSphere& S = spheres[s];
    float p[4][3];
    for (int k = 0; k < 4; ++k) {
      const uint32_t t = picks[s][k];
      out.triangles.push_back(t);
      for (int j = 0; j < 3; ++j) out.vertices.push_back(mesh.indices[3 * t + j]);
      // The centroid exactly as the runtime's refit computes it.
      runtime::TriangleCentroid(&mesh.positions[3 * mesh.indices[3 * t]], &mesh.positions[3 * mesh.indices[3 * t + 1]],
                                &mesh.positions[3 * mesh.indices[3 * t + 2]], p[k]);
    }
    // Bind data with the runtime's own frame functions, so refit reproduces the bind sphere.
    const float c[3] = {float(S.center.x()), float(S.center.y()), float(S.center.z())};
    runtime::PivotFrameBasis basis;
    if (!runtime::BuildPivotFrame(p, &basis))
      return MakeError(Error::Code::kFit, "sphere " + std::to_string(s) + ": degenerate pivot frame");
    float local[3];
    runtime::PivotFrameToLocal(basis, c, local);
    out.frames[s].local_center = {local[0], local[1], local[2]};
    out.frames[s].centroid_offset = {c[0] - basis.origin[0], c[1] - basis.origin[1], c[2] - basis.origin[2]};
    out.frames[s].mean_distance = runtime::PivotMeanDistance(p, c);
  }
  return out;
}

Result<CentreWeights> CentreSkinWeights(const Mesh& mesh, const SurroundingRegions& surrounding,
                                        const Pivots& pivots, uint32_t* unweighted) {
  if (!mesh.skin) return MakeError(Error::Code::kConfig, "centre skin weights: the mesh has no skin");
  const Skin& skin = *mesh.skin;
  if (skin.joints.size() > 65535)
    return MakeError(Error::Code::kConfig, "centre skin weights: " + std::to_string(skin.joints.size()) +
                                               " joints, the asset indexes at most 65,535");
  if (skin.weight_offsets.size() != size_t(mesh.vertex_count()) + 1)
    return MakeError(Error::Code::kConfig, "centre skin weights: skin rows do not match the mesh's vertices");
  const size_t S = surrounding.offsets.empty() ? 0 : surrounding.offsets.size() - 1;
  CentreWeights out;
  out.joint_count = uint32_t(skin.joints.size());
  out.joints.assign(4 * S, 0);
  out.weights.assign(4 * S, 0.0f);
  uint32_t none = 0;
  std::vector<double> sum(skin.joints.size(), 0.0);
  std::vector<uint32_t> touched;
  for (size_t s = 0; s < S; ++s) {
    touched.clear();
    double total = 0.0;
    auto add = [&](const std::vector<uint32_t>& vertices) {
      for (uint32_t v : vertices)
        for (uint32_t k = skin.weight_offsets[v]; k < skin.weight_offsets[v + 1]; ++k) {
          const uint32_t j = skin.weight_joints[k];
          if (j >= sum.size() || !(skin.weights[k] > 0.0f)) continue;
          if (sum[j] == 0.0) touched.push_back(j);
          sum[j] += skin.weights[k];
          total += skin.weights[k];
        }
    };
    add(surrounding.Vertices(mesh, s));
    if (touched.empty() && pivots.vertices.size() >= 12 * (s + 1))
      add(std::vector<uint32_t>(pivots.vertices.begin() + long(12 * s), pivots.vertices.begin() + long(12 * (s + 1))));
    if (touched.empty() || !(total > 0.0)) {
      ++none;
      out.weights[4 * s] = 1.0f;  // joint 0: the skin's root in glTF and assimp order
      continue;
    }
    std::sort(touched.begin(), touched.end(), [&](uint32_t a, uint32_t b) {
      return sum[a] != sum[b] ? sum[a] > sum[b] : a < b;
    });
    const size_t keep = std::min<size_t>(4, touched.size());
    double kept = 0.0;
    for (size_t k = 0; k < keep; ++k) kept += sum[touched[k]];
    float acc = 0.0f;
    for (size_t k = 0; k < keep; ++k) {
      out.joints[4 * s + k] = uint16_t(touched[k]);
      out.weights[4 * s + k] = k + 1 < keep ? float(sum[touched[k]] / kept) : 1.0f - acc;  // sums to 1 in float
      acc += out.weights[4 * s + k];
    }
    for (uint32_t j : touched) sum[j] = 0.0;
  }
  if (unweighted) *unweighted = none;
  return out;
}

}  // namespace spherechain::baker
