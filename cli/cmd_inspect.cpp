// spherechain inspect ASSET [--json]
#include <cstdio>

#include <nlohmann/json.hpp>

#include "animation_source.h"
#include "commands.h"
#include "spherechain/evaluate/inspect.h"

namespace spherechain::cli {

namespace {

struct InspectArgs {
  std::string asset;
  bool json = false;
};

int RunInspect(const InspectArgs& args) {
  LoadedAsset asset;
  std::string error;
  if (!LoadAssetFile(args.asset, &asset, &error)) return Fail(error);
  const nlohmann::json j = evaluate::DescribeAsset(asset.view);
  if (args.json) {
    std::printf("%s\n", JsonText(j).c_str());
    return 0;
  }
  std::printf("%s: spherechain asset, schema v%u, %zu bytes (%s)\n", args.asset.c_str(), j["schema_version"].get<unsigned>(),
              asset.size, j["generator"].get<std::string>().c_str());
  std::printf("mesh: %u vertices, %u triangles, %zu part(s), units %s, up %s, vertex contract %s\n",
              asset.view.vertex_count, asset.view.triangle_count, j["parts"].size(), j["units"].get<std::string>().c_str(),
              j["up_axis"].get<std::string>().c_str(), j["vertex_contract"].get<std::string>().c_str());
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
      std::printf("  %s%s%s", r["kind"].get<std::string>().c_str(),
                  r["bone"].get<std::string>().empty() ? "" : (", from bone " + r["bone"].get<std::string>()).c_str(),
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
  if (!j["skin_contacts"]["crease"].is_null())
    std::printf("skin contacts: the crease rule, crease %.4g (source units); skin weights for the joint-matrix cull: %s\n",
                j["skin_contacts"]["crease"].get<double>(),
                j["skin_contacts"]["skin_weights"].get<bool>() ? "yes" : "no (bake --skin-weights)");
  else
    std::printf("skin contacts: no crease rule (baked before it): the narrow phase's exclusion-based definition only; "
                "re-bake for the skin's own\n");
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
