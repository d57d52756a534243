#include "spherechain/evaluate/evaluate.h"
#include "spherechain/evaluate/check.h"  // BodyHeight

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <set>
#include <tuple>

#include <Eigen/Core>

#include "spherechain/baker/contacts.h"
#include "spherechain/baker/coverage.h"
#include "spherechain/playback/debug_export.h"
#include "spherechain/runtime/narrow_phase.h"
#include "spherechain/runtime/runtime.h"

namespace spherechain::evaluate {

namespace {

using Clock = std::chrono::steady_clock;
using Code = import::Error::Code;
using RegionPair = std::pair<int, int>;
using SpherePairKey = std::pair<uint32_t, uint32_t>;

import::Error Fail(Code code, std::string message) { return import::MakeError(code, std::move(message)); }
import::Error Fail(std::string message) { return import::MakeError(Code::kInternal, std::move(message)); }
const import::Error& Fail(const import::Error& error) { return error; }

/// printf into a string (the report's table).
[[gnu::format(printf, 2, 3)]] void Appendf(std::string* out, const char* format, ...) {
  va_list args;
  va_start(args, format);
  va_list again;
  va_copy(again, args);
  const int n = std::vsnprintf(nullptr, 0, format, args);
  va_end(args);
  if (n > 0) {
    const size_t at = out->size();
    out->resize(at + size_t(n) + 1);
    std::vsnprintf(out->data() + at, size_t(n) + 1, format, again);
    out->resize(at + size_t(n));
  }
  va_end(again);
}

/// One contact margin of --sweep-margin, summed over the frames.
struct SweepPoint {
  double margin_rel = 0;
  size_t found_m1 = 0, found_m2 = 0, sfound_m1 = 0, sfound_m2 = 0, false_m1 = 0, false_m2 = 0, false_frames = 0;
  size_t pairs_m2 = 0;  // sphere pairs M2 reported (the narrow phase's work)
  size_t imprecise_m2 = 0;  // of those, pairs whose own surrounding regions come nowhere within the margin
  // The narrow phase behind M2's pairs at this margin (reach regions): (frame, region pair)s of the truth it
  // finds a contact of, and its time (µs, summed over the frames; it is exact, so it reports no false alarm).
  size_t confirmed_m2 = 0;
  double narrow_us_m2 = 0;
};

std::string RegionName(const RegionPair& p) { return "R" + std::to_string(p.first) + "-R" + std::to_string(p.second); }

nlohmann::json RegionList(const std::set<RegionPair>& s) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& p : s) j.push_back(RegionName(p));
  return j;
}

std::string RegionText(const std::set<RegionPair>& s) {
  std::string t;
  for (const auto& p : s) t += (t.empty() ? "" : " ") + RegionName(p);
  return t.empty() ? "-" : t;
}

template <class T>
size_t CountIn(const std::set<T>& of, const std::set<T>& in) {
  size_t n = 0;
  for (const T& x : of) n += in.count(x);
  return n;
}

/// Ratio with the vacuous case stated: nothing to find → 1.
double Ratio(double hit, double total) { return total > 0 ? hit / total : 1.0; }

struct FrameEval {
  std::string label;
  // Ground truth.
  uint32_t contacts = 0, same_sphere = 0, excluded = 0, unassigned = 0, degenerate = 0;
  std::set<RegionPair> exact_regions;
  std::set<SpherePairKey> exact_spheres;
  // Intersecting triangle pairs per sphere pair: contacts, and those inside excluded pairs (what each
  // exclusion hides: JSON contact_sphere_pairs / excluded_sphere_pairs).
  std::map<SpherePairKey, uint32_t> contacts_by_pair, excluded_by_pair;
  // Narrow phase.
  runtime::NarrowPhaseStats narrow;
  uint32_t narrow_true = 0;  // contacts also in the ground truth
  std::set<RegionPair> narrow_regions;
  double narrow_us = 0, exact_ms = 0;
  // Proxy.
  std::set<RegionPair> m1_regions, m2_regions;
  std::set<SpherePairKey> m1_spheres, m2_spheres;
  std::set<RegionPair> false_m1, false_m2;
  uint32_t missed_contacts = 0;  // contacts in region pairs M2 did not report
  uint32_t missed_sphere_contacts = 0;  // contacts whose sphere pair M2 did not report
  // Per contact (triangle pair), M1 / M2: behind a reported pair (its owning spheres' pair reported: what
  // a NarrowPhaseJob restricted to DetectJob's pairs finds), and localised (the point where the two
  // triangles meet lies inside both spheres of some reported pair of the same two regions, radii grown by
  // the asset's margin: the pair found the contact's place, whichever spheres own its triangles).
  uint32_t behind[2] = {0, 0}, behind_reach[2] = {0, 0}, localised[2] = {0, 0};
  // The proxy and then the narrow phase behind its pairs (reach regions), M1 / M2: the region pairs of the
  // triangle contacts it found — what an engine running the spheres as its broad phase reports.
  std::set<RegionPair> confirmed_regions[2];
  // The asset-independent truth: intersecting triangle pairs whose bind-pose centroids lie at least --crease
  // apart, whatever the asset's exclusions and sphere ownership; and how many of them M2's sphere pairs and
  // region pairs cover (the pair of owning spheres reported, or their regions), or the asset excludes.
  uint32_t apart = 0, apart_sphere = 0, apart_region = 0, apart_excluded = 0, apart_same = 0;
  // Per sphere pair, for an artist (and a tuner) to see which spheres miss or cry wolf: the refit spheres'
  // gap ‖cA − cB‖ − rA − rB − 2·margin [Units: source] (> 0: apart even with the margin).
  std::map<SpherePairKey, float> missed_sphere_gaps;  // exact contact, M2 did not report the pair
  std::map<SpherePairKey, float> false_sphere_gaps;   // M2 reported, inside a false-alarm region pair
  // Imprecise sphere pairs: M2 pairs whose own surrounding regions (the triangles the runtime hands back for
  // them) come nowhere within the margin, whatever else their region pair touches in the frame.
  std::map<SpherePairKey, float> imprecise_gaps;
  // The refit spheres against this frame's deformed mesh (coverage.h; only with coverage on): how well
  // the refit keeps the bind fit's fill and how far the spheres stick out of the deformed skin.
  bool has_refit_coverage = false;
  baker::CoverageStats refit_coverage;
  // The skin's definition (runtime crease.h), on the mesh alone: intersecting triangle pairs (no shared welded
  // corner) that are not near on the welded bind surface. `skin_bind`: of those, pairs that intersect at
  // bind pose already (modelling artefacts, reported apart); `skin_hidden`: pairs the exclusion-based
  // definition above does not count (same owner, excluded pair, unassigned); the narrow phase under the
  // same rule (Exclusions::kCrease) against it; M1 / M2 region pairs and the restricted narrow phase behind
  // them (reach regions) against it.
  uint32_t skin = 0, skin_bind = 0, skin_hidden = 0, skin_behind_reach[2] = {0, 0};
  std::set<RegionPair> skin_regions;
  uint32_t skin_narrow = 0, skin_narrow_true = 0;
  runtime::NarrowPhaseStats skin_stats;
  double skin_us = 0;
};

/// [{"a", "b", "triangle_pairs"}]: sphere pairs with how many intersecting triangle pairs they own.
nlohmann::json PairCountList(const std::map<SpherePairKey, uint32_t>& counts) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& [k, n] : counts) j.push_back({{"a", k.first}, {"b", k.second}, {"triangle_pairs", n}});
  return j;
}

/// [{"a", "b", "gap_rel"}]: sphere pairs with their refit gap as a fraction of the body height.
nlohmann::json SphereGapList(const std::map<SpherePairKey, float>& gaps, double height) {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& [k, g] : gaps) list.push_back({{"a", k.first}, {"b", k.second}, {"gap_rel", g / height}});
  return list;
}

/// The exact-predicate coverage measure of one sphere set (bind pose).
nlohmann::json CoverageJson(const baker::CoverageStats& c) {
  return {{"coverage", c.coverage},       {"protrusion", c.protrusion},       {"outside_p95_rel", c.outside_p95_rel},
          {"outside_max_rel", c.outside_max_rel}, {"voxel_size", c.voxel_size}, {"voxels_undecided", c.voxels_undecided},
          {"skin_outside_p50_rel", c.skin_outside_p50_rel}, {"skin_outside_p95_rel", c.skin_outside_p95_rel},
          {"skin_outside_max_rel", c.skin_outside_max_rel}, {"skin_within_share", c.skin_within_share}};
}

}  // namespace

import::Status ParseSweepMargins(const std::string& text, std::vector<double>* out) {
  out->clear();
  if (text.empty()) return import::Ok{};
  if (text == "auto") {
    out->assign(std::begin(kDefaultSweepMargins), std::end(kDefaultSweepMargins));
    return import::Ok{};
  }
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, comma - start);
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || end != item.c_str() + item.size() || !(v >= 0.0 && v <= 0.1))
      return Fail(Code::kConfig, "--sweep-margin: '" + item + "' is not a margin in [0, 0.1] (a fraction of the body height)");
    out->push_back(v);
    start = comma + 1;
  }
  std::sort(out->begin(), out->end());
  out->erase(std::unique(out->begin(), out->end()), out->end());
  return import::Ok{};
}

import::Result<Evaluation> Evaluate(const runtime::AssetView& view, const import::Mesh& mesh,
                                    const playback::Animation& anim, const EvaluateOptions& a, import::Context* log_in) {
  // ---- options ------------------------------------------------------------------------------------
  if (!(a.margin_rel >= 0.0 && a.margin_rel < 1.0))
    return Fail(Code::kConfig, "--margin must be in [0, 1) (a fraction of the body height)");
  if (!(a.crease_rel >= 0.0 && a.crease_rel <= 1.0))
    return Fail(Code::kConfig, "--crease must be in [0, 1] (a fraction of the body height)");
  if (a.refit != "paper" && a.refit != "frame" && a.refit != "joints")
    return Fail(Code::kConfig, "--refit '" + a.refit + "': expected paper, frame or joints");
  if (!view.valid()) return Fail(Code::kConfig, "'" + a.asset_name + "' is not a loaded asset");
  std::vector<SweepPoint> sweep;
  for (double m : a.sweep_margins_rel) {
    if (!(m >= 0.0 && m <= 0.1))
      return Fail(Code::kConfig, "--sweep-margin: " + std::to_string(m) + " is not a margin in [0, 0.1] (a fraction of the body height)");
    sweep.push_back({m});
  }
  import::Context no_log;
  import::Context& log = log_in ? *log_in : no_log;
  std::string text;  // the table, Evaluation::text
  Evaluation result;

  runtime::Model model;
  runtime::Workspace ws;
  if (runtime::Status s = model.Init(view); runtime::Failed(s) || runtime::Failed(s = ws.Init(model)))
    return Fail("'" + a.asset_name + "': runtime Model / Workspace::Init: " + runtime::ToString(s));
  runtime::NarrowPhaseModel narrow, narrow_reach;  // surrounding regions (the truth's owners), reach regions
  runtime::NarrowPhaseWorkspace narrow_ws, narrow_reach_ws;
  if (runtime::Status s = narrow.Init(view); runtime::Failed(s) || runtime::Failed(s = narrow_ws.Init(narrow)))
    return Fail(s == runtime::Status::kErrorMissingField ? Code::kFormat : Code::kInternal,
                "'" + a.asset_name + "': narrow phase: " + runtime::ToString(s) +
                    (s == runtime::Status::kErrorMissingField ? " (baked before the narrow phase existed: re-bake it)" : ""));
  if (runtime::Status s = narrow_reach.Init(view, runtime::NarrowPhaseRegions::kReach);
      runtime::Failed(s) || runtime::Failed(s = narrow_reach_ws.Init(narrow_reach)))
    return Fail("'" + a.asset_name + "': narrow phase (reach regions): " + runtime::ToString(s));

  const uint32_t V = view.vertex_count, T = view.triangle_count;
  const bool crease_job = narrow.has_crease();
  std::vector<uint32_t> weld(V);
  for (uint32_t v = 0; v < V; ++v) weld[v] = narrow.weld_id(v);
  const auto* sphere_regions = view.asset->sphere_regions();
  // --regions paper: an extended-layout asset (head, hands, feet) scored on the paper's five regions — a hand
  // counts as its arm, a foot as its leg, the head as the torso — so its recall and false alarms compare
  // with a paper-layout asset's (finer regions make a region pair's "nothing within the margin" stricter).
  std::vector<int> region_map;
  if (a.paper_regions && view.asset->regions() && view.asset->biped()) {
    const auto* regions = view.asset->regions();
    const int trunk = int(regions->size()) - 1;
    for (int r = 0; r < int(regions->size()); ++r) {
      int q = r;
      if (r == trunk) q = 4;
      else if (r >= 4) q = regions->Get(r)->parent() >= 0 ? regions->Get(r)->parent() : 4;
      region_map.push_back(q);
    }
  }
  auto sphere_region = [&](uint32_t s) {
    const int r = sphere_regions ? int(sphere_regions->Get(s)) : -1;
    return r >= 0 && size_t(r) < region_map.size() ? region_map[size_t(r)] : r;
  };
  auto region_pair = [&](uint32_t sa, uint32_t sb) {
    const int ra = sphere_region(sa), rb = sphere_region(sb);
    return RegionPair(std::min(ra, rb), std::max(ra, rb));
  };
  // Triangles by the region of their owning sphere, and by the sphere (for the false-alarm distance tests).
  std::map<int, std::vector<uint32_t>> region_triangles;
  std::vector<std::vector<uint32_t>> sphere_triangles(view.asset->spheres()->size());
  for (uint32_t t = 0; t < T; ++t)
    if (const uint32_t s = narrow.triangle_sphere(t); s != 0xFFFF) {
      region_triangles[sphere_region(s)].push_back(t);
      if (s < sphere_triangles.size()) sphere_triangles[s].push_back(t);
    }

  const double height = BodyHeight(mesh), margin = a.margin_rel * height, crease = a.crease_rel * height;
  std::vector<Eigen::Vector3d> bind_centroid(T);
  for (uint32_t t = 0; t < T; ++t) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k)
      c += Eigen::Vector3d(mesh.positions[3 * mesh.indices[3 * t + k]], mesh.positions[3 * mesh.indices[3 * t + k] + 1],
                           mesh.positions[3 * mesh.indices[3 * t + k] + 2]);
    bind_centroid[t] = c / 3.0;
  }
  // The skin's definition on the mesh alone (its own weld ids and bind positions; no asset data): the
  // crease is --crease of the height, or the asset's when larger (a job may only widen the asset's).
  const double skin_crease = std::max(crease, crease_job ? double(narrow.crease()) : 0.0);
  const std::vector<uint32_t> mesh_weld = import::ComputeWeldIds(mesh.positions);
  runtime::CreaseGraph skin_graph;
  runtime::CreaseScratch skin_scratch;
  if (runtime::Status s = skin_graph.Init(mesh.positions.data(), V, mesh.indices.data(), T, mesh_weld.data(),
                                          float(skin_crease));
      runtime::Failed(s) || runtime::Failed(s = skin_scratch.Init(skin_graph)))
    return Fail(std::string("the crease rule's graph: ") + runtime::ToString(s));
  auto skin_near = [&](uint32_t ta, uint32_t tb) {
    const uint32_t* ia = &mesh.indices[3 * size_t{ta}];
    const uint32_t* ib = &mesh.indices[3 * size_t{tb}];
    return skin_scratch.Near(skin_graph, ia, ib, float(skin_crease));
  };
  std::set<baker::TrianglePair> skin_at_bind;  // skin contacts of the bind pose itself
  {
    auto bind = baker::ExactSelfIntersections(mesh.positions.data(), V, mesh.indices, mesh_weld);
    if (!bind.ok()) return Fail(import::Error{bind.error().code, "bind pose: " + bind.error().message});
    for (const baker::TrianglePair& p : bind.value())
      if (!skin_near(p.a, p.b)) skin_at_bind.insert(p);
  }
  const runtime::RefitMode mode = a.refit == "paper" ? runtime::RefitMode::kPaper : runtime::RefitMode::kPivotFrame;
  // --refit joints: the spheres a GPU-skinned game gets (JointRefitJob: linear blend skinning of the
  // centres by the frame's skinning matrices), judged against the same truth.
  const bool joint_refit = a.refit == "joints";
  if (joint_refit && !view.asset->sphere_joints())
    return Fail(Code::kConfig, "'" + a.asset_name + "' has no joint weights (schema v" + std::to_string(view.asset->schema_version()) +
                ", or baked from a mesh without a skin): --refit joints needs an asset baked from a rigged character");
  if (joint_refit && (!mesh.skin || view.asset->joint_count() != mesh.skin->joints.size()))
    return Fail(Code::kConfig, "'" + a.asset_name + "' was baked for " + std::to_string(view.asset->joint_count()) + " joints, '" +
                a.mesh_name + "' has " + std::to_string(mesh.skin ? mesh.skin->joints.size() : 0));
  std::vector<float> joint_matrices;

  std::vector<runtime::Collision> out_m1(runtime::DetectBound(view, runtime::DetectMethod::kM1)),
      out_m2(runtime::DetectBound(view, runtime::DetectMethod::kM2));
  std::vector<runtime::TriangleContact> contacts(1u << 20);
  std::vector<float> positions;
  playback::SkinningScratch scratch;
  std::vector<FrameEval> rows(anim.frames);
  // M1 (m = 0) or M2 (m = 1) on the workspace's current spheres with contact margin `margin` (−1: the
  // asset's); the reported region pairs and sphere pairs are added to the sets.
  uint32_t reported[2] = {0, 0};  // records of the last detect(m, −1, …): the asset's margin
  uint32_t last_reported[2] = {0, 0};  // records of the last detect(m, …), whatever its margin
  // `fold`: DetectJob::fold_margin (−1: the asset's, if any).
  auto detect = [&](int m, float margin, std::set<RegionPair>* regions, std::set<SpherePairKey>* pairs,
                    float fold = -1.0f) {
    auto& out = m == 0 ? out_m1 : out_m2;
    uint32_t n = 0;
    runtime::DetectJob det;
    det.model = &model;
    det.workspace = &ws;
    det.method = m == 0 ? runtime::DetectMethod::kM1 : runtime::DetectMethod::kM2;
    det.margin = margin;
    det.fold_margin = fold;
    det.output = out.data();
    det.capacity = static_cast<uint32_t>(out.size());
    det.count = &n;
    const runtime::Status s = det.Run();
    if (runtime::Failed(s)) return s;
    if (margin < 0.0f) reported[m] = n;
    last_reported[m] = n;
    for (uint32_t i = 0; i < n; ++i) {
      regions->insert(region_pair(out[i].a, out[i].b));
      pairs->insert({out[i].a, out[i].b});
    }
    return s;
  };
  const auto t_start = Clock::now();

  for (uint32_t f = 0; f < anim.frames; ++f) {
    FrameEval& row = rows[f];
    if (auto s = anim.Frame(mesh, f, &scratch, &positions, &row.label); !s.ok()) return Fail(s.error());
    // Proxy: refit, M1, M2.
    runtime::RefitJob refit;
    refit.model = &model;
    refit.workspace = &ws;
    refit.mode = mode;
    refit.positions = {positions.data(), V, 12};
    if (joint_refit) {
      joint_matrices.resize(scratch.matrices.size() * runtime::kJointMatrixFloats);
      for (size_t j = 0; j < scratch.matrices.size(); ++j)
        runtime::JointMatrixFromColumnMajor(scratch.matrices[j].data(), joint_matrices.data() + j * runtime::kJointMatrixFloats);
      runtime::JointRefitJob joints;
      joints.model = &model;
      joints.workspace = &ws;
      joints.joint_matrices = joint_matrices.data();
      joints.joint_count = uint32_t(scratch.matrices.size());
      if (runtime::Status s = joints.Run(); runtime::Failed(s))
        return Fail(std::string("joint refit: ") + runtime::ToString(s));
    } else if (runtime::Status s = refit.Run(); runtime::Failed(s)) {
      return Fail(std::string("refit: ") + runtime::ToString(s));
    }
    if (a.coverage) {
      const runtime::SphereArrays sp = ws.spheres();
      std::vector<baker::Ball> balls(sp.count);
      for (uint32_t s = 0; s < sp.count; ++s) {
        balls[s].center = Eigen::Vector3d(sp.x[s], sp.y[s], sp.z[s]);
        balls[s].radius = sp.r[s];
      }
      baker::CoverageOptions opts;
      opts.per_sphere = true;
      auto c = baker::MeasureCoverage(positions, mesh.indices, balls, opts);
      if (!c.ok()) return Fail(import::Error{c.error().code, "frame " + std::to_string(f) + ": refit coverage: " + c.error().message});
      row.refit_coverage = std::move(c.value());
      row.has_refit_coverage = true;
    }
    if (runtime::Status s = detect(0, -1.0f, &row.m1_regions, &row.m1_spheres); runtime::Failed(s))
      return Fail(std::string("detect: ") + runtime::ToString(s));
    if (runtime::Status s = detect(1, -1.0f, &row.m2_regions, &row.m2_spheres); runtime::Failed(s))
      return Fail(std::string("detect: ") + runtime::ToString(s));
    // Narrow phase.
    uint32_t n_contacts = 0;
    runtime::NarrowPhaseJob job;
    job.model = &narrow;
    job.workspace = &narrow_ws;
    job.positions = refit.positions;
    job.output = contacts.data();
    job.capacity = static_cast<uint32_t>(contacts.size());
    job.count = &n_contacts;
    job.stats = &row.narrow;
    const auto t0 = Clock::now();
    const runtime::Status ns = job.Run();
    row.narrow_us = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
    if (runtime::Failed(ns)) return Fail(std::string("narrow phase: ") + runtime::ToString(ns));
    if (runtime::IsTruncated(ns))
      log.Warn("frame " + std::to_string(f) + ": more than " + std::to_string(contacts.size()) +
               " narrow-phase contacts; precision counts only the first ones");
    std::set<baker::TrianglePair> narrow_pairs;
    for (uint32_t i = 0; i < n_contacts; ++i) {
      const auto& c = contacts[i];
      narrow_pairs.insert({std::min(c.triangle_a, c.triangle_b), std::max(c.triangle_a, c.triangle_b)});
      row.narrow_regions.insert(region_pair(c.sphere_a, c.sphere_b));
    }
    // The narrow phase behind the proxy: restricted to M1's / M2's sphere pairs (what an engine running the
    // spheres as its broad phase gets).
    // With the surrounding regions (a contact behind its two owners only), and with the reach regions (behind
    // every sphere that reaches its triangles: NarrowPhaseRegions::kReach).
    std::set<baker::TrianglePair> behind_pairs[2], behind_reach_pairs[2];
    for (int regions = 0; regions < 2; ++regions)
      for (int m = 0; m < 2; ++m) {
        runtime::NarrowPhaseJob restricted = job;
        if (regions == 1) restricted.model = &narrow_reach, restricted.workspace = &narrow_reach_ws;
        restricted.sphere_pairs = (m == 0 ? out_m1 : out_m2).data();
        restricted.sphere_pair_count = reported[m];
        restricted.stats = nullptr;
        uint32_t n = 0;
        restricted.count = &n;
        if (runtime::Status rs = restricted.Run(); runtime::Failed(rs))
          return Fail(std::string("narrow phase (behind the proxy): ") + runtime::ToString(rs));
        std::set<baker::TrianglePair>& into = regions == 0 ? behind_pairs[m] : behind_reach_pairs[m];
        for (uint32_t i = 0; i < n; ++i) {
          if (regions == 1) row.confirmed_regions[m].insert(region_pair(contacts[i].sphere_a, contacts[i].sphere_b));
          const baker::TrianglePair tp{std::min(contacts[i].triangle_a, contacts[i].triangle_b),
                                       std::max(contacts[i].triangle_a, contacts[i].triangle_b)};
          if (!into.insert(tp).second)
            return Fail("frame " + std::to_string(f) + ": the narrow phase reported triangles " + std::to_string(tp.a) +
                        " and " + std::to_string(tp.b) + " twice");
        }
      }
    // Ground truth.
    const auto t1 = Clock::now();
    auto exact = baker::ExactSelfIntersections(positions.data(), V, mesh.indices, weld, &row.degenerate);
    row.exact_ms = std::chrono::duration<double, std::milli>(Clock::now() - t1).count();
    if (!exact.ok()) return Fail(import::Error{exact.error().code, "frame " + std::to_string(f) + ": " + exact.error().message});
    // The skin's definition, and the narrow phase under it.
    std::set<baker::TrianglePair> skin_pairs;
    for (const baker::TrianglePair& p : exact.value()) {
      if (skin_near(p.a, p.b)) continue;
      skin_pairs.insert(p);
      const uint32_t sa = narrow.triangle_sphere(p.a), sb = narrow.triangle_sphere(p.b);
      row.skin_bind += skin_at_bind.count(p) > 0;
      row.skin_hidden += sa == 0xFFFF || sb == 0xFFFF || sa == sb || narrow.IsExcluded(sa, sb);
      if (sa != 0xFFFF && sb != 0xFFFF) row.skin_regions.insert(region_pair(sa, sb));
      for (int m = 0; m < 2; ++m) row.skin_behind_reach[m] += behind_reach_pairs[m].count(p) > 0;
    }
    row.skin = static_cast<uint32_t>(skin_pairs.size());
    if (crease_job) {
      runtime::NarrowPhaseJob skin_job;
      skin_job.model = &narrow;
      skin_job.workspace = &narrow_ws;
      skin_job.positions = refit.positions;
      skin_job.exclusions = runtime::Exclusions::kCrease;
      skin_job.crease = float(skin_crease);
      skin_job.output = contacts.data();
      skin_job.capacity = static_cast<uint32_t>(contacts.size());
      uint32_t n = 0;
      skin_job.count = &n;
      skin_job.stats = &row.skin_stats;
      const auto ts = Clock::now();
      const runtime::Status ks = skin_job.Run();
      row.skin_us = std::chrono::duration<double, std::micro>(Clock::now() - ts).count();
      if (runtime::Failed(ks)) return Fail(std::string("narrow phase (crease rule): ") + runtime::ToString(ks));
      row.skin_narrow = row.skin_stats.contacts;
      for (uint32_t i = 0; i < n; ++i)
        row.skin_narrow_true += skin_pairs.count({std::min(contacts[i].triangle_a, contacts[i].triangle_b),
                                                  std::max(contacts[i].triangle_a, contacts[i].triangle_b)}) > 0;
    }
    std::vector<baker::TrianglePair> contact_pairs;  // this frame's contacts
    for (const baker::TrianglePair& p : exact.value()) {
      const uint32_t sa = narrow.triangle_sphere(p.a), sb = narrow.triangle_sphere(p.b);
      if ((bind_centroid[p.a] - bind_centroid[p.b]).norm() >= crease) {
        ++row.apart;
        if (sa == 0xFFFF || sb == 0xFFFF) {
        } else if (sa == sb) {
          ++row.apart_same;
        } else {
          row.apart_excluded += narrow.IsExcluded(sa, sb);
          row.apart_sphere += row.m2_spheres.count({std::min(sa, sb), std::max(sa, sb)}) > 0;
          row.apart_region += row.m2_regions.count(region_pair(sa, sb)) > 0;
        }
      }
      if (sa == 0xFFFF || sb == 0xFFFF) {
        ++row.unassigned;
      } else if (sa == sb) {
        ++row.same_sphere;
      } else if (narrow.IsExcluded(sa, sb)) {
        ++row.excluded;
        ++row.excluded_by_pair[{std::min(sa, sb), std::max(sa, sb)}];
      } else {
        ++row.contacts;
        const SpherePairKey key{std::min(sa, sb), std::max(sa, sb)};
        const RegionPair rp = region_pair(sa, sb);
        row.exact_spheres.insert(key);
        ++row.contacts_by_pair[key];
        row.exact_regions.insert(rp);
        row.narrow_true += narrow_pairs.count(p);
        row.missed_contacts += !row.m2_regions.count(rp);
        row.missed_sphere_contacts += !row.m2_spheres.count(key);
        for (int m = 0; m < 2; ++m)
          row.behind[m] += behind_pairs[m].count(p) > 0, row.behind_reach[m] += behind_reach_pairs[m].count(p) > 0;
        contact_pairs.push_back(p);
      }
    }
    // Where each contact lies, against the reported pairs of its two regions.
    if (!contact_pairs.empty()) {
      auto points = baker::ContactPoints(positions.data(), V, mesh.indices, contact_pairs);
      if (!points.ok()) return Fail(import::Error{points.error().code, "frame " + std::to_string(f) + ": " + points.error().message});
      const runtime::SphereArrays sp = ws.spheres();
      const float grow = model.contact_margin();
      auto inside = [&](uint32_t s, const Eigen::Vector3d& x) {
        const double dx = x.x() - sp.x[s], dy = x.y() - sp.y[s], dz = x.z() - sp.z[s];
        return std::sqrt(dx * dx + dy * dy + dz * dz) <= double(sp.r[s]) + grow;
      };
      for (size_t i = 0; i < contact_pairs.size(); ++i) {
        const int ra = sphere_region(narrow.triangle_sphere(contact_pairs[i].a));
        const int rb = sphere_region(narrow.triangle_sphere(contact_pairs[i].b));
        const Eigen::Vector3d& x = points.value()[i];
        for (int m = 0; m < 2; ++m)
          for (const SpherePairKey& k : m == 0 ? row.m1_spheres : row.m2_spheres) {
            const int ka = sphere_region(k.first), kb = sphere_region(k.second);
            if (((ka == ra && kb == rb) || (ka == rb && kb == ra)) && inside(k.first, x) && inside(k.second, x)) {
              ++row.localised[m];
              break;
            }
          }
      }
    }
    // False alarms: region pairs the proxy reports with no contact, where nothing comes within the margin.
    std::map<RegionPair, bool> near_cache;  // per frame: does anything of the pair come within the margin
    auto is_false = [&](const RegionPair& rp) -> import::Result<bool> {
      if (row.exact_regions.count(rp)) return false;
      if (auto it = near_cache.find(rp); it != near_cache.end()) return !it->second;
      auto near = baker::AnyTrianglesWithin(
          positions.data(), V, mesh.indices, weld, region_triangles[rp.first], region_triangles[rp.second], margin,
          [&](uint32_t s, uint32_t t) {
            const uint32_t sa = narrow.triangle_sphere(s), sb = narrow.triangle_sphere(t);
            return sa != sb && !narrow.IsExcluded(sa, sb);
          });
      if (!near.ok()) return near.error();
      near_cache[rp] = near.value();
      return !near.value();
    };
    std::set<RegionPair> reported = row.m1_regions;
    reported.insert(row.m2_regions.begin(), row.m2_regions.end());
    for (const RegionPair& rp : reported) {
      auto f = is_false(rp);
      if (!f.ok()) return Fail(f.error());
      if (!f.value()) continue;
      if (row.m1_regions.count(rp)) row.false_m1.insert(rp);
      if (row.m2_regions.count(rp)) row.false_m2.insert(rp);
    }
    // Sphere-pair precision: does anything of the two spheres' own surrounding regions come within the margin.
    std::map<SpherePairKey, bool> pair_near;  // per frame
    auto is_imprecise = [&](const SpherePairKey& k) -> import::Result<bool> {
      if (row.exact_spheres.count(k)) return false;
      if (auto it = pair_near.find(k); it != pair_near.end()) return !it->second;
      auto near = baker::AnyTrianglesWithin(positions.data(), V, mesh.indices, weld, sphere_triangles[k.first],
                                            sphere_triangles[k.second], margin);
      if (!near.ok()) return near.error();
      pair_near[k] = near.value();
      return !near.value();
    };
    std::set<SpherePairKey> imprecise;
    for (const SpherePairKey& k : row.m2_spheres) {
      auto f = is_imprecise(k);
      if (!f.ok()) return Fail(f.error());
      if (f.value()) imprecise.insert(k);
    }
    // The same refit spheres under other contact margins.
    for (SweepPoint& pt : sweep) {
      std::set<RegionPair> regions[2];
      std::set<SpherePairKey> pairs[2];
      for (int m = 0; m < 2; ++m)
        if (runtime::Status st = detect(m, static_cast<float>(pt.margin_rel * height), &regions[m], &pairs[m]);
            runtime::Failed(st))
          return Fail(std::string("detect (sweep): ") + runtime::ToString(st));
      pt.found_m1 += CountIn(row.exact_regions, regions[0]);
      pt.found_m2 += CountIn(row.exact_regions, regions[1]);
      pt.sfound_m1 += CountIn(row.exact_spheres, pairs[0]);
      pt.sfound_m2 += CountIn(row.exact_spheres, pairs[1]);
      pt.pairs_m2 += pairs[1].size();
      {  // the narrow phase behind M2's pairs at this margin
        // One margin for every pair in front of the exact narrow phase (as play --narrow-behind): an asset's
        // fold margin only keeps the spheres alone from crying wolf at a folding joint.
        if (model.fold_margin() >= 0.0f) {
          std::set<RegionPair> unused_regions;
          std::set<SpherePairKey> unused_pairs;
          const float mg = static_cast<float>(pt.margin_rel * height);
          if (runtime::Status st = detect(1, mg, &unused_regions, &unused_pairs, mg); runtime::Failed(st))
            return Fail(std::string("detect (sweep, one margin): ") + runtime::ToString(st));
        }
        runtime::NarrowPhaseJob restricted = job;  // this frame's positions and output buffer
        restricted.model = &narrow_reach, restricted.workspace = &narrow_reach_ws, restricted.stats = nullptr;
        restricted.sphere_pairs = out_m2.data();
        restricted.sphere_pair_count = last_reported[1];
        uint32_t n = 0;
        restricted.count = &n;
        const auto t_narrow = Clock::now();
        if (runtime::Status rs = restricted.Run(); runtime::Failed(rs))
          return Fail(std::string("narrow phase (sweep): ") + runtime::ToString(rs));
        pt.narrow_us_m2 += std::chrono::duration<double, std::micro>(Clock::now() - t_narrow).count();
        std::set<RegionPair> confirmed;
        for (uint32_t i = 0; i < n; ++i) confirmed.insert(region_pair(contacts[i].sphere_a, contacts[i].sphere_b));
        pt.confirmed_m2 += CountIn(row.exact_regions, confirmed);
      }
      for (const SpherePairKey& k : pairs[1]) {
        auto f = is_imprecise(k);
        if (!f.ok()) return Fail(f.error());
        pt.imprecise_m2 += f.value();
      }
      bool any_false = false;
      for (int m = 0; m < 2; ++m)
        for (const RegionPair& rp : regions[m]) {
          auto f = is_false(rp);
          if (!f.ok()) return Fail(f.error());
          (m == 0 ? pt.false_m1 : pt.false_m2) += f.value();
          any_false |= f.value();
        }
      pt.false_frames += any_false;
    }
    {
      const runtime::SphereArrays sp = ws.spheres();
      const float m = model.contact_margin();
      auto gap = [&](SpherePairKey k) {
        const float dx = sp.x[k.first] - sp.x[k.second], dy = sp.y[k.first] - sp.y[k.second],
                    dz = sp.z[k.first] - sp.z[k.second];
        return std::sqrt(dx * dx + dy * dy + dz * dz) - sp.r[k.first] - sp.r[k.second] - 2 * m;
      };
      for (const SpherePairKey& k : row.exact_spheres)
        if (!row.m2_spheres.count(k)) row.missed_sphere_gaps[k] = gap(k);
      for (const SpherePairKey& k : row.m2_spheres)
        if (row.false_m2.count(region_pair(k.first, k.second))) row.false_sphere_gaps[k] = gap(k);
      for (const SpherePairKey& k : imprecise) row.imprecise_gaps[k] = gap(k);
    }
    if (a.progress) a.progress(f + 1, anim.frames, std::chrono::duration<double>(Clock::now() - t_start).count());
  }

  // ---- bind-pose coverage and protrusion of φ1, φ1', φ2 ------------------------------------------------
  nlohmann::json coverage = nlohmann::json::object(), protrusion = nlohmann::json::object(),
                 coverage_detail = nlohmann::json::object();
  if (a.coverage) {
    const std::pair<const char*, const flatbuffers::Vector<const schema::Sphere*>*> sets[3] = {
        {"phi1", view.asset->spheres_phi1()}, {"phi1_adjusted", view.asset->spheres()}, {"phi2", view.asset->spheres_phi2()}};
    for (const auto& [name, list] : sets) {
      if (!list) continue;
      std::vector<baker::Ball> spheres;
      for (const schema::Sphere* s : *list) {
        baker::Ball b;
        b.center = Eigen::Vector3d(s->center().x(), s->center().y(), s->center().z());
        b.radius = s->radius();
        spheres.push_back(b);
      }
      auto c = baker::MeasureCoverage(mesh.positions, mesh.indices, spheres);
      if (!c.ok()) return Fail(c.error());
      coverage[name] = c->coverage;
      protrusion[name] = c->protrusion;
      coverage_detail[name] = CoverageJson(c.value());
    }
  }

  // ---- summary -------------------------------------------------------------------------------------
  size_t exact_regions = 0, found_m1 = 0, found_m2 = 0, exact_spheres = 0, sfound_m1 = 0, sfound_m2 = 0;
  size_t false_m1 = 0, false_m2 = 0, gt = 0, narrow_total = 0, narrow_true = 0, excluded = 0, same = 0, unassigned = 0;
  nlohmann::json false_frames = nlohmann::json::array();
  size_t imprecise_m2 = 0, reported_m2 = 0, behind[2] = {0, 0}, behind_reach[2] = {0, 0}, localised[2] = {0, 0};
  size_t apart = 0, apart_sphere = 0, apart_region = 0, apart_excluded = 0, apart_same = 0;
  size_t confirmed_found[2] = {0, 0}, confirmed_false[2] = {0, 0}, confirmed_false_frames = 0;
  std::vector<double> narrow_us;
  double exact_ms = 0;
  uint32_t worst = 0;
  // The skin's definition (crease rule), summed over the frames.
  size_t skin = 0, skin_bind = 0, skin_hidden = 0, skin_behind_reach[2] = {0, 0}, skin_regions = 0;
  size_t skin_found[2] = {0, 0}, skin_narrow = 0, skin_narrow_true = 0, skin_folds = 0;
  std::vector<double> skin_us;
  for (uint32_t f = 0; f < anim.frames; ++f) {
    const FrameEval& r = rows[f];
    exact_regions += r.exact_regions.size();
    found_m1 += CountIn(r.exact_regions, r.m1_regions);
    found_m2 += CountIn(r.exact_regions, r.m2_regions);
    exact_spheres += r.exact_spheres.size();
    sfound_m1 += CountIn(r.exact_spheres, r.m1_spheres);
    sfound_m2 += CountIn(r.exact_spheres, r.m2_spheres);
    for (int m = 0; m < 2; ++m)
      behind[m] += r.behind[m], behind_reach[m] += r.behind_reach[m], localised[m] += r.localised[m];
    bool confirmed_false_frame = false;
    for (int m = 0; m < 2; ++m) {
      confirmed_found[m] += CountIn(r.exact_regions, r.confirmed_regions[m]);
      const size_t wrong = r.confirmed_regions[m].size() - CountIn(r.confirmed_regions[m], r.exact_regions);
      confirmed_false[m] += wrong;
      confirmed_false_frame |= wrong > 0;
    }
    confirmed_false_frames += confirmed_false_frame;
    false_m1 += r.false_m1.size();
    false_m2 += r.false_m2.size();
    if (!r.false_m1.empty() || !r.false_m2.empty()) false_frames.push_back(f);
    imprecise_m2 += r.imprecise_gaps.size();
    apart += r.apart, apart_sphere += r.apart_sphere, apart_region += r.apart_region;
    apart_excluded += r.apart_excluded, apart_same += r.apart_same;
    skin += r.skin, skin_bind += r.skin_bind, skin_hidden += r.skin_hidden, skin_regions += r.skin_regions.size();
    for (int m = 0; m < 2; ++m) skin_behind_reach[m] += r.skin_behind_reach[m];
    skin_found[0] += CountIn(r.skin_regions, r.m1_regions), skin_found[1] += CountIn(r.skin_regions, r.m2_regions);
    skin_narrow += r.skin_narrow, skin_narrow_true += r.skin_narrow_true, skin_folds += r.skin_stats.crease_folds;
    if (crease_job) skin_us.push_back(r.skin_us);
    reported_m2 += r.m2_spheres.size();
    gt += r.contacts;
    narrow_total += r.narrow.contacts;
    narrow_true += r.narrow_true;
    excluded += r.excluded;
    same += r.same_sphere;
    unassigned += r.unassigned;
    narrow_us.push_back(r.narrow_us);
    exact_ms += r.exact_ms;
    const auto misses = [](const FrameEval& x) { return std::pair(x.missed_contacts, x.missed_sphere_contacts); };
    if (misses(r) > misses(rows[worst])) worst = f;
  }
  std::sort(narrow_us.begin(), narrow_us.end());
  const double recall_m1 = Ratio(double(found_m1), double(exact_regions)), recall_m2 = Ratio(double(found_m2), double(exact_regions));
  const double srecall_m1 = Ratio(double(sfound_m1), double(exact_spheres)), srecall_m2 = Ratio(double(sfound_m2), double(exact_spheres));
  const double n_recall = Ratio(double(narrow_true), double(gt)), n_precision = Ratio(double(narrow_true), double(narrow_total));

  // The refit spheres across the animation: per-frame coverage / protrusion, and the spheres that stick
  // out of the deformed skin by more than kStickOut of the height (the refit's errors, which cry wolf).
  constexpr double kStickOut = 0.01;
  nlohmann::json refit_summary;
  std::string refit_line, stick_line;
  {
    std::vector<double> cov, prot, p95, skin95;
    double out_max = 0;
    std::map<uint32_t, std::pair<uint32_t, double>> stick;  // sphere -> (frames, max)
    for (const FrameEval& r : rows) {
      if (!r.has_refit_coverage) continue;
      cov.push_back(r.refit_coverage.coverage);
      prot.push_back(r.refit_coverage.protrusion);
      p95.push_back(r.refit_coverage.outside_p95_rel);
      skin95.push_back(r.refit_coverage.skin_outside_p95_rel);
      out_max = std::max(out_max, r.refit_coverage.outside_max_rel);
      for (uint32_t s = 0; s < r.refit_coverage.sphere_outside_max_rel.size(); ++s)
        if (double o = r.refit_coverage.sphere_outside_max_rel[s]; o > kStickOut) {
          auto& e = stick[s];
          ++e.first;
          e.second = std::max(e.second, o);
        }
    }
    if (!cov.empty()) {
      auto median = [](std::vector<double> v) { std::sort(v.begin(), v.end()); return v[v.size() / 2]; };
      std::vector<std::pair<uint32_t, std::pair<uint32_t, double>>> worst_spheres(stick.begin(), stick.end());
      std::sort(worst_spheres.begin(), worst_spheres.end(),
                [](const auto& x, const auto& y) { return std::tie(y.second.first, y.second.second, x.first) < std::tie(x.second.first, x.second.second, y.first); });
      nlohmann::json sj = nlohmann::json::array();
      for (const auto& [sphere, e] : worst_spheres)
        sj.push_back({{"sphere", sphere}, {"region", sphere_region(sphere)}, {"frames", e.first}, {"outside_max_rel", e.second}});
      refit_summary = {{"coverage_median", median(cov)}, {"coverage_min", *std::min_element(cov.begin(), cov.end())},
                       {"protrusion_median", median(prot)}, {"protrusion_max", *std::max_element(prot.begin(), prot.end())},
                       {"outside_p95_rel_median", median(p95)}, {"outside_p95_rel_max", *std::max_element(p95.begin(), p95.end())},
                       {"outside_max_rel", out_max}, {"skin_outside_p95_rel_median", median(skin95)},
                       {"skin_outside_p95_rel_max", *std::max_element(skin95.begin(), skin95.end())},
                       {"stick_out_rel", kStickOut}, {"spheres_sticking_out", sj}};
      char buf[512];
      std::snprintf(buf, sizeof buf,
                    "refit spheres on the deformed mesh: coverage median %.1f %% (min %.1f %%), protrusion median %.1f %% "
                    "(max %.1f %%), outside p95 median %.2f %% (max %.2f %%), max %.2f %% of height; skin outside the "
                    "spheres p95 median %.2f %% of height\n",
                    100 * median(cov), 100 * refit_summary["coverage_min"].get<double>(), 100 * median(prot),
                    100 * refit_summary["protrusion_max"].get<double>(), 100 * median(p95),
                    100 * refit_summary["outside_p95_rel_max"].get<double>(), 100 * out_max, 100 * median(skin95));
      refit_line = buf;
      std::snprintf(buf, sizeof buf, "spheres sticking out of the skin by > %.1f %% of height: %zu", 100 * kStickOut, worst_spheres.size());
      stick_line = buf;
      for (size_t i = 0; i < worst_spheres.size() && i < 6; ++i) {
        std::snprintf(buf, sizeof buf, "%s sphere %u (region %d) in %u frames, up to %.2f %%", i ? "," : ";", worst_spheres[i].first,
                      sphere_region(worst_spheres[i].first), worst_spheres[i].second.first, 100 * worst_spheres[i].second.second);
        stick_line += buf;
      }
      stick_line += "\n";
    }
  }

  Appendf(&text, "evaluate: %s + %s — %s, %u frames, %u spheres, %u triangles, body height %.4g, margin %.4g (%.2f %%)\n",
              a.asset_name.c_str(), a.mesh_name.c_str(), anim.Describe().c_str(), anim.frames, view.sphere_count, T, height, margin,
              100.0 * a.margin_rel);
  if (const std::string legend = playback::RegionLegendLine(view); !legend.empty()) Appendf(&text, "%s\n", legend.c_str());
  Appendf(&text, "\n%5s  %-26s %8s %8s %8s %8s  %-22s %-22s %-22s %s\n", "frame", "pose", "contacts", "narrow", "excluded",
              "same sph", "exact regions", "proxy M1", "proxy M2", "missed by M2 / false alarms");
  for (uint32_t f = 0; f < anim.frames; ++f) {
    const FrameEval& r = rows[f];
    std::set<RegionPair> missed;
    for (const RegionPair& p : r.exact_regions)
      if (!r.m2_regions.count(p)) missed.insert(p);
    std::set<RegionPair> falses = r.false_m1;
    falses.insert(r.false_m2.begin(), r.false_m2.end());
    Appendf(&text, "%5u  %-26s %8u %8u %8u %8u  %-22s %-22s %-22s %s / %s\n", f, r.label.c_str(), r.contacts, r.narrow.contacts,
                r.excluded, r.same_sphere, RegionText(r.exact_regions).c_str(), RegionText(r.m1_regions).c_str(),
                RegionText(r.m2_regions).c_str(), RegionText(missed).c_str(), RegionText(falses).c_str());
  }
  Appendf(&text, "\nground truth: %zu contacts (triangle pairs) in %zu (frame, region pair)s and %zu (frame, sphere pair)s; "
              "apart: %zu in excluded pairs, %zu inside one sphere's region, %zu with an unassigned triangle\n",
              gt, exact_regions, exact_spheres, excluded, same, unassigned);
  Appendf(&text, "proxy recall, region pairs: M1 %.1f %% (%zu/%zu), M2 %.1f %% (%zu/%zu); sphere pairs: M1 %.1f %%, M2 %.1f %%\n",
              100 * recall_m1, found_m1, exact_regions, 100 * recall_m2, found_m2, exact_regions, 100 * srecall_m1,
              100 * srecall_m2);
  Appendf(&text, "contacts behind the proxy's sphere pairs (found by the narrow phase restricted to them): reach regions "
              "M1 %.1f %%, M2 %.1f %%; surrounding regions M1 %.1f %%, M2 %.1f %%; localised (where the triangles meet "
              "lies within the margin of both spheres of a reported pair of their regions): M1 %.1f %%, M2 %.1f %%\n",
              100 * Ratio(double(behind_reach[0]), double(gt)), 100 * Ratio(double(behind_reach[1]), double(gt)),
              100 * Ratio(double(behind[0]), double(gt)), 100 * Ratio(double(behind[1]), double(gt)),
              100 * Ratio(double(localised[0]), double(gt)), 100 * Ratio(double(localised[1]), double(gt)));
  Appendf(&text, "proxy false alarms (nothing within the margin): M1 %zu, M2 %zu, in %zu frames\n", false_m1, false_m2,
              false_frames.size());
  Appendf(&text, "proxy, then the narrow phase behind its pairs (reach regions; the region pairs of the contacts it finds): "
              "region pairs M1 %.1f %% (%zu/%zu), M2 %.1f %% (%zu/%zu); region pairs with no exact contact: M1 %zu, M2 %zu, "
              "in %zu frames\n",
              100 * Ratio(double(confirmed_found[0]), double(exact_regions)), confirmed_found[0], exact_regions,
              100 * Ratio(double(confirmed_found[1]), double(exact_regions)), confirmed_found[1], exact_regions,
              confirmed_false[0], confirmed_false[1], confirmed_false_frames);
  const double sphere_precision_m2 = Ratio(double(reported_m2 - imprecise_m2), double(reported_m2));
  const double apart_recall_sphere = Ratio(double(apart_sphere), double(apart));
  const double apart_recall_region = Ratio(double(apart_region), double(apart));
  Appendf(&text, "contacts by bind distance (the asset-independent truth: intersecting triangles whose bind centroids lie "
              ">= %.3g %% of the height apart): %zu triangle pairs; covered by M2's sphere pairs %.1f %%, by its region "
              "pairs %.1f %%; in pairs the asset excludes %.1f %%, inside one sphere's region %.1f %%\n",
              100 * a.crease_rel, apart, 100 * apart_recall_sphere, 100 * apart_recall_region,
              100 * Ratio(double(apart_excluded), double(apart)) * (apart > 0),
              100 * Ratio(double(apart_same), double(apart)) * (apart > 0));
  std::sort(skin_us.begin(), skin_us.end());
  const double skin_recall = Ratio(double(skin_narrow_true), double(skin)),
               skin_precision = Ratio(double(skin_narrow_true), double(skin_narrow));
  Appendf(&text, "skin contacts (the definition: intersecting triangles not within %.3g %% of the height of each other "
              "along the welded bind surface nor within two triangle rings): %zu triangle pairs in %zu (frame, region "
              "pair)s, %zu of them intersecting at bind pose already; hidden by the exclusion-based count above %.1f %%; "
              "region pairs found by M1 %.1f %%, M2 %.1f %%; behind the proxy's pairs (reach regions) M1 %.1f %%, M2 %.1f %%\n",
              100 * skin_crease / height, skin, skin_regions, skin_bind, 100 * Ratio(double(skin_hidden), double(skin)) * (skin > 0),
              100 * Ratio(double(skin_found[0]), double(skin_regions)), 100 * Ratio(double(skin_found[1]), double(skin_regions)),
              100 * Ratio(double(skin_behind_reach[0]), double(skin)), 100 * Ratio(double(skin_behind_reach[1]), double(skin)));
  if (crease_job)
    Appendf(&text, "narrow phase, crease rule (every triangle pair): recall %.2f %% (%zu/%zu), precision %.2f %% (%zu/%zu), "
                "%zu intersecting pairs found near by the graph (a --crease wider than the asset's); median %.1f us, max %.1f us "
                "a frame\n",
                100 * skin_recall, skin_narrow_true, skin, 100 * skin_precision, skin_narrow_true, skin_narrow, skin_folds,
                skin_us.empty() ? 0.0 : skin_us[skin_us.size() / 2], skin_us.empty() ? 0.0 : skin_us.back());
  else
    Appendf(&text, "narrow phase, crease rule: the asset was baked without it (no Asset.crease): re-bake to run it\n");
  Appendf(&text, "sphere-pair precision M2 (reported pairs whose own surrounding regions come within the margin): "
              "%.1f %% (%zu/%zu)\n",
              100 * sphere_precision_m2, reported_m2 - imprecise_m2, reported_m2);
  Appendf(&text, "narrow phase: recall %.2f %% (%zu/%zu), precision %.2f %% (%zu/%zu); median %.1f us, max %.1f us a frame "
              "(exact ground truth: %.1f ms a frame)\n",
              100 * n_recall, narrow_true, gt, 100 * n_precision, narrow_true, narrow_total,
              narrow_us.empty() ? 0.0 : narrow_us[narrow_us.size() / 2], narrow_us.empty() ? 0.0 : narrow_us.back(),
              anim.frames ? exact_ms / anim.frames : 0.0);
  if (a.coverage)
    for (const char* name : {"phi1", "phi1_adjusted", "phi2"})
      if (coverage_detail.contains(name))
        Appendf(&text, "bind pose %-13s coverage %.1f %%, protrusion %.1f %% (outside: p95 %.2f %%, max %.2f %% of height); "
                    "skin outside the spheres: median %.2f %%, p95 %.2f %%, max %.2f %% of height, %.1f %% of its area "
                    "within %.1f %%\n",
                    name, 100 * coverage_detail[name]["coverage"].get<double>(),
                    100 * coverage_detail[name]["protrusion"].get<double>(),
                    100 * coverage_detail[name]["outside_p95_rel"].get<double>(),
                    100 * coverage_detail[name]["outside_max_rel"].get<double>(),
                    100 * coverage_detail[name]["skin_outside_p50_rel"].get<double>(),
                    100 * coverage_detail[name]["skin_outside_p95_rel"].get<double>(),
                    100 * coverage_detail[name]["skin_outside_max_rel"].get<double>(),
                    100 * coverage_detail[name]["skin_within_share"].get<double>(), 100 * baker::kSkinWithinRel);

  text += refit_line;
  text += stick_line;

  if (!sweep.empty()) {
    Appendf(&text, "\ncontact margin sweep (same refit spheres; the asset's margin is %.4g = %.2f %% of height):\n",
                double(model.contact_margin()), 100.0 * model.contact_margin() / height);
    Appendf(&text, "%10s %8s  %18s  %18s  %18s  %11s  %14s  %14s  %16s  %22s\n", "margin %h", "margin", "region recall M1",
                "region recall M2", "sphere recall M2", "false M1/M2", "false frames", "pairs/frame M2",
                "sphere precision", "M2 + narrow: recall, us");
    for (const SweepPoint& pt : sweep)
      Appendf(&text, "%10.2f %8.4g  %9.1f %% (%3zu)  %9.1f %% (%3zu)  %15.1f %%  %5zu/%-5zu  %6zu of %-4u  %14.1f  %14.1f %%  %9.1f %% %9.1f\n",
                  100 * pt.margin_rel, pt.margin_rel * height, 100 * Ratio(double(pt.found_m1), double(exact_regions)),
                  pt.found_m1, 100 * Ratio(double(pt.found_m2), double(exact_regions)), pt.found_m2,
                  100 * Ratio(double(pt.sfound_m2), double(exact_spheres)), pt.false_m1, pt.false_m2, pt.false_frames,
                  anim.frames, anim.frames ? double(pt.pairs_m2) / anim.frames : 0.0,
                  100 * Ratio(double(pt.pairs_m2 - pt.imprecise_m2), double(pt.pairs_m2)),
                  100 * Ratio(double(pt.confirmed_m2), double(exact_regions)),
                  anim.frames ? pt.narrow_us_m2 / anim.frames : 0.0);
  }

  // ---- outputs (nothing is written before every frame succeeded) ----------------------------------------
  if (!a.png_path.empty()) {
    const uint32_t f = worst;
    std::string label;
    if (auto s = anim.Frame(mesh, f, &scratch, &positions, &label); !s.ok()) return Fail(s.error());
    runtime::RefitJob refit;
    refit.model = &model;
    refit.workspace = &ws;
    refit.mode = mode;
    refit.positions = {positions.data(), V, 12};
    if (runtime::Failed(refit.Run())) return Fail("refit failed on the picture's frame");
    auto exact = baker::ExactSelfIntersections(positions.data(), V, mesh.indices, weld);
    if (!exact.ok()) return Fail(exact.error());
    std::vector<uint8_t> marks(T, 0);
    for (const baker::TrianglePair& p : exact.value()) {
      const uint32_t sa = narrow.triangle_sphere(p.a), sb = narrow.triangle_sphere(p.b);
      if (sa == 0xFFFF || sb == 0xFFFF || sa == sb || narrow.IsExcluded(sa, sb)) continue;
      const bool found = rows[f].m2_spheres.count({std::min(sa, sb), std::max(sa, sb)}) > 0;
      for (uint32_t t : {p.a, p.b}) marks[t] = std::max<uint8_t>(marks[t], found ? 2 : 1);
    }
    const runtime::SphereArrays sp = ws.spheres();
    std::vector<playback::FrameSphere> spheres;
    for (uint32_t s = 0; s < sp.count; ++s)
      spheres.push_back({{sp.x[s], sp.y[s], sp.z[s]}, sp.r[s],
                         playback::RegionColor(view, uint32_t(std::max(sphere_region(s), 0))), 0.35f});
    char caption[256];
    std::snprintf(caption, sizeof caption,
                  "frame %u (%s): %u contacts, %u missed by the proxy's sphere pairs (red), the rest found (amber); "
                  "refit spheres (M2)",
                  f, label.c_str(), rows[f].contacts, rows[f].missed_sphere_contacts);
    if (auto s = playback::SvgToPng(playback::RenderFrameSvg(mesh, view, positions.data(), spheres, marks, caption), a.png_path);
        !s.ok())
      return Fail(s.error());
    result.png_frame = int(f);
  }
  {
    nlohmann::json& j = result.report;
    j["asset"] = a.asset_name;
    if (view.asset->regions() && region_map.empty()) {  // schema v4: what R0..R(n-1) are
      nlohmann::json names = nlohmann::json::array();
      for (uint32_t r = 0; r < runtime::RegionCount(view); ++r) names.push_back(runtime::RegionName(view, r));
      j["regions"] = names;
    }
    if (!region_map.empty()) j["region_pairs_by"] = "paper";
    j["mesh"] = a.mesh_name;
    j["animation"] = anim.Describe();
    j["refit"] = a.refit;
    j["body_height"] = height;
    j["margin_rel"] = a.margin_rel;
    j["contact_margin"] = model.contact_margin();  // the asset's: what the proxy's spheres were grown by
    j["contact_margin_rel"] = double(model.contact_margin()) / height;
    nlohmann::json fr = nlohmann::json::array();
    for (uint32_t f = 0; f < anim.frames; ++f) {
      const FrameEval& r = rows[f];
      fr.push_back({{"frame", f},
                    {"label", r.label},
                    {"contacts", r.contacts},
                    {"excluded_intersections", r.excluded},
                    {"same_sphere_intersections", r.same_sphere},
                    {"unassigned_intersections", r.unassigned},
                    {"degenerate_triangles", r.degenerate},
                    {"exact_region_pairs", RegionList(r.exact_regions)},
                    {"narrow_region_pairs", RegionList(r.narrow_regions)},
                    {"proxy_region_pairs_m1", RegionList(r.m1_regions)},
                    {"proxy_region_pairs_m2", RegionList(r.m2_regions)},
                    {"then_narrow_region_pairs_m2", RegionList(r.confirmed_regions[1])},
                    {"false_alarms_m1", RegionList(r.false_m1)},
                    {"false_alarms_m2", RegionList(r.false_m2)},
                    {"exact_sphere_pairs", r.exact_spheres.size()},
                    {"missed_contacts_m2", r.missed_contacts},
                    {"contacts_behind_pairs_m2", r.behind[1]},
                    {"contacts_behind_reach_m2", r.behind_reach[1]},
                    {"contacts_localised_m2", r.localised[1]},
                    {"missed_sphere_pairs_m2", SphereGapList(r.missed_sphere_gaps, height)},
                    {"false_alarm_sphere_pairs_m2", SphereGapList(r.false_sphere_gaps, height)},
                    {"imprecise_sphere_pairs_m2", SphereGapList(r.imprecise_gaps, height)},
                    {"contact_sphere_pairs", PairCountList(r.contacts_by_pair)},
                    {"excluded_sphere_pairs", PairCountList(r.excluded_by_pair)},
                    {"contacts_by_bind_distance", {{"triangle_pairs", r.apart}, {"covered_by_sphere_pairs_m2", r.apart_sphere},
                                                   {"covered_by_region_pairs_m2", r.apart_region}}},
                    {"narrow", {{"contacts", r.narrow.contacts}, {"true_contacts", r.narrow_true},
                                {"candidate_pairs", r.narrow.candidate_pairs}, {"triangle_tests", r.narrow.triangle_tests},
                                {"us", r.narrow_us}}},
                    {"exact_ms", r.exact_ms}});
      if (r.has_refit_coverage) {
        nlohmann::json rc = CoverageJson(r.refit_coverage), out = nlohmann::json::array();
        for (uint32_t s = 0; s < r.refit_coverage.sphere_outside_max_rel.size(); ++s)
          if (r.refit_coverage.sphere_outside_max_rel[s] > kStickOut)
            out.push_back({{"sphere", s}, {"outside_max_rel", r.refit_coverage.sphere_outside_max_rel[s]}});
        rc["spheres_sticking_out"] = out;
        fr.back()["refit_coverage"] = rc;
      }
    }
    j["frames"] = fr;
    if (!sweep.empty()) {
      nlohmann::json sw = nlohmann::json::array();
      for (const SweepPoint& pt : sweep)
        sw.push_back({{"margin_rel", pt.margin_rel},
                      {"margin", pt.margin_rel * height},
                      {"recall_m1", Ratio(double(pt.found_m1), double(exact_regions))},
                      {"recall_m2", Ratio(double(pt.found_m2), double(exact_regions))},
                      {"sphere_recall_m1", Ratio(double(pt.sfound_m1), double(exact_spheres))},
                      {"sphere_recall_m2", Ratio(double(pt.sfound_m2), double(exact_spheres))},
                      {"false_alarms_m1", pt.false_m1},
                      {"false_alarms_m2", pt.false_m2},
                      {"false_alarm_frames", pt.false_frames},
                      {"sphere_pairs_per_frame_m2", anim.frames ? double(pt.pairs_m2) / anim.frames : 0.0},
                      {"sphere_precision_m2", Ratio(double(pt.pairs_m2 - pt.imprecise_m2), double(pt.pairs_m2))},
                      {"recall_m2_then_narrow", Ratio(double(pt.confirmed_m2), double(exact_regions))},
                      {"narrow_us_per_frame_m2", anim.frames ? pt.narrow_us_m2 / anim.frames : 0.0}});
      j["margin_sweep"] = sw;
    }
    j["summary"] = {
        {"frames", anim.frames},
        {"contacts", gt},
        {"excluded_intersections", excluded},
        {"same_sphere_intersections", same},
        {"exact_region_pairs", exact_regions},
        {"proxy", {{"recall_m1", recall_m1}, {"recall_m2", recall_m2}, {"sphere_recall_m1", srecall_m1},
                   {"sphere_recall_m2", srecall_m2}, {"false_alarms_m1", false_m1}, {"false_alarms_m2", false_m2},
                   {"false_alarm_frames", false_frames}, {"sphere_pairs_m2", reported_m2},
                   {"sphere_precision_m2", sphere_precision_m2},
                   {"contacts_behind_pairs_m1", Ratio(double(behind[0]), double(gt))},
                   {"contacts_behind_pairs_m2", Ratio(double(behind[1]), double(gt))},
                   {"contacts_behind_reach_m1", Ratio(double(behind_reach[0]), double(gt))},
                   {"contacts_behind_reach_m2", Ratio(double(behind_reach[1]), double(gt))},
                   {"contacts_localised_m1", Ratio(double(localised[0]), double(gt))},
                   {"contacts_localised_m2", Ratio(double(localised[1]), double(gt))}}},
        {"proxy_then_narrow", {{"recall_m1", Ratio(double(confirmed_found[0]), double(exact_regions))},
                               {"recall_m2", Ratio(double(confirmed_found[1]), double(exact_regions))},
                               {"wrong_region_pairs_m1", confirmed_false[0]},
                               {"wrong_region_pairs_m2", confirmed_false[1]},
                               {"wrong_frames", confirmed_false_frames}}},
        {"contacts_by_bind_distance", {{"crease_rel", a.crease_rel}, {"triangle_pairs", apart},
                                       {"covered_by_sphere_pairs_m2", apart_recall_sphere},
                                       {"covered_by_region_pairs_m2", apart_recall_region},
                                       {"in_excluded_pairs", apart_excluded}, {"inside_one_sphere", apart_same}}},
        {"skin_contacts",
         {{"crease", skin_crease}, {"crease_rel", skin_crease / height}, {"triangle_pairs", skin},
          {"region_pairs", skin_regions}, {"at_bind_pose", skin_bind}, {"hidden_by_exclusions", skin_hidden},
          {"region_recall_m1", Ratio(double(skin_found[0]), double(skin_regions))},
          {"region_recall_m2", Ratio(double(skin_found[1]), double(skin_regions))},
          {"behind_reach_m1", Ratio(double(skin_behind_reach[0]), double(skin))},
          {"behind_reach_m2", Ratio(double(skin_behind_reach[1]), double(skin))},
          {"narrow", crease_job ? nlohmann::json{{"recall", skin_recall}, {"precision", skin_precision},
                                                 {"contacts", skin_narrow}, {"folds", skin_folds},
                                                 {"median_us", skin_us.empty() ? 0.0 : skin_us[skin_us.size() / 2]},
                                                 {"max_us", skin_us.empty() ? 0.0 : skin_us.back()}}
                                : nlohmann::json(nullptr)}}},
        {"narrow", {{"recall", n_recall}, {"precision", n_precision}, {"contacts", narrow_total},
                    {"median_us", narrow_us.empty() ? 0.0 : narrow_us[narrow_us.size() / 2]},
                    {"max_us", narrow_us.empty() ? 0.0 : narrow_us.back()}}},
        {"coverage", coverage},
        {"protrusion", protrusion},
        {"bind_pose", coverage_detail}};
    if (!refit_summary.is_null()) j["summary"]["refit"] = refit_summary;
  }
  result.text = std::move(text);
  result.recall_m1 = recall_m1;
  result.recall_m2 = recall_m2;
  return result;
}


}  // namespace spherechain::evaluate
