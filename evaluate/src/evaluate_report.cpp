// Evaluate()'s report (evaluate_internal.h): the frames summed, the human table and the JSON document.
#include <algorithm>

#include "evaluate_internal.h"
#include "spherechain/playback/debug_export.h"

namespace spherechain::evaluate::detail {

namespace {

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

double Median(const std::vector<double>& sorted) { return sorted.empty() ? 0.0 : sorted[sorted.size() / 2]; }
double Max(const std::vector<double>& sorted) { return sorted.empty() ? 0.0 : sorted.back(); }

/// The frames summed (the summary's counts), and the ratios made of them.
struct Totals {
  size_t exact_regions = 0, found_m1 = 0, found_m2 = 0, exact_spheres = 0, sfound_m1 = 0, sfound_m2 = 0;
  size_t false_m1 = 0, false_m2 = 0, gt = 0, narrow_total = 0, narrow_true = 0, excluded = 0, same = 0, unassigned = 0;
  nlohmann::json false_frames = nlohmann::json::array();
  size_t imprecise_m2 = 0, reported_m2 = 0, behind[2] = {0, 0}, behind_reach[2] = {0, 0}, localised[2] = {0, 0};
  size_t apart = 0, apart_sphere = 0, apart_region = 0, apart_excluded = 0, apart_same = 0;
  size_t confirmed_found[2] = {0, 0}, confirmed_false[2] = {0, 0}, confirmed_false_frames = 0;
  std::vector<double> narrow_us;  // sorted
  double exact_ms = 0;
  // The skin's definition (crease rule).
  size_t skin = 0, skin_bind = 0, skin_hidden = 0, skin_behind_reach[2] = {0, 0}, skin_regions = 0;
  size_t skin_found[2] = {0, 0}, skin_narrow = 0, skin_narrow_true = 0, skin_folds = 0;
  std::vector<double> skin_us;  // sorted
  size_t restricted = 0, restricted_true = 0, restricted_regions = 0, restricted_pairs = 0, restricted_folds = 0;
  std::vector<double> restricted_us;  // sorted
  double recall_m1 = 1, recall_m2 = 1, srecall_m1 = 1, srecall_m2 = 1, n_recall = 1, n_precision = 1;
  double skin_recall = 1, skin_precision = 1, sphere_precision_m2 = 1, apart_recall_sphere = 1, apart_recall_region = 1;
};

Totals Sum(const Context& c, const std::vector<FrameEval>& rows) {
  Totals t;
  for (uint32_t f = 0; f < rows.size(); ++f) {
    const FrameEval& r = rows[f];
    t.exact_regions += r.exact_regions.size();
    t.found_m1 += CountIn(r.exact_regions, r.m1_regions);
    t.found_m2 += CountIn(r.exact_regions, r.m2_regions);
    t.exact_spheres += r.exact_spheres.size();
    t.sfound_m1 += CountIn(r.exact_spheres, r.m1_spheres);
    t.sfound_m2 += CountIn(r.exact_spheres, r.m2_spheres);
    bool confirmed_false_frame = false;
    for (int m = 0; m < 2; ++m) {
      t.behind[m] += r.behind[m], t.behind_reach[m] += r.behind_reach[m], t.localised[m] += r.localised[m];
      t.confirmed_found[m] += CountIn(r.exact_regions, r.confirmed_regions[m]);
      const size_t wrong = r.confirmed_regions[m].size() - CountIn(r.confirmed_regions[m], r.exact_regions);
      t.confirmed_false[m] += wrong;
      confirmed_false_frame |= wrong > 0;
      t.skin_behind_reach[m] += r.skin_behind_reach[m];
    }
    t.confirmed_false_frames += confirmed_false_frame;
    t.false_m1 += r.false_m1.size();
    t.false_m2 += r.false_m2.size();
    if (!r.false_m1.empty() || !r.false_m2.empty()) t.false_frames.push_back(f);
    t.imprecise_m2 += r.imprecise_gaps.size();
    t.apart += r.apart, t.apart_sphere += r.apart_sphere, t.apart_region += r.apart_region;
    t.apart_excluded += r.apart_excluded, t.apart_same += r.apart_same;
    t.skin += r.skin, t.skin_bind += r.skin_bind, t.skin_hidden += r.skin_hidden, t.skin_regions += r.skin_regions.size();
    t.skin_found[0] += CountIn(r.skin_regions, r.m1_regions), t.skin_found[1] += CountIn(r.skin_regions, r.m2_regions);
    t.skin_narrow += r.skin_narrow, t.skin_narrow_true += r.skin_narrow_true, t.skin_folds += r.skin_stats.crease_folds;
    if (c.crease_job) t.skin_us.push_back(r.skin_us), t.restricted_us.push_back(r.skin_restricted_us);
    t.restricted += r.skin_restricted, t.restricted_true += r.skin_restricted_true;
    t.restricted_regions += CountIn(r.skin_regions, r.skin_restricted_regions);
    t.restricted_pairs += r.restricted_pairs, t.restricted_folds += r.restricted_folds;
    t.reported_m2 += r.m2_spheres.size();
    t.gt += r.contacts;
    t.narrow_total += r.narrow.contacts;
    t.narrow_true += r.narrow_true;
    t.excluded += r.excluded;
    t.same += r.same_sphere;
    t.unassigned += r.unassigned;
    t.narrow_us.push_back(r.narrow_us);
    t.exact_ms += r.exact_ms;
  }
  std::sort(t.narrow_us.begin(), t.narrow_us.end());
  std::sort(t.skin_us.begin(), t.skin_us.end());
  std::sort(t.restricted_us.begin(), t.restricted_us.end());
  t.recall_m1 = Ratio(double(t.found_m1), double(t.exact_regions)), t.recall_m2 = Ratio(double(t.found_m2), double(t.exact_regions));
  t.srecall_m1 = Ratio(double(t.sfound_m1), double(t.exact_spheres)), t.srecall_m2 = Ratio(double(t.sfound_m2), double(t.exact_spheres));
  t.n_recall = Ratio(double(t.narrow_true), double(t.gt)), t.n_precision = Ratio(double(t.narrow_true), double(t.narrow_total));
  t.skin_recall = Ratio(double(t.skin_narrow_true), double(t.skin)), t.skin_precision = Ratio(double(t.skin_narrow_true), double(t.skin_narrow));
  t.sphere_precision_m2 = Ratio(double(t.reported_m2 - t.imprecise_m2), double(t.reported_m2));
  t.apart_recall_sphere = Ratio(double(t.apart_sphere), double(t.apart));
  t.apart_recall_region = Ratio(double(t.apart_region), double(t.apart));
  return t;
}

/// The header and one line per frame.
void TableOfFrames(const Context& c, const std::vector<FrameEval>& rows, std::string* text) {
  const auto& a = c.a;
  Appendf(text, "evaluate: %s + %s — %s, %u frames, %u spheres, %u triangles, body height %.4g, margin %.4g (%.2f %%)\n",
          a.asset_name.c_str(), a.mesh_name.c_str(), c.anim.Describe().c_str(), c.anim.frames, c.view.sphere_count, c.T,
          c.height, c.margin, 100.0 * a.margin_rel);
  if (const std::string legend = playback::RegionLegendLine(c.view); !legend.empty()) Appendf(text, "%s\n", legend.c_str());
  Appendf(text, "\n%5s  %-26s %8s %8s %8s %8s  %-22s %-22s %-22s %s\n", "frame", "pose", "contacts", "narrow", "excluded",
          "same sph", "exact regions", "proxy M1", "proxy M2", "missed by M2 / false alarms");
  for (uint32_t f = 0; f < rows.size(); ++f) {
    const FrameEval& r = rows[f];
    std::set<RegionPair> missed;
    for (const RegionPair& p : r.exact_regions)
      if (!r.m2_regions.count(p)) missed.insert(p);
    std::set<RegionPair> falses = r.false_m1;
    falses.insert(r.false_m2.begin(), r.false_m2.end());
    Appendf(text, "%5u  %-26s %8u %8u %8u %8u  %-22s %-22s %-22s %s / %s\n", f, r.label.c_str(), r.contacts, r.narrow.contacts,
            r.excluded, r.same_sphere, RegionText(r.exact_regions).c_str(), RegionText(r.m1_regions).c_str(),
            RegionText(r.m2_regions).c_str(), RegionText(missed).c_str(), RegionText(falses).c_str());
  }
}

/// The summary lines: the truth, the proxy, the narrow phase (asset exclusions and crease rule).
void TableOfTotals(const Context& c, const Totals& t, std::string* text) {
  Appendf(text, "\nground truth: %zu contacts (triangle pairs) in %zu (frame, region pair)s and %zu (frame, sphere pair)s; "
          "apart: %zu in excluded pairs, %zu inside one sphere's region, %zu with an unassigned triangle\n",
          t.gt, t.exact_regions, t.exact_spheres, t.excluded, t.same, t.unassigned);
  Appendf(text, "proxy recall, region pairs: M1 %.1f %% (%zu/%zu), M2 %.1f %% (%zu/%zu); sphere pairs: M1 %.1f %%, M2 %.1f %%\n",
          100 * t.recall_m1, t.found_m1, t.exact_regions, 100 * t.recall_m2, t.found_m2, t.exact_regions, 100 * t.srecall_m1,
          100 * t.srecall_m2);
  const double gt = double(t.gt);
  Appendf(text, "contacts behind the proxy's sphere pairs (found by the narrow phase restricted to them): reach regions "
          "M1 %.1f %%, M2 %.1f %%; surrounding regions M1 %.1f %%, M2 %.1f %%; localised (where the triangles meet "
          "lies within the margin of both spheres of a reported pair of their regions): M1 %.1f %%, M2 %.1f %%\n",
          100 * Ratio(double(t.behind_reach[0]), gt), 100 * Ratio(double(t.behind_reach[1]), gt),
          100 * Ratio(double(t.behind[0]), gt), 100 * Ratio(double(t.behind[1]), gt), 100 * Ratio(double(t.localised[0]), gt),
          100 * Ratio(double(t.localised[1]), gt));
  Appendf(text, "proxy false alarms (nothing within the margin): M1 %zu, M2 %zu, in %zu frames\n", t.false_m1, t.false_m2,
          t.false_frames.size());
  Appendf(text, "proxy, then the narrow phase behind its pairs (reach regions; the region pairs of the contacts it finds): "
          "region pairs M1 %.1f %% (%zu/%zu), M2 %.1f %% (%zu/%zu); region pairs with no exact contact: M1 %zu, M2 %zu, "
          "in %zu frames\n",
          100 * Ratio(double(t.confirmed_found[0]), double(t.exact_regions)), t.confirmed_found[0], t.exact_regions,
          100 * Ratio(double(t.confirmed_found[1]), double(t.exact_regions)), t.confirmed_found[1], t.exact_regions,
          t.confirmed_false[0], t.confirmed_false[1], t.confirmed_false_frames);
  const double apart = double(t.apart), skin = double(t.skin);
  Appendf(text, "contacts by bind distance (the asset-independent truth: intersecting triangles whose bind centroids lie "
          ">= %.3g %% of the height apart): %zu triangle pairs; covered by M2's sphere pairs %.1f %%, by its region "
          "pairs %.1f %%; in pairs the asset excludes %.1f %%, inside one sphere's region %.1f %%\n",
          100 * c.a.crease_rel, t.apart, 100 * t.apart_recall_sphere, 100 * t.apart_recall_region,
          100 * Ratio(double(t.apart_excluded), apart) * (t.apart > 0), 100 * Ratio(double(t.apart_same), apart) * (t.apart > 0));
  Appendf(text, "skin contacts (the definition: intersecting triangles not within %.3g %% of the height of each other "
          "along the welded bind surface nor within two triangle rings): %zu triangle pairs in %zu (frame, region "
          "pair)s, %zu of them intersecting at bind pose already; hidden by the exclusion-based count above %.1f %%; "
          "region pairs found by M1 %.1f %%, M2 %.1f %%; behind the proxy's pairs (reach regions) M1 %.1f %%, M2 %.1f %%\n",
          100 * c.skin_crease / c.height, t.skin, t.skin_regions, t.skin_bind,
          100 * Ratio(double(t.skin_hidden), skin) * (t.skin > 0), 100 * Ratio(double(t.skin_found[0]), double(t.skin_regions)),
          100 * Ratio(double(t.skin_found[1]), double(t.skin_regions)), 100 * Ratio(double(t.skin_behind_reach[0]), skin),
          100 * Ratio(double(t.skin_behind_reach[1]), skin));
  if (c.crease_job)
    Appendf(text, "narrow phase, crease rule (every triangle pair): recall %.2f %% (%zu/%zu), precision %.2f %% (%zu/%zu), "
            "%zu intersecting pairs found near by the graph (a --crease wider than the asset's); median %.1f us, max %.1f us "
            "a frame\n",
            100 * t.skin_recall, t.skin_narrow_true, t.skin, 100 * t.skin_precision, t.skin_narrow_true, t.skin_narrow,
            t.skin_folds, Median(t.skin_us), Max(t.skin_us));
  if (c.crease_job)
    Appendf(text, "narrow phase, crease rule behind the proxy's pairs and folds (M2 at %.3g x the margin, folds closing "
            "by %.3g x it; reach regions; %.1f pairs a frame, %.1f of them folds): contacts %.2f %% (%zu/%zu), (frame, "
            "region pair)s %.2f %% (%zu/%zu), precision %.2f %% (%zu/%zu); median %.1f us, max %.1f us a frame with "
            "M2 and the folds\n",
            double(playback::SessionOptions{}.narrow_behind_margin), double(playback::SessionOptions{}.fold_closing),
            Ratio(double(t.restricted_pairs), double(t.restricted_us.size())), Ratio(double(t.restricted_folds), double(t.restricted_us.size())),
            100 * Ratio(double(t.restricted_true), skin), t.restricted_true, t.skin,
            100 * Ratio(double(t.restricted_regions), double(t.skin_regions)), t.restricted_regions, t.skin_regions,
            100 * Ratio(double(t.restricted_true), double(t.restricted)), t.restricted_true, t.restricted,
            Median(t.restricted_us), Max(t.restricted_us));
  else
    Appendf(text, "narrow phase, crease rule: the asset was baked without it (no Asset.crease): re-bake to run it\n");
  Appendf(text, "sphere-pair precision M2 (reported pairs whose own surrounding regions come within the margin): "
          "%.1f %% (%zu/%zu)\n",
          100 * t.sphere_precision_m2, t.reported_m2 - t.imprecise_m2, t.reported_m2);
  Appendf(text, "narrow phase: recall %.2f %% (%zu/%zu), precision %.2f %% (%zu/%zu); median %.1f us, max %.1f us a frame "
          "(exact ground truth: %.1f ms a frame)\n",
          100 * t.n_recall, t.narrow_true, t.gt, 100 * t.n_precision, t.narrow_true, t.narrow_total, Median(t.narrow_us),
          Max(t.narrow_us), c.anim.frames ? t.exact_ms / c.anim.frames : 0.0);
}

/// The bind pose's coverage lines (`detail`: MeasureBindCoverage's "bind_pose").
void TableOfBindCoverage(const Context& c, const nlohmann::json& detail, std::string* text) {
  if (c.a.coverage)
    for (const char* name : {"phi1", "phi1_adjusted", "phi2"})
      if (detail.contains(name))
        Appendf(text, "bind pose %-13s coverage %.1f %%, protrusion %.1f %% (outside: p95 %.2f %%, max %.2f %% of height); "
                "skin outside the spheres: median %.2f %%, p95 %.2f %%, max %.2f %% of height, %.1f %% of its area "
                "within %.1f %%\n",
                name, 100 * detail[name]["coverage"].get<double>(), 100 * detail[name]["protrusion"].get<double>(),
                100 * detail[name]["outside_p95_rel"].get<double>(), 100 * detail[name]["outside_max_rel"].get<double>(),
                100 * detail[name]["skin_outside_p50_rel"].get<double>(), 100 * detail[name]["skin_outside_p95_rel"].get<double>(),
                100 * detail[name]["skin_outside_max_rel"].get<double>(), 100 * detail[name]["skin_within_share"].get<double>(),
                100 * baker::kSkinWithinRel);
}

/// The contact margin sweep's table.
void TableOfSweep(const Context& c, const Totals& t, const std::vector<SweepPoint>& sweep, std::string* text) {
  if (sweep.empty()) return;
  const float cm = c.session.model().contact_margin();
  const uint32_t F = c.anim.frames;
  Appendf(text, "\ncontact margin sweep (same refit spheres; the asset's margin is %.4g = %.2f %% of height):\n", double(cm),
          100.0 * cm / c.height);
  Appendf(text, "%10s %8s  %18s  %18s  %18s  %11s  %14s  %14s  %16s  %22s\n", "margin %h", "margin", "region recall M1",
          "region recall M2", "sphere recall M2", "false M1/M2", "false frames", "pairs/frame M2", "sphere precision",
          "M2 + narrow: recall, us");
  for (const SweepPoint& pt : sweep)
    Appendf(text, "%10.2f %8.4g  %9.1f %% (%3zu)  %9.1f %% (%3zu)  %15.1f %%  %5zu/%-5zu  %6zu of %-4u  %14.1f  %14.1f %%  %9.1f %% %9.1f\n",
            100 * pt.margin_rel, pt.margin_rel * c.height, 100 * Ratio(double(pt.found_m1), double(t.exact_regions)),
            pt.found_m1, 100 * Ratio(double(pt.found_m2), double(t.exact_regions)), pt.found_m2,
            100 * Ratio(double(pt.sfound_m2), double(t.exact_spheres)), pt.false_m1, pt.false_m2, pt.false_frames, F,
            F ? double(pt.pairs_m2) / F : 0.0, 100 * Ratio(double(pt.pairs_m2 - pt.imprecise_m2), double(pt.pairs_m2)),
            100 * Ratio(double(pt.confirmed_m2), double(t.exact_regions)), F ? pt.narrow_us_m2 / F : 0.0);
}

/// One frame of the JSON document.
nlohmann::json FrameJson(const Context& c, uint32_t f, const FrameEval& r) {
  nlohmann::json o = {
      {"frame", f},
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
      {"missed_sphere_pairs_m2", SphereGapList(r.missed_sphere_gaps, c.height)},
      {"false_alarm_sphere_pairs_m2", SphereGapList(r.false_sphere_gaps, c.height)},
      {"imprecise_sphere_pairs_m2", SphereGapList(r.imprecise_gaps, c.height)},
      {"contact_sphere_pairs", PairCountList(r.contacts_by_pair)},
      {"excluded_sphere_pairs", PairCountList(r.excluded_by_pair)},
      {"contacts_by_bind_distance", {{"triangle_pairs", r.apart}, {"covered_by_sphere_pairs_m2", r.apart_sphere},
                                     {"covered_by_region_pairs_m2", r.apart_region}}},
      {"narrow", {{"contacts", r.narrow.contacts}, {"true_contacts", r.narrow_true},
                  {"candidate_pairs", r.narrow.candidate_pairs}, {"triangle_tests", r.narrow.triangle_tests},
                  {"us", r.narrow_us}}},
      {"exact_ms", r.exact_ms}};
  if (r.has_refit_coverage) o["refit_coverage"] = RefitCoverageJson(r.refit_coverage);
  return o;
}

nlohmann::json SweepJson(const Context& c, const Totals& t, const std::vector<SweepPoint>& sweep) {
  const uint32_t F = c.anim.frames;
  nlohmann::json sw = nlohmann::json::array();
  for (const SweepPoint& pt : sweep)
    sw.push_back({{"margin_rel", pt.margin_rel},
                  {"margin", pt.margin_rel * c.height},
                  {"recall_m1", Ratio(double(pt.found_m1), double(t.exact_regions))},
                  {"recall_m2", Ratio(double(pt.found_m2), double(t.exact_regions))},
                  {"sphere_recall_m1", Ratio(double(pt.sfound_m1), double(t.exact_spheres))},
                  {"sphere_recall_m2", Ratio(double(pt.sfound_m2), double(t.exact_spheres))},
                  {"false_alarms_m1", pt.false_m1},
                  {"false_alarms_m2", pt.false_m2},
                  {"false_alarm_frames", pt.false_frames},
                  {"sphere_pairs_per_frame_m2", F ? double(pt.pairs_m2) / F : 0.0},
                  {"sphere_precision_m2", Ratio(double(pt.pairs_m2 - pt.imprecise_m2), double(pt.pairs_m2))},
                  {"recall_m2_then_narrow", Ratio(double(pt.confirmed_m2), double(t.exact_regions))},
                  {"narrow_us_per_frame_m2", F ? pt.narrow_us_m2 / F : 0.0}});
  return sw;
}

nlohmann::json SummaryJson(const Context& c, const Totals& t, const nlohmann::json& bind_coverage) {
  const double gt = double(t.gt), er = double(t.exact_regions), skin = double(t.skin);
  return {
      {"frames", c.anim.frames},
      {"contacts", t.gt},
      {"excluded_intersections", t.excluded},
      {"same_sphere_intersections", t.same},
      {"exact_region_pairs", t.exact_regions},
      {"proxy", {{"recall_m1", t.recall_m1}, {"recall_m2", t.recall_m2}, {"sphere_recall_m1", t.srecall_m1},
                 {"sphere_recall_m2", t.srecall_m2}, {"false_alarms_m1", t.false_m1}, {"false_alarms_m2", t.false_m2},
                 {"false_alarm_frames", t.false_frames}, {"sphere_pairs_m2", t.reported_m2},
                 {"sphere_precision_m2", t.sphere_precision_m2},
                 {"contacts_behind_pairs_m1", Ratio(double(t.behind[0]), gt)},
                 {"contacts_behind_pairs_m2", Ratio(double(t.behind[1]), gt)},
                 {"contacts_behind_reach_m1", Ratio(double(t.behind_reach[0]), gt)},
                 {"contacts_behind_reach_m2", Ratio(double(t.behind_reach[1]), gt)},
                 {"contacts_localised_m1", Ratio(double(t.localised[0]), gt)},
                 {"contacts_localised_m2", Ratio(double(t.localised[1]), gt)}}},
      {"proxy_then_narrow", {{"recall_m1", Ratio(double(t.confirmed_found[0]), er)},
                             {"recall_m2", Ratio(double(t.confirmed_found[1]), er)},
                             {"wrong_region_pairs_m1", t.confirmed_false[0]},
                             {"wrong_region_pairs_m2", t.confirmed_false[1]},
                             {"wrong_frames", t.confirmed_false_frames}}},
      {"contacts_by_bind_distance", {{"crease_rel", c.a.crease_rel}, {"triangle_pairs", t.apart},
                                     {"covered_by_sphere_pairs_m2", t.apart_recall_sphere},
                                     {"covered_by_region_pairs_m2", t.apart_recall_region},
                                     {"in_excluded_pairs", t.apart_excluded}, {"inside_one_sphere", t.apart_same}}},
      {"skin_contacts",
       {{"crease", c.skin_crease}, {"crease_rel", c.skin_crease / c.height}, {"triangle_pairs", t.skin},
        {"region_pairs", t.skin_regions}, {"at_bind_pose", t.skin_bind}, {"hidden_by_exclusions", t.skin_hidden},
        {"region_recall_m1", Ratio(double(t.skin_found[0]), double(t.skin_regions))},
        {"region_recall_m2", Ratio(double(t.skin_found[1]), double(t.skin_regions))},
        {"behind_reach_m1", Ratio(double(t.skin_behind_reach[0]), skin)},
        {"behind_reach_m2", Ratio(double(t.skin_behind_reach[1]), skin)},
        {"narrow", c.crease_job ? nlohmann::json{{"recall", t.skin_recall}, {"precision", t.skin_precision},
                                                 {"contacts", t.skin_narrow}, {"folds", t.skin_folds},
                                                 {"median_us", Median(t.skin_us)}, {"max_us", Max(t.skin_us)}}
                                : nlohmann::json(nullptr)},
        {"behind_proxy_and_folds",
         c.crease_job ? nlohmann::json{{"behind_margin", playback::SessionOptions{}.narrow_behind_margin},
                                       {"fold_closing", playback::SessionOptions{}.fold_closing},
                                       {"recall", Ratio(double(t.restricted_true), skin)},
                                       {"region_recall", Ratio(double(t.restricted_regions), double(t.skin_regions))},
                                       {"precision", Ratio(double(t.restricted_true), double(t.restricted))},
                                       {"contacts", t.restricted}, {"pairs", t.restricted_pairs}, {"folds", t.restricted_folds},
                                       {"median_us", Median(t.restricted_us)}, {"max_us", Max(t.restricted_us)}}
                      : nlohmann::json(nullptr)}}},
      {"narrow", {{"recall", t.n_recall}, {"precision", t.n_precision}, {"contacts", t.narrow_total},
                  {"median_us", Median(t.narrow_us)}, {"max_us", Max(t.narrow_us)}}},
      {"coverage", bind_coverage["coverage"]},
      {"protrusion", bind_coverage["protrusion"]},
      {"bind_pose", bind_coverage["bind_pose"]}};
}

}  // namespace

void Report(const Context& c, const std::vector<FrameEval>& rows, const std::vector<SweepPoint>& sweep,
            const nlohmann::json& bind_coverage, Evaluation* out) {
  const Totals t = Sum(c, rows);
  std::string refit_lines;
  const nlohmann::json refit_summary = SummarizeRefitCoverage(c, rows, &refit_lines);
  std::string& text = out->text;
  TableOfFrames(c, rows, &text);
  TableOfTotals(c, t, &text);
  TableOfBindCoverage(c, bind_coverage["bind_pose"], &text);
  text += refit_lines;
  TableOfSweep(c, t, sweep, &text);

  nlohmann::json& j = out->report;
  j["asset"] = c.a.asset_name;
  if (c.view.asset->regions() && c.region_map.empty()) {  // schema v4: what R0..R(n-1) are
    nlohmann::json names = nlohmann::json::array();
    for (uint32_t r = 0; r < runtime::RegionCount(c.view); ++r) names.push_back(runtime::RegionName(c.view, r));
    j["regions"] = names;
  }
  if (!c.region_map.empty()) j["region_pairs_by"] = "paper";
  j["mesh"] = c.a.mesh_name;
  j["animation"] = c.anim.Describe();
  j["refit"] = c.a.refit;
  j["body_height"] = c.height;
  j["margin_rel"] = c.a.margin_rel;
  j["contact_margin"] = c.session.model().contact_margin();  // the asset's: what the proxy's spheres were grown by
  j["contact_margin_rel"] = double(c.session.model().contact_margin()) / c.height;
  nlohmann::json fr = nlohmann::json::array();
  for (uint32_t f = 0; f < rows.size(); ++f) fr.push_back(FrameJson(c, f, rows[f]));
  j["frames"] = fr;
  if (!sweep.empty()) j["margin_sweep"] = SweepJson(c, t, sweep);
  j["summary"] = SummaryJson(c, t, bind_coverage);
  if (!refit_summary.is_null()) j["summary"]["refit"] = refit_summary;
  out->recall_m1 = t.recall_m1;
  out->recall_m2 = t.recall_m2;
}

}  // namespace spherechain::evaluate::detail
