// spherechain view ASSET --mesh INPUT [--clip NAME | --morph POSES...] [--frames N] [--method m1|m2] -o OUT.html
//                  [--three DIR] [--poses-dir DIR] [--rig MHSKEL]
//
// Writes one self-contained HTML file that shows the animation as the runtime sees it: the mesh coloured
// by region, the refit spheres (§5.1), the colliding sphere pairs (M1 or M2, §5.2) and the triangles in
// contact (narrow phase) frame by frame — playback::Session's frames —, with a timeline of the per-frame counts,
// play / pause / step and an orbit camera. three.js (viewer/package.json, `npm ci` there) is embedded in
// the file, so it opens offline from disk. The page itself is viewer/page.html, compiled in.
//
// Size: per-frame positions are quantised to int16 over the animation's bounding box and base64-encoded
// (#V × 3 × 2 bytes × 4/3 a frame); spheres are float32; contacts are triangle index pairs.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <span>
#include <sstream>

#include <nlohmann/json.hpp>

#include "animation_source.h"
#include "commands.h"
#include "spherechain/playback/animation.h"
#include "spherechain/playback/debug_export.h"
#include "spherechain/playback/session.h"
#include "spherechain/import/import.h"
#include "spherechain/baker/write.h"
#include "spherechain/runtime/runtime.h"
#include "html_embed.h"
#include "view_page.h"  // generated from viewer/page.html: kViewPage

namespace spherechain::cli {

namespace {

namespace fs = std::filesystem;

struct ViewArgs {
  std::string asset, output, rig, three, method = "m2";
  AnimationArgs anim;  // --mesh, --clip, --morph, --poses-dir, --frames
};

int RunView(const ViewArgs& a) {
  if (int clash = OutputsClash({{"-o", &a.output}}, {{"ASSET", &a.asset}, {"--mesh", &a.anim.mesh}, {"--rig", &a.rig}},
                               PoseInputs(a.anim)))
    return clash;
  if (const std::string why = OutputPathProblem(a.output); !why.empty()) return UsageError(why);  // before the frames
  // three.js first: without it nothing can be written, and the message says how to get it.
  std::string looked;
  const std::string three_dir = FindThree(a.three, &looked);
  if (three_dir.empty())
    return Fail("view: three.js not found (looked in " + looked + " for " + kThreeModule + " and " + kOrbitControls +
                "): run `npm ci` in " + SPHERECHAIN_SOURCE_VIEWER_DIR +
                " (npm registry; three is pinned in viewer/package.json), or pass --three DIR (a three package folder)");
  std::string three_src, orbit_src, three_pkg;
  if (!ReadText(fs::path(three_dir) / kThreeModule, &three_src) ||
      !ReadText(fs::path(three_dir) / kOrbitControls, &orbit_src))
    return Fail("view: cannot read three.js from " + three_dir);
  std::string three_version = "unknown";
  if (ReadText(fs::path(three_dir) / "package.json", &three_pkg)) {
    const nlohmann::json pkg = nlohmann::json::parse(three_pkg, nullptr, false);
    if (pkg.is_object() && pkg.contains("version") && pkg["version"].is_string()) three_version = pkg["version"];
  }

  LoadedAsset asset;
  import::Mesh mesh;
  std::string error;
  if (!OpenAssetAndMesh(a.asset, a.anim.mesh, a.rig, &asset, &mesh, &error)) return Fail(error);
  const runtime::AssetView& view = asset.view;

  const AnimationArgs& anim_args = a.anim;
  AnimationSource anim;
  if (!OpenAnimation(mesh, anim_args, &anim, &error)) return Fail(error);

  // The frame pipeline (playback::Session): refit, the method's pairs, and every contact of the frame (the
  // crease rule with depths on an asset baked with it), the contact buffer grown until all fit.
  playback::SessionOptions so;
  so.m1 = a.method == "m1";
  so.m2 = !so.m1;
  so.narrow = playback::SessionNarrow::kEvery;
  so.contact_capacity = 1u << 14;
  so.grow_contacts = true;
  playback::Session session;
  if (auto s = session.Init(view, mesh, so); !s.ok()) return Fail("'" + a.asset + "': " + s.error().message);
  const bool crease = session.exclusions() == runtime::Exclusions::kCrease;

  const uint32_t V = view.vertex_count, T = view.triangle_count, S = view.sphere_count, F = anim.frames;
  // Every frame's positions are held, then embedded (16-bit, base64: about 8 bytes a vertex a frame), and its
  // spheres (float32, base64: about 22 bytes a sphere a frame): a page past 512 MB is refused before any
  // frame is skinned, not left to run out of memory. The contacts are known only after; the page is checked
  // again before it is written.
  const uint64_t page_bytes = uint64_t{F} * (uint64_t{V} * 8 + uint64_t{S} * 22);
  if (page_bytes > (uint64_t{512} << 20))
    return Fail("view: " + std::to_string(F) + " frames of " + std::to_string(V) + " vertices make a page of about " +
                std::to_string(page_bytes >> 20) + " MB, over 512 MB: ask for fewer --frames");
  std::vector<std::vector<float>> frames(F);
  std::vector<std::string> labels(F);
  playback::SkinningScratch scratch;
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (uint32_t f = 0; f < F; ++f) {
    if (auto s = anim.Frame(mesh, f, &scratch, &frames[f], &labels[f]); !s.ok()) return Fail(s.error());
    for (uint32_t v = 0; v < V; ++v)
      for (int k = 0; k < 3; ++k) {
        const float x = frames[f][3 * v + k];
        if (!std::isfinite(x)) return Fail("view: frame " + std::to_string(f) + " has a non-finite vertex position");
        lo[k] = std::min(lo[k], x);
        hi[k] = std::max(hi[k], x);
      }
  }

  nlohmann::json frames_json = nlohmann::json::array();
  const auto* sr = view.asset->sphere_regions();
  uint64_t total_contacts = 0;
  uint32_t max_pairs = 0, max_contacts = 0;
  for (uint32_t f = 0; f < F; ++f) {
    if (auto s = session.Run(frames[f].data(), nullptr, f, labels[f]); !s.ok())
      return Fail("view: frame " + std::to_string(f) + ": " + s.error().message);
    const playback::SessionFrame& fr = session.frame();
    const runtime::SphereArrays& sp = fr.spheres;
    std::vector<float> spheres(4 * size_t(S));
    for (uint32_t s = 0; s < S; ++s) {
      spheres[4 * s] = sp.x[s];
      spheres[4 * s + 1] = sp.y[s];
      spheres[4 * s + 2] = sp.z[s];
      spheres[4 * s + 3] = sp.r[s];
    }
    const std::span<const runtime::Collision> pairs = so.m1 ? fr.m1 : fr.m2;
    const uint32_t pair_count = uint32_t(pairs.size()), contact_count = uint32_t(fr.contacts.size());
    nlohmann::json pj = nlohmann::json::array(), cj = nlohmann::json::array();
    for (const runtime::Collision& p : pairs) pj.push_back(p.a), pj.push_back(p.b);
    for (const runtime::TriangleContact& c : fr.contacts) cj.push_back(c.triangle_a), cj.push_back(c.triangle_b);
    std::vector<int16_t> q(3 * size_t(V));
    for (uint32_t v = 0; v < V; ++v)
      for (int k = 0; k < 3; ++k) {
        const float ext = hi[k] - lo[k];
        const double t = ext > 0 ? (frames[f][3 * v + k] - lo[k]) / ext : 0.0;
        q[3 * v + k] = static_cast<int16_t>(std::lround(t * 65535.0) - 32768);
      }
    frames_json.push_back({{"label", labels[f]},
                           {"positions", Base64(q)},
                           {"spheres", Base64(spheres)},
                           {"pairs", pj},
                           {"contacts", cj},
                           {"deepest", crease && contact_count ? std::max_element(fr.depths.begin(), fr.depths.end(),
                                                                                   [](const auto& x, const auto& y) { return x.depth < y.depth; })->depth
                                                               : 0.0f}});
    total_contacts += contact_count;
    max_pairs = std::max(max_pairs, pair_count);
    max_contacts = std::max(max_contacts, contact_count);
  }

  std::vector<uint8_t> tri_regions(T, 255), sphere_regions(S, 255);
  if (const auto* tr = view.asset->triangle_regions(); tr && tr->size() == T)
    for (uint32_t t = 0; t < T; ++t) tri_regions[t] = tr->Get(t);
  if (sr && sr->size() == S)
    for (uint32_t s = 0; s < S; ++s) sphere_regions[s] = sr->Get(s);
  const bool wide = V > 65535;
  std::string indices;
  if (wide) {
    indices = Base64(mesh.indices);
  } else {
    std::vector<uint16_t> idx(mesh.indices.begin(), mesh.indices.end());
    indices = Base64(idx);
  }
  const char* up = "y";
  if (view.asset->up_axis() == schema::UpAxis::Z) up = "z";
  if (view.asset->up_axis() == schema::UpAxis::X) up = "x";
  // The page names files, not the machine's folders: the poses folder by its last component.
  std::string animation = anim.Describe();
  if (const size_t at = animation.find(anim.poses_from); !anim.poses_from.empty() && at != std::string::npos)
    animation.replace(at, anim.poses_from.size(), fs::path(anim.poses_from).filename().string());
  nlohmann::json data = {
      {"format", "spherechain-view 1"},
      {"asset", fs::path(a.asset).filename().string()},
      {"mesh", fs::path(a.anim.mesh).filename().string()},
      {"animation", animation},
      {"method", a.method},
      {"vertex_count", V},
      {"triangle_count", T},
      {"sphere_count", S},
      {"units", view.asset->units() ? view.asset->units()->str() : std::string()},
      {"up_axis", up},
      {"box_min", {lo[0], lo[1], lo[2]}},
      {"box_max", {hi[0], hi[1], hi[2]}},
      {"index_bytes", wide ? 4 : 2},
      {"indices", indices},
      {"triangle_regions", Base64(tri_regions)},
      {"sphere_regions", Base64(sphere_regions)},
      {"frames", frames_json}};
  if (view.asset->regions()) {  // a creature (schema v4): its regions' names and the PNGs' colours
    nlohmann::json names = nlohmann::json::array(), colors = nlohmann::json::array();
    for (uint32_t r = 0; r < runtime::RegionCount(view); ++r) {
      names.push_back("R" + std::to_string(r) + " " + runtime::RegionName(view, r));
      const auto c = playback::RegionColor(view, r);
      auto q = [](float x) { return int(std::clamp(x, 0.0f, 1.0f) * 255.0f + 0.5f); };
      colors.push_back((q(c[0]) << 16) | (q(c[1]) << 8) | q(c[2]));
    }
    data["region_names"] = names;
    data["region_colors"] = colors;
  }

  // three.js and OrbitControls as data: URLs behind an import map: ES modules that import each other
  // ("three") and load from file:// with no server and no network.
  const std::string importmap =
      "<!-- three.js " + three_version + " (MIT, https://threejs.org), embedded -->\n"
      "<script type=\"importmap\">{\"imports\":{\"three\":\"data:text/javascript;base64," + Base64(three_src.data(), three_src.size()) +
      "\",\"three/addons/controls/OrbitControls.js\":\"data:text/javascript;base64," +
      Base64(orbit_src.data(), orbit_src.size()) + "\"}}</script>";
  std::string page = kViewPage;
  if (!ReplaceOnce(&page, "<!--SPHERECHAIN_IMPORTMAP-->", importmap) ||
      !ReplaceOnce(&page, "<!--SPHERECHAIN_DATA-->", ScriptSafeJson(data)))
    return Fail("view: the compiled-in page (viewer/page.html) lacks its markers");
  if (page.size() > (size_t{512} << 20))
    return Fail("view: " + std::to_string(F) + " frames make a page of " + std::to_string(page.size() >> 20) +
                " MB, over 512 MB: ask for fewer --frames (nothing written)");
  if (auto s = import::WriteFileAtomic(a.output, page); !s.ok()) return Fail(s.error());
  Out("view: %s + %s — %s, %u frames, %u spheres; %s pairs max %u, contacts %llu (max %u a frame)\n",
              a.asset.c_str(), a.anim.mesh.c_str(), anim.Describe().c_str(), F, S, a.method == "m1" ? "M1" : "M2", max_pairs,
              static_cast<unsigned long long>(total_contacts), max_contacts);
  Out("wrote %s (%.2f MB, three.js %s embedded; open it from disk, #frame=N shows frame N)\n", a.output.c_str(),
              double(page.size()) / (1024.0 * 1024.0), three_version.c_str());
  return 0;
}

}  // namespace

void RegisterView(CLI::App& app, Commands* commands) {
  auto args = std::make_shared<ViewArgs>();
  CLI::App* sub = app.add_subcommand(
      "view", "Write a self-contained HTML viewer (three.js embedded, opens offline): the animated mesh by region, "
              "refit spheres, colliding sphere pairs and contact triangles (narrow phase) per frame, with a timeline");
  AddAnimationOptions(sub, &args->asset, &args->rig, &args->anim);
  sub->add_option("-o,--output", args->output, "HTML file to write")->required();
  sub->add_option("--method", args->method, "Broad phase whose sphere pairs are shown: m1 (chains) or m2 (all, default)")
      ->check(CLI::IsMember({"m1", "m2"}));
  sub->add_option("--three", args->three,
                  "three.js package folder (build/three.module.min.js, examples/jsm/controls/OrbitControls.js); "
                  "default: the installed share/spherechain/three, else viewer/node_modules/three (npm ci in viewer/)");
  commands->handlers.emplace_back(sub, [args] { return RunView(*args); });
}

}  // namespace spherechain::cli
