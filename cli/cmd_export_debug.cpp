// spherechain export-debug ASSET --mesh INPUT -o OUT.gltf [--png OUT.png] [--clip NAME | --morph [POSES...]]
// Static (bind pose) by default; with --clip or --morph the glTF is animated (playback::ExportAnimatedGltf):
// the skinned character and the refit spheres as animated nodes, playable in any glTF viewer.
#include <cstdio>
#include <filesystem>

#include "animation_source.h"
#include "commands.h"
#include "spherechain/import/vertex_contract.h"
#include "spherechain/playback/debug_export.h"
#include "spherechain/import/import.h"
#include "spherechain/playback/debug_gltf.h"

namespace spherechain::cli {

namespace {

struct ExportArgs {
  std::string asset, output, png, rig, refit = "frame";
  AnimationArgs anim;  // --mesh, --clip, --morph, --poses-dir, --frames
};

int RunExport(const ExportArgs& a) {
  // The PNG's path first (default: -o with .png), so that an -o ending in .png clashes with it.
  std::string png = a.png;
  if (png.empty()) png = std::filesystem::path(a.output).replace_extension(".png").string();
  if (int clash = OutputsClash({{"-o", &a.output}, {a.png.empty() ? "the picture (-o with .png)" : "--png", &png}},
                               {{"ASSET", &a.asset}, {"--mesh", &a.anim.mesh}, {"--rig", &a.rig}}, PoseInputs(a.anim)))
    return clash;
  const bool animated = !a.anim.clip.empty() || a.anim.morph_requested();
  LoadedAsset asset;
  import::Mesh mesh;
  std::string error;
  // The mesh checked against the asset's fingerprint (a mesh of other triangles would be coloured wrongly).
  if (!OpenAssetAndMesh(a.asset, a.anim.mesh, a.rig, &asset, &mesh, &error)) return Fail(error);
  // Everything that can be refused before anything is written: the animation, the output folders.
  AnimationSource anim;
  if (animated && !OpenAnimation(mesh, a.anim, &anim, &error)) return Fail(error);
  for (const std::string* out : std::initializer_list<const std::string*>{&a.output, &png}) {
    if (const std::string why = OutputPathProblem(*out); !why.empty()) return Fail(why);
  }
  // All or nothing: the PNG and the glTF are written to temporaries and renamed into place once both are
  // written, so a failure leaves an earlier run's files as they were. The PNG first: it needs an outside
  // tool (rsvg-convert). The glTF's temporary keeps its extension (.glb: binary).
  import::OutputFiles outputs;
  if (auto s = playback::RenderDebugPng(mesh, asset.view, outputs.Stage(png, ".png")); !s.ok())
    return Fail(outputs.Explain(s.error()));
  const std::string gltf = outputs.Stage(a.output, std::filesystem::path(a.output).extension().string());
  if (animated) {
    playback::AnimatedGltfStats stats;
    const runtime::RefitMode mode = a.refit == "paper" ? runtime::RefitMode::kPaper : runtime::RefitMode::kPivotFrame;
    import::Status s = import::Ok{};
    try {  // out of memory (a huge --frames) or a writer's exception: nothing of this run written
      s = playback::ExportAnimatedGltf(mesh, asset.view, anim, gltf, mode, &stats);
    } catch (const std::exception& e) {
      return Fail(std::string("export-debug: the animated glTF of '") + a.output + "': " + e.what());
    }
    if (!s.ok()) return Fail(outputs.Explain(s.error()));
    if (auto c = outputs.Commit(); !c.ok()) return Fail(c.error());
    Out("wrote %s (animated glTF: %s, %u frames; skinned mesh coloured by region, %u joints' nodes, %u "
                "spheres as animated nodes; %u channels, %.1f MB)\n",
                a.output.c_str(), anim.Describe().c_str(), stats.frames, stats.skeleton_nodes, stats.spheres,
                stats.channels, double(stats.bytes) / 1e6);
  } else {
    if (auto s = playback::ExportDebugGltf(mesh, asset.view, gltf); !s.ok()) return Fail(outputs.Explain(s.error()));
    if (auto c = outputs.Commit(); !c.ok()) return Fail(c.error());
  }
  if (animated)
    Out("wrote %s (front and side views, bind pose)\n", png.c_str());
  else
    Out("wrote %s (glTF: mesh coloured by region + %u spheres) and %s (front and side views)\n",
                a.output.c_str(), asset.view.sphere_count, png.c_str());
  return 0;
}

}  // namespace

void RegisterExportDebug(CLI::App& app, Commands* commands) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* sub = app.add_subcommand(
      "export-debug",
      "Write a glTF (regions + spheres) and PNG views of a bake; with --clip NAME or --morph the glTF is animated: "
      "the skinned character and the refit spheres as animated nodes (one glTF animation), for any glTF viewer");
  AddAnimationOptions(sub, &args->asset, &args->rig, &args->anim);
  sub->add_option("-o,--output", args->output, "glTF to write (.gltf: buffers embedded; .glb: binary glTF)")->required();
  sub->add_option("--png", args->png, "PNG to write (default: OUTPUT with .png)");
  sub->add_option("--refit", args->refit, "Sphere refit of an animated export: paper or frame (pivot frame, default, as play)")
      ->check(CLI::IsMember({"paper", "frame"}));
  commands->handlers.emplace_back(sub, [args, sub] {
    // A static export is the bind pose: an animation's options without an animation are a mistake, not ignored.
    if (args->anim.clip.empty() && !args->anim.morph_requested())
      for (const char* option : {"--frames", "--refit", "--poses-dir"})
        if (sub->count(option)) return UsageError(std::string(option) + " needs --clip or --morph (without them export-debug writes the bind pose)");
    return RunExport(*args);
  });
}

}  // namespace spherechain::cli
