// spherechain validate ASSET [--mesh INPUT] [--json OUT] — what a game's asset-validation CI runs.
// Thin: the checks are playback::ValidateAssetFile (spherechain/playback/validate.h); this prints them.
#include <cstdio>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "spherechain/baker/write.h"
#include "spherechain/playback/validate.h"

namespace spherechain::cli {

namespace {

struct ValidateArgs {
  std::string asset, mesh, json, rig, vertices;
};

int RunValidate(const ValidateArgs& a) {
  if (int clash = OutputsClash({{"--json", &a.json}}, {{"ASSET", &a.asset}, {"--mesh", &a.mesh}, {"--rig", &a.rig}}))
    return clash;
  // Where the JSON goes, checked before the asset is read: a run that cannot write it is a usage error
  // (exit 2), never mistaken for an invalid asset (exit 1).
  if (!a.json.empty())
    if (const std::string why = OutputPathProblem(a.json); !why.empty()) return UsageError(why);
  import::Context log = MakeLoggingContext();
  const import::VertexContract vertices = a.vertices == "joined"   ? import::VertexContract::kJoined
                                        : a.vertices == "source" ? import::VertexContract::kSource
                                                                 : import::VertexContract::kAuto;
  const std::vector<playback::Finding> findings = playback::ValidateAssetFile(a.asset, a.mesh, a.rig, &log, vertices);
  const size_t errors = playback::CountErrors(findings);
  for (const playback::Finding& f : findings)
    std::printf("%-7s %-15s %s: %s\n", playback::ToString(f.severity), f.code.c_str(), f.location.ToString().c_str(),
                f.message.c_str());
  if (findings.empty()) Out("%s: valid%s\n", a.asset.c_str(), a.mesh.empty() ? "" : ", matches its mesh, bind pose collision-free");
  if (!a.json.empty()) {
    nlohmann::json j = {{"asset", a.asset}, {"mesh", a.mesh}, {"valid", errors == 0}, {"findings", nlohmann::json::array()}};
    for (const playback::Finding& f : findings) {
      nlohmann::json where = {{"file", f.location.file}};
      if (f.location.sphere >= 0) where["sphere"] = f.location.sphere;
      if (f.location.other_sphere >= 0) where["other_sphere"] = f.location.other_sphere;
      if (f.location.chain >= 0) where["chain"] = f.location.chain;
      if (!f.location.field.empty()) where["field"] = f.location.field;
      j["findings"].push_back({{"code", f.code}, {"severity", playback::ToString(f.severity)},
                               {"location", f.location.ToString()}, {"where", where}, {"message", f.message}});
    }
    if (auto s = import::WriteFileAtomic(a.json, JsonText(j) + "\n"); !s.ok()) return Fail(s.error());
  }
  return errors ? 1 : 0;
}

}  // namespace

void RegisterValidate(CLI::App& app, Commands* commands) {
  auto args = std::make_shared<ValidateArgs>();
  CLI::App* sub = app.add_subcommand(
      "validate",
      "Check an asset (loadable, every sphere in a chain and with a surrounding region) and, with --mesh, that it "
      "belongs to that mesh (fingerprint) and its bind pose reports no sphere pair. Prints one line per finding "
      "(severity, code, location, message); exit 1 on any error (warnings do not fail). C++: "
      "playback::ValidateAsset");
  sub->add_option("asset", args->asset, "Asset (.sphc)")->required();
  CLI::Option* mesh = sub->add_option("--mesh", args->mesh, "The character file it should belong to (fingerprint, bind pose)");
  sub->add_option("--rig", args->rig, "MakeHuman rig (.mhskel) of --mesh, as for bake")->needs(mesh);
  sub->add_option("--vertices", args->vertices,
                  "Vertex contract to read an assimp-format --mesh with, i.e. the buffer your game feeds: joined or "
                  "source (default: the one the asset records)")
      ->check(CLI::IsMember({"joined", "source"}))
      ->needs(mesh);
  sub->add_option("--json", args->json, "Write the findings as JSON (code, severity, location, where{file, sphere, other_sphere, chain, field}, message)");
  commands->handlers.emplace_back(sub, [args] { return RunValidate(*args); });
}

}  // namespace spherechain::cli
