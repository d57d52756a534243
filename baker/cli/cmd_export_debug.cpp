// spherechain export-debug ASSET --mesh INPUT -o OUT.gltf [--png OUT.png]
#include <cstdio>
#include <filesystem>

#include "asset_file.h"
#include "commands.h"
#include "spherechain/baker/debug_export.h"
#include "spherechain/baker/import.h"

namespace spherechain::cli {

namespace {

struct ExportArgs {
  std::string asset, mesh, output, png, rig;
};

int RunExport(const ExportArgs& a) {
  LoadedAsset asset;
  std::string error;
  if (!LoadAssetFile(a.asset, &asset, &error)) return Fail(error);
  baker::ImportOptions opts;
  opts.rig_path = a.rig;
  opts.read_clips = false;
  baker::Context ctx = MakeLoggingContext();
  auto mesh = baker::ImportMesh(a.mesh, opts, &ctx);
  if (!mesh.ok()) return Fail(mesh.error());
  if (auto s = baker::ExportDebugGltf(mesh.value(), asset.view, a.output); !s.ok()) return Fail(s.error());
  std::string png = a.png;
  if (png.empty()) png = std::filesystem::path(a.output).replace_extension(".png").string();
  if (auto s = baker::RenderDebugPng(mesh.value(), asset.view, png); !s.ok()) return Fail(s.error());
  std::printf("wrote %s (glTF: mesh coloured by region + %u spheres) and %s (front and side views)\n", a.output.c_str(),
              asset.view.sphere_count, png.c_str());
  return 0;
}

}  // namespace

void RegisterExportDebug(CLI::App& app, Commands* commands) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* sub = app.add_subcommand("export-debug", "Write a glTF (regions + spheres) and PNG views of a bake");
  sub->add_option("asset", args->asset, "Asset (.sphc)")->required();
  sub->add_option("--mesh", args->mesh, "The character file the asset was baked from")->required()->check(CLI::ExistingFile);
  sub->add_option("-o,--output", args->output, "glTF to write (.gltf, buffers embedded)")->required();
  sub->add_option("--png", args->png, "PNG to write (default: OUTPUT with .png)");
  sub->add_option("--rig", args->rig, "MakeHuman rig (.mhskel), as for bake");
  commands->handlers.emplace_back(sub, [args] { return RunExport(*args); });
}

}  // namespace spherechain::cli
