// Play(): an animation through the runtime, frame by frame, with timings (play.h).
#include "spherechain/playback/play.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <span>

#include "spherechain/runtime/runtime.h"

namespace spherechain::playback {

namespace {

/// How well the refitted spheres follow the deformed surface (§5.1, and the pivot-frame variant):
/// for every vertex v of a sphere's surrounding region, F = r − ‖c − v‖ at the bind pose and at the
/// frame; |ΔF| = 0 when the sphere moves and scales exactly with its surface. Mean and max over all
/// (sphere, vertex) of a frame, in source units.
class RefitTracking {
 public:
  RefitTracking(const runtime::AssetView& view, const Mesh& mesh, const runtime::SphereArrays& bind) {
    offsets_.push_back(0);
    for (uint32_t s = 0; s < view.sphere_count; ++s) {
      const runtime::TriangleSpan tris = runtime::SurroundingTriangles(view, s);
      std::vector<uint32_t> vs;
      for (uint32_t k = 0; k < tris.count; ++k)
        for (int j = 0; j < 3; ++j) vs.push_back(mesh.indices[3 * size_t(tris.data[k]) + j]);
      std::sort(vs.begin(), vs.end());
      vs.erase(std::unique(vs.begin(), vs.end()), vs.end());
      for (uint32_t v : vs) {
        verts_.push_back(v);
        f0_.push_back(F(bind, s, mesh.positions.data(), v));
      }
      offsets_.push_back(static_cast<uint32_t>(verts_.size()));
    }
  }
  void Measure(const runtime::SphereArrays& now, const float* positions, double* mean, double* max) const {
    double sum = 0, mx = 0;
    for (uint32_t s = 0; s + 1 < offsets_.size(); ++s)
      for (uint32_t k = offsets_[s]; k < offsets_[s + 1]; ++k) {
        const double d = std::abs(F(now, s, positions, verts_[k]) - f0_[k]);
        sum += d;
        mx = std::max(mx, d);
      }
    *mean = verts_.empty() ? 0.0 : sum / double(verts_.size());
    *max = mx;
  }

 private:
  static double F(const runtime::SphereArrays& sp, uint32_t s, const float* p, uint32_t v) {
    const double dx = sp.x[s] - p[3 * size_t(v)], dy = sp.y[s] - p[3 * size_t(v) + 1], dz = sp.z[s] - p[3 * size_t(v) + 2];
    return sp.r[s] - std::sqrt(dx * dx + dy * dy + dz * dz);
  }
  std::vector<uint32_t> offsets_, verts_;
  std::vector<double> f0_;
};

/// A FrameReport from the session's frame: counters, timings, pairs and their regions, contacts with their
/// regions and depths, the joint refit's error against its reference, and (keep_spheres) the spheres.
void Record(const runtime::AssetView& view, const SessionFrame& fr, const PlayOptions& o, FrameReport* row) {
  row->m1 = fr.m1_stats, row->m2 = fr.m2_stats;
  row->refit_us = fr.refit_us, row->detect_m1_us = fr.detect_m1_us, row->detect_m2_us = fr.detect_m2_us;
  if (!fr.reference.empty()) {  // kJoints: ‖c_joints − c_pivot_frame‖ / r_pivot_frame per sphere
    const runtime::SphereArrays& j = fr.spheres;
    const uint32_t S = j.count;
    const float* ref = fr.reference.data();
    row->joint_error.resize(S);
    for (uint32_t s = 0; s < S; ++s) {
      const double dx = j.x[s] - ref[s], dy = j.y[s] - ref[S + s], dz = j.z[s] - ref[2 * S + s];
      row->joint_error[s] = 100.0 * std::sqrt(dx * dx + dy * dy + dz * dz) / ref[3 * S + s];
    }
  }
  const auto* sr = view.asset->sphere_regions();
  const std::span<const runtime::Collision> pairs = o.m2 ? fr.m2 : fr.m1;  // M2 sees every pair: prefer it
  if (o.narrow_phase) {
    row->narrow = fr.narrow;
    row->narrow_us = fr.narrow_us;
    row->narrow_pairs = fr.behind_pairs;
    row->narrow_folds = fr.behind_folds;
    const bool depths = fr.exclusions == runtime::Exclusions::kCrease;
    std::map<std::pair<int, int>, float> cr;  // region pair → its deepest contact (0 without depths)
    for (size_t i = 0; i < fr.contacts.size(); ++i) {
      const uint16_t a = fr.contacts[i].sphere_a, b = fr.contacts[i].sphere_b;  // 0xFFFF: an unassigned triangle
      const int ra = sr && a < sr->size() ? sr->Get(a) : -1, rb = sr && b < sr->size() ? sr->Get(b) : -1;
      float& deepest = cr[{std::min(ra, rb), std::max(ra, rb)}];
      if (depths) deepest = std::max(deepest, fr.depths[i].depth);
    }
    row->contact_regions.clear(), row->contact_region_depth.clear(), row->depths.clear();
    for (const auto& [pair, depth] : cr) {
      row->contact_regions.push_back(pair);
      if (depths) row->contact_region_depth.push_back(depth);
    }
    row->contacts.assign(fr.contacts.begin(), fr.contacts.end());
    if (depths) row->depths.assign(fr.depths.begin(), fr.depths.end());
  }
  std::set<std::pair<int, int>> regions;
  row->pairs.assign(pairs.begin(), pairs.end());
  for (const runtime::Collision& c : pairs) {
    const int a = sr ? sr->Get(c.a) : -1, b = sr ? sr->Get(c.b) : -1;
    regions.emplace(std::min(a, b), std::max(a, b));
  }
  row->regions.assign(regions.begin(), regions.end());
  if (o.keep_spheres) {
    const runtime::SphereArrays& sp = fr.spheres;
    row->spheres.resize(size_t(sp.count) * 4);
    for (uint32_t s = 0; s < sp.count; ++s) {
      float* o = &row->spheres[size_t(s) * 4];
      o[0] = sp.x[s], o[1] = sp.y[s], o[2] = sp.z[s], o[3] = sp.r[s];
    }
  }
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(q * double(v.size() - 1) + 0.5))];
}

}  // namespace

std::string RegionPairsText(const std::vector<std::pair<int, int>>& pairs) {
  std::string s;
  for (const auto& [a, b] : pairs) {
    if (!s.empty()) s += ' ';
    s += "R" + std::to_string(a) + "-R" + std::to_string(b);
  }
  return s.empty() ? "-" : s;
}

PlaySummary Summarize(const std::vector<FrameReport>& rows) {
  PlaySummary m;
  m.frames = uint32_t(rows.size());
  double sum_refit = 0, sum_m1 = 0, sum_m2 = 0, sum_raw = 0, sum_dist = 0, sum_pm2 = 0, track_sum = 0;
  std::map<std::pair<int, int>, uint32_t> region_frames;
  std::vector<double> joint_errors, narrow_us;
  for (const FrameReport& r : rows) {
    sum_refit += r.refit_us;
    sum_m1 += r.detect_m1_us;
    sum_m2 += r.detect_m2_us;
    sum_raw += r.m1.raw_pairs;
    sum_dist += r.m1.distinct_pairs;
    sum_pm2 += r.m2.distinct_pairs;
    m.max_pairs_m1_raw = std::max(m.max_pairs_m1_raw, r.m1.raw_pairs);
    m.max_pairs_m2 = std::max(m.max_pairs_m2, r.m2.distinct_pairs);
    m.frames_with_pairs += !r.regions.empty();
    for (const auto& p : r.regions) ++region_frames[p];
    track_sum += r.tracking_mean;
    m.tracking_max = std::max(m.tracking_max, r.tracking_max);
    joint_errors.insert(joint_errors.end(), r.joint_error.begin(), r.joint_error.end());
    narrow_us.push_back(r.narrow_us);
    m.contacts += r.narrow.contacts;
    m.frames_with_contacts += r.narrow.contacts > 0;
  }
  const double n = double(rows.size());
  if (!rows.empty()) {
    m.mean_refit_us = sum_refit / n;
    m.mean_detect_m1_us = sum_m1 / n;
    m.mean_detect_m2_us = sum_m2 / n;
    m.mean_pairs_m1_raw = sum_raw / n;
    m.mean_pairs_m1 = sum_dist / n;
    m.mean_pairs_m2 = sum_pm2 / n;
    m.tracking_mean = track_sum / n;
  }
  m.joint_error_median = Percentile(joint_errors, 0.5);
  m.joint_error_p95 = Percentile(joint_errors, 0.95);
  m.joint_error_max = Percentile(joint_errors, 1.0);
  std::sort(narrow_us.begin(), narrow_us.end());
  m.narrow_median_us = narrow_us.empty() ? 0.0 : narrow_us[narrow_us.size() / 2];
  m.narrow_max_us = narrow_us.empty() ? 0.0 : narrow_us.back();
  m.region_frames.assign(region_frames.begin(), region_frames.end());
  return m;
}

Result<PlayReport> Play(const Mesh& mesh, const runtime::AssetView& view, const Animation& anim, const PlayOptions& o) {
  if (!view.valid()) return MakeError(Error::Code::kConfig, "play: the asset is not loaded");
  if (mesh.vertex_count() != view.vertex_count)
    return MakeError(Error::Code::kConfig, "play: the mesh has " + std::to_string(mesh.vertex_count()) +
                                               " vertices, the asset was baked from " + std::to_string(view.vertex_count));
  if (!mesh.skin) return MakeError(Error::Code::kConfig, "play: the mesh has no skin ('" + mesh.source_path + "')");
  const bool joints = o.refit == PlayRefit::kJoints;
  if (joints && !view.asset->sphere_joints())
    return MakeError(Error::Code::kConfig,
                     "the asset has no joint weights (schema v" + std::to_string(view.asset->schema_version()) +
                         ", or baked from a mesh without a skin): --refit joints needs an asset baked by this version "
                         "from a rigged character; re-bake it");
  if (joints && view.asset->joint_count() != mesh.skin->joints.size())
    return MakeError(Error::Code::kConfig, "the asset was baked for " + std::to_string(view.asset->joint_count()) +
                                               " joints, the mesh has " + std::to_string(mesh.skin->joints.size()));
  if (!std::isfinite(o.narrow_behind_margin) || o.narrow_behind_margin < 0.0f)
    return MakeError(Error::Code::kConfig, "narrow_behind_margin " + std::to_string(o.narrow_behind_margin) +
                                               ": expected a finite multiple of the contact margin >= 0");
  SessionOptions so;
  so.refit = o.refit;
  so.joint_reference = true;
  so.m1 = o.m1;
  so.m2 = o.m2;
  so.narrow = !o.narrow_phase                  ? SessionNarrow::kNone
              : o.narrow_behind_margin > 0.0f ? SessionNarrow::kBehindM2
                                              : SessionNarrow::kEvery;
  so.crease = o.crease;
  if (o.narrow_behind_margin > 0.0f) so.narrow_behind_margin = o.narrow_behind_margin;
  so.contact_capacity = o.contact_capacity;
  so.joint_matrices = bool(o.on_frame);
  so.repeat = o.repeat;
  Session session;
  if (auto s = session.Init(view, mesh, so); !s.ok()) return s.error();

  PlayReport report;
  report.animation = anim.Describe();
  report.sphere_count = view.sphere_count;
  report.chain_count = view.chain_count;
  report.frames.resize(anim.frames);
  // The bind pose first: refit to the undeformed mesh (what a correct asset reports as no pairs).
  if (auto s = session.StepBind(); !s.ok()) return s.error();
  report.bind.label = "bind";
  Record(view, session.frame(), o, &report.bind);
  const RefitTracking tracking(view, mesh, session.frame().spheres);
  auto played = session.Play(anim, [&](const SessionFrame& fr) -> Status {
    FrameReport& row = report.frames[fr.frame];
    row.frame = fr.frame;
    row.label = fr.label;
    Record(view, fr, o, &row);
    tracking.Measure(fr.spheres, fr.positions.data(), &row.tracking_mean, &row.tracking_max);
    if (o.on_frame)
      return o.on_frame(fr.frame, session.positions(), fr.joint_matrices.empty() ? nullptr : &session.joint_matrices());
    return Ok{};
  });
  if (!played.ok()) return played.error();
  report.summary = Summarize(report.frames);
  return report;
}

}  // namespace spherechain::playback
