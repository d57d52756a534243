#include "animation_source.h"

#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "spherechain/baker/import.h"
#include "spherechain/baker/write.h"

namespace spherechain::cli {

namespace {

namespace fs = std::filesystem;

/// Folder of the character's default key poses, the first that exists of: --poses-dir; the installed
/// data, <executable's folder>/SPHERECHAIN_BIN_TO_DATA/poses/<character> (bin/ → share/spherechain/);
/// the source tree's data/poses/<character> (a build tree, compiled-in path); data/poses/<character>
/// walking up from the current directory. Empty when none exists.
std::string FindPosesDir(const std::string& character, const std::string& explicit_dir) {
  if (!explicit_dir.empty()) return explicit_dir;
  std::vector<fs::path> candidates;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) candidates.push_back(exe.parent_path() / SPHERECHAIN_BIN_TO_DATA / "poses" / character);
  candidates.push_back(fs::path(SPHERECHAIN_SOURCE_DATA_DIR) / "poses" / character);
  const fs::path rel = fs::path("data") / "poses" / character;
  fs::path p = fs::current_path(ec);
  for (int up = 0; up < 6 && !ec && !p.empty(); ++up, p = p.parent_path()) {
    candidates.push_back(p / rel);
    if (p == p.parent_path()) break;
  }
  for (const fs::path& c : candidates)
    if (fs::is_directory(c, ec)) return c.lexically_normal().string();
  return {};
}

std::string Hex(uint64_t v) {
  char b[24];
  std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(v));
  return b;
}

}  // namespace

void AddAnimationOptions(CLI::App* sub, std::string* asset, std::string* rig, AnimationArgs* anim) {
  sub->add_option("asset", *asset, ".sphc asset baked from the mesh")->required()->check(CLI::ExistingFile);
  sub->add_option("--mesh", anim->mesh, "The character file the asset was baked from (checked by fingerprint)")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--clip", anim->clip, "Clip to play (default: the first clip; none: the morph)");
  sub->add_option("--morph", anim->morph,
                  "Key pose files (.json), pose names in the poses folder, or folders; morph through them");
  sub->add_option("--poses-dir", anim->poses_dir,
                  "Folder of default key poses (default: poses/<character> in the installed share/spherechain/, "
                  "else the source tree's data/, else data/poses/<character> upward from the current directory)");
  sub->add_option("--frames", anim->frames, "Frames: the morph's length, or uniform samples of the clip (default 40)");
  sub->add_option("--rig", *rig, "MakeHuman rig (.mhskel) for an OBJ; default: default.mhskel beside the OBJ");
}

std::string AnimationSource::Describe() const {
  if (clip) return "clip '" + clip->name + "' (" + std::to_string(clip->duration_s) + " s)";
  return "morph through " + std::to_string(poses.size()) + " key poses from " + poses_from;
}

baker::Status AnimationSource::Frame(const baker::Mesh& mesh, uint32_t f, baker::SkinningScratch* scratch,
                                     std::vector<float>* out, std::string* label) const {
  out->resize(mesh.positions.size());
  char text[96];
  if (clip) {
    const float t = clip->duration_s * float(f) / float(frames);
    std::snprintf(text, sizeof text, "t=%.3fs", t);
    if (auto s = baker::SkinClip(mesh, *clip, t, scratch, out->data(), out->size()); !s.ok()) return s;
  } else {
    auto mf = baker::MorphFrameAt(f, frames, static_cast<uint32_t>(poses.size()));
    if (!mf.ok()) return mf.error();
    std::snprintf(text, sizeof text, "%s t=%.3f", poses[mf->key].name.c_str(), mf->t);
    if (auto s = baker::SkinMorphFrame(mesh, poses, f, frames, scratch, out->data(), out->size()); !s.ok()) return s;
  }
  *label = text;
  return baker::Ok{};
}

bool OpenAnimation(const baker::Mesh& mesh, const AnimationArgs& a, AnimationSource* out, std::string* error) {
  *out = AnimationSource{};
  if (!a.clip.empty() && !a.morph.empty()) return *error = "--clip and --morph exclude each other", false;
  if (!mesh.skin)
    return *error = "'" + a.mesh + "' has no skin: animating it needs a rigged character (glTF skin, assimp bones, "
                    "or a MakeHuman .mhskel beside base.obj / --rig)",
           false;
  if (!a.clip.empty()) {
    for (const auto& c : mesh.clips)
      if (c.name == a.clip) out->clip = &c;
    if (!out->clip) {
      std::string names;
      for (const auto& c : mesh.clips) names += (names.empty() ? "" : ", ") + ("'" + c.name + "'");
      return *error = "no clip named '" + a.clip + "' in '" + a.mesh + "' (clips: " + (names.empty() ? "none" : names) +
                      ")",
             false;
    }
  } else if (a.morph.empty() && !mesh.clips.empty()) {
    out->clip = &mesh.clips.front();
  }
  if (!out->clip) {
    const std::string character = mesh.skin->source == "mhskel" ? "makehuman" : fs::path(a.mesh).stem().string();
    const std::string dir = FindPosesDir(character, a.poses_dir);
    if (a.morph.empty()) {
      if (dir.empty())
        return *error = "'" + a.mesh + "' has no clips and no default key poses (data/poses/" + character +
                        " not found in the installed share/spherechain/, the source tree or upward from the current "
                        "directory); pass --morph POSE.json... or "
                        "--poses-dir DIR",
               false;
      auto loaded = baker::LoadPoseFolder(dir, *mesh.skin);
      if (!loaded.ok()) return *error = loaded.error().message, false;
      out->poses = std::move(loaded).value();
      out->poses_from = dir;
    } else {
      for (const std::string& m : a.morph) {
        std::string path = m;
        if (!fs::exists(path) && !dir.empty() && fs::exists(fs::path(dir) / (m + ".json")))
          path = (fs::path(dir) / (m + ".json")).string();
        if (fs::is_directory(path)) {
          auto loaded = baker::LoadPoseFolder(path, *mesh.skin);
          if (!loaded.ok()) return *error = loaded.error().message, false;
          for (auto& p : loaded.value()) out->poses.push_back(std::move(p));
        } else {
          auto p = baker::LoadPose(path, *mesh.skin);
          if (!p.ok()) return *error = p.error().message, false;
          out->poses.push_back(std::move(p).value());
        }
      }
      out->poses_from = "--morph";
    }
  }
  out->frames = a.frames;
  if (a.frames == 0) return *error = "--frames must be > 0", false;
  if (!out->clip && a.frames < 2 * out->poses.size())
    return *error = "--frames " + std::to_string(a.frames) + " is too few for " + std::to_string(out->poses.size()) +
                    " key poses (each needs a rest frame and its key frame: at least " +
                    std::to_string(2 * out->poses.size()) + ")",
           false;
  if (out->clip) {
    if (auto s = baker::ValidateClip(*mesh.skin, *out->clip); !s.ok()) return *error = s.error().message, false;
  }
  return true;
}

bool OpenAssetAndMesh(const std::string& asset_path, const std::string& mesh_path, const std::string& rig,
                      LoadedAsset* asset, baker::Mesh* mesh, std::string* error) {
  if (!LoadAssetFile(asset_path, asset, error)) return false;
  baker::ImportOptions opts;
  opts.rig_path = rig;
  baker::Context log = MakeLoggingContext();
  auto imported = baker::ImportMesh(mesh_path, opts, &log);
  if (!imported.ok())
    return *error = std::string(baker::ToString(imported.error().code)) + ": " + imported.error().message, false;
  *mesh = std::move(imported).value();
  return CheckFingerprint(asset->view, *mesh, asset_path, mesh_path, error);
}

bool CheckFingerprint(const runtime::AssetView& view, const baker::Mesh& mesh, const std::string& asset_path,
                      const std::string& mesh_path, std::string* error) {
  const baker::Fingerprint f = baker::ComputeFingerprint(mesh);
  const auto* af = view.asset->fingerprint();
  const std::string pair = "mesh '" + mesh_path + "' does not match asset '" + asset_path + "': ";
  if (f.vertex_count != af->vertex_count()) {
    *error = pair + "the mesh has " + std::to_string(f.vertex_count) + " vertices, the asset was baked from " +
             std::to_string(af->vertex_count());
    return false;
  }
  if (f.triangle_count != af->triangle_count()) {
    *error = pair + "the mesh has " + std::to_string(f.triangle_count) + " triangles, the asset was baked from " +
             std::to_string(af->triangle_count());
    return false;
  }
  if (f.positions_hash != af->positions_hash() || f.indices_hash != af->indices_hash()) {
    *error = pair + "same counts but different content (positions hash " + Hex(f.positions_hash) + " vs " +
             Hex(af->positions_hash()) + ", indices hash " + Hex(f.indices_hash) + " vs " + Hex(af->indices_hash()) +
             "); re-bake the asset from this mesh";
    return false;
  }
  return true;
}

}  // namespace spherechain::cli
