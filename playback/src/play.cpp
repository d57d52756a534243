// Play(): an animation through the runtime, frame by frame, with timings (play.h).
#include "spherechain/playback/play.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <set>

#include "spherechain/runtime/runtime.h"

namespace spherechain::playback {

namespace {

using Clock = std::chrono::steady_clock;

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

Error RuntimeError(runtime::Status s) { return MakeError(Error::Code::kInternal, std::string("runtime: ") + runtime::ToString(s)); }

/// Refit + detect (+ narrow phase) on one frame's positions, timing each job as the minimum over `repeat` runs.
class Player {
 public:
  Player(const runtime::AssetView& view, const runtime::Model* model, runtime::Workspace* ws, const PlayOptions& o,
         const runtime::NarrowPhaseModel* narrow, runtime::NarrowPhaseWorkspace* narrow_ws)
      : view_(view), model_(model), ws_(ws), o_(o), repeat_(std::max(1u, o.repeat)), narrow_(narrow), narrow_ws_(narrow_ws) {
    mode_ = o.refit == PlayRefit::kPaper ? runtime::RefitMode::kPaper : runtime::RefitMode::kPivotFrame;
    out_m1_.resize(runtime::DetectBound(view, runtime::DetectMethod::kM1));
    out_m2_.resize(runtime::DetectBound(view, runtime::DetectMethod::kM2));
    if (narrow_) contacts_.resize(o.contact_capacity), depths_.resize(o.contact_capacity);
    if (narrow_ && o.narrow_behind_margin > 0.0f) out_behind_.resize(runtime::DetectBound(view, runtime::DetectMethod::kM2));
  }

  /// Fills the row's counters, timings, pairs and regions. With `joint_matrices` (#J × 12) the spheres
  /// come from the joints (timed) and the vertex refit (pivot frame) on `positions` is their reference.
  Status Run(const float* positions, FrameReport* row, const float* joint_matrices) {
    runtime::RefitJob refit;
    refit.model = model_;
    refit.workspace = ws_;
    refit.mode = mode_;
    refit.positions = {positions, view_.vertex_count, 12};
    if (joint_matrices) {
      runtime::RefitJob reference = refit;
      reference.mode = runtime::RefitMode::kPivotFrame;
      if (runtime::Status s = reference.Run(); runtime::Failed(s)) return RuntimeError(s);
      const runtime::SphereArrays v = ws_->spheres();
      ref_.assign(v.x, v.x + v.count);
      ref_.insert(ref_.end(), v.y, v.y + v.count);
      ref_.insert(ref_.end(), v.z, v.z + v.count);
      ref_.insert(ref_.end(), v.r, v.r + v.count);
      runtime::JointRefitJob joints;
      joints.model = model_;
      joints.workspace = ws_;
      joints.joint_matrices = joint_matrices;
      joints.joint_count = view_.asset->joint_count();
      if (auto s = Time([&] { return joints.Run(); }, &row->refit_us); !s.ok()) return s;
      const runtime::SphereArrays j = ws_->spheres();
      const uint32_t S = j.count;
      row->joint_error.resize(S);
      for (uint32_t s = 0; s < S; ++s) {
        const double dx = j.x[s] - ref_[s], dy = j.y[s] - ref_[S + s], dz = j.z[s] - ref_[2 * S + s];
        row->joint_error[s] = 100.0 * std::sqrt(dx * dx + dy * dy + dz * dz) / ref_[3 * S + s];
      }
    } else {
      if (auto s = Time([&] { return refit.Run(); }, &row->refit_us); !s.ok()) return s;
    }
    const runtime::Collision* regions_from = nullptr;
    uint32_t regions_count = 0;
    if (o_.m1) {
      if (auto s = Detect(runtime::DetectMethod::kM1, &out_m1_, &count_m1_, &row->m1, &row->detect_m1_us); !s.ok()) return s;
      regions_from = out_m1_.data();
      regions_count = count_m1_;
    }
    if (o_.m2) {
      if (auto s = Detect(runtime::DetectMethod::kM2, &out_m2_, &count_m2_, &row->m2, &row->detect_m2_us); !s.ok()) return s;
      regions_from = out_m2_.data();  // M2 sees every pair: prefer it for the region summary
      regions_count = count_m2_;
    }
    const auto* sr = view_.asset->sphere_regions();
    if (narrow_) {
      runtime::NarrowPhaseJob job;
      job.model = narrow_;
      job.workspace = narrow_ws_;
      job.positions = refit.positions;
      job.output = contacts_.data();
      job.capacity = static_cast<uint32_t>(contacts_.size());
      job.count = &count_contacts_;
      job.stats = &row->narrow;
      // Behind the spheres' pairs: M2 with the wider margin, then the narrow phase on those pairs (timed together).
      const bool behind = o_.narrow_behind_margin > 0.0f;
      runtime::DetectJob broad = MakeDetect(runtime::DetectMethod::kM2, &out_behind_, &row->narrow_pairs, nullptr);
      broad.margin = o_.narrow_behind_margin * model_->contact_margin();
      // One margin for every pair: the fold margin only keeps the spheres alone from crying wolf at a folding
      // joint, and the exact narrow phase behind them cannot cry wolf (README "The spheres as a broad phase").
      if (model_->fold_margin() >= 0.0f) broad.fold_margin = broad.margin;
      if (behind) job.sphere_pairs = out_behind_.data();
      // Unrestricted on an asset with the crease rule: every self-contact the skin makes (Exclusions::kCrease).
      else if (o_.crease && narrow_->has_crease()) job.exclusions = runtime::Exclusions::kCrease, job.depths = depths_.data();
      auto run = [&] {
        if (behind) {
          if (const runtime::Status s = broad.Run(); runtime::Failed(s)) return s;
          job.sphere_pair_count = row->narrow_pairs;
        }
        return job.Run();
      };
      if (auto s = Time(run, &row->narrow_us); !s.ok()) return s;
      std::map<std::pair<int, int>, float> cr;  // region pair → its deepest contact (0 without depths)
      for (uint32_t i = 0; i < count_contacts_; ++i) {
        const uint16_t a = contacts_[i].sphere_a, b = contacts_[i].sphere_b;  // 0xFFFF: an unassigned triangle
        const int ra = sr && a < sr->size() ? sr->Get(a) : -1, rb = sr && b < sr->size() ? sr->Get(b) : -1;
        float& deepest = cr[{std::min(ra, rb), std::max(ra, rb)}];
        if (job.depths) deepest = std::max(deepest, depths_[i].depth);
      }
      row->contact_regions.clear(), row->contact_region_depth.clear(), row->depths.clear();
      for (const auto& [pair, depth] : cr) {
        row->contact_regions.push_back(pair);
        if (job.depths) row->contact_region_depth.push_back(depth);
      }
      row->contacts.assign(contacts_.begin(), contacts_.begin() + count_contacts_);
      if (job.depths) row->depths.assign(depths_.begin(), depths_.begin() + count_contacts_);
    }
    std::set<std::pair<int, int>> regions;
    row->pairs.assign(regions_from, regions_from + regions_count);
    for (uint32_t i = 0; i < regions_count; ++i) {
      const int a = sr ? sr->Get(regions_from[i].a) : -1, b = sr ? sr->Get(regions_from[i].b) : -1;
      regions.emplace(std::min(a, b), std::max(a, b));
    }
    row->regions.assign(regions.begin(), regions.end());
    if (o_.keep_spheres) {
      const runtime::SphereArrays sp = ws_->spheres();
      row->spheres.resize(size_t(sp.count) * 4);
      for (uint32_t s = 0; s < sp.count; ++s) {
        float* o = &row->spheres[size_t(s) * 4];
        o[0] = sp.x[s], o[1] = sp.y[s], o[2] = sp.z[s], o[3] = sp.r[s];
      }
    }
    return Ok{};
  }

 private:
  template <class F>
  Status Time(F&& f, double* us_out) {
    double best = 1e300;
    for (uint32_t r = 0; r < repeat_; ++r) {
      const auto t0 = Clock::now();
      const runtime::Status s = f();
      const double us = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
      if (runtime::Failed(s)) return RuntimeError(s);
      best = std::min(best, us);
    }
    *us_out = best;
    return Ok{};
  }

  runtime::DetectJob MakeDetect(runtime::DetectMethod method, std::vector<runtime::Collision>* out, uint32_t* count,
                                runtime::DetectStats* stats) const {
    runtime::DetectJob job;
    job.model = model_;
    job.workspace = ws_;
    job.method = method;
    job.output = out->data();
    job.capacity = static_cast<uint32_t>(out->size());
    job.count = count;
    job.stats = stats;
    return job;
  }

  Status Detect(runtime::DetectMethod method, std::vector<runtime::Collision>* out, uint32_t* count,
                runtime::DetectStats* stats, double* us) {
    const runtime::DetectJob job = MakeDetect(method, out, count, stats);
    return Time([&] { return job.Run(); }, us);
  }

  runtime::AssetView view_;
  const runtime::Model* model_;
  runtime::Workspace* ws_;
  const PlayOptions& o_;
  runtime::RefitMode mode_;
  uint32_t repeat_;
  std::vector<runtime::Collision> out_m1_, out_m2_, out_behind_;
  uint32_t count_m1_ = 0, count_m2_ = 0;
  const runtime::NarrowPhaseModel* narrow_ = nullptr;
  runtime::NarrowPhaseWorkspace* narrow_ws_ = nullptr;
  std::vector<runtime::TriangleContact> contacts_;
  std::vector<runtime::ContactDepth> depths_;
  uint32_t count_contacts_ = 0;
  std::vector<float> ref_;  // the vertex refit's spheres (x, y, z, r blocks) under kJoints
};

/// The skinning matrices of `scratch` (column-major 4×4, what the last skinning used) in the runtime's
/// joint layout (#J × 12, row-major 3×4).
void JointMatrices(const SkinningScratch& scratch, std::vector<float>* out) {
  out->resize(scratch.matrices.size() * runtime::kJointMatrixFloats);
  for (size_t j = 0; j < scratch.matrices.size(); ++j)
    runtime::JointMatrixFromColumnMajor(scratch.matrices[j].data(), out->data() + j * runtime::kJointMatrixFloats);
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(q * double(v.size() - 1) + 0.5))];
}

}  // namespace

const char* ToString(PlayRefit r) {
  switch (r) {
    case PlayRefit::kPaper: return "paper";
    case PlayRefit::kPivotFrame: return "frame";
    case PlayRefit::kJoints: return "joints";
  }
  return "?";
}

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
  runtime::Model model;
  runtime::Workspace workspace;
  if (runtime::Status s = model.Init(view); runtime::Failed(s))
    return MakeError(Error::Code::kInternal, std::string("runtime Model::Init: ") + runtime::ToString(s));
  if (runtime::Status s = workspace.Init(model); runtime::Failed(s))
    return MakeError(Error::Code::kInternal, std::string("runtime Workspace::Init: ") + runtime::ToString(s));
  runtime::NarrowPhaseModel narrow;
  runtime::NarrowPhaseWorkspace narrow_ws;
  if (!std::isfinite(o.narrow_behind_margin) || o.narrow_behind_margin < 0.0f)
    return MakeError(Error::Code::kConfig, "narrow_behind_margin " + std::to_string(o.narrow_behind_margin) +
                                               ": expected a finite multiple of the contact margin >= 0");
  if (o.narrow_phase) {
    const runtime::NarrowPhaseRegions kind =
        o.narrow_behind_margin > 0.0f ? runtime::NarrowPhaseRegions::kReach : runtime::NarrowPhaseRegions::kSurrounding;
    if (runtime::Status s = narrow.Init(view, kind); runtime::Failed(s) || runtime::Failed(s = narrow_ws.Init(narrow)))
      return MakeError(Error::Code::kConfig,
                       std::string("narrow phase: ") + runtime::ToString(s) +
                           (s == runtime::Status::kErrorMissingField ? " (baked before the narrow phase existed: re-bake it)" : ""));
  }
  Player player(view, &model, &workspace, o, o.narrow_phase ? &narrow : nullptr, o.narrow_phase ? &narrow_ws : nullptr);

  PlayReport report;
  report.animation = anim.Describe();
  report.sphere_count = view.sphere_count;
  report.chain_count = view.chain_count;
  std::vector<float> positions(mesh.positions.size());
  SkinningScratch scratch;
  report.frames.resize(anim.frames);

  // The bind pose first: refit to the undeformed mesh (what a correct asset reports as no pairs); the
  // joint refit gets the rest pose's skinning matrices.
  report.bind.label = "bind";
  std::vector<float> joint_matrices;
  if (joints) {
    RestLocals(*mesh.skin, &scratch.locals);
    if (auto s = GlobalMatrices(*mesh.skin, scratch.locals, &scratch.globals); !s.ok()) return s.error();
    if (auto s = SkinningMatrices(*mesh.skin, scratch.globals, &scratch.matrices); !s.ok()) return s.error();
    JointMatrices(scratch, &joint_matrices);
  }
  if (auto s = player.Run(mesh.positions.data(), &report.bind, joints ? joint_matrices.data() : nullptr); !s.ok())
    return s.error();
  const RefitTracking tracking(view, mesh, workspace.spheres());

  for (uint32_t f = 0; f < anim.frames; ++f) {
    FrameReport& row = report.frames[f];
    row.frame = f;
    if (auto s = anim.Frame(mesh, f, &scratch, &positions, &row.label); !s.ok()) return s.error();
    // The frame's joint matrices, in the runtime's layout: for the joint refit and for on_frame.
    const bool give_joints = o.on_frame && view.asset->sphere_joints() &&
                             view.asset->joint_count() == scratch.matrices.size();
    if (joints || give_joints) JointMatrices(scratch, &joint_matrices);
    if (auto s = player.Run(positions.data(), &row, joints ? joint_matrices.data() : nullptr); !s.ok()) return s.error();
    tracking.Measure(workspace.spheres(), positions.data(), &row.tracking_mean, &row.tracking_max);
    if (o.on_frame) {
      if (auto s = o.on_frame(f, positions, give_joints ? &joint_matrices : nullptr); !s.ok()) return s.error();
    }
  }
  report.summary = Summarize(report.frames);
  return report;
}

}  // namespace spherechain::playback
