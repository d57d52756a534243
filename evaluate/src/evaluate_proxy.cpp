// Evaluate()'s proxy stages (evaluate_internal.h): the narrow phase behind the proxy's pairs, where each contact
// lies against the reported pairs, false alarms, sphere-pair precision and the refit gaps of the pairs.
#include <cmath>

#include "evaluate_internal.h"

namespace spherechain::evaluate::detail {

import::Status RunBehindTheProxy(Context& c, const playback::SessionFrame& fr, FrameEval* row,
                                 std::set<baker::TrianglePair> behind[2], std::set<baker::TrianglePair> behind_reach[2]) {
  // The narrow phase restricted to M1's / M2's sphere pairs (what an engine running the spheres as its broad
  // phase gets): with the surrounding regions (a contact behind its two owners only), and with the reach
  // regions (behind every sphere that reaches its triangles: NarrowPhaseRegions::kReach).
  for (int regions = 0; regions < 2; ++regions)
    for (int m = 0; m < 2; ++m) {
      const std::span<const runtime::Collision> pairs = m == 0 ? fr.m1 : fr.m2;
      uint32_t n = 0;
      runtime::NarrowPhaseJob job;
      job.model = regions == 0 ? &c.session.narrow_model() : &c.session.reach_model();
      job.workspace = regions == 0 ? &c.session.narrow_workspace() : &c.session.reach_workspace();
      job.positions = {fr.positions.data(), c.V, 12};
      job.sphere_pairs = pairs.data();
      job.sphere_pair_count = uint32_t(pairs.size());
      job.output = c.contacts.data();
      job.capacity = static_cast<uint32_t>(c.contacts.size());
      job.count = &n;
      if (runtime::Status rs = job.Run(); runtime::Failed(rs))
        return Fail(std::string("narrow phase (behind the proxy): ") + runtime::ToString(rs));
      std::set<baker::TrianglePair>& into = regions == 0 ? behind[m] : behind_reach[m];
      for (uint32_t i = 0; i < n; ++i) {
        const runtime::TriangleContact& k = c.contacts[i];
        if (regions == 1) row->confirmed_regions[m].insert(c.RegionPairOf(k.sphere_a, k.sphere_b));
        const baker::TrianglePair tp = Ordered(k.triangle_a, k.triangle_b);
        if (!into.insert(tp).second)
          return Fail("frame " + std::to_string(fr.frame) + ": the narrow phase reported triangles " + std::to_string(tp.a) +
                      " and " + std::to_string(tp.b) + " twice");
      }
    }
  return import::Ok{};
}

import::Status LocaliseContacts(const Context& c, const playback::SessionFrame& fr,
                                const std::vector<baker::TrianglePair>& contact_pairs, FrameEval* row) {
  if (contact_pairs.empty()) return import::Ok{};
  auto points = baker::ContactPoints(fr.positions.data(), c.V, c.mesh.indices, contact_pairs);
  if (!points.ok()) return Fail(import::Error{points.error().code, "frame " + std::to_string(fr.frame) + ": " + points.error().message});
  const runtime::SphereArrays& sp = fr.spheres;
  const float grow = c.session.model().contact_margin();
  auto inside = [&](uint32_t s, const Eigen::Vector3d& x) {
    const double dx = x.x() - sp.x[s], dy = x.y() - sp.y[s], dz = x.z() - sp.z[s];
    return std::sqrt(dx * dx + dy * dy + dz * dz) <= double(sp.r[s]) + grow;
  };
  for (size_t i = 0; i < contact_pairs.size(); ++i) {
    const int ra = c.SphereRegion(c.narrow().triangle_sphere(contact_pairs[i].a));
    const int rb = c.SphereRegion(c.narrow().triangle_sphere(contact_pairs[i].b));
    const Eigen::Vector3d& x = points.value()[i];
    for (int m = 0; m < 2; ++m)
      for (const SpherePairKey& k : m == 0 ? row->m1_spheres : row->m2_spheres) {
        const int ka = c.SphereRegion(k.first), kb = c.SphereRegion(k.second);
        if (((ka == ra && kb == rb) || (ka == rb && kb == ra)) && inside(k.first, x) && inside(k.second, x)) {
          ++row->localised[m];
          break;
        }
      }
  }
  return import::Ok{};
}

import::Result<bool> IsFalseAlarm(const Context& c, const float* positions, const FrameEval& row, NearCache* cache,
                                  const RegionPair& rp) {
  if (row.exact_regions.count(rp)) return false;
  if (auto it = cache->regions.find(rp); it != cache->regions.end()) return !it->second;
  static const std::vector<uint32_t> kNone;
  auto triangles = [&](int r) -> const std::vector<uint32_t>& {
    const auto it = c.region_triangles.find(r);
    return it == c.region_triangles.end() ? kNone : it->second;
  };
  const runtime::NarrowPhaseModel& narrow = c.narrow();
  auto near = baker::AnyTrianglesWithin(positions, c.V, c.mesh.indices, c.weld, triangles(rp.first), triangles(rp.second),
                                        c.margin, [&](uint32_t s, uint32_t t) {
                                          const uint32_t sa = narrow.triangle_sphere(s), sb = narrow.triangle_sphere(t);
                                          return sa != sb && !narrow.IsExcluded(sa, sb);
                                        });
  if (!near.ok()) return near.error();
  cache->regions[rp] = near.value();
  return !near.value();
}

import::Result<bool> IsImprecise(const Context& c, const float* positions, const FrameEval& row, NearCache* cache,
                                 const SpherePairKey& k) {
  if (row.exact_spheres.count(k)) return false;
  if (auto it = cache->pairs.find(k); it != cache->pairs.end()) return !it->second;
  auto near = baker::AnyTrianglesWithin(positions, c.V, c.mesh.indices, c.weld, c.sphere_triangles[k.first],
                                        c.sphere_triangles[k.second], c.margin);
  if (!near.ok()) return near.error();
  cache->pairs[k] = near.value();
  return !near.value();
}

import::Status MeasureFalseAlarms(const Context& c, const playback::SessionFrame& fr, NearCache* cache, FrameEval* row) {
  const float* positions = fr.positions.data();
  // False alarms: region pairs the proxy reports with no contact, where nothing comes within the margin.
  std::set<RegionPair> reported = row->m1_regions;
  reported.insert(row->m2_regions.begin(), row->m2_regions.end());
  for (const RegionPair& rp : reported) {
    auto f = IsFalseAlarm(c, positions, *row, cache, rp);
    if (!f.ok()) return Fail(f.error());
    if (!f.value()) continue;
    if (row->m1_regions.count(rp)) row->false_m1.insert(rp);
    if (row->m2_regions.count(rp)) row->false_m2.insert(rp);
  }
  // Sphere-pair precision: does anything of the two spheres' own surrounding regions come within the margin.
  std::set<SpherePairKey> imprecise;
  for (const SpherePairKey& k : row->m2_spheres) {
    auto f = IsImprecise(c, positions, *row, cache, k);
    if (!f.ok()) return Fail(f.error());
    if (f.value()) imprecise.insert(k);
  }
  // The refit gaps of the missed, false-alarm and imprecise pairs.
  const runtime::SphereArrays& sp = fr.spheres;
  const float m = c.session.model().contact_margin();
  auto gap = [&](SpherePairKey k) {
    const float dx = sp.x[k.first] - sp.x[k.second], dy = sp.y[k.first] - sp.y[k.second], dz = sp.z[k.first] - sp.z[k.second];
    return std::sqrt(dx * dx + dy * dy + dz * dz) - sp.r[k.first] - sp.r[k.second] - 2 * m;
  };
  for (const SpherePairKey& k : row->exact_spheres)
    if (!row->m2_spheres.count(k)) row->missed_sphere_gaps[k] = gap(k);
  for (const SpherePairKey& k : row->m2_spheres)
    if (row->false_m2.count(c.RegionPairOf(k.first, k.second))) row->false_sphere_gaps[k] = gap(k);
  for (const SpherePairKey& k : imprecise) row->imprecise_gaps[k] = gap(k);
  return import::Ok{};
}

}  // namespace spherechain::evaluate::detail
