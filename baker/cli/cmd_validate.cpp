// spherechain validate ASSET [--mesh INPUT] [--json OUT] — what a game's asset-validation CI runs.
#include <cstdio>
#include <vector>

#include <nlohmann/json.hpp>

#include "asset_file.h"
#include "commands.h"
#include "spherechain/baker/import.h"
#include "spherechain/runtime/runtime.h"

namespace spherechain::cli {

namespace {

struct ValidateArgs {
  std::string asset, mesh, json, rig;
};

/// One finding: a stable code, a severity and where it is.
struct Finding {
  std::string code, severity, location, message;
};

int RunValidate(const ValidateArgs& a) {
  std::vector<Finding> findings;
  auto add = [&](std::string code, std::string severity, std::string location, std::string message) {
    findings.push_back({std::move(code), std::move(severity), std::move(location), std::move(message)});
  };
  LoadedAsset asset;
  std::string error;
  const bool loaded = LoadAssetFile(a.asset, &asset, &error);
  if (!loaded) add("SPHC-LOAD", "error", a.asset, error);

  if (loaded && !a.mesh.empty()) {
    baker::ImportOptions opts;
    opts.rig_path = a.rig;
    opts.read_clips = false;
    auto mesh = baker::ImportMesh(a.mesh, opts);
    if (!mesh.ok()) {
      add("MESH-IMPORT", "error", a.mesh, mesh.error().message);
    } else {
      const baker::Fingerprint fp = baker::ComputeFingerprint(mesh.value());
      const auto* f = asset.view.asset->fingerprint();
      if (fp.vertex_count != f->vertex_count() || fp.triangle_count != f->triangle_count()) {
        add("FP-COUNTS", "error", a.mesh,
            "mesh has " + std::to_string(fp.vertex_count) + " vertices / " + std::to_string(fp.triangle_count) +
                " triangles, the asset was baked from " + std::to_string(f->vertex_count()) + " / " +
                std::to_string(f->triangle_count()));
      } else {
        if (fp.indices_hash != f->indices_hash())
          add("FP-INDICES", "error", a.mesh, "triangle indices differ from the baked mesh (re-bake the asset)");
        if (fp.positions_hash != f->positions_hash())
          add("FP-POSITIONS", "warning", a.mesh, "bind positions differ from the baked mesh (moved vertices?)");
        // The bind pose must report no self-collision.
        runtime::Model model;
        runtime::Workspace ctx;
        runtime::Status s = model.Init(asset.view);
        if (runtime::Succeeded(s)) s = ctx.Init(model);
        std::vector<runtime::Collision> pairs(runtime::DetectBound(asset.view, runtime::DetectMethod::kM2));
        uint32_t count = 0;
        if (runtime::Succeeded(s)) {
          runtime::RefitJob refit;
          refit.model = &model;
          refit.workspace = &ctx;
          refit.positions = {mesh->positions.data(), mesh->vertex_count(), 12};
          s = refit.Run();
        }
        if (runtime::Succeeded(s)) {
          runtime::DetectJob detect;
          detect.model = &model;
          detect.workspace = &ctx;
          detect.method = runtime::DetectMethod::kM2;
          detect.output = pairs.data();
          detect.capacity = uint32_t(pairs.size());
          detect.count = &count;
          s = detect.Run();
        }
        if (runtime::Failed(s)) add("RUNTIME", "error", a.asset, runtime::ToString(s));
        for (uint32_t i = 0; i < count; ++i)
          add("BIND-COLLISION", "error", "spheres " + std::to_string(pairs[i].a) + "," + std::to_string(pairs[i].b),
              "the bind pose reports a self-collision (depth " + std::to_string(pairs[i].depth) + ")");
      }
    }
  }
  size_t errors = 0;
  for (const Finding& f : findings) {
    errors += f.severity == "error";
    std::printf("%-7s %-15s %s: %s\n", f.severity.c_str(), f.code.c_str(), f.location.c_str(), f.message.c_str());
  }
  if (findings.empty()) std::printf("%s: valid%s\n", a.asset.c_str(), a.mesh.empty() ? "" : ", matches its mesh, bind pose collision-free");
  if (!a.json.empty()) {
    nlohmann::json j = {{"asset", a.asset}, {"mesh", a.mesh}, {"valid", errors == 0}, {"findings", nlohmann::json::array()}};
    for (const Finding& f : findings)
      j["findings"].push_back({{"code", f.code}, {"severity", f.severity}, {"location", f.location}, {"message", f.message}});
    if (auto s = baker::WriteFileAtomic(a.json, j.dump(2) + "\n"); !s.ok()) return Fail(s.error());
  }
  return errors ? 1 : 0;
}

}  // namespace

void RegisterValidate(CLI::App& app, Commands* commands) {
  auto args = std::make_shared<ValidateArgs>();
  CLI::App* sub = app.add_subcommand("validate", "Check an asset (and that it belongs to a mesh); non-zero exit on any error");
  sub->add_option("asset", args->asset, "Asset (.sphc)")->required();
  sub->add_option("--mesh", args->mesh, "The character file it should belong to (fingerprint, bind pose)");
  sub->add_option("--rig", args->rig, "MakeHuman rig (.mhskel), as for bake");
  sub->add_option("--json", args->json, "Write the findings as JSON");
  commands->handlers.emplace_back(sub, [args] { return RunValidate(*args); });
}

}  // namespace spherechain::cli
