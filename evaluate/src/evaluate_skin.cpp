// Evaluate()'s skin contacts (evaluate_internal.h): the skin's definition (runtime crease.h) on the mesh alone —
// intersecting triangles not near on the welded bind surface — and the narrow phase under the same rule.
#include <chrono>

#include "evaluate_internal.h"

namespace spherechain::evaluate::detail {

import::Status MeasureSkinContacts(Context& c, const playback::SessionFrame& fr,
                                   const std::vector<baker::TrianglePair>& exact,
                                   const std::set<baker::TrianglePair> behind_reach[2], FrameEval* row) {
  const runtime::NarrowPhaseModel& narrow = c.narrow();
  std::set<baker::TrianglePair> skin_pairs;
  for (const baker::TrianglePair& p : exact) {
    if (c.SkinNear(p.a, p.b)) continue;
    skin_pairs.insert(p);
    const uint32_t sa = narrow.triangle_sphere(p.a), sb = narrow.triangle_sphere(p.b);
    row->skin_bind += c.skin_at_bind.count(p) > 0;
    row->skin_hidden += sa == 0xFFFF || sb == 0xFFFF || sa == sb || narrow.IsExcluded(sa, sb);
    if (sa != 0xFFFF && sb != 0xFFFF) row->skin_regions.insert(c.RegionPairOf(sa, sb));
    for (int m = 0; m < 2; ++m) row->skin_behind_reach[m] += behind_reach[m].count(p) > 0;
  }
  row->skin = static_cast<uint32_t>(skin_pairs.size());
  if (!c.crease_job) return import::Ok{};
  // The narrow phase under the rule (every pair, at the skin's crease), on the session's narrow-phase workspace.
  uint32_t n = 0;
  runtime::NarrowPhaseJob job;
  job.model = &narrow;
  job.workspace = &c.session.narrow_workspace();
  job.positions = {fr.positions.data(), c.V, 12};
  job.exclusions = runtime::Exclusions::kCrease;
  job.crease = float(c.skin_crease);
  job.output = c.contacts.data();
  job.capacity = static_cast<uint32_t>(c.contacts.size());
  job.count = &n;
  job.stats = &row->skin_stats;
  if (narrow.has_joint_cull() && fr.joint_matrices.size() == size_t{narrow.joint_count()} * runtime::kJointMatrixFloats)
    job.joint_matrices = fr.joint_matrices.data(), job.joint_count = narrow.joint_count();
  const auto t0 = std::chrono::steady_clock::now();
  const runtime::Status ks = job.Run();
  row->skin_us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  if (runtime::Failed(ks)) return Fail(std::string("narrow phase (crease rule): ") + runtime::ToString(ks));
  row->skin_narrow = row->skin_stats.contacts;
  for (uint32_t i = 0; i < n; ++i)
    row->skin_narrow_true += skin_pairs.count(Ordered(c.contacts[i].triangle_a, c.contacts[i].triangle_b)) > 0;
  // The restricted path (play --narrow-behind's, at the session's defaults): the same rule behind M2's pairs
  // at the wider margin and the proxy's folds, on the reach regions; timed with M2 and the folds.
  const playback::SessionOptions defaults;
  const float margin = c.session.model().contact_margin();
  runtime::NarrowPhaseJob behind;
  behind.model = &c.session.reach_model();
  behind.workspace = &c.session.reach_workspace();
  behind.positions = job.positions;
  behind.exclusions = runtime::Exclusions::kCrease;
  behind.crease = job.crease;
  behind.output = c.contacts.data();
  behind.capacity = static_cast<uint32_t>(c.contacts.size());
  behind.count = &n;
  runtime::NarrowPhaseStats behind_stats;
  behind.stats = &behind_stats;
  const auto t1 = std::chrono::steady_clock::now();
  runtime::Status bs = playback::BehindPairs(c.view, c.session.model(), c.session.workspace(), &c.session.reach_model(),
                                             defaults.narrow_behind_margin * margin, defaults.fold_closing * margin,
                                             &c.behind, &row->restricted_pairs, &row->restricted_folds);
  if (runtime::Succeeded(bs)) {
    behind.sphere_pairs = c.behind.data();
    behind.sphere_pair_count = row->restricted_pairs;
    bs = behind.Run();
  }
  row->skin_restricted_us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t1).count();
  if (runtime::Failed(bs)) return Fail(std::string("narrow phase (crease rule, behind the proxy): ") + runtime::ToString(bs));
  row->skin_restricted = behind_stats.contacts;
  for (uint32_t i = 0; i < n; ++i) {
    const runtime::TriangleContact& k = c.contacts[i];
    if (!skin_pairs.count(Ordered(k.triangle_a, k.triangle_b))) continue;
    ++row->skin_restricted_true;
    if (k.sphere_a != 0xFFFF && k.sphere_b != 0xFFFF) row->skin_restricted_regions.insert(c.RegionPairOf(k.sphere_a, k.sphere_b));
  }
  return import::Ok{};
}

}  // namespace spherechain::evaluate::detail
