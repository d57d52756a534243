// Evaluate()'s coverage measures (evaluate_internal.h): the refit spheres against each deformed frame, their
// summary over the animation, and the bind pose's φ1, φ1' and φ2 (baker/coverage.h).
#include <algorithm>
#include <cstdio>
#include <tuple>

#include "evaluate_internal.h"

namespace spherechain::evaluate::detail {

namespace {

/// The exact-predicate coverage measure of one sphere set.
nlohmann::json CoverageJson(const baker::CoverageStats& c) {
  return {{"coverage", c.coverage},       {"protrusion", c.protrusion},       {"outside_p95_rel", c.outside_p95_rel},
          {"outside_max_rel", c.outside_max_rel}, {"voxel_size", c.voxel_size}, {"voxels_undecided", c.voxels_undecided},
          {"skin_outside_p50_rel", c.skin_outside_p50_rel}, {"skin_outside_p95_rel", c.skin_outside_p95_rel},
          {"skin_outside_max_rel", c.skin_outside_max_rel}, {"skin_within_share", c.skin_within_share}};
}

}  // namespace

nlohmann::json RefitCoverageJson(const baker::CoverageStats& c) {
  nlohmann::json rc = CoverageJson(c), out = nlohmann::json::array();
  for (uint32_t s = 0; s < c.sphere_outside_max_rel.size(); ++s)
    if (c.sphere_outside_max_rel[s] > kStickOut) out.push_back({{"sphere", s}, {"outside_max_rel", c.sphere_outside_max_rel[s]}});
  rc["spheres_sticking_out"] = out;
  return rc;
}

import::Status MeasureRefitCoverage(Context& c, const playback::SessionFrame& fr, FrameEval* row) {
  const runtime::SphereArrays& sp = fr.spheres;
  std::vector<baker::Ball> balls(sp.count);
  for (uint32_t s = 0; s < sp.count; ++s) {
    balls[s].center = Eigen::Vector3d(sp.x[s], sp.y[s], sp.z[s]);
    balls[s].radius = sp.r[s];
  }
  baker::CoverageOptions opts;
  opts.per_sphere = true;
  const std::vector<float>& animated = c.session.positions();
  const std::vector<float> given = animated.data() == fr.positions.data()
                                       ? std::vector<float>()
                                       : std::vector<float>(fr.positions.begin(), fr.positions.end());
  auto cov = baker::MeasureCoverage(given.empty() ? animated : given, c.mesh.indices, balls, opts);
  if (!cov.ok())
    return Fail(import::Error{cov.error().code, "frame " + std::to_string(fr.frame) + ": refit coverage: " + cov.error().message});
  row->refit_coverage = std::move(cov.value());
  row->has_refit_coverage = true;
  return import::Ok{};
}

import::Result<nlohmann::json> MeasureBindCoverage(const Context& c) {
  nlohmann::json coverage = nlohmann::json::object(), protrusion = nlohmann::json::object(),
                 detail = nlohmann::json::object();
  if (c.a.coverage) {
    const std::pair<const char*, const flatbuffers::Vector<const schema::Sphere*>*> sets[3] = {
        {"phi1", c.view.asset->spheres_phi1()}, {"phi1_adjusted", c.view.asset->spheres()}, {"phi2", c.view.asset->spheres_phi2()}};
    for (const auto& [name, list] : sets) {
      if (!list) continue;
      std::vector<baker::Ball> spheres;
      for (const schema::Sphere* s : *list) {
        baker::Ball b;
        b.center = Eigen::Vector3d(s->center().x(), s->center().y(), s->center().z());
        b.radius = s->radius();
        spheres.push_back(b);
      }
      auto m = baker::MeasureCoverage(c.mesh.positions, c.mesh.indices, spheres);
      if (!m.ok()) return Fail(m.error());
      coverage[name] = m->coverage;
      protrusion[name] = m->protrusion;
      detail[name] = CoverageJson(m.value());
    }
  }
  return nlohmann::json{{"coverage", coverage}, {"protrusion", protrusion}, {"bind_pose", detail}};
}

nlohmann::json SummarizeRefitCoverage(const Context& c, const std::vector<FrameEval>& rows, std::string* lines) {
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
  if (cov.empty()) return nlohmann::json();
  auto median = [](std::vector<double> v) { std::sort(v.begin(), v.end()); return v[v.size() / 2]; };
  std::vector<std::pair<uint32_t, std::pair<uint32_t, double>>> worst(stick.begin(), stick.end());
  std::sort(worst.begin(), worst.end(), [](const auto& x, const auto& y) {
    return std::tie(y.second.first, y.second.second, x.first) < std::tie(x.second.first, x.second.second, y.first);
  });
  nlohmann::json sj = nlohmann::json::array();
  for (const auto& [sphere, e] : worst)
    sj.push_back({{"sphere", sphere}, {"region", c.SphereRegion(sphere)}, {"frames", e.first}, {"outside_max_rel", e.second}});
  nlohmann::json summary = {{"coverage_median", median(cov)}, {"coverage_min", *std::min_element(cov.begin(), cov.end())},
                            {"protrusion_median", median(prot)}, {"protrusion_max", *std::max_element(prot.begin(), prot.end())},
                            {"outside_p95_rel_median", median(p95)}, {"outside_p95_rel_max", *std::max_element(p95.begin(), p95.end())},
                            {"outside_max_rel", out_max}, {"skin_outside_p95_rel_median", median(skin95)},
                            {"skin_outside_p95_rel_max", *std::max_element(skin95.begin(), skin95.end())},
                            {"stick_out_rel", kStickOut}, {"spheres_sticking_out", sj}};
  Appendf(lines,
          "refit spheres on the deformed mesh: coverage median %.1f %% (min %.1f %%), protrusion median %.1f %% "
          "(max %.1f %%), outside p95 median %.2f %% (max %.2f %%), max %.2f %% of height; skin outside the "
          "spheres p95 median %.2f %% of height\n",
          100 * median(cov), 100 * summary["coverage_min"].get<double>(), 100 * median(prot),
          100 * summary["protrusion_max"].get<double>(), 100 * median(p95), 100 * summary["outside_p95_rel_max"].get<double>(),
          100 * out_max, 100 * median(skin95));
  Appendf(lines, "spheres sticking out of the skin by > %.1f %% of height: %zu", 100 * kStickOut, worst.size());
  for (size_t i = 0; i < worst.size() && i < 6; ++i)
    Appendf(lines, "%s sphere %u (region %d) in %u frames, up to %.2f %%", i ? "," : ";", worst[i].first,
            c.SphereRegion(worst[i].first), worst[i].second.first, 100 * worst[i].second.second);
  *lines += "\n";
  return summary;
}

}  // namespace spherechain::evaluate::detail
