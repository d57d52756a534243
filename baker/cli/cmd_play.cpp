// spherechain play ASSET --mesh INPUT [--clip NAME | --morph POSES...] [--frames N] [--method m1|m2|both]
//                  [--refit paper|frame|joints] [--json OUT] [--poses-dir DIR] [--rig MHSKEL] [--repeat R]
//
// Plays an animation of the character the asset was baked from — a skinned clip, or the paper's
// Bézier morph through key poses (§5.1, §6: 40 frames) — and runs the runtime on every frame: refit
// the spheres to the skinned vertices, detect overlapping sphere pairs with M1 (chains) and/or M2 (all
// spheres) (§5.2). Prints a per-frame table (pairs, timings, which regions touch) and a summary.
#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "animation_source.h"
#include "asset_file.h"
#include "commands.h"
#include "spherechain/baker/animation.h"
#include "spherechain/baker/import.h"
#include "spherechain/baker/morph.h"
#include "spherechain/baker/write.h"
#include "spherechain/runtime/narrow_phase.h"
#include "spherechain/runtime/runtime.h"

namespace spherechain::cli {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct PlayArgs {
  std::string asset, json, rig, dump_frames, method = "both", refit = "frame";
  AnimationArgs anim;  // --mesh, --clip, --morph, --poses-dir, --frames
  uint32_t repeat = 5;
  bool narrow_phase = false;
};

/// "R0-R4 R1-R4": the region pairs of the given colliding sphere pairs, sorted, each once.
std::string RegionsTouching(const std::set<std::pair<int, int>>& pairs) {
  std::string s;
  for (const auto& [a, b] : pairs) {
    if (!s.empty()) s += ' ';
    s += "R" + std::to_string(a) + "-R" + std::to_string(b);
  }
  return s.empty() ? "-" : s;
}

struct FrameRow {
  uint32_t frame = 0;
  std::string label;  // "t=0.533s" or "arms_crossed t=0.50"
  runtime::DetectStats m1, m2;
  double refit_us = 0, detect_m1_us = 0, detect_m2_us = 0;
  double tracking_mean = 0, tracking_max = 0;  // |ΔF| vs the bind pose (see RefitTracking)
  std::vector<double> joint_error;              // --refit joints: per sphere ‖c_joints − c_vertices‖ / r, %
  std::set<std::pair<int, int>> regions;
  std::vector<runtime::Collision> pairs;  // of M2 when run, else M1
  runtime::NarrowPhaseStats narrow;       // with --narrow-phase
  double narrow_us = 0;
  std::set<std::pair<int, int>> contact_regions;  // region pairs of the narrow phase's contacts
};

/// How well the refitted spheres follow the deformed surface (§5.1, and the pivot-frame variant):
/// for every vertex v of a sphere's surrounding region, F = r − ‖c − v‖ at the bind pose and at the
/// frame; |ΔF| = 0 when the sphere moves and scales exactly with its surface. Mean and max over all
/// (sphere, vertex) of a frame, in source units.
class RefitTracking {
 public:
  RefitTracking(const runtime::AssetView& view, const baker::Mesh& mesh, const runtime::SphereArrays& bind) {
    offsets_.push_back(0);
    for (uint32_t s = 0; s < view.sphere_count; ++s) {
      const runtime::TriangleSpan tris = runtime::SurroundingTriangles(view, s);
      std::vector<uint32_t> vs;
      for (uint32_t k = 0; k < tris.count; ++k)
        for (int j = 0; j < 3; ++j) vs.push_back(mesh.indices[3 * tris.data[k] + j]);
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
    const double dx = sp.x[s] - p[3 * v], dy = sp.y[s] - p[3 * v + 1], dz = sp.z[s] - p[3 * v + 2];
    return sp.r[s] - std::sqrt(dx * dx + dy * dy + dz * dz);
  }
  std::vector<uint32_t> offsets_, verts_;
  std::vector<double> f0_;
};

/// Refit + detect on `positions`, timing each job as the minimum over `repeat` runs.
class Player {
 public:
  Player(const runtime::AssetView& view, const runtime::Model* model, runtime::Workspace* ctx, runtime::RefitMode mode, bool m1, bool m2,
         uint32_t repeat, runtime::NarrowPhaseContext* narrow)
      : view_(view), model_(model), ctx_(ctx), mode_(mode), run_m1_(m1), run_m2_(m2), repeat_(std::max(1u, repeat)), narrow_(narrow) {
    out_m1_.resize(runtime::DetectBound(view, runtime::DetectMethod::kM1));
    out_m2_.resize(runtime::DetectBound(view, runtime::DetectMethod::kM2));
    if (narrow_) contacts_.resize(1u << 16);
  }

  /// Fills row counters, timings and touching regions; returns false with `*error` on a runtime error.
  /// With `joint_matrices` (#J × 12, runtime JointRefitJob layout) the spheres come from the joints (timed)
  /// and the vertex refit (pivot frame) on `positions` is their reference (row->joint_error).
  bool Run(const float* positions, FrameRow* row, std::string* error, const float* joint_matrices = nullptr) {
    runtime::RefitJob refit;
    refit.model = model_;
    refit.workspace = ctx_;
    refit.mode = mode_;
    refit.positions = {positions, view_.vertex_count, 12};
    if (joint_matrices) {
      runtime::RefitJob reference = refit;
      reference.mode = runtime::RefitMode::kPivotFrame;
      if (runtime::Status s = reference.Run(); runtime::Failed(s))
        return *error = std::string("runtime: ") + runtime::ToString(s), false;
      const runtime::SphereArrays v = ctx_->spheres();
      ref_.assign(v.x, v.x + v.count);
      ref_.insert(ref_.end(), v.y, v.y + v.count);
      ref_.insert(ref_.end(), v.z, v.z + v.count);
      ref_.insert(ref_.end(), v.r, v.r + v.count);
      runtime::JointRefitJob joints;
      joints.model = model_;
      joints.workspace = ctx_;
      joints.joint_matrices = joint_matrices;
      joints.joint_count = view_.asset->joint_count();
      row->refit_us = Time([&] { return joints.Run(); }, error);
      if (row->refit_us < 0) return false;
      const runtime::SphereArrays j = ctx_->spheres();
      const uint32_t S = j.count;
      row->joint_error.resize(S);
      for (uint32_t s = 0; s < S; ++s) {
        const double dx = j.x[s] - ref_[s], dy = j.y[s] - ref_[S + s], dz = j.z[s] - ref_[2 * S + s];
        row->joint_error[s] = 100.0 * std::sqrt(dx * dx + dy * dy + dz * dz) / ref_[3 * S + s];
      }
    } else {
      row->refit_us = Time([&] { return refit.Run(); }, error);
      if (row->refit_us < 0) return false;
    }
    const runtime::Collision* regions_from = nullptr;
    uint32_t regions_count = 0;
    if (run_m1_) {
      row->detect_m1_us = Detect(runtime::DetectMethod::kM1, &out_m1_, &count_m1_, &row->m1, error);
      if (row->detect_m1_us < 0) return false;
      regions_from = out_m1_.data();
      regions_count = count_m1_;
    }
    if (run_m2_) {
      row->detect_m2_us = Detect(runtime::DetectMethod::kM2, &out_m2_, &count_m2_, &row->m2, error);
      if (row->detect_m2_us < 0) return false;
      regions_from = out_m2_.data();  // M2 sees every pair: prefer it for the region summary
      regions_count = count_m2_;
    }
    const auto* sr = view_.asset->sphere_regions();
    if (narrow_) {
      runtime::NarrowPhaseJob job;
      job.context = narrow_;
      job.positions = refit.positions;
      job.output = contacts_.data();
      job.capacity = static_cast<uint32_t>(contacts_.size());
      job.count = &count_contacts_;
      job.stats = &row->narrow;
      row->narrow_us = Time([&] { return job.Run(); }, error);
      if (row->narrow_us < 0) return false;
      row->contact_regions.clear();
      for (uint32_t i = 0; i < count_contacts_; ++i) {
        const int ra = sr ? sr->Get(contacts_[i].sphere_a) : -1, rb = sr ? sr->Get(contacts_[i].sphere_b) : -1;
        row->contact_regions.emplace(std::min(ra, rb), std::max(ra, rb));
      }
    }
    row->regions.clear();
    row->pairs.assign(regions_from, regions_from + regions_count);
    for (uint32_t i = 0; i < regions_count; ++i) {
      const int a = sr ? sr->Get(regions_from[i].a) : -1, b = sr ? sr->Get(regions_from[i].b) : -1;
      row->regions.emplace(std::min(a, b), std::max(a, b));
    }
    return true;
  }

 private:
  template <class F>
  double Time(F&& f, std::string* error) {
    double best = 1e300;
    for (uint32_t r = 0; r < repeat_; ++r) {
      const auto t0 = Clock::now();
      const runtime::Status s = f();
      const double us = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
      if (runtime::Failed(s)) {
        *error = std::string("runtime: ") + runtime::ToString(s);
        return -1;
      }
      best = std::min(best, us);
    }
    return best;
  }

  double Detect(runtime::DetectMethod method, std::vector<runtime::Collision>* out, uint32_t* count,
                runtime::DetectStats* stats, std::string* error) {
    runtime::DetectJob job;
    job.model = model_;
    job.workspace = ctx_;
    job.method = method;
    job.output = out->data();
    job.capacity = static_cast<uint32_t>(out->size());
    job.count = count;
    job.stats = stats;
    return Time([&] { return job.Run(); }, error);
  }

  runtime::AssetView view_;
  const runtime::Model* model_;
  runtime::Workspace* ctx_;
  runtime::RefitMode mode_;
  bool run_m1_, run_m2_;
  uint32_t repeat_;
  std::vector<runtime::Collision> out_m1_, out_m2_;
  uint32_t count_m1_ = 0, count_m2_ = 0;
  runtime::NarrowPhaseContext* narrow_ = nullptr;
  std::vector<runtime::TriangleContact> contacts_;
  uint32_t count_contacts_ = 0;
  std::vector<float> ref_;  // the vertex refit's spheres (x, y, z, r blocks) under --refit joints
};

/// The skinning matrices of `scratch` (column-major 4×4, what the last SkinClip / SkinMorphFrame used)
/// in the runtime's joint layout (#J × 12, row-major 3×4).
void JointMatrices(const baker::SkinningScratch& scratch, std::vector<float>* out) {
  out->resize(scratch.matrices.size() * runtime::kJointMatrixFloats);
  for (size_t j = 0; j < scratch.matrices.size(); ++j)
    runtime::JointMatrixFromColumnMajor(scratch.matrices[j].data(), out->data() + j * runtime::kJointMatrixFloats);
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(q * double(v.size() - 1) + 0.5))];
}

int RunPlay(const PlayArgs& a) {
  LoadedAsset asset;
  baker::Mesh mesh;
  std::string error;
  if (!OpenAssetAndMesh(a.asset, a.anim.mesh, a.rig, &asset, &mesh, &error)) return Fail(error);
  const runtime::AssetView& view = asset.view;

  const AnimationArgs& anim_args = a.anim;
  AnimationSource anim;
  if (!OpenAnimation(mesh, anim_args, &anim, &error)) return Fail(error);
  const baker::Clip* clip = anim.clip;
  const std::vector<baker::Pose>& poses = anim.poses;
  const uint32_t frames = anim.frames;

  // ---- runtime ------------------------------------------------------------------------------------
  runtime::Model model;
  runtime::Workspace ctx;
  if (runtime::Status s = model.Init(view); runtime::Failed(s) || runtime::Failed(s = ctx.Init(model)))
    return Fail(std::string("runtime Model / Workspace::Init: ") + runtime::ToString(s));
  const bool m1 = a.method != "m2", m2 = a.method != "m1";
  const runtime::RefitMode mode = a.refit == "paper" ? runtime::RefitMode::kPaper : runtime::RefitMode::kPivotFrame;
  const bool joints = a.refit == "joints";
  if (joints && !view.asset->sphere_joints())
    return Fail("'" + a.asset + "' has no joint weights (schema v" + std::to_string(view.asset->schema_version()) +
                ", or baked from a mesh without a skin): --refit joints needs an asset baked by this version from a "
                "rigged character; re-bake it");
  if (joints && view.asset->joint_count() != mesh.skin->joints.size())
    return Fail("'" + a.asset + "' was baked for " + std::to_string(view.asset->joint_count()) + " joints, '" + a.anim.mesh +
                "' has " + std::to_string(mesh.skin->joints.size()));
  runtime::NarrowPhaseContext narrow;
  if (a.narrow_phase) {
    if (runtime::Status s = narrow.Init(view); runtime::Failed(s))
      return Fail("'" + a.asset + "': narrow phase: " + runtime::ToString(s) +
                  (s == runtime::Status::kErrorMissingField ? " (baked before the narrow phase existed: re-bake it)" : ""));
  }
  Player player(view, &model, &ctx, mode, m1, m2, a.repeat, a.narrow_phase ? &narrow : nullptr);

  std::vector<float> positions(mesh.positions.size());
  baker::SkinningScratch scratch;
  std::vector<FrameRow> rows(frames);

  // The bind pose first: refit to the undeformed mesh (what a correct asset reports as no pairs); the
  // joint refit gets the rest pose's skinning matrices.
  FrameRow bind;
  bind.label = "bind";
  std::vector<float> joint_matrices;
  if (joints) {
    baker::RestLocals(*mesh.skin, &scratch.locals);
    if (auto s = baker::GlobalMatrices(*mesh.skin, scratch.locals, &scratch.globals); !s.ok()) return Fail(s.error());
    if (auto s = baker::SkinningMatrices(*mesh.skin, scratch.globals, &scratch.matrices); !s.ok())
      return Fail(s.error());
    JointMatrices(scratch, &joint_matrices);
  }
  if (!player.Run(mesh.positions.data(), &bind, &error, joints ? joint_matrices.data() : nullptr)) return Fail(error);
  const RefitTracking tracking(view, mesh, ctx.spheres());

  for (uint32_t f = 0; f < frames; ++f) {
    FrameRow& row = rows[f];
    row.frame = f;
    if (auto s = anim.Frame(mesh, f, &scratch, &positions, &row.label); !s.ok()) return Fail(s.error());
    // The frame's joint matrices, in the runtime's layout: for the joint refit and for --dump-frames.
    const bool dump_joints = !a.dump_frames.empty() && view.asset->sphere_joints() &&
                             view.asset->joint_count() == scratch.matrices.size();
    if (joints || dump_joints) JointMatrices(scratch, &joint_matrices);
    if (!player.Run(positions.data(), &row, &error, joints ? joint_matrices.data() : nullptr)) return Fail(error);
    tracking.Measure(ctx.spheres(), positions.data(), &row.tracking_mean, &row.tracking_max);
    if (!a.dump_frames.empty()) {
      // One raw frame per file: #V×3 little-endian float32, for bench/runtime_bench and the CUDA bench.
      char name[32];
      std::snprintf(name, sizeof name, "frame_%04u.f32", f);
      const std::string path = (fs::path(a.dump_frames) / name).string();
      if (auto s = baker::WriteFileAtomic(path, positions.data(), positions.size() * sizeof(float)); !s.ok())
        return Fail(s.error());
      // And its joint matrices (frame_NNNN.joints: #J × 12 float32, JointRefitJob's layout) when the
      // asset can refit from them.
      if (dump_joints) {
        std::snprintf(name, sizeof name, "frame_%04u.joints", f);
        const std::string jpath = (fs::path(a.dump_frames) / name).string();
        if (auto s = baker::WriteFileAtomic(jpath, joint_matrices.data(), joint_matrices.size() * sizeof(float)); !s.ok())
          return Fail(s.error());
      }
    }
  }

  // ---- report ------------------------------------------------------------------------------------
  std::printf("play: %s + %s — %s, %u frames, %u spheres, %u chains, refit %s, timings = min of %u runs\n",
              a.asset.c_str(), a.anim.mesh.c_str(),
              anim.Describe().c_str(),
              frames, view.sphere_count, view.chain_count, a.refit.c_str(), std::max(1u, a.repeat));
  if (!clip) {
    std::printf("key poses:");
    for (size_t k = 0; k < poses.size(); ++k)
      std::printf(" %s@%u", poses[k].name.c_str(),
                  baker::MorphKeyFrame(uint32_t(k), frames, uint32_t(poses.size())));
    std::printf("\n");
  }
  std::printf("\n%5s  %-26s %7s %7s %8s %7s %8s %8s %9s %9s", "frame", "pose", "testsM1", "M1 raw", "M1 dist", "M2",
              "testsM2", "refit us", "M1 us", "M2 us");
  if (a.narrow_phase) std::printf(" %8s %8s %9s", "contacts", "tri tests", "narrow us");
  std::printf("  %s%s\n", "regions touching", a.narrow_phase ? " | regions in contact (narrow phase)" : "");
  auto print_row = [&](const FrameRow& r, const std::string& frame) {
    std::printf("%5s  %-26s %7u %7u %8u %7u %8u %8.1f %9.1f %9.1f", frame.c_str(), r.label.c_str(), r.m1.tests,
                r.m1.raw_pairs, r.m1.distinct_pairs, r.m2.distinct_pairs, r.m2.tests, r.refit_us, r.detect_m1_us,
                r.detect_m2_us);
    if (a.narrow_phase) std::printf(" %8u %8u %9.1f", r.narrow.contacts, r.narrow.triangle_tests, r.narrow_us);
    std::printf("  %s", RegionsTouching(r.regions).c_str());
    if (a.narrow_phase) std::printf(" | %s", RegionsTouching(r.contact_regions).c_str());
    std::printf("\n");
  };
  print_row(bind, "bind");
  for (const FrameRow& r : rows) print_row(r, std::to_string(r.frame));

  double sum_refit = 0, sum_m1 = 0, sum_m2 = 0, sum_raw = 0, sum_dist = 0, sum_pm2 = 0;
  uint32_t max_raw = 0, max_pm2 = 0, frames_with_pairs = 0;
  std::map<std::pair<int, int>, uint32_t> region_frames;
  for (const FrameRow& r : rows) {
    sum_refit += r.refit_us;
    sum_m1 += r.detect_m1_us;
    sum_m2 += r.detect_m2_us;
    sum_raw += r.m1.raw_pairs;
    sum_dist += r.m1.distinct_pairs;
    sum_pm2 += r.m2.distinct_pairs;
    max_raw = std::max(max_raw, r.m1.raw_pairs);
    max_pm2 = std::max(max_pm2, r.m2.distinct_pairs);
    frames_with_pairs += !r.regions.empty();
    for (const auto& p : r.regions) ++region_frames[p];
  }
  const double n = frames;
  std::printf("\nsummary: %u frames, %u with collisions; bind pose: M1 %u pairs, M2 %u pairs\n", frames,
              frames_with_pairs, bind.m1.distinct_pairs, bind.m2.distinct_pairs);
  if (m1)
    std::printf("  M1: mean %.1f raw / %.1f distinct pairs (max raw %u), %u tests, detect mean %.1f us\n", sum_raw / n,
                sum_dist / n, max_raw, rows.empty() ? 0u : rows[0].m1.tests, sum_m1 / n);
  if (m2)
    std::printf("  M2: mean %.1f pairs (max %u), %u tests, detect mean %.1f us\n", sum_pm2 / n, max_pm2,
                rows.empty() ? 0u : rows[0].m2.tests, sum_m2 / n);
  double track_sum = 0, track_max = 0;
  for (const FrameRow& r : rows) track_sum += r.tracking_mean, track_max = std::max(track_max, r.tracking_max);
  std::printf("  refit (%s): mean %.1f us; tracking |dF| vs bind over surrounding-region vertices: mean %.4f, max %.4f\n",
              a.refit.c_str(), sum_refit / n, rows.empty() ? 0.0 : track_sum / n, track_max);
  std::vector<double> joint_errors;
  for (const FrameRow& r : rows) joint_errors.insert(joint_errors.end(), r.joint_error.begin(), r.joint_error.end());
  if (joints)
    std::printf("  joint refit vs vertex refit (pivot frame), centre distance / radius over spheres x frames: "
                "median %.2f %%, p95 %.2f %%, max %.2f %%\n",
                Percentile(joint_errors, 0.5), Percentile(joint_errors, 0.95), Percentile(joint_errors, 1.0));
  if (a.narrow_phase) {
    std::vector<double> us;
    uint64_t contacts = 0, frames_with_contacts = 0;
    for (const FrameRow& r : rows) {
      us.push_back(r.narrow_us);
      contacts += r.narrow.contacts;
      frames_with_contacts += r.narrow.contacts > 0;
    }
    std::sort(us.begin(), us.end());
    std::printf("  narrow phase: %llu contacts (triangle pairs) in %llu frames; median %.1f us, max %.1f us a frame\n",
                static_cast<unsigned long long>(contacts), static_cast<unsigned long long>(frames_with_contacts),
                us.empty() ? 0.0 : us[us.size() / 2], us.empty() ? 0.0 : us.back());
  }
  std::printf("  regions touching (frames):");
  if (region_frames.empty()) std::printf(" none");
  for (const auto& [p, c] : region_frames) std::printf(" R%d-R%d(%u)", p.first, p.second, c);
  std::printf("\n");

  if (!a.json.empty()) {
    nlohmann::json j;
    j["asset"] = a.asset;
    j["mesh"] = a.anim.mesh;
    j["method"] = a.method;
    j["refit"] = a.refit;
    j["repeat"] = std::max(1u, a.repeat);
    if (clip) {
      j["animation"] = {{"kind", "clip"}, {"name", clip->name}, {"duration_s", clip->duration_s}};
    } else {
      nlohmann::json keys = nlohmann::json::array();
      for (size_t k = 0; k < poses.size(); ++k)
        keys.push_back({{"name", poses[k].name},
                        {"frame", baker::MorphKeyFrame(uint32_t(k), frames, uint32_t(poses.size()))}});
      j["animation"] = {{"kind", "morph"}, {"poses_from", anim.poses_from}, {"keys", keys}};
    }
    auto row_json = [&](const FrameRow& r) {
      nlohmann::json regions = nlohmann::json::array();
      for (const auto& [ra, rb] : r.regions) regions.push_back("R" + std::to_string(ra) + "-R" + std::to_string(rb));
      nlohmann::json o = {{"label", r.label},
                          {"tests_m1", r.m1.tests},
                          {"pairs_m1_raw", r.m1.raw_pairs},
                          {"pairs_m1", r.m1.distinct_pairs},
                          {"tests_m2", r.m2.tests},
                          {"pairs_m2", r.m2.distinct_pairs},
                          {"refit_us", r.refit_us},
                          {"detect_m1_us", r.detect_m1_us},
                          {"detect_m2_us", r.detect_m2_us},
                          {"tracking_mean_abs_dF", r.tracking_mean},
                          {"tracking_max_abs_dF", r.tracking_max},
                          {"regions_touching", regions}};
      if (a.narrow_phase) {
        nlohmann::json cr = nlohmann::json::array();
        for (const auto& [ra, rb] : r.contact_regions) cr.push_back("R" + std::to_string(ra) + "-R" + std::to_string(rb));
        o["narrow_phase"] = {{"contacts", r.narrow.contacts},
                             {"candidate_pairs", r.narrow.candidate_pairs},
                             {"triangle_tests", r.narrow.triangle_tests},
                             {"degenerate_triangles", r.narrow.degenerate_triangles},
                             {"us", r.narrow_us},
                             {"regions_in_contact", cr}};
      }
      const auto* sr = view.asset->sphere_regions();
      nlohmann::json pairs = nlohmann::json::array();
      for (const runtime::Collision& c : r.pairs)
        pairs.push_back({{"a", c.a}, {"b", c.b}, {"region_a", sr ? int(sr->Get(c.a)) : -1},
                         {"region_b", sr ? int(sr->Get(c.b)) : -1}, {"depth", c.depth}});
      o["pairs"] = pairs;  // M2's when run, else M1's
      return o;
    };
    j["bind"] = row_json(bind);
    nlohmann::json fr = nlohmann::json::array();
    for (const FrameRow& r : rows) {
      nlohmann::json o = row_json(r);
      o["frame"] = r.frame;
      fr.push_back(o);
    }
    j["frames"] = fr;
    nlohmann::json rf = nlohmann::json::object();
    for (const auto& [p, c] : region_frames) rf["R" + std::to_string(p.first) + "-R" + std::to_string(p.second)] = c;
    j["summary"] = {{"frames", frames},
                    {"frames_with_collisions", frames_with_pairs},
                    {"mean_pairs_m1_raw", sum_raw / n},
                    {"mean_pairs_m1", sum_dist / n},
                    {"mean_pairs_m2", sum_pm2 / n},
                    {"mean_refit_us", sum_refit / n},
                    {"tracking_mean_abs_dF", rows.empty() ? 0.0 : track_sum / n},
                    {"tracking_max_abs_dF", track_max},
                    {"joint_vs_vertex_centre_error_pct",
                     joints ? nlohmann::json{{"median", Percentile(joint_errors, 0.5)},
                                             {"p95", Percentile(joint_errors, 0.95)},
                                             {"max", Percentile(joint_errors, 1.0)}}
                            : nlohmann::json()},
                    {"mean_detect_m1_us", sum_m1 / n},
                    {"mean_detect_m2_us", sum_m2 / n},
                    {"regions_touching_frames", rf}};
    const std::string text = j.dump(2) + "\n";
    if (auto s = baker::WriteFileAtomic(a.json, text); !s.ok()) return Fail(s.error());
    std::printf("wrote %s\n", a.json.c_str());
  }
  return 0;
}

}  // namespace

void RegisterPlay(CLI::App& app, Commands* commands) {
  auto args = std::make_shared<PlayArgs>();
  CLI::App* sub = app.add_subcommand(
      "play", "Play an animation (skinned clip or the paper's Bezier morph of key poses, §5.1/§6) and report "
              "sphere collisions per frame with M1 and M2 (§5.2)");
  AddAnimationOptions(sub, &args->asset, &args->rig, &args->anim);
  sub->add_option("--method", args->method, "Broad phase: m1 (chains), m2 (all spheres), both")
      ->check(CLI::IsMember({"m1", "m2", "both"}));
  sub->add_option("--refit", args->refit,
                  "Refit: paper (centre = mean pivot displacement), frame (pivot frame, default) or joints (linear "
                  "blend skinning of the centres from the joint matrices, JointRefitJob; reports its centre error "
                  "against the pivot-frame refit)")
      ->check(CLI::IsMember({"paper", "frame", "joints"}));
  sub->add_option("--repeat", args->repeat, "Runs per job per frame; timings are the minimum (default 5)");
  sub->add_option("--dump-frames", args->dump_frames,
                  "Folder to write each frame's deformed positions to (frame_NNNN.f32: #V×3 float32), for bench/; "
                  "with a v3 asset also its joint matrices (frame_NNNN.joints: #J×12 float32, JointRefitJob's layout)")
      ->check(CLI::ExistingDirectory);
  sub->add_option("--json", args->json, "Write the per-frame table and summary as JSON");
  sub->add_flag("--narrow-phase", args->narrow_phase,
                "Also find the exact triangle contacts between surrounding regions (runtime NarrowPhaseJob): "
                "contacts per frame in the table and the JSON");
  commands->handlers.emplace_back(sub, [args] { return RunPlay(*args); });
}

}  // namespace spherechain::cli
