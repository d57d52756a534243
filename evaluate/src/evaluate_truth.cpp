// Evaluate()'s truth stages (evaluate_internal.h): the session's pairs and contacts as sets, the frame's exact
// self-intersections, and their sorting into contacts, exclusions and the asset-independent truth.
#include <chrono>

#include "evaluate_internal.h"

namespace spherechain::evaluate::detail {

void RecordProxyPairs(const Context& c, const playback::SessionFrame& fr, FrameEval* row) {
  for (const runtime::Collision& p : fr.m1) {
    row->m1_regions.insert(c.RegionPairOf(p.a, p.b));
    row->m1_spheres.insert({p.a, p.b});
  }
  for (const runtime::Collision& p : fr.m2) {
    row->m2_regions.insert(c.RegionPairOf(p.a, p.b));
    row->m2_spheres.insert({p.a, p.b});
  }
}

void RecordNarrowPhase(Context& c, const playback::SessionFrame& fr, FrameEval* row,
                       std::set<baker::TrianglePair>* narrow_pairs) {
  row->narrow = fr.narrow;
  row->narrow_us = fr.narrow_us;
  if (runtime::IsTruncated(fr.narrow_status))
    c.log.Warn("frame " + std::to_string(fr.frame) + ": more than " + std::to_string(c.session.options().contact_capacity) +
               " narrow-phase contacts; precision counts only the first ones");
  for (const runtime::TriangleContact& k : fr.contacts) {
    narrow_pairs->insert(Ordered(k.triangle_a, k.triangle_b));
    row->narrow_regions.insert(c.RegionPairOf(k.sphere_a, k.sphere_b));
  }
}

import::Result<std::vector<baker::TrianglePair>> ExactTruth(const Context& c, const playback::SessionFrame& fr,
                                                            FrameEval* row) {
  const auto t0 = std::chrono::steady_clock::now();
  auto exact = baker::ExactSelfIntersections(fr.positions.data(), c.V, c.mesh.indices, c.weld, &row->degenerate);
  row->exact_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!exact.ok()) return Fail(import::Error{exact.error().code, "frame " + std::to_string(fr.frame) + ": " + exact.error().message});
  return exact;
}

void ClassifyIntersections(const Context& c, const std::vector<baker::TrianglePair>& exact,
                           const std::set<baker::TrianglePair>& narrow_pairs, const std::set<baker::TrianglePair> behind[2],
                           const std::set<baker::TrianglePair> behind_reach[2], FrameEval* row,
                           std::vector<baker::TrianglePair>* contact_pairs) {
  const runtime::NarrowPhaseModel& narrow = c.narrow();
  for (const baker::TrianglePair& p : exact) {
    const uint32_t sa = narrow.triangle_sphere(p.a), sb = narrow.triangle_sphere(p.b);
    // The asset-independent truth: bind centroids at least --crease apart.
    if ((c.bind_centroid[p.a] - c.bind_centroid[p.b]).norm() >= c.crease) {
      ++row->apart;
      if (sa == 0xFFFF || sb == 0xFFFF) {
      } else if (sa == sb) {
        ++row->apart_same;
      } else {
        row->apart_excluded += narrow.IsExcluded(sa, sb);
        row->apart_sphere += row->m2_spheres.count({std::min(sa, sb), std::max(sa, sb)}) > 0;
        row->apart_region += row->m2_regions.count(c.RegionPairOf(sa, sb)) > 0;
      }
    }
    // The truth by the asset's owners and exclusions.
    if (sa == 0xFFFF || sb == 0xFFFF) {
      ++row->unassigned;
    } else if (sa == sb) {
      ++row->same_sphere;
    } else if (narrow.IsExcluded(sa, sb)) {
      ++row->excluded;
      ++row->excluded_by_pair[{std::min(sa, sb), std::max(sa, sb)}];
    } else {
      ++row->contacts;
      const SpherePairKey key{std::min(sa, sb), std::max(sa, sb)};
      const RegionPair rp = c.RegionPairOf(sa, sb);
      row->exact_spheres.insert(key);
      ++row->contacts_by_pair[key];
      row->exact_regions.insert(rp);
      row->narrow_true += narrow_pairs.count(p);
      row->missed_contacts += !row->m2_regions.count(rp);
      row->missed_sphere_contacts += !row->m2_spheres.count(key);
      for (int m = 0; m < 2; ++m)
        row->behind[m] += behind[m].count(p) > 0, row->behind_reach[m] += behind_reach[m].count(p) > 0;
      contact_pairs->push_back(p);
    }
  }
}

}  // namespace spherechain::evaluate::detail
