// Evaluate()'s stages (evaluate.h), shared by its translation units: what one run knows (Context), what one
// frame measured (FrameEval), one margin of the sweep (SweepPoint), and the stages themselves:
//   evaluate.cpp           options, the context, the frame loop over playback::Session's frames, the picture
//   evaluate_truth.cpp     the exact ground truth of a frame and the narrow phase against it
//   evaluate_proxy.cpp     the proxy's pairs: behind them, localised, false alarms, precision, gaps
//   evaluate_sweep.cpp     the contact margin sweep
//   evaluate_skin.cpp      skin contacts (the crease rule on the mesh alone) and the narrow phase under it
//   evaluate_coverage.cpp  the refit spheres' coverage per frame, the bind pose's φ1 / φ1' / φ2
//   evaluate_report.cpp    the totals, the table and the JSON document
// Not API: the library's own files only.
#pragma once

#include <cstdarg>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "spherechain/baker/contacts.h"
#include "spherechain/baker/coverage.h"
#include "spherechain/evaluate/evaluate.h"
#include "spherechain/playback/session.h"
#include "spherechain/runtime/crease.h"
#include "spherechain/runtime/narrow_phase.h"

namespace spherechain::evaluate::detail {

using Code = import::Error::Code;
using RegionPair = std::pair<int, int>;
using SpherePairKey = std::pair<uint32_t, uint32_t>;

inline import::Error Fail(Code code, std::string message) { return import::MakeError(code, std::move(message)); }
inline import::Error Fail(std::string message) { return import::MakeError(Code::kInternal, std::move(message)); }
inline const import::Error& Fail(const import::Error& error) { return error; }

/// printf into a string (the report's table).
[[gnu::format(printf, 2, 3)]] void Appendf(std::string* out, const char* format, ...);

/// Ratio with the vacuous case stated: nothing to find → 1.
inline double Ratio(double hit, double total) { return total > 0 ? hit / total : 1.0; }

template <class T>
size_t CountIn(const std::set<T>& of, const std::set<T>& in) {
  size_t n = 0;
  for (const T& x : of) n += in.count(x);
  return n;
}

inline baker::TrianglePair Ordered(uint32_t a, uint32_t b) { return {std::min(a, b), std::max(a, b)}; }

/// The refit spheres sticking out of the deformed skin by more than this share of the height are listed.
inline constexpr double kStickOut = 0.01;

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

/// What one frame measured.
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
  // The restricted path under the same rule (what play --narrow-behind runs): behind M2's pairs at the
  // session's behind margin and the proxy's folds (playback::BehindPairs), on the reach regions: its
  // contacts, those true, their (region pair)s among skin_regions, its time with M2 and the folds, the pairs.
  uint32_t skin_restricted = 0, skin_restricted_true = 0, restricted_pairs = 0, restricted_folds = 0;
  std::set<RegionPair> skin_restricted_regions;
  double skin_restricted_us = 0;
  std::vector<float> spheres;  // with a picture asked for: the refit spheres, x, y, z, r per sphere
};

/// What one Evaluate() knows before the first frame: the inputs, the session (the frame pipeline), the
/// lengths, the region and sphere maps, the bind data, the skin's crease graph and the consumer's buffers.
struct Context {
  Context(const runtime::AssetView& v, const import::Mesh& m, const playback::Animation& an,
          const EvaluateOptions& o, import::Context& l)
      : view(v), mesh(m), anim(an), a(o), log(l) {}
  /// Builds everything below the inputs. Errors: kFormat / kInternal from the session (the asset predates the
  /// narrow phase, a runtime Init), kInternal for the crease graph, the bind pose's exact intersections'.
  import::Status Init();

  const runtime::AssetView& view;
  const import::Mesh& mesh;
  const playback::Animation& anim;
  const EvaluateOptions& a;
  import::Context& log;
  playback::Session session;  // refit, M1, M2 and the narrow phase (asset exclusions); + reach regions
  uint32_t V = 0, T = 0;
  double height = 0, margin = 0, crease = 0;  // [Units: source]
  bool crease_job = false;   // the asset carries the crease rule (its narrow phase runs under it)
  double skin_crease = 0;    // the skin's definition's crease: --crease, or the asset's when larger
  std::vector<uint32_t> weld;       // the asset's weld ids
  std::vector<uint32_t> mesh_weld;  // the mesh's own (ComputeWeldIds)
  std::vector<int> region_map;      // --regions paper: asset region → paper region (empty: the asset's)
  std::map<int, std::vector<uint32_t>> region_triangles;  // by the region of their owning sphere
  std::vector<std::vector<uint32_t>> sphere_triangles;    // by their owning sphere
  std::vector<Eigen::Vector3d> bind_centroid;             // #T
  runtime::CreaseGraph skin_graph;
  runtime::CreaseScratch skin_scratch;
  std::set<baker::TrianglePair> skin_at_bind;  // skin contacts of the bind pose itself
  std::vector<runtime::TriangleContact> contacts;  // the output of the consumer's own narrow-phase jobs
  std::vector<runtime::Collision> out_m1, out_m2;  // the output of the sweep's detect jobs
  std::vector<runtime::Collision> behind;          // the restricted skin contacts' pairs (BehindPairs)

  const runtime::NarrowPhaseModel& narrow() const { return session.narrow_model(); }
  int SphereRegion(uint32_t s) const;
  RegionPair RegionPairOf(uint32_t sa, uint32_t sb) const {
    const int ra = SphereRegion(sa), rb = SphereRegion(sb);
    return RegionPair(std::min(ra, rb), std::max(ra, rb));
  }
  /// The crease rule on the mesh alone: triangles ta and tb are near on the welded bind surface.
  bool SkinNear(uint32_t ta, uint32_t tb);
};

/// Per frame: whether anything of a region pair / of a sphere pair's own surrounding regions comes within the
/// margin (false alarms and sphere-pair precision, shared by the frame's measures and its sweep).
struct NearCache {
  std::map<RegionPair, bool> regions;
  std::map<SpherePairKey, bool> pairs;
};
/// A reported region pair with no contact where nothing of the two regions comes within the margin.
import::Result<bool> IsFalseAlarm(const Context& c, const float* positions, const FrameEval& row, NearCache* cache,
                                  const RegionPair& rp);
/// A reported sphere pair with no contact whose own surrounding regions come nowhere within the margin.
import::Result<bool> IsImprecise(const Context& c, const float* positions, const FrameEval& row, NearCache* cache,
                                 const SpherePairKey& k);

// ---- the stages of one frame (in the order Evaluate runs them) -----------------------------------------
/// The refit spheres against the frame's deformed mesh (coverage on).
import::Status MeasureRefitCoverage(Context& c, const playback::SessionFrame& fr, FrameEval* row);
/// The session's M1 / M2 pairs as region and sphere pair sets.
void RecordProxyPairs(const Context& c, const playback::SessionFrame& fr, FrameEval* row);
/// The session's narrow phase: its contacts as triangle pairs (`narrow_pairs`) and region pairs.
void RecordNarrowPhase(Context& c, const playback::SessionFrame& fr, FrameEval* row,
                       std::set<baker::TrianglePair>* narrow_pairs);
/// The narrow phase restricted to M1's / M2's pairs, on the surrounding regions (`behind`) and on the reach
/// regions (`behind_reach`; their region pairs into row->confirmed_regions).
import::Status RunBehindTheProxy(Context& c, const playback::SessionFrame& fr, FrameEval* row,
                                 std::set<baker::TrianglePair> behind[2], std::set<baker::TrianglePair> behind_reach[2]);
/// The frame's exact self-intersections (timed into row->exact_ms).
import::Result<std::vector<baker::TrianglePair>> ExactTruth(const Context& c, const playback::SessionFrame& fr,
                                                            FrameEval* row);
/// Skin contacts (the crease rule on the mesh) among `exact`, and the narrow phase under the rule against them.
import::Status MeasureSkinContacts(Context& c, const playback::SessionFrame& fr,
                                   const std::vector<baker::TrianglePair>& exact,
                                   const std::set<baker::TrianglePair> behind_reach[2], FrameEval* row);
/// The exact intersections sorted into contacts, excluded, same sphere, unassigned; by bind distance; the
/// narrow phase's and the proxy's share of the contacts. The contacts into `contact_pairs`.
void ClassifyIntersections(const Context& c, const std::vector<baker::TrianglePair>& exact,
                           const std::set<baker::TrianglePair>& narrow_pairs, const std::set<baker::TrianglePair> behind[2],
                           const std::set<baker::TrianglePair> behind_reach[2], FrameEval* row,
                           std::vector<baker::TrianglePair>* contact_pairs);
/// Per contact, M1 / M2: does a reported pair of its two regions hold the point where its triangles meet.
import::Status LocaliseContacts(const Context& c, const playback::SessionFrame& fr,
                                const std::vector<baker::TrianglePair>& contact_pairs, FrameEval* row);
/// False alarms (region pairs) and imprecise M2 sphere pairs; the refit gaps of missed, false and imprecise pairs.
import::Status MeasureFalseAlarms(const Context& c, const playback::SessionFrame& fr, NearCache* cache, FrameEval* row);
/// The same refit spheres under the sweep's contact margins.
import::Status SweepMargins(Context& c, const playback::SessionFrame& fr, const FrameEval& row, NearCache* cache,
                            std::vector<SweepPoint>* sweep);

// ---- after the last frame ----------------------------------------------------------------------------
/// Bind-pose coverage and protrusion of φ1, φ1', φ2 (coverage on): {"coverage", "protrusion", "bind_pose"}.
import::Result<nlohmann::json> MeasureBindCoverage(const Context& c);
/// One frame's refit coverage as JSON (with the spheres sticking out by more than kStickOut).
nlohmann::json RefitCoverageJson(const baker::CoverageStats& c);
/// The refit spheres across the animation: the JSON summary (null without coverage) and its two lines.
nlohmann::json SummarizeRefitCoverage(const Context& c, const std::vector<FrameEval>& rows, std::string* lines);
/// The table, the JSON document and the recall figures of `rows` (and of the sweep) into `out`.
void Report(const Context& c, const std::vector<FrameEval>& rows, const std::vector<SweepPoint>& sweep,
            const nlohmann::json& bind_coverage, Evaluation* out);
/// The frame with the most missed contacts (by contacts, then by sphere pairs, then the most contacts; the
/// first of equals) — the picture's frame.
uint32_t WorstFrame(const std::vector<FrameEval>& rows);

}  // namespace spherechain::evaluate::detail
