// spherechain bake INPUT -o OUT.sphc [--report R.json] [--config C.json] [--depfile OUT.d] ...
// spherechain bake INPUT... --out-dir DIR [-j N]   (several inputs: bake_batch.cpp)
#include <cstdio>

#include <spdlog/spdlog.h>

#include "bake_batch.h"
#include "commands.h"
#include "spherechain/baker/coverage.h"
#include "spherechain/baker/bake.h"
#include "spherechain/import/file_io.h"
#include "spherechain/playback/debug_export.h"

namespace spherechain::cli {

namespace {

struct BakeArgs {
  std::vector<std::string> inputs;
  std::string output, out_dir, report, config, ray_csv, png, depfile;
  unsigned jobs = 1;
  baker::BakeOptions options;  // --regions, --segmentation, --region-map, --vertices, --rig, --disk-step, --force
};

void PrintSummary(const baker::BakeResult& r, const import::Context& ctx) {
  using import::Region;
  const import::RegionLayout& layout = r.segmentation.layout;
  Out("\n%-10s %10s %8s\n", "region", "triangles", "spheres");
  for (int k = 0; k < layout.count(); ++k) {
    const Region reg = static_cast<Region>(k);
    size_t tris = 0, sph = 0;
    for (uint8_t t : r.segmentation.triangle_regions) tris += t == k;
    for (const auto& s : r.fit.spheres) sph += s.region == reg;
    Out("%-3s %-6s %10zu %8zu", import::RegionSymbol(reg), layout.Name(reg), tris, sph);
    if (!layout.paper)
      Out("   %s, from bone %s", layout.IsTrunk(reg) ? "trunk" : "limb", layout.regions[size_t(k)].bone.c_str());
    Out("\n");
  }
  Out("%-10s %10u %8zu   (unassigned triangles: %u)\n", "total", r.mesh.triangle_count(), r.fit.spheres.size(),
              r.unassigned_triangles);
  Out("vertices: %u (contract %s", r.mesh.vertex_count(), r.mesh.vertex_contract.c_str());
  if (r.mesh.source_vertex_count) Out("; source %u, joined %u", r.mesh.source_vertex_count, r.mesh.joined_vertex_count);
  Out(")\n");
  Out("\nchains:");
  for (const auto& c : r.chains) Out(" %s=%zu", c.name.c_str(), c.spheres.size());
  Out("   excluded pairs: %zu\n", r.excluded.size());
  if (r.agreement)
    Out("segmentation: %s; agreement with %s: %.1f%% of triangles, %.1f%% of area\n",
                r.segmentation.method.c_str(), r.other_segmentation->method.c_str(),
                100.0 * r.agreement->triangle_fraction, 100.0 * r.agreement->area_fraction);
  else
    Out("segmentation: %s\n", r.segmentation.method.c_str());
  if (r.plausibility.empty()) {
    Out("plausibility: every check passed\n");
  } else {
    Out("plausibility: %zu check(s) FAILED, written anyway (--force; recorded in the asset, validate "
                "reports them as errors):\n", r.plausibility.size());
    for (const auto& f : r.plausibility) Out("  %s: %s\n", f.code.c_str(), f.message.c_str());
  }
  if (r.coverage)
    Out("bind pose: coverage %.1f %% of the body volume, protrusion %.1f %% (outside: p95 %.2f %% of height); "
                "skin outside the spheres: p95 %.2f %% of height, %.1f %% of its area within %.1f %%\n",
                100 * r.coverage->coverage, 100 * r.coverage->protrusion, 100 * r.coverage->outside_p95_rel,
                100 * r.coverage->skin_outside_p95_rel, 100 * r.coverage->skin_within_share, 100 * baker::kSkinWithinRel);
  Out("\naccuracy F = r - |c - v| over surrounding-region vertices\n");
  Out("%-14s %10s %10s %10s %10s\n", "method", "mean|F|", "RMS", "min", "max");
  auto row = [](const char* n, const baker::AccuracyStats& s) {
    Out("%-14s %10.4f %10.4f %10.4f %10.4f\n", n, s.mean_abs_f, s.rms_f, s.min_f, s.max_f);
  };
  row("phi1", r.accuracy.phi1);
  row("phi1' (adj.)", r.accuracy.phi1_adjusted);
  row("phi2 (MEB)", r.accuracy.phi2);
  Out("\ntimings (ms):");
  double total = 0;
  for (const auto& [n, ms] : ctx.timings_ms) {
    Out(" %s=%.1f", n.c_str(), ms);
    if (n.find('.') == std::string::npos) total += ms;  // "a.b" is a sub-stage of "a"
  }
  Out("  total=%.1f\n", total);
}

int RunBake(const BakeArgs& a) {
  const bool batch = !a.out_dir.empty();
  if (batch && !a.output.empty()) return UsageError("bake: give -o (one input) or --out-dir (any number), not both");
  if (!batch && a.output.empty()) return UsageError("bake: -o OUT.sphc is required (or --out-dir DIR)");
  if (!batch && a.inputs.size() > 1)
    return UsageError("bake: " + std::to_string(a.inputs.size()) + " inputs need --out-dir DIR (-o names one asset)");
  if (batch)
    for (const std::string* per_file : {&a.report, &a.ray_csv, &a.png, &a.depfile})
      if (!per_file->empty())
        return UsageError("bake: --report, --ray-csv, --png and --depfile name one file: with --out-dir, bake each "
                          "input on its own with -o to get them");

  // An output that would overwrite an input or another output: refused before anything is read.
  const std::string no_input;
  if (!batch)
    if (int clash = OutputsClash({{"-o", &a.output}, {"--report", &a.report}, {"--ray-csv", &a.ray_csv},
                                  {"--png", &a.png}, {"--depfile", &a.depfile}},
                                 {{"the input", a.inputs.empty() ? &no_input : &a.inputs.front()}, {"--config", &a.config},
                                  {"--region-map", &a.options.region_map}, {"--rig", &a.options.rig}}))
      return clash;
  import::Context ctx = MakeLoggingContext();  // records the files read, the configuration's too (--depfile)
  baker::BakeConfig config;
  if (!a.config.empty()) {
    auto c = baker::LoadBakeConfig(a.config, &ctx);
    if (!c.ok()) return Fail(c.error());
    config = std::move(c).value();
  }
  if (auto s = baker::ApplyBakeOptions(a.options, &config); !s.ok()) return Fail(s.error());
  if (batch) return RunBatchBake(a.inputs, a.out_dir, a.jobs, config);

  // Fail before the work when an output cannot be written: exit 1 and an io: error, as a failed write (a build
  // system's rule sees the same failure either way).
  for (const std::string* out : {&a.output, &a.report, &a.ray_csv, &a.png, &a.depfile}) {
    if (out->empty()) continue;
    if (const std::string why = OutputPathProblem(*out); !why.empty())
      return Fail(import::Error{import::Error::Code::kIo, why});
  }
  auto result = baker::Bake(a.inputs.front(), config, &ctx);
  if (!result.ok()) return Fail(result.error());
  const baker::BakeResult& r = result.value();
  // Every file the bake read (glTF buffers, a rig, its weights...), now that they are known.
  if (int clash = OutputsClash({{"-o", &a.output}, {"--report", &a.report}, {"--ray-csv", &a.ray_csv}, {"--png", &a.png},
                                {"--depfile", &a.depfile}},
                               {}, ctx.files_read))
    return clash;
  std::string depfile;  // made before anything is written: a path it cannot name fails the bake
  if (!a.depfile.empty()) {
    auto d = import::MakeDepfile(a.output, ctx.files_read);
    if (!d.ok()) return Fail(d.error());
    depfile = std::move(d).value();
  }

  // Everything is in memory. All or nothing: every output is written whole to a temporary beside its path,
  // then all are renamed into place, the asset after the files about it and the depfile last (it names an
  // asset that is there). When one cannot be written, none is renamed and an earlier run's outputs stay as
  // they were, a consistent set that a build system sees as out of date (the command failed).
  import::OutputFiles outputs;
  if (!a.png.empty()) {  // first: it needs an outside tool, rsvg-convert
    runtime::AssetView view;
    if (runtime::Failed(runtime::LoadAsset(r.asset.data(), r.asset.size(), &view)))
      return Fail("internal: the baked asset does not load");
    if (auto s = playback::RenderDebugPng(r.mesh, view, outputs.Stage(a.png, ".png")); !s.ok())
      return Fail(outputs.Explain(s.error()));
  }
  if (!a.report.empty())
    if (auto s = outputs.Write(a.report, JsonText(baker::MakeBakeReport(r, config, ctx)) + "\n"); !s.ok())
      return Fail(s.error());
  if (!a.ray_csv.empty())
    if (auto s = outputs.Write(a.ray_csv, baker::TorsoRayCsv(r)); !s.ok()) return Fail(s.error());
  if (auto s = outputs.Write(a.output, r.asset.data(), r.asset.size()); !s.ok()) return Fail(s.error());
  if (!a.depfile.empty())
    if (auto s = outputs.Write(a.depfile, depfile); !s.ok()) return Fail(s.error());
  if (auto s = outputs.Commit(); !s.ok()) return Fail(s.error());
  PrintSummary(r, ctx);
  Out("\nwrote %s (%zu bytes)", a.output.c_str(), r.asset.size());
  if (!a.report.empty()) Out(", %s", a.report.c_str());
  if (!a.ray_csv.empty()) Out(", %s", a.ray_csv.c_str());
  if (!a.png.empty()) Out(", %s", a.png.c_str());
  if (!a.depfile.empty()) Out(", %s", a.depfile.c_str());
  Out("\n");
  return 0;
}

}  // namespace

void RegisterBake(CLI::App& app, Commands* commands) {
  auto args = std::make_shared<BakeArgs>();
  CLI::App* sub = app.add_subcommand("bake", "Bake a character into a .sphc sphere-chain asset (paper §3-§5.1)");
  sub->add_option("input", args->inputs,
                  "Character file(s): .gltf/.glb (tinygltf); .obj (own reader); .fbx .dae .x .blend ... (assimp). Several: with --out-dir")
      ->required();
  sub->add_option("-o,--output", args->output, "Asset to write (.sphc); written atomically");
  sub->add_option("--out-dir", args->out_dir,
                  "Bake each input into DIR/<input stem>.sphc (created when missing), each on its own: a failed input "
                  "writes nothing and stops nothing; a summary table at the end; exit 1 when any failed");
  sub->add_option("-j,--jobs", args->jobs, "With --out-dir: bakes at a time (default 1; 0: one per core)");
  sub->add_option("--depfile", args->depfile,
                  "Makefile-syntax dependency file to write: the asset's rule naming every file the bake read (input, "
                  "glTF buffers and images, rig and weights, config, region map), for Make, Ninja and CMake DEPFILE; "
                  "written last, atomically, and only when the bake succeeded");
  sub->add_option("--report", args->report, "JSON bake report to write");
  sub->add_option("--config", args->config, "JSON bake configuration (parameters, chains, segmentation)")
      ->check(CLI::ExistingFile);
  sub->add_option("--rig", args->options.rig, "MakeHuman rig (.mhskel) for an OBJ; default: default.mhskel beside the OBJ");
  sub->add_option("--segmentation", args->options.segmentation,
                  "auto (rig when rigged, else geometry; a rigged creature that is no standing body: skeleton), rig, "
                  "geometry, skeleton (the any-skeleton path: limbs branching off the trunk of the bone tree), map")
      ->check(CLI::IsMember({"auto", "rig", "geometry", "skeleton", "map"}));
  sub->add_option("--regions", args->options.regions,
                  "Regions of a standing biped: extended (default: arms, legs, head, hands, feet and the torso, "
                  "ten regions whose chains let a hand meet the face and a foot the other leg) or paper (the "
                  "paper's five: arms, legs, torso with the head; Table 1's six chains); overrides the config's "
                  "\"regions\". Creatures keep their own")
      ->check(CLI::IsMember({"paper", "extended"}));
  sub->add_option("--vertices", args->options.vertices,
                  "Vertex contract for assimp formats (.x .fbx .dae ...): joined (default; what engines' importers "
                  "give: aiProcess_JoinIdenticalVertices) or source (the importer's own buffer); recorded in the "
                  "asset. glTF/OBJ: no-op with a warning (their buffer is the engine's)")
      ->check(CLI::IsMember({"joined", "source"}));
  sub->add_flag("--force", args->options.force,
                "Write the asset even when a plausibility check fails (a limb in pieces or detached from the "
                "torso, left/right imbalance, the head in a limb, a lying trunk, spheres outside the body, rig "
                "and geometry segmentations disagreeing). Without it such a bake exits 1 naming each failed "
                "check (PLAUS-... code, what and where) and writes nothing; with it the findings are printed, "
                "go to the report as errors and into the asset, where `validate` reports them as errors");
  sub->add_flag("--skin-weights", args->options.skin_weights,
                "Also write the skin weights per vertex (about 3 bytes an influence: +134 KB for MakeHuman), so that "
                "a narrow phase given the joint matrices skips neighbouring skin that moved rigidly (config "
                "\"skin_weights\")");
  sub->add_option("--region-map", args->options.region_map,
                  "JSON region map {\"triangle_regions\": [...]} of region values or names (implies map); "
                  "\"regions\": [names] makes a creature's layout (limbs, the trunk last)");
  sub->add_option("--disk-step", args->options.disk_step,
                  "Torso disk step delta in source units (default, or 0: relative to height)")
      ->check(WithinRange(0.0, 1e9));  // the configuration key's limit; 0: the default
  sub->add_option("--ray-csv", args->ray_csv, "CSV of the paper's per-ray comparison for the torso spheres");
  sub->add_option("--png", args->png, "PNG views (front and side) of regions and spheres (needs rsvg-convert)");
  commands->handlers.emplace_back(sub, [args] { return RunBake(*args); });
}

}  // namespace spherechain::cli
