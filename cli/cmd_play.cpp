// spherechain play ASSET --mesh INPUT [--clip NAME | --morph POSES...] [--frames N] [--method m1|m2|both]
//                  [--refit paper|frame|joints] [--json OUT] [--poses-dir DIR] [--rig MHSKEL] [--repeat R]
//
// Plays an animation of the character the asset was baked from — a skinned clip, or the paper's
// Bézier morph through key poses (§5.1, §6: 40 frames) — and runs the runtime on every frame: refit
// the spheres to the skinned vertices, detect overlapping sphere pairs with M1 (chains) and/or M2 (all
// spheres) (§5.2). Prints a per-frame table (pairs, timings, which regions touch) and a summary.
// Thin: the playing is playback::Play (spherechain/playback/play.h); this parses, prints and writes JSON.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "animation_source.h"
#include "commands.h"
#include "spherechain/baker/write.h"
#include "spherechain/playback/play.h"

namespace spherechain::cli {

namespace {

namespace fs = std::filesystem;

struct PlayArgs {
  std::string asset, json, rig, dump_frames, method = "both", refit = "frame";
  AnimationArgs anim;  // --mesh, --clip, --morph, --poses-dir, --frames
  uint32_t repeat = 5;
  bool narrow_phase = false;
  bool asset_exclusions = false;
  float narrow_behind = 0.0f;  // --narrow-behind: the narrow phase behind M2's pairs at this × the asset's margin
};

nlohmann::json RegionsJson(const std::vector<std::pair<int, int>>& pairs) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& [ra, rb] : pairs) a.push_back("R" + std::to_string(ra) + "-R" + std::to_string(rb));
  return a;
}

/// The per-frame table and the summary, on stdout.
void PrintReport(const PlayArgs& a, const runtime::AssetView& view, const AnimationSource& anim,
                 const playback::PlayOptions& opts, const playback::PlayReport& report) {
  const uint32_t frames = anim.frames;
  const bool joints = opts.refit == playback::PlayRefit::kJoints;
  const playback::PlaySummary& sum = report.summary;
  const std::vector<playback::FrameReport>& rows = report.frames;
  const playback::FrameReport& bind = report.bind;
  Out("play: %s + %s — %s, %u frames, %u spheres, %u chains, refit %s, timings = min of %u runs\n",
              a.asset.c_str(), a.anim.mesh.c_str(), report.animation.c_str(), frames, view.sphere_count,
              view.chain_count, a.refit.c_str(), std::max(1u, a.repeat));
  if (const std::string legend = RegionLegendLine(view); !legend.empty()) Out("%s\n", legend.c_str());
  if (!anim.clip) {
    Out("key poses:");
    for (size_t k = 0; k < anim.poses.size(); ++k)
      Out(" %s@%u", anim.poses[k].name.c_str(),
                  playback::MorphKeyFrame(uint32_t(k), frames, uint32_t(anim.poses.size())));
    Out("\n");
  }
  Out("\n%5s  %-26s %7s %7s %8s %7s %8s %8s %9s %9s", "frame", "pose", "testsM1", "M1 raw", "M1 dist", "M2",
              "testsM2", "refit us", "M1 us", "M2 us");
  if (opts.narrow_phase) Out(" %8s %8s %9s", "contacts", "tri tests", "narrow us");
  Out("  %s%s\n", "regions touching", opts.narrow_phase ? " | regions in contact (narrow phase)" : "");
  auto print_row = [&](const playback::FrameReport& r, const std::string& frame) {
    Out("%5s  %-26s %7u %7u %8u %7u %8u %8.1f %9.1f %9.1f", frame.c_str(), r.label.c_str(), r.m1.tests,
                r.m1.raw_pairs, r.m1.distinct_pairs, r.m2.distinct_pairs, r.m2.tests, r.refit_us, r.detect_m1_us,
                r.detect_m2_us);
    if (opts.narrow_phase) Out(" %8u %8u %9.1f", r.narrow.contacts, r.narrow.triangle_tests, r.narrow_us);
    Out("  %s", playback::RegionPairsText(r.regions).c_str());
    if (opts.narrow_phase) Out(" | %s", playback::RegionPairsText(r.contact_regions).c_str());
    if (!r.contact_region_depth.empty())
      Out(" (deepest %.3g)", double(*std::max_element(r.contact_region_depth.begin(), r.contact_region_depth.end())));
    Out("\n");
  };
  print_row(bind, "bind");
  for (const playback::FrameReport& r : rows) print_row(r, std::to_string(r.frame));

  Out("\nsummary: %u frames, %u with collisions; bind pose: M1 %u pairs, M2 %u pairs\n", frames,
              sum.frames_with_pairs, bind.m1.distinct_pairs, bind.m2.distinct_pairs);
  if (opts.m1)
    Out("  M1: mean %.1f raw / %.1f distinct pairs (max raw %u), %u tests, detect mean %.1f us\n",
                sum.mean_pairs_m1_raw, sum.mean_pairs_m1, sum.max_pairs_m1_raw, rows.empty() ? 0u : rows[0].m1.tests,
                sum.mean_detect_m1_us);
  if (opts.m2)
    Out("  M2: mean %.1f pairs (max %u), %u tests, detect mean %.1f us\n", sum.mean_pairs_m2, sum.max_pairs_m2,
                rows.empty() ? 0u : rows[0].m2.tests, sum.mean_detect_m2_us);
  Out("  refit (%s): mean %.1f us; tracking |dF| vs bind over surrounding-region vertices: mean %.4f, max %.4f\n",
              a.refit.c_str(), sum.mean_refit_us, sum.tracking_mean, sum.tracking_max);
  if (joints)
    Out("  joint refit vs vertex refit (pivot frame), centre distance / radius over spheres x frames: "
                "median %.2f %%, p95 %.2f %%, max %.2f %%\n",
                sum.joint_error_median, sum.joint_error_p95, sum.joint_error_max);
  if (opts.narrow_phase) {
    Out("  narrow phase");
    if (opts.narrow_behind_margin > 0.0f && opts.crease && view.asset->crease() > 0.0f)
      Out(" (the crease rule) behind M2's pairs at %g x the contact margin and the proxy's folds (reach regions; the "
          "M2 run and the folds included)", double(opts.narrow_behind_margin));
    else if (opts.narrow_behind_margin > 0.0f)
      Out(" behind M2's pairs at %g x the contact margin (reach regions; the M2 run included)",
                  double(opts.narrow_behind_margin));
    Out(": %llu contacts (triangle pairs) in %llu frames; median %.1f us, max %.1f us a frame\n",
                static_cast<unsigned long long>(sum.contacts), static_cast<unsigned long long>(sum.frames_with_contacts),
                sum.narrow_median_us, sum.narrow_max_us);
  }
  Out("  regions touching (frames):");
  if (sum.region_frames.empty()) Out(" none");
  for (const auto& [p, c] : sum.region_frames) Out(" %s(%u)", RegionPairName(view, p.first, p.second).c_str(), c);
  Out("\n");

}

/// What --json writes: the options, the animation, every frame (the bind pose first) and the summary.
nlohmann::json PlayJson(const PlayArgs& a, const runtime::AssetView& view, const AnimationSource& anim,
                        const playback::PlayOptions& opts, const playback::PlayReport& report) {
  const uint32_t frames = anim.frames;
  const bool joints = opts.refit == playback::PlayRefit::kJoints;
  const playback::PlaySummary& sum = report.summary;
  const std::vector<playback::FrameReport>& rows = report.frames;
  const playback::FrameReport& bind = report.bind;
  nlohmann::json j;
  j["asset"] = a.asset;
  if (view.asset->regions()) {  // a creature (schema v4): what R0..R(n-1) are
    nlohmann::json names = nlohmann::json::array();
    for (uint32_t r = 0; r < runtime::RegionCount(view); ++r) names.push_back(runtime::RegionName(view, r));
    j["regions"] = names;
  }
  j["mesh"] = a.anim.mesh;
  j["method"] = a.method;
  j["refit"] = a.refit;
  j["repeat"] = std::max(1u, a.repeat);
  if (anim.clip) {
    j["animation"] = {{"kind", "clip"}, {"name", anim.clip->name}, {"duration_s", anim.clip->duration_s}};
  } else {
    nlohmann::json keys = nlohmann::json::array();
    for (size_t k = 0; k < anim.poses.size(); ++k)
      keys.push_back({{"name", anim.poses[k].name},
                      {"frame", playback::MorphKeyFrame(uint32_t(k), frames, uint32_t(anim.poses.size()))}});
    j["animation"] = {{"kind", "morph"}, {"poses_from", anim.poses_from}, {"keys", keys}};
  }
  const auto* sr = view.asset->sphere_regions();
  auto row_json = [&](const playback::FrameReport& r) {
    nlohmann::json o = {{"label", r.label},
                        {"tests_m1", r.m1.tests},
                        {"pairs_m1_raw", r.m1.raw_pairs},
                        {"pairs_m1", r.m1.distinct_pairs},
                        {"tests_m2", r.m2.tests},
                        {"pairs_m2", r.m2.distinct_pairs},
                        {"refit_us", r.refit_us},
                        {"detect_m1_us", r.detect_m1_us},
                        {"detect_m2_us", r.detect_m2_us},
                        {"tracking_mean_abs_dF", r.tracking_mean},
                        {"tracking_max_abs_dF", r.tracking_max},
                        {"regions_touching", RegionsJson(r.regions)}};
    if (opts.narrow_phase)
      o["narrow_phase"] = {{"contacts", r.narrow.contacts},
                           {"candidate_pairs", r.narrow.candidate_pairs},
                           {"box_tests", r.narrow.box_tests},
                           {"joint_culled", r.narrow.joint_culled},
                           {"triangle_tests", r.narrow.triangle_tests},
                           {"degenerate_triangles", r.narrow.degenerate_triangles},
                           {"us", r.narrow_us},
                           {"regions_in_contact", RegionsJson(r.contact_regions)}};
    if (opts.narrow_phase && !r.contact_region_depth.empty())
      o["narrow_phase"]["regions_in_contact_depth"] = r.contact_region_depth;
    if (opts.narrow_behind_margin > 0.0f) {
      o["narrow_phase"]["behind_m2_pairs"] = r.narrow_pairs - r.narrow_folds;
      o["narrow_phase"]["behind_folds"] = r.narrow_folds;
      o["narrow_phase"]["behind_margin_scale"] = opts.narrow_behind_margin;
    }
    nlohmann::json pairs = nlohmann::json::array();
    for (const runtime::Collision& c : r.pairs)
      pairs.push_back({{"a", c.a}, {"b", c.b}, {"region_a", sr ? int(sr->Get(c.a)) : -1},
                       {"region_b", sr ? int(sr->Get(c.b)) : -1}, {"depth", c.depth}});
    o["pairs"] = pairs;  // M2's when run, else M1's
    return o;
  };
  j["bind"] = row_json(bind);
  nlohmann::json fr = nlohmann::json::array();
  for (const playback::FrameReport& r : rows) {
    nlohmann::json o = row_json(r);
    o["frame"] = r.frame;
    fr.push_back(o);
  }
  j["frames"] = fr;
  nlohmann::json rf = nlohmann::json::object();
  for (const auto& [p, c] : sum.region_frames) rf["R" + std::to_string(p.first) + "-R" + std::to_string(p.second)] = c;
  j["summary"] = {{"frames", frames},
                  {"frames_with_collisions", sum.frames_with_pairs},
                  {"mean_pairs_m1_raw", sum.mean_pairs_m1_raw},
                  {"mean_pairs_m1", sum.mean_pairs_m1},
                  {"mean_pairs_m2", sum.mean_pairs_m2},
                  {"mean_refit_us", sum.mean_refit_us},
                  {"tracking_mean_abs_dF", sum.tracking_mean},
                  {"tracking_max_abs_dF", sum.tracking_max},
                  {"joint_vs_vertex_centre_error_pct",
                   joints ? nlohmann::json{{"median", sum.joint_error_median},
                                           {"p95", sum.joint_error_p95},
                                           {"max", sum.joint_error_max}}
                          : nlohmann::json()},
                  {"mean_detect_m1_us", sum.mean_detect_m1_us},
                  {"mean_detect_m2_us", sum.mean_detect_m2_us},
                  {"regions_touching_frames", rf}};
  return j;
}

/// Removes the regular files of `dir` named as this command names a dumped frame (frame_ + at least 4 digits +
/// .f32 or .joints) that are not in `kept` (this run's): a later benchmark reads every frame file of the folder.
/// Returns how many it removed.
size_t RemoveOtherFrames(const std::string& dir, const std::vector<std::string>& kept) {
  const std::set<std::string> keep(kept.begin(), kept.end());
  std::vector<fs::path> stale;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    const size_t dot = name.rfind('.');
    if (name.rfind("frame_", 0) != 0 || dot == std::string::npos || dot < 10 || keep.count(name)) continue;
    const std::string ext = name.substr(dot);
    const bool digits =
        std::all_of(name.begin() + 6, name.begin() + static_cast<std::ptrdiff_t>(dot), [](char c) { return c >= '0' && c <= '9'; });
    if ((ext == ".f32" || ext == ".joints") && digits && fs::symlink_status(it->path(), ec).type() == fs::file_type::regular)
      stale.push_back(it->path());
  }
  size_t removed = 0;
  for (const fs::path& p : stale) removed += fs::remove(p, ec);
  return removed;
}

int RunPlay(const PlayArgs& a) {
  if (int clash = OutputsClash({{"--json", &a.json}}, {{"ASSET", &a.asset}, {"--mesh", &a.anim.mesh}, {"--rig", &a.rig}},
                               PoseInputs(a.anim)))
    return clash;
  // Usage errors (exit 2), before the asset is read and the frames are played.
  if (a.asset_exclusions && !a.narrow_phase && !(a.narrow_behind > 0.0f))
    return UsageError("--asset-exclusions chooses the narrow phase's definition of a contact: it needs --narrow-phase "
                 "or --narrow-behind");
  if (!a.json.empty())
    if (const std::string why = OutputPathProblem(a.json); !why.empty()) return UsageError(why);
  LoadedAsset asset;
  import::Mesh mesh;
  std::string error;
  if (!OpenAssetAndMesh(a.asset, a.anim.mesh, a.rig, &asset, &mesh, &error)) return Fail(error);
  const runtime::AssetView& view = asset.view;
  AnimationSource anim;
  if (!OpenAnimation(mesh, a.anim, &anim, &error)) return Fail(error);

  playback::PlayOptions opts;
  opts.m1 = a.method != "m2";
  opts.m2 = a.method != "m1";
  opts.refit = a.refit == "paper" ? playback::PlayRefit::kPaper
               : a.refit == "joints" ? playback::PlayRefit::kJoints
                                     : playback::PlayRefit::kPivotFrame;
  opts.repeat = a.repeat;
  opts.narrow_phase = a.narrow_phase || a.narrow_behind > 0.0f;
  opts.crease = !a.asset_exclusions;
  opts.narrow_behind_margin = a.narrow_behind;
  const bool joints = opts.refit == playback::PlayRefit::kJoints;
  if (joints && !view.asset->sphere_joints())
    return Fail("'" + a.asset + "' has no joint weights (schema v" + std::to_string(view.asset->schema_version()) +
                ", or baked from a mesh without a skin): --refit joints needs an asset baked by this version from a "
                "rigged character; re-bake it");
  if (joints && view.asset->joint_count() != mesh.skin->joints.size())
    return Fail("'" + a.asset + "' was baked for " + std::to_string(view.asset->joint_count()) + " joints, '" + a.anim.mesh +
                "' has " + std::to_string(mesh.skin->joints.size()));
  // Every output written all or nothing: the frames and the JSON to temporaries, renamed into place once the
  // run succeeded (a failed run leaves the folder and the JSON as they were).
  import::OutputFiles outputs;
  std::vector<std::string> frame_files;  // the names this run writes in --dump-frames
  if (!a.dump_frames.empty()) {
    // One raw frame per file: #V×3 little-endian float32, for bench/runtime_bench and the CUDA bench; and
    // its joint matrices (frame_NNNN.joints: #J × 12 float32, JointRefitJob's layout) when the asset can
    // refit from them.
    opts.on_frame = [&](uint32_t f, const std::vector<float>& positions, const std::vector<float>* joint_matrices) {
      char name[32];
      std::snprintf(name, sizeof name, "frame_%04u.f32", f);
      frame_files.emplace_back(name);
      if (auto s = outputs.Write((fs::path(a.dump_frames) / name).string(), positions.data(),
                                 positions.size() * sizeof(float));
          !s.ok())
        return s;
      if (joint_matrices) {
        std::snprintf(name, sizeof name, "frame_%04u.joints", f);
        frame_files.emplace_back(name);
        return outputs.Write((fs::path(a.dump_frames) / name).string(), joint_matrices->data(),
                             joint_matrices->size() * sizeof(float));
      }
      return import::Status(import::Ok{});
    };
  }
  auto played = playback::Play(mesh, view, anim, opts);
  if (!played.ok())  // the session's errors name the runtime job; the asset is named here
    return Fail(import::Error{played.error().code, "'" + a.asset + "': " + played.error().message});
  const playback::PlayReport& report = played.value();

  PrintReport(a, view, anim, opts, report);
  if (!a.json.empty())
    if (auto s = outputs.Write(a.json, JsonText(PlayJson(a, view, anim, opts, report)) + "\n"); !s.ok())
      return Fail(s.error());
  if (auto s = outputs.Commit(); !s.ok()) return Fail(s.error());
  if (!a.dump_frames.empty()) {  // the folder holds this run's frames only: an earlier run's others go
    const size_t removed = RemoveOtherFrames(a.dump_frames, frame_files);
    Out("wrote %zu files to %s", frame_files.size(), a.dump_frames.c_str());
    if (removed) Out(" (removed %zu frame files of an earlier run)", removed);
    Out("\n");
  }
  if (!a.json.empty()) Out("wrote %s\n", a.json.c_str());
  return 0;
}

}  // namespace

void RegisterPlay(CLI::App& app, Commands* commands) {
  auto args = std::make_shared<PlayArgs>();
  CLI::App* sub = app.add_subcommand(
      "play", "Play an animation (skinned clip or the paper's Bezier morph of key poses, §5.1/§6) and report "
              "sphere collisions per frame with M1 and M2 (§5.2)");
  AddAnimationOptions(sub, &args->asset, &args->rig, &args->anim);
  sub->add_option("--method", args->method, "Broad phase: m1 (chains), m2 (all spheres), both")
      ->check(CLI::IsMember({"m1", "m2", "both"}));
  sub->add_option("--refit", args->refit,
                  "Refit: paper (centre = mean pivot displacement), frame (pivot frame, default) or joints (linear "
                  "blend skinning of the centres from the joint matrices, JointRefitJob; reports its centre error "
                  "against the pivot-frame refit)")
      ->check(CLI::IsMember({"paper", "frame", "joints"}));
  sub->add_option("--repeat", args->repeat, "Runs per job per frame; timings are the minimum (default 5)");
  sub->add_option("--dump-frames", args->dump_frames,
                  "Folder to write each frame's deformed positions to (frame_NNNN.f32: #V×3 float32), for bench/; "
                  "with a v3 asset also its joint matrices (frame_NNNN.joints: #J×12 float32, JointRefitJob's layout); "
                  "afterwards the folder holds this run's frames only (an earlier run's other frame files removed)")
      ->check(CLI::ExistingDirectory);
  sub->add_option("--json", args->json, "Write the per-frame table and summary as JSON");
  sub->add_flag("--narrow-phase", args->narrow_phase,
                "Also find the exact triangle contacts (runtime NarrowPhaseJob): every self-contact the skin makes "
                "(the crease rule, Exclusions::kCrease) on an asset baked with it, else those between surrounding "
                "regions of spheres the asset does not exclude; contacts per frame in the table and the JSON");
  sub->add_flag("--asset-exclusions", args->asset_exclusions,
                "With --narrow-phase: the asset's excluded sphere pairs define a contact (Exclusions::kAsset), the "
                "asset's own definition");
  sub->add_option("--narrow-behind", args->narrow_behind,
                  "The narrow phase only behind M2's sphere pairs found with SCALE times the asset's contact margin "
                  "and, under the crease rule, the proxy's folds (excluded neighbours that came together): the "
                  "spheres as a game's broad phase, on the reach regions (what it finds: docs/evaluation.md, skin contacts); "
                  "implies --narrow-phase; its time includes that M2 run")
      ->check(WithinRange(0.0, 100.0, /*lo_open=*/true, /*as_float=*/true))
      ->type_name("SCALE");
  commands->handlers.emplace_back(sub, [args] { return RunPlay(*args); });
}

}  // namespace spherechain::cli
