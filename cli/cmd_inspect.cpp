// spherechain inspect ASSET [--json]
#include <cstdio>

#include <nlohmann/json.hpp>

#include "animation_source.h"
#include "commands.h"

namespace spherechain::cli {

namespace {

struct InspectArgs {
  std::string asset;
  bool json = false;
};

nlohmann::json Describe(const runtime::AssetView& v) {
  const schema::Asset& a = *v.asset;
  nlohmann::json j;
  j["schema_version"] = a.schema_version();
  j["generator"] = a.generator() ? a.generator()->str() : "";
  j["vertices"] = v.vertex_count;
  j["triangles"] = v.triangle_count;
  // The vertex contract (import.h VertexContract; "unrecorded": baked before the field).
  j["vertex_contract"] = a.vertex_contract() ? a.vertex_contract()->str() : "unrecorded";
  if (a.source_vertex_count() || a.joined_vertex_count())
    j["vertices_by_contract"] = {{"source", a.source_vertex_count()}, {"joined", a.joined_vertex_count()}};
  j["spheres"] = v.sphere_count;
  j["units"] = a.units() ? a.units()->str() : "";
  j["unit_scale_m"] = a.unit_scale_m();
  j["up_axis"] = schema::EnumNameUpAxis(a.up_axis());
  char hash[40];
  std::snprintf(hash, sizeof hash, "%016llx", (unsigned long long)a.fingerprint()->positions_hash());
  j["fingerprint"]["positions_hash"] = hash;
  std::snprintf(hash, sizeof hash, "%016llx", (unsigned long long)a.fingerprint()->indices_hash());
  j["fingerprint"]["indices_hash"] = hash;
  nlohmann::json parts = nlohmann::json::array();
  if (a.parts())
    for (const auto* p : *a.parts())
      parts.push_back({{"name", p->name() ? p->name()->str() : ""}, {"first_vertex", p->first_vertex()},
                       {"vertices", p->vertex_count()}, {"first_triangle", p->first_triangle()},
                       {"triangles", p->triangle_count()}});
  j["parts"] = parts;
  // The paper's five regions, or (schema v4) the creature's that Asset.regions names.
  const uint32_t R = runtime::RegionCount(v);
  std::vector<size_t> tris(R, 0), sph(R, 0);
  for (uint8_t r : *a.triangle_regions())
    if (r < R) ++tris[r];
  for (uint8_t r : *a.sphere_regions())
    if (r < R) ++sph[r];
  for (uint32_t k = 0; k < R; ++k) {
    nlohmann::json& e = j["regions"][runtime::RegionName(v, k)];
    e = {{"triangles", tris[k]}, {"spheres", sph[k]}};
    if (const auto* regions = a.regions()) {
      const auto* info = regions->Get(k);
      e["symbol"] = "R" + std::to_string(k);
      e["kind"] = info->kind() == schema::RegionKind::Trunk ? "trunk" : "limb";
      e["bone"] = info->bone() ? info->bone()->str() : "";
      if (info->mirror() >= 0 && uint32_t(info->mirror()) < R) e["mirror"] = runtime::RegionName(v, uint32_t(info->mirror()));
    }
  }
  if (a.regions()) j["body"] = "creature (any-skeleton path)";
  nlohmann::json chains = nlohmann::json::array();
  size_t total = 0;
  for (const auto* c : *a.chains()) {
    chains.push_back({{"name", c->name() ? c->name()->str() : ""}, {"spheres", c->spheres()->size()}});
    total += c->spheres()->size();
  }
  j["chains"] = chains;
  j["mean_spheres_per_chain"] = chains.empty() ? 0.0 : double(total) / double(chains.size());
  j["excluded_pairs"] = a.excluded_pairs() ? a.excluded_pairs()->size() : 0;
  // Schema v3: the refit from joint matrices (0 joints: not available — older schema or no skin).
  j["joint_refit"] = {{"available", a.sphere_joints() != nullptr}, {"joints", a.sphere_joints() ? a.joint_count() : 0}};
  j["unassigned_triangles"] = v.triangle_count - (a.surrounding_triangles() ? a.surrounding_triangles()->size() : 0);
  // Reach regions (absent before them): how many spheres a triangle stands behind, on average.
  j["reach_spheres_per_triangle"] =
      a.reach_triangles() && v.triangle_count ? nlohmann::json(double(a.reach_triangles()->size()) / v.triangle_count)
                                              : nlohmann::json(nullptr);
  if (const auto* p = a.params())
    j["params"] = {{"rays", p->rays()}, {"spheres_per_level", p->spheres_per_level()}, {"disk_step", p->disk_step()},
                   {"penetration_depth", p->penetration_depth()}, {"pivots_per_sphere", p->pivots_per_sphere()},
                   {"segmentation", p->segmentation() ? p->segmentation()->str() : ""}};
  auto stats = [](const schema::AccuracyStats* s) -> nlohmann::json {
    if (!s) return nullptr;
    return {{"mean_abs_F", s->mean_abs_f()}, {"rms_F", s->rms_f()}, {"min_F", s->min_f()}, {"max_F", s->max_f()}};
  };
  if (const auto* acc = a.accuracy())
    j["accuracy"] = {{"phi1", stats(acc->phi1())}, {"phi1_adjusted", stats(acc->phi1_adjusted())},
                     {"phi2", stats(acc->phi2())}};
  // Schema v2: the fit, the contact margin and the bake's bind-pose coverage measure.
  j["fit"] = a.fit_method() ? a.fit_method()->str() : "paper";
  j["contact_margin"] = a.contact_margin();
  j["fold_margin"] = a.fold_margin() >= 0.0f ? nlohmann::json(a.fold_margin()) : nlohmann::json(nullptr);
  if (const auto* c = a.coverage())
    j["coverage"] = {{"coverage", c->coverage()},
                     {"protrusion", c->protrusion()},
                     {"outside_p95_rel", c->outside_p95_rel()},
                     {"outside_max_rel", c->outside_max_rel()},
                     {"voxel_rel", c->voxel_rel()}};
  // Plausibility checks the bake failed and was forced past (bake --force; validate reports them as errors).
  nlohmann::json forced = nlohmann::json::array();
  if (const auto* f = a.forced_findings())
    for (const auto* x : *f)
      forced.push_back({{"code", x->code() ? x->code()->str() : ""}, {"message", x->message() ? x->message()->str() : ""}});
  j["forced_findings"] = forced;
  return j;
}

int RunInspect(const InspectArgs& args) {
  LoadedAsset asset;
  std::string error;
  if (!LoadAssetFile(args.asset, &asset, &error)) return Fail(error);
  const nlohmann::json j = Describe(asset.view);
  if (args.json) {
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  std::printf("%s: spherechain asset, schema v%u, %zu bytes (%s)\n", args.asset.c_str(), j["schema_version"].get<unsigned>(),
              asset.size, j["generator"].get<std::string>().c_str());
  std::printf("mesh: %u vertices, %u triangles, %zu part(s), units %s, up %s\n", asset.view.vertex_count,
              asset.view.triangle_count, j["parts"].size(), j["units"].get<std::string>().c_str(),
              j["up_axis"].get<std::string>().c_str());
  for (const auto& p : j["parts"])
    std::printf("  part %-24s vertices %u+%u  triangles %u+%u\n", p["name"].get<std::string>().c_str(),
                p["first_vertex"].get<unsigned>(), p["vertices"].get<unsigned>(), p["first_triangle"].get<unsigned>(),
                p["triangles"].get<unsigned>());
  std::printf("spheres: %u\n", asset.view.sphere_count);
  for (uint32_t k = 0; k < runtime::RegionCount(asset.view); ++k) {  // in region order
    const std::string name = runtime::RegionName(asset.view, k);
    const auto& r = j["regions"][name];
    std::printf("  R%-2u %-10s triangles %6zu  spheres %3zu", k, name.c_str(), r["triangles"].get<size_t>(),
                r["spheres"].get<size_t>());
    if (r.contains("kind"))
      std::printf("  %s, from bone %s%s", r["kind"].get<std::string>().c_str(), r["bone"].get<std::string>().c_str(),
                  r.contains("mirror") ? (", mirror " + r["mirror"].get<std::string>()).c_str() : "");
    std::printf("\n");
  }
  std::printf("chains:");
  for (const auto& c : j["chains"]) std::printf(" %s=%zu", c["name"].get<std::string>().c_str(), c["spheres"].get<size_t>());
  std::printf(" (mean %.1f)\nexcluded pairs: %zu, unassigned triangles: %zu\n", j["mean_spheres_per_chain"].get<double>(),
              j["excluded_pairs"].get<size_t>(), j["unassigned_triangles"].get<size_t>());
  if (!j["reach_spheres_per_triangle"].is_null())
    std::printf("reach regions: a triangle stands behind %.2f spheres on average (the narrow phase behind the proxy's pairs)\n",
                j["reach_spheres_per_triangle"].get<double>());
  if (j.contains("accuracy"))
    for (const char* m : {"phi1", "phi1_adjusted", "phi2"})
      if (!j["accuracy"][m].is_null())
        std::printf("accuracy %-14s mean|F| %.4f  RMS %.4f\n", m, j["accuracy"][m]["mean_abs_F"].get<double>(),
                    j["accuracy"][m]["rms_F"].get<double>());
  std::printf("refit from joint matrices: %s\n",
              j["joint_refit"]["available"].get<bool>()
                  ? ("yes, " + std::to_string(j["joint_refit"]["joints"].get<unsigned>()) + " joints").c_str()
                  : "no (schema v1/v2 or a mesh without a skin: vertex refit only)");
  std::printf("fit: %s, contact margin %.4g (source units)", j["fit"].get<std::string>().c_str(),
              j["contact_margin"].get<double>());
  if (!j["fold_margin"].is_null())
    std::printf(", fold margin %.4g (pairs of one region)", j["fold_margin"].get<double>());
  std::printf("\n");
  if (j.contains("coverage")) {
    const auto& c = j["coverage"];
    std::printf("bind pose: coverage %.1f %% of the body volume, protrusion %.1f %% of the spheres' volume outside; "
                "outside distance p95 %.2f %%, max %.2f %% of height (voxels %.2f %% of height)\n",
                100 * c["coverage"].get<double>(), 100 * c["protrusion"].get<double>(),
                100 * c["outside_p95_rel"].get<double>(), 100 * c["outside_max_rel"].get<double>(),
                100 * c["voxel_rel"].get<double>());
  } else {
    std::printf("bind pose coverage: not recorded (schema v1 asset or paper fit; `spherechain evaluate` measures it)\n");
  }
  if (!j["forced_findings"].empty()) {
    std::printf("FORCED: baked with --force although %zu plausibility check(s) failed:\n", j["forced_findings"].size());
    for (const auto& f : j["forced_findings"])
      std::printf("  %s: %s\n", f["code"].get<std::string>().c_str(), f["message"].get<std::string>().c_str());
  }
  return 0;
}

}  // namespace

void RegisterInspect(CLI::App& app, Commands* commands) {
  auto args = std::make_shared<InspectArgs>();
  CLI::App* sub = app.add_subcommand("inspect", "Show what a .sphc asset holds (verified with the runtime loader)");
  sub->add_option("asset", args->asset, "Asset (.sphc)")->required();
  sub->add_flag("--json", args->json, "Print JSON instead of text");
  commands->handlers.emplace_back(sub, [args] { return RunInspect(*args); });
}

}  // namespace spherechain::cli
