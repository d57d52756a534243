// spherechain check CHARACTER [--asset A.sphc] [--clip NAME]... [--poses [POSES...]] [--fps N | --key-times] [--max-depth D]
//                   [--policy P.json] [--baseline OLD.json] [--json OUT] [--junit OUT.xml] [--html OUT.html]
//
// Animation QA for a game's CI (spherechain/evaluate/check.h says what is measured): plays every clip, finds
// every self-contact the skin makes on every frame, groups them into events and fails a clip when an event
// is deeper than the policy allows. Bakes the asset when none is given (cached by content). Exit codes:
// 0 every clip passes, 1 a clip failed, 2 bad input (nothing written but the reports asked for, complete).
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include <spdlog/spdlog.h>

#include "animation_source.h"
#include "commands.h"
#include "check_html.h"
#include "spherechain/baker/bake.h"
#include "spherechain/evaluate/check.h"
#include "spherechain/import/import.h"
#include "spherechain/playback/character.h"

namespace spherechain::cli {

namespace {

namespace fs = std::filesystem;

constexpr int kExitFailed = 1;  // usage errors: UsageError (2)
// With the baker's version (baker::kGenerator, bumped when its output for the same input changes): bump when
// check's own bake settings change. Cached assets of other versions are not reused.
constexpr const char* kCacheVersion = "check bake defaults 1";

struct CheckArgs {
  std::string character, asset, rig, max_depth, policy, baseline, json, junit, html, cache_dir;
  std::vector<std::string> clips, poses;
  CLI::Option* poses_option = nullptr;
  double fps = 30;
  uint32_t morph_frames = 40;
  bool no_cache = false, key_times = false;
};

// The cache folder: --cache-dir, $SPHERECHAIN_CACHE_DIR, $XDG_CACHE_HOME/spherechain, ~/.cache/spherechain.
fs::path CacheDir(const std::string& explicit_dir) {
  if (!explicit_dir.empty()) return explicit_dir;
  if (const char* d = std::getenv("SPHERECHAIN_CACHE_DIR"); d && *d) return d;
  if (const char* d = std::getenv("XDG_CACHE_HOME"); d && *d) return fs::path(d) / "spherechain";
  if (const char* h = std::getenv("HOME"); h && *h) return fs::path(h) / ".cache" / "spherechain";
  return fs::temp_directory_path() / "spherechain-cache";
}

// What the bake of `mesh` depends on: bind positions and triangles, skin weights, the bone tree, the
// importer's vertex contract, the baker's version.
uint64_t BakeKey(const import::Mesh& mesh, const std::string& rig) {
  std::string k = std::string(kCacheVersion) + "|" + baker::kGenerator;
  // The importer's reading of the file beyond the vertices: the up axis and the unit steer the bake.
  k += "|up " + std::to_string(static_cast<int>(mesh.up_axis));
  k.append(reinterpret_cast<const char*>(&mesh.unit_scale_m), sizeof(float));
  const import::Fingerprint fp = import::ComputeFingerprint(mesh);
  k += "|" + std::to_string(fp.vertex_count) + "|" + std::to_string(fp.triangle_count) + "|" +
       std::to_string(fp.positions_hash) + "|" + std::to_string(fp.indices_hash) + "|" + mesh.vertex_contract + "|" + rig;
  if (mesh.skin) {
    const import::Skin& s = *mesh.skin;
    k += "|" + std::to_string(import::Hash64(s.weight_offsets.data(), s.weight_offsets.size() * 4)) + "|" +
         std::to_string(import::Hash64(s.weight_joints.data(), s.weight_joints.size() * 4)) + "|" +
         std::to_string(import::Hash64(s.weights.data(), s.weights.size() * 4));
    for (const import::SkinJoint& j : s.joints) k += "|" + std::to_string(j.node);
    for (const import::Node& n : s.nodes) {
      k += "|" + n.name + ":" + std::to_string(n.parent);
      k.append(reinterpret_cast<const char*>(n.translation.data()), sizeof(float) * 3);
      k.append(reinterpret_cast<const char*>(n.rotation.data()), sizeof(float) * 4);
    }
  }
  return import::Hash64(k.data(), k.size());
}

// The asset: --asset (imported mesh checked by fingerprint), else a cached bake, else a fresh bake (cached).
// A mesh with no clips has nothing to check unless key poses are given: said before any bake.
bool HasAnimation(const CheckArgs& a, const import::Mesh& mesh, std::string* error) {
  if (!mesh.clips.empty() || (a.poses_option && a.poses_option->count() > 0)) return true;
  *error = "'" + a.character + "' has no animation clips: nothing to check (a static mesh); --poses [POSES...] checks "
           "a morph through key poses (bare: the character's default poses)";
  return false;
}

bool OpenOrBake(const CheckArgs& a, LoadedAsset* asset, import::Mesh* mesh, std::string* asset_name, std::string* error) {
  if (!a.asset.empty()) {
    *asset_name = a.asset;
    return OpenAssetAndMesh(a.asset, a.character, a.rig, asset, mesh, error) && HasAnimation(a, *mesh, error);
  }
  import::Context log = MakeLoggingContext();
  import::ImportOptions io;
  io.rig_path = a.rig;
  auto imported = import::ImportMesh(a.character, io, &log);
  if (!imported.ok()) return *error = import::ToString(imported.error()), false;
  *mesh = std::move(imported).value();
  if (!HasAnimation(a, *mesh, error)) return false;
  char name[32];
  std::snprintf(name, sizeof name, "%016llx.sphc", static_cast<unsigned long long>(BakeKey(*mesh, a.rig)));
  const fs::path cached = CacheDir(a.cache_dir) / name;
  std::error_code ec;
  if (!a.no_cache && fs::is_regular_file(cached, ec) && import::LoadAssetFile(cached.string(), asset).ok() &&
      playback::CheckFingerprint(asset->view, *mesh, cached.string(), a.character).ok()) {
    *asset_name = cached.string();
    spdlog::info("asset: {} (cached bake)", cached.string());
    return true;
  }
  spdlog::info("baking {} (no --asset given)...", a.character);
  baker::BakeConfig config;
  config.import.rig_path = a.rig;
  auto baked = baker::Bake(a.character, config, &log);
  if (!baked.ok()) return *error = import::ToString(baked.error()), false;
  const std::vector<uint8_t>& bytes = baked->asset;
  *mesh = std::move(baked->mesh);
  if (!a.no_cache) {
    fs::create_directories(cached.parent_path(), ec);
    if (ec) {
      spdlog::warn("cannot cache the bake: cannot make the folder '{}': {}", cached.parent_path().string(), ec.message());
    } else if (auto s = import::WriteFileAtomic(cached.string(), bytes.data(), bytes.size()); s.ok()) {
      spdlog::info("asset: {} (baked, cached)", cached.string());
      if (import::LoadAssetFile(cached.string(), asset).ok()) return *asset_name = cached.string(), true;
    } else {
      spdlog::warn("cannot cache the bake: {}", s.error().message);
    }
  }
  // Not cached: loaded from memory (copied into aligned storage and verified, as a file is).
  if (auto s = import::LoadAssetBytes(bytes.data(), bytes.size(), "the baked asset", asset); !s.ok())
    return *error = "the baked asset does not load: " + s.error().message, false;
  *asset_name = a.character + " (baked)";
  return true;
}

// The files --poses may read: its files, the files in its folders and, for a bare --poses, the default folder's.
std::vector<std::string> PoseInputFiles(const CheckArgs& a) {
  if (!a.poses_option || a.poses_option->count() == 0) return {};
  std::vector<std::string> files = playback::PoseInputFiles(a.poses, "");
  const std::vector<std::string> defaults = DefaultPoseFiles(a.character);
  files.insert(files.end(), defaults.begin(), defaults.end());
  return files;
}

int RunCheck(const CheckArgs& a) {
  if (int clash = OutputsClash({{"--json", &a.json}, {"--junit", &a.junit}, {"--html", &a.html}},
                               {{"CHARACTER", &a.character}, {"--asset", &a.asset}, {"--rig", &a.rig},
                                {"--policy", &a.policy}, {"--baseline", &a.baseline}},
                               PoseInputFiles(a)))
    return clash;
  // ---- what needs no file -----------------------------------------------------------------------------
  if (!(a.fps > 0 && a.fps <= 1000)) return UsageError("--fps " + std::to_string(a.fps) + " is outside (0, 1000]");
  for (const std::string* out : {&a.json, &a.junit, &a.html}) {
    if (out->empty()) continue;
    if (const std::string why = OutputPathProblem(*out); !why.empty()) return UsageError(why);
  }
  nlohmann::json baseline;
  if (!a.baseline.empty()) {
    auto bytes = import::ReadFileBytes(a.baseline);
    if (!bytes.ok()) return UsageError(bytes.error().message);
    baseline = nlohmann::json::parse(bytes->begin(), bytes->end(), nullptr, false);
    if (baseline.is_discarded()) return UsageError("--baseline '" + a.baseline + "' is not JSON");
  }

  LoadedAsset asset;
  import::Mesh mesh;
  std::string asset_name, error;
  if (!OpenOrBake(a, &asset, &mesh, &asset_name, &error)) return UsageError(error);
  if (!a.baseline.empty()) {  // another character's baseline, or not a report: refused before any clip is played
    evaluate::CheckReport none;  // no clip: only the baseline's form and fingerprint are checked
    none.positions_hash = import::ComputeFingerprint(mesh).positions_hash;
    if (auto s = evaluate::ApplyBaseline(baseline, &none); !s.ok()) return UsageError("--baseline: " + s.error().message);
  }

  evaluate::CheckOptions options;
  options.mesh_name = a.character;
  options.asset_name = asset_name;
  options.clips = a.clips;
  options.fps = a.fps;
  options.key_times = a.key_times;
  options.morph_frames = a.morph_frames;
  if (a.poses_option && a.poses_option->count() > 0) {
    for (const std::string& p : a.poses)
      if (!p.empty()) options.poses.push_back(p);
    if (options.poses.empty()) {  // bare --poses: the character's default key poses
      const std::string dir = FindPosesDir(playback::DefaultPoseCharacter(mesh, a.character), "");
      if (dir.empty()) return UsageError("--poses: no default key poses for '" + a.character + "'; name pose files or a folder");
      options.poses.push_back(dir);
    }
  }
  const double height = evaluate::BodyHeight(mesh);
  if (!a.policy.empty())
    if (auto s = evaluate::LoadCheckPolicy(a.policy, asset.view, height, mesh.unit_scale_m, &options.policy); !s.ok())
      return UsageError(s.error().message);
  if (!a.max_depth.empty()) {  // after the policy: the command line overrides its default_max_depth
    auto d = evaluate::ParseDepth(a.max_depth, height, mesh.unit_scale_m);
    if (!d.ok()) return UsageError("--max-depth: " + d.error().message);
    options.policy.max_depth = d.value();
  }

  const bool tty = isatty(2) && !Quiet();
  const auto start = std::chrono::steady_clock::now();
  if (!Quiet()) options.progress = [&](size_t clip, size_t clips, uint32_t frame, uint32_t frames) {
    if (tty) {
      const int width = 30, filled = int(width * (clip + double(frame) / frames) / clips);
      std::fprintf(stderr, "\rcheck [%-*s] clip %zu/%zu frame %u/%u", width, std::string(size_t(filled), '#').c_str(),
                   clip + 1, clips, frame, frames);
      if (clip + 1 == clips && frame == frames) std::fprintf(stderr, "\n");
    } else if (frame == frames) {
      std::fprintf(stderr, "check: clip %zu/%zu done (%u frames, %.1f s)\n", clip + 1, clips, frames,
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
  };
  auto checked = evaluate::CheckClips(asset.view, mesh, options);
  if (!checked.ok()) return UsageError(checked.error().message);
  evaluate::CheckReport& r = checked.value();
  if (!a.baseline.empty())
    if (auto s = evaluate::ApplyBaseline(baseline, &r); !s.ok()) return UsageError("--baseline: " + s.error().message);

  // ---- the table ------------------------------------------------------------------------------------
  Out("%-24s %7s %7s %8s  %-22s %s\n", "clip", "frames", "events", "failing", "deepest", "result");
  for (const evaluate::CheckClip& c : r.clips) {
    size_t failing = 0;
    for (const auto& e : c.events) failing += e.failed;
    Out("%-24s %7u %7zu %8zu  %-22s %s\n", c.name.c_str(), c.frames, c.events.size(), failing,
        DepthText(c.deepest(), r).c_str(), c.failed() ? "FAIL" : "PASS");
  }
  for (const evaluate::CheckClip& c : r.clips) {
    for (const evaluate::CheckEvent& e : c.events)
      if (e.failed)
        Out("  FAIL %s: %s frames %u-%u, depth %s at frame %u (over %s), joints %s / %s%s\n", c.name.c_str(),
            e.name.c_str(), e.first_frame, e.last_frame, DepthText(e.depth, r).c_str(), e.deepest_frame,
            DepthText(e.threshold, r).c_str(), e.joints[0].c_str(), e.joints[1].c_str(),
            e.baseline.empty() ? "" : (" (" + e.baseline + ")").c_str());
    for (const std::string& f : c.fixed) Out("  fixed %s: %s\n", c.name.c_str(), f.c_str());
  }
  Out("threshold %s by default; %s\n", DepthText(r.max_depth, r).c_str(), r.failed() ? "FAIL" : "PASS");

  // ---- the reports: all made first, then written all or nothing (an earlier run's stay as they were) ----
  std::vector<std::pair<const std::string*, std::string>> reports;
  if (!a.json.empty()) reports.emplace_back(&a.json, JsonText(evaluate::CheckReportJson(r)) + "\n");
  if (!a.junit.empty()) reports.emplace_back(&a.junit, evaluate::CheckReportJUnit(r));
  if (!a.html.empty()) {
    const CheckPage page{a.character, asset_name, a.key_times, a.rig, asset_name == a.character + " (baked)"};
    std::string html;
    if (!MakeCheckHtml(page, asset.view, mesh, options, r, &html, &error))
      return UsageError("--html '" + a.html + "': " + error + " (the check itself: " + (r.failed() ? "FAIL" : "PASS") +
                      "; no report written)");
    reports.emplace_back(&a.html, std::move(html));
  }
  import::OutputFiles outputs;  // all or nothing: renamed into place once every report is written
  for (const auto& [path, text] : reports)
    if (auto s = outputs.Write(*path, text); !s.ok())
      return UsageError(s.error().message + " (the check itself: " + (r.failed() ? "FAIL" : "PASS") + "; no report written)");
  if (auto s = outputs.Commit(); !s.ok())
    return UsageError(s.error().message + " (the check itself: " + (r.failed() ? "FAIL" : "PASS") + ")");
  for (const auto& [path, text] : reports) Out("wrote %s\n", path->c_str());
  return r.failed() ? kExitFailed : 0;
}

}  // namespace

void RegisterCheck(CLI::App& app, Commands* commands) {
  auto args = std::make_shared<CheckArgs>();
  CLI::App* sub = app.add_subcommand(
      "check",
      "Animation QA: play every clip, find every self-contact the skin makes, fail a clip when one goes deeper than "
      "the policy allows. Exit 0 pass, 1 a clip failed, 2 bad input");
  sub->footer(
      "Example:\n  spherechain check CesiumMan.gltf --max-depth 1cm --junit check.xml --html check.html\n"
      "  spherechain check base.obj --poses --json old.json   # MakeHuman: its default key poses\n"
      "  spherechain check hero.fbx --baseline old.json --policy policy.json\n"
      "Policy file: {\"allow\": [\"left_hand-head\"], \"max_depth\": {\"left_arm-torso\": \"2cm\"}, "
      "\"default_max_depth\": \"1%\"}");
  sub->add_option("character", args->character, "Character file with clips: .gltf/.glb, .fbx, .dae, .x, ...")
      ->required()->check(CLI::ExistingFile);
  sub->add_option("--asset", args->asset, "Asset baked from it (default: bake it, cached by content)")
      ->check(CLI::ExistingFile);
  sub->add_option("--rig", args->rig, "MakeHuman rig (.mhskel) for an OBJ; default: default.mhskel beside the OBJ");
  sub->add_option("--clip", args->clips, "Clip to check (repeatable; default: every clip)");
  args->poses_option = sub->add_option("--poses", args->poses,
                                       "Also check the morph through key poses (files, folders); bare: the "
                                       "character's default poses. How a mesh without clips is checked")
                           ->expected(0, CLI::detail::expected_max_vector_size);
  sub->add_option("--morph-frames", args->morph_frames, "Frames of the morph (default 40, at most 1,000,000)")
      ->check(WithinRange(1, kMaxFrames))
      ->needs(args->poses_option);
  CLI::Option* fps = sub->add_option("--fps", args->fps, "Frames per second a clip is sampled at (default 30)");
  sub->add_flag("--key-times", args->key_times,
                "Play each clip at its own key times instead of --fps (the poses the animator set)")
      ->excludes(fps);
  sub->add_option("--max-depth", args->max_depth,
                  "Deepest penetration allowed: 1cm, 5mm, 0.02m, 1% (of the height; the default) or model units");
  sub->add_option("--policy", args->policy, "JSON policy: allowed region pairs and per-pair depths (see below)")
      ->check(CLI::ExistingFile);
  sub->add_option("--baseline", args->baseline,
                  "An earlier --json of the same character: fail only on new or deeper events, list the fixed ones")
      ->check(CLI::ExistingFile);
  sub->add_option("--json", args->json, "Write the events as JSON (a later --baseline)");
  sub->add_option("--junit", args->junit, "Write JUnit XML: one testcase per clip (CI test reporters)");
  sub->add_option("--html", args->html, "Write one self-contained HTML report with a picture per failing event");
  sub->add_option("--cache-dir", args->cache_dir,
                  "Where bakes are cached (default $SPHERECHAIN_CACHE_DIR, else $XDG_CACHE_HOME/spherechain, else "
                  "~/.cache/spherechain)");
  sub->add_flag("--no-cache", args->no_cache, "Bake afresh and do not cache");
  commands->handlers.emplace_back(sub, [args] { return RunCheck(*args); });
}

}  // namespace spherechain::cli
