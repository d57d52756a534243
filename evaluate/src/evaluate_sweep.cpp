// Evaluate()'s margin sweep (evaluate_internal.h): the frame's refit spheres under other contact margins, M1 and
// M2 each, with the narrow phase behind M2's pairs at each margin.
#include <chrono>

#include "evaluate_internal.h"

namespace spherechain::evaluate::detail {

namespace {

/// M1 (m = 0) or M2 (m = 1) on the session's current spheres with contact margin `margin` and fold margin
/// `fold` (−1: the asset's), into c.out_m1 / c.out_m2; its region and sphere pairs added to the sets.
runtime::Status Detect(Context& c, int m, float margin, float fold, std::set<RegionPair>* regions,
                       std::set<SpherePairKey>* pairs, uint32_t* count) {
  std::vector<runtime::Collision>& out = m == 0 ? c.out_m1 : c.out_m2;
  runtime::DetectJob det;
  det.model = &c.session.model();
  det.workspace = &c.session.workspace();
  det.method = m == 0 ? runtime::DetectMethod::kM1 : runtime::DetectMethod::kM2;
  det.margin = margin;
  det.fold_margin = fold;
  det.output = out.data();
  det.capacity = static_cast<uint32_t>(out.size());
  det.count = count;
  const runtime::Status s = det.Run();
  if (runtime::Failed(s)) return s;
  for (uint32_t i = 0; i < *count; ++i) {
    regions->insert(c.RegionPairOf(out[i].a, out[i].b));
    pairs->insert({out[i].a, out[i].b});
  }
  return s;
}

/// The narrow phase behind M2's pairs at `margin` (reach regions), one margin for every pair (as play
/// --narrow-behind: an asset's fold margin only keeps the spheres alone from crying wolf at a folding joint):
/// the region pairs of its contacts into `confirmed`, its time added to *us.
import::Status NarrowBehind(Context& c, const playback::SessionFrame& fr, float margin, uint32_t m2_count,
                            std::set<RegionPair>* confirmed, double* us) {
  if (c.session.model().fold_margin() >= 0.0f) {
    std::set<RegionPair> unused_regions;
    std::set<SpherePairKey> unused_pairs;
    if (runtime::Status st = Detect(c, 1, margin, margin, &unused_regions, &unused_pairs, &m2_count); runtime::Failed(st))
      return Fail(std::string("detect (sweep, one margin): ") + runtime::ToString(st));
  }
  uint32_t n = 0;
  runtime::NarrowPhaseJob job;
  job.model = &c.session.reach_model();
  job.workspace = &c.session.reach_workspace();
  job.positions = {fr.positions.data(), c.V, 12};
  job.sphere_pairs = c.out_m2.data();
  job.sphere_pair_count = m2_count;
  job.output = c.contacts.data();
  job.capacity = static_cast<uint32_t>(c.contacts.size());
  job.count = &n;
  const auto t0 = std::chrono::steady_clock::now();
  if (runtime::Status rs = job.Run(); runtime::Failed(rs))
    return Fail(std::string("narrow phase (sweep): ") + runtime::ToString(rs));
  *us += std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  for (uint32_t i = 0; i < n; ++i) confirmed->insert(c.RegionPairOf(c.contacts[i].sphere_a, c.contacts[i].sphere_b));
  return import::Ok{};
}

}  // namespace

import::Status SweepMargins(Context& c, const playback::SessionFrame& fr, const FrameEval& row, NearCache* cache,
                            std::vector<SweepPoint>* sweep) {
  const float* positions = fr.positions.data();
  for (SweepPoint& pt : *sweep) {
    const float mg = static_cast<float>(pt.margin_rel * c.height);
    std::set<RegionPair> regions[2];
    std::set<SpherePairKey> pairs[2];
    uint32_t counts[2] = {0, 0};
    for (int m = 0; m < 2; ++m)
      if (runtime::Status st = Detect(c, m, mg, -1.0f, &regions[m], &pairs[m], &counts[m]); runtime::Failed(st))
        return Fail(std::string("detect (sweep): ") + runtime::ToString(st));
    pt.found_m1 += CountIn(row.exact_regions, regions[0]);
    pt.found_m2 += CountIn(row.exact_regions, regions[1]);
    pt.sfound_m1 += CountIn(row.exact_spheres, pairs[0]);
    pt.sfound_m2 += CountIn(row.exact_spheres, pairs[1]);
    pt.pairs_m2 += pairs[1].size();
    std::set<RegionPair> confirmed;
    if (auto s = NarrowBehind(c, fr, mg, counts[1], &confirmed, &pt.narrow_us_m2); !s.ok()) return s;
    pt.confirmed_m2 += CountIn(row.exact_regions, confirmed);
    for (const SpherePairKey& k : pairs[1]) {
      auto f = IsImprecise(c, positions, row, cache, k);
      if (!f.ok()) return Fail(f.error());
      pt.imprecise_m2 += f.value();
    }
    bool any_false = false;
    for (int m = 0; m < 2; ++m)
      for (const RegionPair& rp : regions[m]) {
        auto f = IsFalseAlarm(c, positions, row, cache, rp);
        if (!f.ok()) return Fail(f.error());
        (m == 0 ? pt.false_m1 : pt.false_m2) += f.value();
        any_false |= f.value();
      }
    pt.false_frames += any_false;
  }
  return import::Ok{};
}

}  // namespace spherechain::evaluate::detail
