// OpenAnimation and Animation: which clip or key poses a tool plays, and its frames (animation_source.h).
#include "spherechain/playback/animation_source.h"

#include <cstdio>
#include <filesystem>

namespace spherechain::playback {

namespace fs = std::filesystem;

std::string DefaultPoseCharacter(const Mesh& mesh, const std::string& mesh_name) {
  return mesh.skin && mesh.skin->source == "mhskel" ? "makehuman" : fs::path(mesh_name).stem().string();
}

std::string FindPosesDir(const std::string& character, const std::vector<std::string>& data_dirs) {
  std::error_code ec;
  for (const std::string& d : data_dirs) {
    const fs::path c = fs::path(d) / "poses" / character;
    if (fs::is_directory(c, ec)) return c.lexically_normal().string();
  }
  return {};
}

std::vector<std::string> PoseInputFiles(const std::vector<std::string>& morph, const std::string& poses_dir) {
  std::vector<std::string> files;
  auto add_folder = [&](const std::string& dir) {
    std::error_code ec;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
      if (it->is_regular_file(ec)) files.push_back(it->path().string());
  };
  for (const std::string& m : morph) {
    if (m.empty()) continue;
    files.push_back(m);
    std::error_code ec;
    if (fs::is_directory(m, ec)) add_folder(m);
  }
  if (!poses_dir.empty()) add_folder(poses_dir);
  return files;
}

std::string Animation::Describe() const {
  if (clip) return "clip '" + clip->name + "' (" + std::to_string(clip->duration_s) + " s)";
  return "morph through " + std::to_string(poses.size()) + " key poses from " + poses_from;
}

float Animation::FrameTime(uint32_t f) const {
  if (clip && !times.empty()) return times[f];
  if (clip) return clip->duration_s * float(f) / float(frames);
  return float(f) / kMorphFps;
}

std::string Animation::FrameLabel(uint32_t f) const {
  char t[32];  // the time alone: a pose's name may be any length
  if (clip) {
    std::snprintf(t, sizeof t, "t=%.3fs", FrameTime(f));
    return t;
  }
  auto mf = MorphFrameAt(f, frames, static_cast<uint32_t>(poses.size()));
  if (!mf.ok()) return "frame " + std::to_string(f);
  std::snprintf(t, sizeof t, " t=%.3f", mf->t);
  return poses[mf->key].name + t;
}

Status Animation::FrameLocals(const Skin& skin, uint32_t f, std::vector<Transform>* locals) const {
  if (clip) return SampleClip(skin, *clip, FrameTime(f), locals);
  auto mf = MorphFrameAt(f, frames, static_cast<uint32_t>(poses.size()));
  if (!mf.ok()) return mf.error();
  return MorphLocals(skin, poses[mf->key], mf->t, locals);
}

Status Animation::Frame(const Mesh& mesh, uint32_t f, SkinningScratch* scratch, std::vector<float>* out,
                        std::string* label) const {
  out->resize(mesh.positions.size());
  if (clip) {
    if (auto s = SkinClip(mesh, *clip, FrameTime(f), scratch, out->data(), out->size()); !s.ok()) return s;
  } else {
    if (auto s = SkinMorphFrame(mesh, poses, f, frames, scratch, out->data(), out->size()); !s.ok()) return s;
  }
  if (label) *label = FrameLabel(f);
  return Ok{};
}

Result<Animation> OpenAnimation(const Mesh& mesh, const AnimationRequest& a) {
  auto fail = [](std::string m) { return MakeError(Error::Code::kConfig, std::move(m)); };
  Animation out;
  const bool morph = a.use_morph || !a.morph.empty();
  if (!a.clip.empty() && morph) return fail("--clip and --morph exclude each other");
  if (!mesh.skin)
    return fail("'" + a.mesh_name + "' has no skin: animating it needs a rigged character (glTF skin, assimp bones, "
                "or a MakeHuman .mhskel beside base.obj / --rig)");
  if (!a.clip.empty()) {
    for (const auto& c : mesh.clips)
      if (c.name == a.clip) out.clip = &c;
    if (!out.clip) {
      std::string names;
      for (const auto& c : mesh.clips) names += (names.empty() ? "" : ", ") + ("'" + c.name + "'");
      return fail("no clip named '" + a.clip + "' in '" + a.mesh_name + "' (clips: " + (names.empty() ? "none" : names) +
                  ")");
    }
  } else if (!morph && !mesh.clips.empty()) {
    out.clip = &mesh.clips.front();
  }
  if (!out.clip) {
    const std::string& dir = a.poses_dir;
    if (a.morph.empty()) {
      if (dir.empty()) {
        const std::string character = DefaultPoseCharacter(mesh, a.mesh_name);
        return fail("'" + a.mesh_name + "' has " + (mesh.clips.empty() ? "no clips and " : "") +
                    "no default key poses (data/poses/" + character +
                    " not found in the installed share/spherechain/, the source tree or upward from the current "
                    "directory); pass --morph POSE.json... or --poses-dir DIR");
      }
      auto loaded = LoadPoseFolder(dir, *mesh.skin);
      if (!loaded.ok()) return loaded.error();
      out.poses = std::move(loaded).value();
      out.poses_from = dir;
    } else {
      for (const std::string& m : a.morph) {
        std::string path = m;
        if (!fs::exists(path) && !dir.empty() && fs::exists(fs::path(dir) / (m + ".json")))
          path = (fs::path(dir) / (m + ".json")).string();
        if (fs::is_directory(path)) {
          auto loaded = LoadPoseFolder(path, *mesh.skin);
          if (!loaded.ok()) return loaded.error();
          for (auto& p : loaded.value()) out.poses.push_back(std::move(p));
        } else {
          auto p = LoadPose(path, *mesh.skin);
          if (!p.ok()) return p.error();
          out.poses.push_back(std::move(p).value());
        }
      }
      out.poses_from = "--morph";
    }
  }
  out.frames = a.frames;
  if (a.frames == 0 || a.frames > kMaxFrames)
    return fail(a.frames_option + ": " + std::to_string(a.frames) + " is not in [1, " + std::to_string(kMaxFrames) + "]");
  if (!out.clip && a.frames < 2 * out.poses.size())
    return fail(a.frames_option + " " + std::to_string(a.frames) + " is too few for " + std::to_string(out.poses.size()) +
                " key poses (each needs a rest frame and its key frame: at least " +
                std::to_string(2 * out.poses.size()) + ")");
  if (out.clip) {
    if (auto s = ValidateClip(*mesh.skin, *out.clip); !s.ok()) return s.error();
  }
  return out;
}

}  // namespace spherechain::playback
