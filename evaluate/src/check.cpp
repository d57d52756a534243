// spherechain evaluate — animation QA (check.h): clips → frames → skin contacts → events → policy.
#include "spherechain/evaluate/check.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <set>
#include <span>
#include <sstream>

#include "spherechain/import/file_io.h"
#include "spherechain/playback/animation_source.h"
#include "spherechain/playback/character.h"
#include "spherechain/playback/debug_export.h"
#include "spherechain/playback/session.h"
#include "spherechain/runtime/narrow_phase.h"
#include "evaluate_internal.h"

namespace spherechain::evaluate {

namespace {

using Code = import::Error::Code;
using playback::XmlEscape;
import::Error Fail(Code code, std::string message) { return import::MakeError(code, std::move(message)); }

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kDeeperTolerance = 1.05;  // a baseline event this much shallower is "deeper" now

std::string RegionLabel(const runtime::AssetView& view, int r) {
  if (r < 0) return "unassigned";
  const char* n = runtime::RegionName(view, uint32_t(r));
  return *n ? n : "R" + std::to_string(r);
}

std::string PairLabel(const runtime::AssetView& view, const CheckPair& p) {
  return RegionLabel(view, p.first) + "-" + RegionLabel(view, p.second);
}

// A region by name ("left_hand") or symbol ("R3"); −1 when neither.
int FindRegion(const runtime::AssetView& view, const std::string& s) {
  const uint32_t n = runtime::RegionCount(view);
  for (uint32_t r = 0; r < n; ++r)
    if (s == runtime::RegionName(view, r) || s == "R" + std::to_string(r)) return int(r);
  return -1;
}

std::string RegionList(const runtime::AssetView& view) {
  std::string out;
  for (uint32_t r = 0; r < runtime::RegionCount(view); ++r)
    out += (r ? ", " : "") + std::string("R") + std::to_string(r) + " " + runtime::RegionName(view, r);
  return out;
}

// "a-b" → a region pair; tries every '-' (a region name may hold one).
import::Result<CheckPair> ParsePair(const runtime::AssetView& view, const std::string& text) {
  for (size_t k = text.find('-'); k != std::string::npos; k = text.find('-', k + 1)) {
    const int a = FindRegion(view, text.substr(0, k)), b = FindRegion(view, text.substr(k + 1));
    if (a >= 0 && b >= 0) return CheckPair(std::min(a, b), std::max(a, b));
  }
  return Fail(Code::kConfig, "policy: '" + text + "' is not a region pair 'a-b' of this asset (regions: " +
                                 RegionList(view) + ")");
}

// The joint (node name) weighing most on triangle t's corners; "" without a skin.
std::string TriangleJoint(const import::Mesh& mesh, uint32_t t) {
  if (!mesh.skin || mesh.skin->weight_offsets.size() != mesh.vertex_count() + 1) return "";
  const import::Skin& s = *mesh.skin;
  std::map<uint32_t, float> sum;
  for (int k = 0; k < 3; ++k) {
    const uint32_t v = mesh.indices[3 * size_t{t} + k];
    for (uint32_t i = s.weight_offsets[v]; i < s.weight_offsets[v + 1]; ++i) sum[s.weight_joints[i]] += s.weights[i];
  }
  uint32_t best = ~0u;
  float w = -1;
  for (const auto& [j, x] : sum)
    if (x > w) best = j, w = x;
  if (best >= s.joints.size() || s.joints[best].node < 0 || size_t(s.joints[best].node) >= s.nodes.size()) return "";
  return s.nodes[size_t(s.joints[best].node)].name;
}

std::string Hex64(uint64_t v) {
  char b[17];
  std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(v));
  return b;
}

// The animation CheckClips plays: the morph through options.poses, or the character's clip `name`
// (CheckOptions::key_times: at its own key times, playback::Animation::times).
import::Result<playback::Animation> OpenCheckAnimation(const import::Mesh& mesh, const CheckOptions& o,
                                                       const std::string& name, bool morph) {
  playback::AnimationRequest request;
  request.mesh_name = o.mesh_name;
  if (morph) {
    request.morph = o.poses;
    request.frames = o.morph_frames;
    request.frames_option = "--morph-frames";
    return playback::OpenAnimation(mesh, request);
  }
  const import::Clip* clip = nullptr;
  for (const import::Clip& c : mesh.clips)
    if (c.name == name) clip = &c;
  request.clip = name;
  std::vector<float> times;
  if (clip && o.key_times) {
    for (const import::Channel& ch : clip->channels)
      for (const float t : ch.times)
        if (t >= 0.0f && t <= clip->duration_s) times.push_back(t);
    std::sort(times.begin(), times.end());
    times.erase(std::unique(times.begin(), times.end(), [](float a, float b) { return b - a < 1e-6f; }), times.end());
    if (times.empty()) times.push_back(0.0f);
  }
  const double frames = !times.empty() ? double(times.size())
                        : clip         ? std::max(1.0, std::ceil(double(clip->duration_s) * o.fps - 1e-6))
                                       : 1.0;
  if (frames > o.max_frames)
    return Fail(Code::kConfig, "clip '" + name + "' is " + std::to_string(clip->duration_s) + " s: " +
                                   std::to_string(uint64_t(frames)) + " frames, over the limit of " +
                                   std::to_string(o.max_frames));
  request.frames = uint32_t(frames);
  auto anim = playback::OpenAnimation(mesh, request);  // an unknown clip: the message lists the clips
  if (!anim.ok()) return anim.error();
  anim->times = std::move(times);
  return anim;
}

}  // namespace

import::Status CheckFrame(const import::Mesh& mesh, const CheckOptions& options, const CheckClip& clip,
                          uint32_t frame, std::vector<float>* positions) {
  auto anim = OpenCheckAnimation(mesh, options, clip.name, clip.morph);
  if (!anim.ok()) return anim.error();
  if (frame >= anim->frames)
    return Fail(Code::kConfig, "clip '" + clip.name + "' has " + std::to_string(anim->frames) + " frames, not " +
                                   std::to_string(frame + 1));
  playback::SkinningScratch scratch;
  return anim->Frame(mesh, frame, &scratch, positions);
}

double BodyHeight(const import::Mesh& mesh) {
  const int up = mesh.up_axis == import::UpAxis::kZ ? 2 : mesh.up_axis == import::UpAxis::kX ? 0 : 1;
  double lo = kInf, hi = -kInf;
  for (size_t v = 0; 3 * v + 2 < mesh.positions.size(); ++v)
    lo = std::min(lo, double(mesh.positions[3 * v + up])), hi = std::max(hi, double(mesh.positions[3 * v + up]));
  return hi > lo ? hi - lo : 0.0;
}

double CheckPolicy::Threshold(const CheckPair& pair) const {
  if (std::find(allow.begin(), allow.end(), pair) != allow.end()) return kInf;
  const auto it = pair_max_depth.find(pair);
  return it != pair_max_depth.end() ? it->second : max_depth;
}

bool CheckClip::failed() const {
  return std::any_of(events.begin(), events.end(), [](const CheckEvent& e) { return e.failed; });
}
float CheckClip::deepest() const {
  float d = 0;
  for (const CheckEvent& e : events) d = std::max(d, e.depth);
  return d;
}
bool CheckReport::failed() const {
  return std::any_of(clips.begin(), clips.end(), [](const CheckClip& c) { return c.failed(); });
}

import::Result<double> ParseDepth(const std::string& text, double height, double unit_scale_m) {
  const auto bad = [&] {
    return Fail(Code::kConfig, "'" + text + "' is not a depth (a number > 0 of model units, or with a unit: 1cm, "
                                            "5mm, 0.02m, or a share of the body height: 1%)");
  };
  // Decimal only (from_chars: no hexadecimal, sign or leading space, as std::stod would take).
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value, std::chars_format::general);
  if (ec != std::errc()) return bad();
  std::string unit(end, text.data() + text.size());
  unit.erase(0, unit.find_first_not_of(' '));
  if (!(value > 0) || !std::isfinite(value)) return bad();
  if (unit.empty()) return value;
  if (unit == "%") return value / 100.0 * height;
  double metres = 0;
  if (unit == "m") metres = value;
  else if (unit == "cm") metres = value / 100.0;
  else if (unit == "mm") metres = value / 1000.0;
  else return bad();
  if (!(unit_scale_m > 0))
    return Fail(Code::kConfig, "'" + text + "': the character's units are unknown; give the depth in model units "
                                            "(a bare number) or as a share of the height (1%)");
  return metres / unit_scale_m;
}

import::Status LoadCheckPolicy(const std::string& path, const runtime::AssetView& asset, double height,
                               double unit_scale_m, CheckPolicy* policy) {
  auto bytes = import::ReadFileBytes(path, size_t(1) << 24);
  if (!bytes.ok()) return bytes.error();
  nlohmann::json j = nlohmann::json::parse(bytes->begin(), bytes->end(), nullptr, false);
  if (j.is_discarded() || !j.is_object()) return Fail(Code::kFormat, "policy '" + path + "': not a JSON object");
  const auto depth = [&](const nlohmann::json& v, const std::string& where) -> import::Result<double> {
    if (v.is_number()) {  // model units, as a bare number is (not through text: no rounding)
      const double d = v.get<double>();
      if (!(d > 0) || !std::isfinite(d))
        return Fail(Code::kConfig, "policy '" + path + "': " + where + ": " + v.dump() + " is not a depth (> 0)");
      return d;
    }
    if (!v.is_string()) return Fail(Code::kFormat, "policy '" + path + "': " + where + " must be a string or a number");
    auto d = ParseDepth(v.get<std::string>(), height, unit_scale_m);
    if (!d.ok()) return Fail(Code::kConfig, "policy '" + path + "': " + where + ": " + d.error().message);
    return d;
  };
  for (const auto& [key, value] : j.items()) {
    if (key == "allow") {
      if (!value.is_array()) return Fail(Code::kFormat, "policy '" + path + "': \"allow\" must be a list of region pairs");
      for (const auto& p : value) {
        if (!p.is_string()) return Fail(Code::kFormat, "policy '" + path + "': \"allow\" holds a non-string");
        auto pair = ParsePair(asset, p.get<std::string>());
        if (!pair.ok()) return Fail(Code::kConfig, "policy '" + path + "': " + pair.error().message);
        policy->allow.push_back(pair.value());
      }
    } else if (key == "max_depth") {
      if (!value.is_object())
        return Fail(Code::kFormat, "policy '" + path + "': \"max_depth\" must map region pairs to depths");
      std::map<CheckPair, std::string> spelled;  // pair → its key, to name both of two spellings of one pair
      for (const auto& [name, d] : value.items()) {
        auto pair = ParsePair(asset, name);
        if (!pair.ok()) return Fail(Code::kConfig, "policy '" + path + "': " + pair.error().message);
        if (auto [at, fresh] = spelled.try_emplace(pair.value(), name); !fresh)
          return Fail(Code::kConfig, "policy '" + path + "': \"max_depth\" gives one region pair twice, as \"" +
                                         at->second + "\" and \"" + name + "\"");
        auto v = depth(d, "max_depth." + name);
        if (!v.ok()) return v.error();
        policy->pair_max_depth[pair.value()] = v.value();
      }
    } else if (key == "default_max_depth") {
      auto v = depth(value, "default_max_depth");
      if (!v.ok()) return v.error();
      policy->max_depth = v.value();
    } else {
      return Fail(Code::kConfig, "policy '" + path + "': unknown key \"" + key +
                                     "\" (known: allow, max_depth, default_max_depth)");
    }
  }
  return import::Ok{};
}

import::Result<CheckReport> CheckClips(const runtime::AssetView& view, const import::Mesh& mesh,
                                       const CheckOptions& o) {
  if (!view.valid()) return Fail(Code::kConfig, "no asset");
  if (auto s = playback::CheckFingerprint(view, mesh, o.asset_name, o.mesh_name); !s.ok())
    return Fail(Code::kConfig, s.error().message);
  if (!(o.fps > 0 && o.fps <= 1000)) return Fail(Code::kConfig, "--fps " + std::to_string(o.fps) + " is outside (0, 1000]");
  if (o.max_frames == 0) return Fail(Code::kConfig, "max_frames must be > 0");
  CheckReport report;
  report.mesh_name = o.mesh_name;
  report.height = BodyHeight(mesh);
  report.unit_scale_m = mesh.unit_scale_m;
  report.positions_hash = import::ComputeFingerprint(mesh).positions_hash;
  report.max_depth = o.policy.max_depth > 0 ? o.policy.max_depth : 0.01 * report.height;
  if (!(report.max_depth > 0)) return Fail(Code::kConfig, "max_depth must be > 0 (a flat mesh has no height)");
  CheckPolicy policy = o.policy;
  policy.max_depth = report.max_depth;
  for (const auto& [pair, d] : policy.pair_max_depth)
    if (!(d > 0)) return Fail(Code::kConfig, "policy: the depth of a region pair must be > 0");

  // The clips to play, in the mesh's order (or the order asked).
  std::vector<std::string> names = o.clips;
  for (size_t i = 0; i < names.size(); ++i)
    if (std::find(names.begin(), names.begin() + i, names[i]) != names.begin() + i)
      return Fail(Code::kConfig, "clip '" + names[i] + "' is asked for twice");
  if (names.empty())
    for (const import::Clip& c : mesh.clips) names.push_back(c.name);
  if (names.empty() && o.poses.empty())
    return Fail(Code::kConfig, "the character has no animation clips: nothing to check (a static mesh; give key poses "
                               "to check a morph through them)");
  std::vector<playback::Animation> animations;
  for (const std::string& name : names) {
    auto anim = OpenCheckAnimation(mesh, o, name, false);
    if (!anim.ok()) return anim.error();
    animations.push_back(std::move(anim).value());
  }
  const size_t morph = o.poses.empty() ? names.size() + 1 : names.size();  // its index, when played
  if (!o.poses.empty()) {
    auto anim = OpenCheckAnimation(mesh, o, "", true);
    if (!anim.ok()) return anim.error();
    animations.push_back(std::move(anim).value());
    // "morph", unless the character has a clip of that name (reports and baselines name one clip each)
    std::string name = "morph";
    const auto taken = [&](const std::string& n) {
      return std::any_of(mesh.clips.begin(), mesh.clips.end(), [&](const import::Clip& c) { return c.name == n; });
    };
    while (taken(name)) name += name == "morph" ? " (key poses)" : "'";
    names.push_back(name);
  }

  // The frame pipeline without spheres: skin each frame, then every skin contact (the crease rule) with depths.
  playback::SessionOptions so;
  so.spheres = false;
  so.narrow = playback::SessionNarrow::kEvery;
  so.grow_contacts = true;  // every contact of a frame, however many: a truncated frame could hide an event
  playback::Session session;
  if (auto s = session.Init(view, mesh, so); !s.ok())
    return Fail(s.error().code, "'" + o.asset_name + "': " + s.error().message);
  const runtime::NarrowPhaseModel& model = session.narrow_model();
  if (!model.has_crease())
    return Fail(Code::kConfig, "the asset has no crease rule (baked before skin contacts existed): re-bake it");
  report.crease = model.crease();

  const auto* tri_regions = view.asset->triangle_regions();
  const auto region_of = [&](uint32_t t) { return tri_regions && t < tri_regions->size() ? int(tri_regions->Get(t)) : -1; };

  for (size_t c = 0; c < animations.size(); ++c) {
    const playback::Animation& anim = animations[c];
    CheckClip clip;
    clip.name = names[c];
    clip.morph = c == morph;
    clip.frames = anim.frames;
    clip.duration = anim.clip ? anim.clip->duration_s : anim.frames / playback::Animation::kMorphFps;
    std::map<CheckPair, size_t> open;  // region pair → index of its event running up to the previous frame
    const auto t0 = std::chrono::steady_clock::now();
    uint32_t done = 0;  // frames consumed: a failing step is frame `done`
    auto played = session.Play(anim, [&](const playback::SessionFrame& fr) -> import::Status {
      const uint32_t f = fr.frame;
      ++done;
      const std::span<const runtime::TriangleContact> contacts = fr.contacts;
      const std::span<const runtime::ContactDepth> depths = fr.depths;
      const std::span<const float> positions = fr.positions;
      const uint32_t kept = uint32_t(contacts.size());
      // Per region pair: contacts this frame and the deepest.
      std::map<CheckPair, std::pair<uint32_t, uint32_t>> here;  // pair → (count, index of the deepest)
      for (uint32_t i = 0; i < kept; ++i) {
        const runtime::TriangleContact& k = contacts[i];
        if (model.IntersectsAtBind(k.triangle_a, k.triangle_b)) {
          ++clip.bind_contacts;
          continue;
        }
        ++clip.contacts;
        const int ra = region_of(k.triangle_a), rb = region_of(k.triangle_b);
        auto [it, fresh] = here.try_emplace(CheckPair(std::min(ra, rb), std::max(ra, rb)), 0u, i);
        ++it->second.first;
        if (!fresh && depths[i].depth > depths[it->second.second].depth) it->second.second = i;
      }
      clip.frames_with_contacts += !here.empty();
      std::map<CheckPair, size_t> next;
      for (const auto& [pair, cd] : here) {
        const auto [n, deepest] = cd;
        const auto prev = open.find(pair);
        size_t e;
        if (prev != open.end()) {
          e = prev->second;
        } else {
          e = clip.events.size();
          CheckEvent ev;
          ev.regions = pair;
          ev.name = PairLabel(view, pair);
          ev.first_frame = f;
          ev.first_time = anim.FrameTime(f);
          ev.depth = -1;
          clip.events.push_back(ev);
        }
        CheckEvent& ev = clip.events[e];
        ev.last_frame = f;
        ev.last_time = anim.FrameTime(f);
        ev.max_contacts = std::max(ev.max_contacts, n);
        if (depths[deepest].depth > ev.depth) {
          const runtime::TriangleContact& k = contacts[deepest];
          const bool swap = region_of(k.triangle_a) > region_of(k.triangle_b);  // the pair's order
          ev.depth = depths[deepest].depth;
          ev.deepest_frame = f;
          ev.deepest_time = anim.FrameTime(f);
          ev.triangles[0] = swap ? k.triangle_b : k.triangle_a;
          ev.triangles[1] = swap ? k.triangle_a : k.triangle_b;
          ev.contacts.clear();
          for (uint32_t i = 0; i < kept; ++i) {
            const uint32_t ta = contacts[i].triangle_a, tb = contacts[i].triangle_b;
            const int ra = region_of(ta), rb = region_of(tb);
            if (CheckPair(std::min(ra, rb), std::max(ra, rb)) != pair || model.IntersectsAtBind(ta, tb)) continue;
            ev.contacts.emplace_back(ra <= rb ? ta : tb, ra <= rb ? tb : ta);
          }
          for (int d = 0; d < 3; ++d) {
            float sum = 0;
            for (const uint32_t t : {k.triangle_a, k.triangle_b})
              for (int q = 0; q < 3; ++q) sum += positions[3 * size_t{mesh.indices[3 * size_t{t} + q]} + d];
            ev.point[d] = sum / 6.0f;
          }
        }
        next[pair] = e;
      }
      open.swap(next);
      if (o.progress) o.progress(c, animations.size(), f + 1, anim.frames);
      return import::Ok{};
    });
    if (!played.ok())
      return Fail(played.error().code, "clip '" + clip.name + "' frame " + std::to_string(done) + ": " +
                                           played.error().message);
    clip.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (CheckEvent& ev : clip.events) {
      ev.depth = std::max(ev.depth, 0.0f);
      for (int s = 0; s < 2; ++s) ev.joints[s] = TriangleJoint(mesh, ev.triangles[s]);
      ev.threshold = policy.Threshold(ev.regions);
      ev.over_threshold = double(ev.depth) > ev.threshold;
      ev.failed = ev.over_threshold;
    }
    std::stable_sort(clip.events.begin(), clip.events.end(), [](const CheckEvent& a, const CheckEvent& b) {
      return std::tie(a.first_frame, a.regions) < std::tie(b.first_frame, b.regions);
    });
    report.clips.push_back(std::move(clip));
  }
  return report;
}

import::Status ApplyBaseline(const nlohmann::json& baseline, CheckReport* report) {
  if (!baseline.is_object() || !baseline.contains("clips") || !baseline["clips"].is_array() ||
      !baseline.contains("fingerprint") || !baseline["fingerprint"].is_string())
    return Fail(Code::kConfig, "the baseline is not a `spherechain check --json` report");
  if (baseline["fingerprint"].get<std::string>() != Hex64(report->positions_hash))
    return Fail(Code::kConfig, "the baseline is of another character (fingerprint " +
                                   baseline["fingerprint"].get<std::string>() + ", this one " +
                                   Hex64(report->positions_hash) + ")");
  // (clip, region pair name) → the deepest event of the baseline over its threshold ("over_threshold";
  // reports written before it existed: "failed").
  std::map<std::pair<std::string, std::string>, double> failing;
  try {
    for (const auto& c : baseline["clips"]) {
      if (!c.is_object() || !c.contains("events") || !c["events"].is_array())
        return Fail(Code::kConfig, "the baseline's clips hold no events");
      for (const auto& e : c["events"]) {
        if (!e.is_object()) return Fail(Code::kConfig, "the baseline's events are not objects");
        if (!e.value("over_threshold", e.value("failed", false))) continue;
        double& d = failing[{c.value("name", ""), e.value("name", "")}];
        d = std::max(d, e.value("depth", 0.0));
      }
    }
  } catch (const nlohmann::json::exception& e) {  // a value of the wrong type
    return Fail(Code::kConfig, std::string("the baseline is not a `spherechain check --json` report: ") + e.what());
  }
  for (CheckClip& clip : report->clips) {
    std::set<std::string> failing_now;
    for (CheckEvent& ev : clip.events) {
      const auto it = failing.find({clip.name, ev.name});
      if (it == failing.end()) ev.baseline = "new";
      else ev.baseline = double(ev.depth) > it->second * kDeeperTolerance ? "deeper" : "known";
      if (ev.over_threshold) failing_now.insert(ev.name);
      ev.failed = ev.over_threshold && ev.baseline != "known";
    }
    for (const auto& [key, d] : failing)
      if (key.first == clip.name && !failing_now.count(key.second)) clip.fixed.push_back(key.second);
  }
  return import::Ok{};
}

nlohmann::json CheckReportJson(const CheckReport& r) {
  const double h = r.height > 0 ? r.height : 1.0;
  nlohmann::json clips = nlohmann::json::array();
  for (const CheckClip& c : r.clips) {
    nlohmann::json events = nlohmann::json::array();
    for (const CheckEvent& e : c.events) {
      nlohmann::json j = {{"regions", {e.regions.first, e.regions.second}},
                          {"name", e.name},
                          {"first_frame", e.first_frame},
                          {"last_frame", e.last_frame},
                          {"first_time", e.first_time},
                          {"last_time", e.last_time},
                          {"max_contacts", e.max_contacts},
                          {"depth", e.depth},
                          {"depth_rel", e.depth / h},
                          {"deepest_frame", e.deepest_frame},
                          {"deepest_time", e.deepest_time},
                          {"triangles", {e.triangles[0], e.triangles[1]}},
                          {"joints", {e.joints[0], e.joints[1]}},
                          {"point", {e.point[0], e.point[1], e.point[2]}},
                          {"threshold", std::isfinite(e.threshold) ? nlohmann::json(e.threshold) : nlohmann::json("allowed")},
                          {"over_threshold", e.over_threshold},
                          {"failed", e.failed}};
      if (!e.baseline.empty()) j["baseline"] = e.baseline;
      events.push_back(std::move(j));
    }
    clips.push_back({{"name", c.name}, {"duration", c.duration}, {"frames", c.frames},
                     {"frames_with_contacts", c.frames_with_contacts}, {"contacts", c.contacts},
                     {"bind_contacts", c.bind_contacts}, {"failed", c.failed()}, {"deepest", c.deepest()},
                     {"deepest_rel", c.deepest() / h}, {"seconds", c.seconds}, {"fixed", c.fixed},
                     {"events", std::move(events)}});
  }
  return {{"tool", "spherechain check"}, {"mesh", r.mesh_name},   {"fingerprint", Hex64(r.positions_hash)},
          {"height", r.height},          {"unit_scale_m", r.unit_scale_m}, {"max_depth", r.max_depth},
          {"max_depth_rel", r.max_depth / h}, {"crease", r.crease}, {"failed", r.failed()},
          {"clips", std::move(clips)}};
}

std::string CheckReportJUnit(const CheckReport& r) {
  size_t failures = 0;
  double seconds = 0;
  for (const CheckClip& c : r.clips) failures += c.failed(), seconds += c.seconds;
  std::ostringstream x;
  x.precision(6);
  x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  x << "<testsuites name=\"spherechain check\" tests=\"" << r.clips.size() << "\" failures=\"" << failures
    << "\" errors=\"0\" time=\"" << std::fixed << seconds << "\">\n";
  x << "  <testsuite name=\"spherechain check " << XmlEscape(r.mesh_name) << "\" tests=\"" << r.clips.size()
    << "\" failures=\"" << failures << "\" errors=\"0\" skipped=\"0\" time=\"" << seconds << "\">\n";
  for (const CheckClip& c : r.clips) {
    x << "    <testcase classname=\"" << XmlEscape("self-contacts." + r.mesh_name) << "\" name=\""
      << XmlEscape(c.name) << "\" time=\"" << c.seconds << "\"";
    if (!c.failed()) {
      x << "/>\n";
      continue;
    }
    std::string lines;
    size_t n = 0;
    for (const CheckEvent& e : c.events) {
      if (!e.failed) continue;
      ++n;
      detail::Appendf(&lines, "%s frames %u-%u (%.3f-%.3f s): depth %.4g (%.2f %% of the height) at frame %u, over %.4g; "
                              "triangles %u/%u, joints %s/%s%s\n",
                      e.name.c_str(), e.first_frame, e.last_frame, e.first_time, e.last_time, e.depth,
                      100.0 * e.depth / (r.height > 0 ? r.height : 1.0), e.deepest_frame, e.threshold, e.triangles[0],
                      e.triangles[1], e.joints[0].c_str(), e.joints[1].c_str(),
                      e.baseline.empty() ? "" : (" (" + e.baseline + ")").c_str());
    }
    const std::string message = std::to_string(n) + " self-contact event(s) over the depth threshold";
    x << ">\n      <failure type=\"self-contact\" message=\"" << XmlEscape(message) << "\">" << XmlEscape(lines)
      << "</failure>\n    </testcase>\n";
  }
  x << "  </testsuite>\n</testsuites>\n";
  return x.str();
}

}  // namespace spherechain::evaluate
