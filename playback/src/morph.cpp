// spherechain playback — the paper's Bézier morph between key poses (§5.1, §6) and readable pose files.
#include "spherechain/playback/morph.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

namespace spherechain::playback {

namespace fs = std::filesystem;

Result<MorphFrame> MorphFrameAt(uint32_t frame, uint32_t frame_count, uint32_t key_count) {
  if (key_count == 0) return MakeError(Error::Code::kConfig, "morph: no key poses");
  if (frame_count < 2 * key_count)
    return MakeError(Error::Code::kConfig, "morph: " + std::to_string(frame_count) + " frames cannot show " +
                                               std::to_string(key_count) + " key poses (needs at least " +
                                               std::to_string(2 * key_count) + ")");
  if (frame >= frame_count)
    return MakeError(Error::Code::kConfig,
                     "morph: frame " + std::to_string(frame) + " out of range (" + std::to_string(frame_count) + ")");
  const uint32_t base = frame_count / key_count, extra = frame_count % key_count;
  // Keys 0..extra-1 have base+1 frames, the rest base.
  uint32_t key, start;
  if (frame < extra * (base + 1)) {
    key = frame / (base + 1);
    start = key * (base + 1);
  } else {
    key = extra + (frame - extra * (base + 1)) / base;
    start = extra * (base + 1) + (key - extra) * base;
  }
  const uint32_t n = base + (key < extra ? 1 : 0);
  const uint32_t i = frame - start;
  const float t = (n % 2 == 0) ? float(i) / float(n) : float(i) / float(n - 1);
  return MorphFrame{key, t};
}

uint32_t MorphKeyFrame(uint32_t key, uint32_t frame_count, uint32_t key_count) {
  if (key_count == 0 || frame_count < 2 * key_count || key >= key_count) return frame_count;
  const uint32_t base = frame_count / key_count, extra = frame_count % key_count;
  const uint32_t start = key < extra ? key * (base + 1) : extra * (base + 1) + (key - extra) * base;
  const uint32_t n = base + (key < extra ? 1 : 0);
  return start + n / 2;
}

Quat QuadraticBezierRotation(const Quat& p0, const Quat& c, const Quat& p2, float t) {
  return QuatSlerpArc(QuatSlerpArc(p0, c, t), QuatSlerpArc(c, p2, t), t);
}

Status MorphLocals(const Skin& skin, const Pose& key, float t, std::vector<Transform>* locals) {
  RestLocals(skin, locals);
  for (const Pose::Rotation& r : key.rotations) {
    if (r.node < 0 || static_cast<size_t>(r.node) >= skin.nodes.size())
      return MakeError(Error::Code::kConfig, "pose '" + key.name + "': node index " + std::to_string(r.node) +
                                                 " out of range (the skin has " + std::to_string(skin.nodes.size()) +
                                                 " nodes)");
    const Quat rest = QuatNormalize(skin.nodes[static_cast<size_t>(r.node)].rotation);
    Quat delta = QuatMultiply(QuatConjugate(rest), QuatNormalize(r.rotation));
    if (delta[3] < 0) delta = {-delta[0], -delta[1], -delta[2], -delta[3]};  // the short way, ≤ 180°
    if (t == 0.0f) continue;  // exactly the rest pose
    Quat q;
    if (t == 0.5f) {
      q = QuatMultiply(rest, delta);  // B(½) = key; skip the rounding of two slerps
    } else if (delta[3] < 0.01f) {
      // Within 1.2° of a half turn, C = rest·δ² is (nearly) −rest, where slerp's arc is undefined: the closed
      // form B(t) = rest·δ^(4t(1−t)) (QuadraticBezierRotation's identity for P0 = P2) instead.
      const float v = std::sqrt(delta[0] * delta[0] + delta[1] * delta[1] + delta[2] * delta[2]);
      const float half = std::atan2(v, delta[3]) * 4.0f * t * (1.0f - t);
      const float s = std::sin(half) / v;
      q = QuatMultiply(rest, Quat{delta[0] * s, delta[1] * s, delta[2] * s, std::cos(half)});
    } else {
      const Quat control = QuatMultiply(rest, QuatMultiply(delta, delta));
      q = QuadraticBezierRotation(rest, control, rest, t);
    }
    (*locals)[static_cast<size_t>(r.node)].rotation = q;
  }
  return Ok{};
}

Status SkinMorphFrame(const Mesh& mesh, const std::vector<Pose>& keys, uint32_t frame, uint32_t frame_count,
                      SkinningScratch* scratch, float* out, size_t out_floats) {
  if (!mesh.skin) return MakeError(Error::Code::kConfig, "the mesh has no skin ('" + mesh.source_path + "')");
  Result<MorphFrame> f = MorphFrameAt(frame, frame_count, static_cast<uint32_t>(keys.size()));
  if (!f.ok()) return f.error();
  if (auto s = MorphLocals(*mesh.skin, keys[f->key], f->t, &scratch->locals); !s.ok()) return s;
  return SkinLocals(mesh, scratch->locals, scratch, out, out_floats);
}

// ---- pose files ---------------------------------------------------------------------------------------

namespace {

std::string SuggestBones(const Skin& skin, const std::string& bone) {
  // Names that contain the bone's stem (before any '.' side suffix), case-insensitive; a few at most.
  auto lower = [](std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return s;
  };
  std::string stem = lower(bone.substr(0, bone.find('.')));
  while (!stem.empty() && std::isdigit(static_cast<unsigned char>(stem.back()))) stem.pop_back();
  std::string out;
  int n = 0;
  if (stem.size() >= 3)
    for (const Node& node : skin.nodes)
      if (lower(node.name).find(stem) != std::string::npos && n < 6) {
        out += (n++ ? ", " : "") + node.name;
      }
  return out.empty() ? "" : " (did you mean: " + out + "?)";
}

}  // namespace

Result<Pose> ParsePose(std::string_view json_text, const Skin& skin, const std::string& origin) {
  const nlohmann::json j = nlohmann::json::parse(json_text, nullptr, /*allow_exceptions=*/false);
  auto fail = [&](const std::string& m) { return MakeError(Error::Code::kConfig, "pose '" + origin + "': " + m); };
  if (j.is_discarded()) return fail("not valid JSON");
  if (!j.is_object()) return fail("not a JSON object");
  Pose pose;
  pose.name = fs::path(origin).stem().string();
  if (j.contains("name")) {
    if (!j["name"].is_string()) return fail("\"name\" is not a string");
    pose.name = j["name"].get<std::string>();
  }
  if (j.contains("description") && j["description"].is_string()) pose.description = j["description"].get<std::string>();
  if (!j.contains("rotations") || !j["rotations"].is_object())
    return fail("needs \"rotations\": {\"bone\": {\"axis\": [x, y, z], \"degrees\": d}, ...}");
  for (const auto& [bone, r] : j["rotations"].items()) {
    const int32_t node = FindNode(skin, bone);
    if (node < 0)
      return fail("unknown bone '" + bone + "': the skin (" + skin.source + ", " + std::to_string(skin.nodes.size()) +
                  " nodes) has no node of that name" + SuggestBones(skin, bone));
    if (!r.is_object()) return fail("bone '" + bone + "': expected {\"axis\": [x, y, z], \"degrees\": d}");
    if (!r.contains("axis") || !r["axis"].is_array() || r["axis"].size() != 3)
      return fail("bone '" + bone + "': \"axis\" must be an array of 3 numbers");
    std::array<float, 3> axis{};
    double len2 = 0;
    for (int k = 0; k < 3; ++k) {
      const auto& a = r["axis"][static_cast<size_t>(k)];
      if (!a.is_number() || !std::isfinite(a.get<double>()))
        return fail("bone '" + bone + "': \"axis\" component " + std::to_string(k) + " is not a finite number");
      axis[k] = a.get<float>();
      if (!std::isfinite(axis[k]))  // finite as a double, past a float's range (±3.4e38)
        return fail("bone '" + bone + "': \"axis\" component " + std::to_string(k) + " is not a finite number as a "
                    "32-bit float (its magnitude must be below 3.4e38)");
      len2 += double(axis[k]) * axis[k];
    }
    if (!(len2 > 1e-12)) return fail("bone '" + bone + "': \"axis\" has zero length");
    if (!r.contains("degrees") || !r["degrees"].is_number() || !std::isfinite(r["degrees"].get<double>()))
      return fail("bone '" + bone + "': \"degrees\" must be a finite number");
    const float degrees = r["degrees"].get<float>();
    if (std::fabs(degrees) > 180.0f) return fail("bone '" + bone + "': \"degrees\" must be within [-180, 180]");
    const Quat rest = QuatNormalize(skin.nodes[static_cast<size_t>(node)].rotation);
    pose.rotations.push_back({node, QuatNormalize(QuatMultiply(QuatFromAxisAngle(axis, degrees), rest))});
  }
  return pose;
}

Result<Pose> LoadPose(const std::string& path, const Skin& skin) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return MakeError(Error::Code::kIo, "cannot read pose file '" + path + "'");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ParsePose(ss.str(), skin, path);
}

Result<std::vector<Pose>> LoadPoseFolder(const std::string& folder, const Skin& skin) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return MakeError(Error::Code::kIo, "pose folder '" + folder + "' not found");
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(folder, ec))
    if (e.is_regular_file() && e.path().extension() == ".json") files.push_back(e.path().string());
  if (ec) return MakeError(Error::Code::kIo, "cannot list pose folder '" + folder + "': " + ec.message());
  if (files.empty()) return MakeError(Error::Code::kConfig, "pose folder '" + folder + "' holds no *.json pose");
  std::sort(files.begin(), files.end());
  std::vector<Pose> poses;
  for (const std::string& f : files) {
    Result<Pose> p = LoadPose(f, skin);
    if (!p.ok()) return p.error();
    poses.push_back(std::move(p).value());
  }
  return poses;
}

}  // namespace spherechain::playback
