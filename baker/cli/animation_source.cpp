#include "animation_source.h"

#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "spherechain/baker/import.h"
#include "spherechain/baker/vertex_contract.h"
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
  anim->morph_option = sub->add_option("--morph", anim->morph,
                                       "Morph through key poses: pose files (.json), pose names in the poses folder, "
                                       "or folders; bare --morph: the character's default poses (even when it has clips)")
                           ->expected(0, CLI::detail::expected_max_vector_size);
  sub->add_option("--poses-dir", anim->poses_dir,
                  "Folder of default key poses (default: poses/<character> in the installed share/spherechain/, "
                  "else the source tree's data/, else data/poses/<character> upward from the current directory)");
  sub->add_option("--frames", anim->frames, "Frames: the morph's length, or uniform samples of the clip (default 40)");
  sub->add_option("--rig", *rig, "MakeHuman rig (.mhskel) for an OBJ; default: default.mhskel beside the OBJ");
}

bool OpenAnimation(const baker::Mesh& mesh, const AnimationArgs& a, AnimationSource* out, std::string* error) {
  playback::AnimationRequest request;
  request.mesh_name = a.mesh;
  request.clip = a.clip;
  for (const std::string& m : a.morph)
    if (!m.empty()) request.morph.push_back(m);  // a bare --morph parses as one empty value
  request.use_morph = a.morph_requested();
  request.frames = a.frames;
  request.poses_dir = FindPosesDir(playback::DefaultPoseCharacter(mesh, a.mesh), a.poses_dir);
  auto opened = playback::OpenAnimation(mesh, request);
  if (!opened.ok()) return *error = opened.error().message, false;
  *out = std::move(opened).value();
  return true;
}

bool OpenAssetAndMesh(const std::string& asset_path, const std::string& mesh_path, const std::string& rig,
                      LoadedAsset* asset, baker::Mesh* mesh, std::string* error) {
  if (!LoadAssetFile(asset_path, asset, error)) return false;
  baker::ImportOptions opts;
  opts.rig_path = rig;
  opts.vertices = baker::ContractForReimport(asset->view, mesh_path);  // the buffer the asset was baked from
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
             std::to_string(af->vertex_count()) + " (" + baker::DescribeVertexMismatch(view, f.vertex_count) + ")";
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
