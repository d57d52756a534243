#include "animation_source.h"

#include <filesystem>

#include "commands.h"
#include "spherechain/playback/character.h"

namespace spherechain::cli {

namespace fs = std::filesystem;

std::string FindPosesDir(const std::string& character, const std::string& explicit_dir) {
  if (!explicit_dir.empty()) return explicit_dir;
  std::vector<std::string> data_dirs;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) data_dirs.push_back((exe.parent_path() / SPHERECHAIN_BIN_TO_DATA).string());
  data_dirs.push_back(SPHERECHAIN_SOURCE_DATA_DIR);
  fs::path p = fs::current_path(ec);
  for (int up = 0; up < 6 && !ec && !p.empty(); ++up, p = p.parent_path()) {
    data_dirs.push_back((p / "data").string());
    if (p == p.parent_path()) break;
  }
  return playback::FindPosesDir(character, data_dirs);
}

std::vector<std::string> DefaultPoseFiles(const std::string& mesh) {
  std::vector<std::string> files;
  for (const std::string& character : {std::string("makehuman"), fs::path(mesh).stem().string()}) {
    const std::string dir = FindPosesDir(character, "");
    if (dir.empty()) continue;
    const std::vector<std::string> more = playback::PoseInputFiles({}, dir);
    files.insert(files.end(), more.begin(), more.end());
  }
  return files;
}

std::vector<std::string> PoseInputs(const AnimationArgs& a) {
  std::vector<std::string> files = playback::PoseInputFiles(a.morph, a.poses_dir);
  if (a.poses_dir.empty()) {  // the default folder: where a bare --morph, a pose name or a mesh without clips reads
    const std::vector<std::string> more = DefaultPoseFiles(a.mesh);
    files.insert(files.end(), more.begin(), more.end());
  }
  return files;
}

void AddAnimationOptions(CLI::App* sub, std::string* asset, std::string* rig, AnimationArgs* anim) {
  sub->add_option("asset", *asset, ".sphc asset baked from the mesh")->required()->check(CLI::ExistingFile);
  sub->add_option("--mesh", anim->mesh, "The character file the asset was baked from (checked by fingerprint)")
      ->required()
      ->check(CLI::ExistingFile);
  CLI::Option* clip = sub->add_option("--clip", anim->clip, "Clip to play (default: the first clip; none: the morph)");
  anim->morph_option = sub->add_option("--morph", anim->morph,
                                       "Morph through key poses: pose files (.json), pose names in the poses folder, "
                                       "or folders; bare --morph: the character's default poses (even when it has clips)")
                           ->expected(0, CLI::detail::expected_max_vector_size)
                           ->excludes(clip);
  sub->add_option("--poses-dir", anim->poses_dir,
                  "Folder of default key poses (default: poses/<character> in the installed share/spherechain/, "
                  "else the source tree's data/, else data/poses/<character> upward from the current directory)");
  sub->add_option("--frames", anim->frames,
                  "Frames: the morph's length, or uniform samples of the clip (default 40, at most 1,000,000)")
      ->check(WithinRange(1, kMaxFrames));
  sub->add_option("--rig", *rig, "MakeHuman rig (.mhskel) for an OBJ; default: default.mhskel beside the OBJ");
}

bool LoadAssetFile(const std::string& path, LoadedAsset* out, std::string* error) {
  auto s = import::LoadAssetFile(path, out);
  if (!s.ok()) *error = s.error().message;
  return s.ok();
}

playback::AnimationRequest MakeAnimationRequest(const import::Mesh& mesh, const AnimationArgs& a) {
  playback::AnimationRequest request;
  request.mesh_name = a.mesh;
  request.clip = a.clip;
  for (const std::string& m : a.morph)
    if (!m.empty()) request.morph.push_back(m);  // a bare --morph parses as one empty value
  request.use_morph = a.morph_requested();
  request.frames = a.frames;
  request.poses_dir = FindPosesDir(playback::DefaultPoseCharacter(mesh, a.mesh), a.poses_dir);
  return request;
}

bool OpenAnimation(const import::Mesh& mesh, const AnimationArgs& a, AnimationSource* out, std::string* error) {
  auto opened = playback::OpenAnimation(mesh, MakeAnimationRequest(mesh, a));
  if (!opened.ok()) return *error = opened.error().message, false;
  *out = std::move(opened).value();
  return true;
}

bool OpenAssetAndMesh(const std::string& asset_path, const std::string& mesh_path, const std::string& rig,
                      LoadedAsset* asset, import::Mesh* mesh, std::string* error) {
  import::Context log = MakeLoggingContext();
  auto s = playback::OpenCharacter(asset_path, mesh_path, rig, asset, mesh, &log);
  if (!s.ok()) *error = s.error().message;
  return s.ok();
}

}  // namespace spherechain::cli
