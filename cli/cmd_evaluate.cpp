// spherechain evaluate ASSET --mesh INPUT [--clip NAME | --morph POSES...] [--frames N] [--margin REL] [--crease REL]
//                      [--refit paper|frame|joints] [--regions asset|paper] [--json OUT] [--png OUT] [--min-recall R]
//                      [--no-coverage] [--sweep-margin[=M1,M2,...]]
//
// Measures the proxy against the truth (spherechain/evaluate/evaluate.h says what and how): opens the character
// and its animation, runs evaluate::Evaluate, prints its table and writes its JSON; --min-recall turns the
// region-pair recall into the exit code (a game's CI).
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>


#include "animation_source.h"
#include "commands.h"
#include "spherechain/evaluate/evaluate.h"

namespace spherechain::cli {

namespace {

struct EvaluateArgs {
  std::string asset, rig, json, png, refit = "frame", regions = "asset";
  AnimationArgs anim;  // --mesh, --clip, --morph, --poses-dir, --frames
  double margin = 0.01;
  double crease = 0.03;  // --crease: the asset-independent truth's bind-distance bound, fraction of the height
  double min_recall = std::numeric_limits<double>::quiet_NaN();  // NaN: not given
  CLI::Option* min_recall_option = nullptr;
  bool coverage = true;
  std::string sweep;  // "" (no sweep), "auto" (the default margins) or a comma-separated list of fractions of height
};

int RunEvaluate(const EvaluateArgs& a) {
  if (int clash = OutputsClash({{"--json", &a.json}, {"--png", &a.png}},
                               {{"ASSET", &a.asset}, {"--mesh", &a.anim.mesh}, {"--rig", &a.rig}}, PoseInputs(a.anim)))
    return clash;
  // ---- arguments that need no file: usage errors (exit 2; the line Python's EvaluateError carries too),
  // before any frame is computed ------------------------------------------------------------------------
  if (a.min_recall_option && a.min_recall_option->count() > 0 && !(a.min_recall >= 0.0 && a.min_recall <= 1.0))
    return UsageError("--min-recall " + std::to_string(a.min_recall) + " is outside [0, 1]");
  if (!(a.margin >= 0.0 && a.margin < 1.0)) return UsageError("--margin must be in [0, 1) (a fraction of the body height)");
  if (!a.png.empty() && a.png == a.json) return UsageError("--png and --json name the same file");
  evaluate::EvaluateOptions options;
  if (auto s = evaluate::ParseSweepMargins(a.sweep, &options.sweep_margins_rel); !s.ok()) return UsageError(s.error().message);
  for (const std::string* out : {&a.json, &a.png}) {  // where the outputs go, checked before minutes of frames
    if (out->empty()) continue;
    if (const std::string why = OutputPathProblem(*out); !why.empty()) return UsageError(why);
  }

  LoadedAsset asset;
  import::Mesh mesh;
  std::string error;
  if (!OpenAssetAndMesh(a.asset, a.anim.mesh, a.rig, &asset, &mesh, &error)) return Fail(error);
  AnimationSource anim;
  if (!OpenAnimation(mesh, a.anim, &anim, &error)) return Fail(error);

  options.asset_name = a.asset;
  options.mesh_name = a.anim.mesh;
  options.margin_rel = a.margin;
  options.crease_rel = a.crease;
  options.refit = a.refit;
  options.paper_regions = a.regions == "paper";
  options.coverage = a.coverage;
  // The picture and the JSON written all or nothing: both renamed into place once both are written.
  import::OutputFiles outputs;
  if (!a.png.empty()) options.png_path = outputs.Stage(a.png, ".png");
  const bool tty = isatty(2);
  if (!Quiet()) options.progress = [tty](uint32_t done, uint32_t frames, double elapsed) {
    if (tty) {
      std::fprintf(stderr, "\revaluate: frame %u/%u  %.1f s", done, frames, elapsed);
      if (done == frames) std::fprintf(stderr, "\n");
    } else if (done % 10 == 0 || done == frames) {
      std::fprintf(stderr, "evaluate: frame %u/%u  %.1f s\n", done, frames, elapsed);
    }
  };
  import::Context log = MakeLoggingContext();
  auto result = evaluate::Evaluate(asset.view, mesh, anim, options, &log);
  if (!result.ok()) return Fail(outputs.Explain(result.error()));
  const evaluate::Evaluation& e = result.value();
  if (!Quiet()) std::fputs(e.text.c_str(), stdout);
  if (!a.json.empty())
    if (auto s = outputs.Write(a.json, JsonText(e.report) + "\n"); !s.ok()) return Fail(s.error());
  if (auto s = outputs.Commit(); !s.ok()) return Fail(s.error());
  if (e.png_frame >= 0) Out("wrote %s (frame %d)\n", a.png.c_str(), e.png_frame);
  if (!a.json.empty()) Out("wrote %s\n", a.json.c_str());
  if (!std::isnan(a.min_recall)) {
    const double recall = std::min(e.recall_m1, e.recall_m2);
    if (recall < a.min_recall) {
      std::fprintf(stderr, "error: proxy recall %.3f (region pairs, min of M1 and M2) is below --min-recall %.3f\n", recall,
                   a.min_recall);
      return 1;
    }
    Out("proxy recall %.3f >= --min-recall %.3f\n", recall, a.min_recall);
  }
  return 0;
}

}  // namespace

void RegisterEvaluate(CLI::App& app, Commands* commands) {
  auto args = std::make_shared<EvaluateArgs>();
  CLI::App* sub = app.add_subcommand(
      "evaluate",
      "Measure the proxy against exact triangle intersection of the deformed mesh, frame by frame: the proxy's "
      "recall and false alarms, the narrow phase's recall and precision, bind-pose coverage and protrusion");
  AddAnimationOptions(sub, &args->asset, &args->rig, &args->anim);
  sub->add_option("--margin", args->margin,
                  "A reported region pair is a false alarm when no triangles of the two regions come within this "
                  "distance, as a fraction of the body height (default 0.01)");
  sub->add_option("--crease", args->crease,
                  "The asset-independent truth counts intersecting triangles whose bind-pose centroids lie at least "
                  "this far apart, as a fraction of the body height (default 0.03; nearer pairs are skin folding at "
                  "a joint); printed and in the JSON as contacts_by_bind_distance. Wider than the asset's crease, it "
                  "also widens the skin contacts' definition (the geodesic crease) and their narrow phase")
      ->check(WithinRange(0.0, 1.0));
  sub->add_option("--refit", args->refit,
                  "Refit: paper, frame (default; both from the deformed vertices) or joints (JointRefitJob: the centres "
                  "skinned by the frame's joint matrices, what a GPU-skinned game runs; needs a rigged input)")
      ->check(CLI::IsMember({"paper", "frame", "joints"}));
  sub->add_option("--regions", args->regions,
                  "Region pairs by the asset's regions (default) or by the paper's five (paper: an extended asset's "
                  "hands count as arms, feet as legs, the head as the torso — comparable with a paper-layout asset)")
      ->check(CLI::IsMember({"asset", "paper"}));
  sub->add_option("--json", args->json, "Write per-frame results and the summary as JSON");
  sub->add_option("--png", args->png,
                  "Write a picture of the frame with the most missed contacts: contact triangles red (missed) / amber "
                  "(found) and the refit spheres");
  args->min_recall_option = sub->add_option("--min-recall", args->min_recall,
                  "Exit 1 when the proxy's region-pair recall (the lower of M1 and M2) is below this, in [0, 1] "
                  "(for a game's CI)");
  sub->add_flag("!--no-coverage", args->coverage, "Skip the coverage / protrusion measurements (bind pose, and the refit spheres on every frame)");
  sub->add_option("--sweep-margin", args->sweep,
                  "Also run M1 and M2 with other contact margins (fractions of the body height, comma-separated; "
                  "alone: 0,0.001,...,0.015) and print recall and false alarms against the margin, and the recall of the "
                  "narrow phase run behind M2's pairs at each margin (no false alarm: it is exact); JSON: margin_sweep")
      ->expected(0, 1)
      ->default_str("auto");
  commands->handlers.emplace_back(sub, [args] { return RunEvaluate(*args); });
}

}  // namespace spherechain::cli
