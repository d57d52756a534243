// What the importer and configuration fuzzers run on one input, shared with the corpus-replay doctest
// (tests/fuzz/bake_corpus_test.cpp) so every configuration, the ASan suite included, replays the corpora
// without libFuzzer.
//
// Importers: the bytes are written as a file of their format into a private scratch folder, then what a bake
// does with it up to and including the fit: ImportMesh → Segment (auto) → CheckPlausibility → head, hands and
// feet (a standing biped) → FitSpheres with a small budget. A failing plausibility check does not stop it
// (as `bake --force`), so the fit also sees bodies the checks would refuse. Configurations: ParseBakeConfig,
// then the whole Bake() of a fixed small body (fuzz/data/body.obj) with that configuration and, when the
// input has one, its region map. Every outcome is checked: an error has the documented code and a message;
// a result has the documented shape. Header-only; needs spherechain::baker.
#pragma once

#include <spherechain/baker/bake.h>

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <string>

namespace spherechain::fuzz {

using namespace spherechain::import;  // Mesh, Result, Error, ImportMesh, ...

/// The harness's mesh limits (HarnessImportOptions) and the largest mesh it segments and fits.
inline constexpr uint32_t kHarnessMaxVertices = uint32_t{1} << 18;
inline constexpr uint32_t kHarnessMaxTriangles = uint32_t{1} << 18;
inline constexpr uint32_t kHarnessMaxFitTriangles = uint32_t{1} << 15;

/// A folder of this process's own for the files the harness writes (/tmp/spherechain-fuzz-PID, or under
/// $TMPDIR). Created on first use; removed at a normal exit. libFuzzer ends its processes with _exit, which removes
/// nothing, so the first use also removes the folders of processes that have ended (a campaign's merge starts one
/// process after another).
inline const std::filesystem::path& ScratchDir() {
  // Never destroyed: the exit handler below runs after the destructors of statics made before it was registered.
  static const std::filesystem::path& dir = *[] {
    namespace fs = std::filesystem;
    const fs::path tmp = fs::temp_directory_path();
    const std::string prefix = "spherechain-fuzz-";
    std::error_code ec;
    for (fs::directory_iterator it(tmp, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string name = it->path().filename().string();
      if (name.rfind(prefix, 0) != 0 || name.size() == prefix.size() || name.size() > prefix.size() + 9 ||
          name.find_first_not_of("0123456789", prefix.size()) != std::string::npos)
        continue;
      const pid_t pid = static_cast<pid_t>(std::stol(name.substr(prefix.size())));
      std::error_code ignored;
      if (pid > 0 && ::kill(pid, 0) != 0 && errno == ESRCH) fs::remove_all(it->path(), ignored);
    }
    auto* d = new fs::path(tmp / (prefix + std::to_string(::getpid())));
    fs::create_directories(*d);
    std::atexit([] {  // a normal exit (the corpus tests) removes it at once
      std::error_code ignored;
      fs::remove_all(ScratchDir(), ignored);
    });
    return d;
  }();
  return dir;
}

/// Writes `data[0..size)` to ScratchDir()/name (replacing it) and returns its path; empty on failure.
inline std::string WriteScratch(const std::string& name, const uint8_t* data, size_t size) {
  const std::string path = (ScratchDir() / name).string();
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return {};
  const bool ok = (size == 0 || std::fwrite(data, 1, size, f) == size);
  return std::fclose(f) == 0 && ok ? path : std::string();
}

/// The fit a fuzzed bake runs: the cover fit with small budgets, so that one run on a body of the corpora
/// stays far under the fuzzers' timeout (a configuration asking for a big fit is slow by request, not a finding).
/// Interior voxels: at most 625 for a creature and FitParams::kBipedVoxelFactor times that (2,500) for a
/// biped, so a body whose voxels come out small (one lying down, measured by its thickness) is voxelised
/// coarser. A quarter of the assimp target's corpus (and 99 of the 218 inputs one run added) became mutations
/// of such a body (an STL), each run taking 1.4–3.0 s at a biped's former 10,000 voxels (fuzz build), 0.6–1.5 s
/// at 2,500. The seeds reach the same stages either way.
inline baker::FitParams SmallFit(baker::FitParams p = {}) {
  p.max_spheres = std::min(p.max_spheres, 64);
  p.skin_spheres = p.skin_spheres < 0 ? 4 : std::min(p.skin_spheres, p.max_spheres - 5);
  p.cover_voxel_rel = std::max(p.cover_voxel_rel, 0.02);
  p.cover_max_voxels = p.cover_max_voxels <= 0 ? 625 : std::min(p.cover_max_voxels, 625);
  p.refine_sweeps = std::min(p.refine_sweeps, 1);
  p.rays = std::min(p.rays, 32);
  p.disk_step_rel = std::max(p.disk_step_rel, 0.05);
  p.disk_step = 0.0;  // relative to the height only: an absolute δ may be tiny for the body
  return p;
}

/// What the harness imports with: the product's options, with smaller mesh limits (ImportOptions::max_vertices /
/// max_triangles, enforced the same way) so that no input makes one run slow by size alone.
/// assimp runs in its child process as in the product (ImportOptions::isolate_assimp), with 3 s to read a
/// file: libFuzzer runs an input a second time when its mallocs and frees differ (-detect_leaks=1), and both
/// runs, each child's teardown included, must stay under the fuzzers' 10 s timeout on a busy machine (with
/// 5 s, a PLY that loops assimp's reader took 10.1 s alone).
inline ImportOptions HarnessImportOptions() {
  ImportOptions o;
  o.max_vertices = kHarnessMaxVertices;
  o.max_triangles = kHarnessMaxTriangles;
  o.assimp_seconds = 3.0;
  return o;
}

/// How far one input got (for the replay's statistics).
struct Reached {
  bool imported = false, segmented = false, fitted = false, baked = false;
};

/// Checks a failure's shape: a message, and one of the codes a user can get from bad input.
inline const char* CheckError(const Error& e) {
  if (e.message.empty()) return "an error without a message";
  if (e.code == Error::Code::kInternal) return "kInternal (a library threw or memory ran out) on bad input";
  return nullptr;
}

/// Checks a segmentation's documented shape: a region of the layout for every triangle.
inline const char* CheckSegmentation(const Mesh& mesh, const baker::Segmentation& seg) {
  if (seg.triangle_regions.size() != mesh.triangle_count()) return "segmentation: triangle_regions is not #T long";
  if (seg.layout.count() < 1 || seg.layout.count() > kMaxRegions) return "segmentation: layout size out of range";
  for (uint8_t r : seg.triangle_regions)
    if (r >= seg.layout.count()) return "segmentation: a triangle without a region of the layout";
  return nullptr;
}

/// Checks fitted spheres: finite, positive radii, in a region of the layout.
inline const char* CheckSpheres(const std::vector<baker::FittedSphere>& spheres, const RegionLayout& layout) {
  for (const baker::FittedSphere& s : spheres) {
    if (!s.center.allFinite() || !std::isfinite(s.radius) || !(s.radius > 0.0)) return "fit: a non-finite sphere";
    if (static_cast<int>(s.region) >= layout.count()) return "fit: a sphere outside the layout";
  }
  return nullptr;
}

/// The importer fuzzers' sequence on the file at `path` (module comment). Returns nullptr when every stage
/// behaved as documented, else a static description of the broken invariant.
inline const char* RunImportSequence(const std::string& path, const ImportOptions& options = {},
                                     Reached* reached = nullptr) {
  Reached local;
  Reached& r = reached ? *reached : local;
  Result<Mesh> mesh = ImportMesh(path, options);
  // The child's time limit is wall-clock, and the fuzzers run at nice 19: on a busy machine a child that
  // finished reading may run out of time in our conversion of the scene without any fault of ours (a 7 KB
  // PLY that converts in 51 ms did). The import then runs again in a child with an hour, so that a
  // conversion that truly never ends is libFuzzer's timeout (assimp stays out of this process).
  if (!mesh.ok() && options.isolate_assimp &&
      mesh.error().message.rfind(path + ": assimp did not finish converting", 0) == 0) {
    ImportOptions longer = options;
    longer.assimp_seconds = 3600.0;
    mesh = ImportMesh(path, longer);
  }
  if (!mesh.ok()) {
    if (mesh.error().code != Error::Code::kFormat && mesh.error().code != Error::Code::kInvalidMesh &&
        mesh.error().code != Error::Code::kIo)
      return "import: an error other than kFormat / kInvalidMesh / kIo";
    if (mesh.error().message.find(ScratchDir().string()) == std::string::npos)
      return "import: the error does not name the file";
    // assimp crashing or looping in its child process is contained (a format error); our code converting its
    // scene must not (the child's sanitizer report, if any, is on stderr above). Checked as the message's
    // start ("PATH: the assimp importer's process died converting …"), never found anywhere in it: a parser's
    // message may quote the input, and libFuzzer puts the phrase into inputs (it watches this very search).
    const std::string& message = mesh.error().message;
    for (const char* ours : {"the assimp importer's process died converting", "assimp did not finish converting"})
      if (message.rfind(path + ": " + ours, 0) == 0)
        return "import: the assimp importer's child process died or hung in our conversion of assimp's scene";
    return CheckError(mesh.error());
  }
  r.imported = true;
  if (!ValidateMesh(mesh.value()).ok()) return "import: ImportMesh returned a mesh ValidateMesh refuses";
  if (mesh->vertex_count() > options.max_vertices || mesh->triangle_count() > options.max_triangles)
    return "import: a mesh over ImportOptions' limits";
  if (mesh->triangle_count() > kHarnessMaxFitTriangles) return nullptr;  // legal, but slow to segment under ASan

  Result<baker::Segmentation> seg = baker::Segment(mesh.value(), baker::SegmentMethod::kAuto);
  if (!seg.ok()) return CheckError(seg.error());
  if (const char* broken = CheckSegmentation(mesh.value(), seg.value())) return broken;
  r.segmented = true;
  (void)baker::CheckPlausibility(mesh.value(), seg.value(), nullptr, nullptr);
  if (seg->layout.IsPaperFive()) {
    Result<baker::ExtremitySplit> split = baker::SplitExtremities(mesh.value(), seg.value());
    if (!split.ok()) return CheckError(split.error());
    if (Status s = baker::ApplyExtremities(mesh.value(), split.value(), &seg.value()); !s.ok()) return CheckError(s.error());
    if (const char* broken = CheckSegmentation(mesh.value(), seg.value())) return broken;
  }
  Result<baker::FitResult> fit = baker::FitSpheres(mesh.value(), seg.value(), SmallFit());
  if (!fit.ok()) return CheckError(fit.error());
  r.fitted = true;
  return CheckSpheres(fit->spheres, seg->layout);
}

/// The fixed body the MakeHuman and configuration fuzzers bake (a standing figure of boxes, 880 triangles:
/// fuzz/make_seeds.py). SPHERECHAIN_SOURCE_DIR: the checkout (a compile definition of the targets and tests).
inline std::string FixedBodyPath() { return SPHERECHAIN_SOURCE_DIR "/fuzz/data/body.obj"; }

/// The configuration fuzzer's sequence: `config_text` as a bake configuration and, when not empty,
/// `region_map` as its region map (written to the scratch folder; the configuration's own paths — region map
/// and rig — are replaced, so no input names a file of the machine), then the whole bake of `body_path`
/// with the fit's budgets made small (SmallFit).
inline const char* RunBakeConfigSequence(const std::string& config_text, const std::string& region_map,
                                         const std::string& body_path, Reached* reached = nullptr) {
  Reached local;
  Reached& r = reached ? *reached : local;
  Result<baker::BakeConfig> config = baker::ParseBakeConfig(config_text, "config.json");
  if (!config.ok()) {
    if (config.error().code != Error::Code::kConfig) return "config: an error other than kConfig";
    if (config.error().message.rfind("config.json", 0) != 0) return "config: the error does not name the file";
    return CheckError(config.error());
  }
  (void)baker::CanonicalConfig(config.value());
  config->import.rig_path.clear();
  config->region_map.clear();
  if (!region_map.empty()) {
    config->region_map = WriteScratch("map.json", reinterpret_cast<const uint8_t*>(region_map.data()), region_map.size());
    if (config->region_map.empty()) return nullptr;  // the scratch folder is full: not the input's fault
  }
  config->fit = SmallFit(config->fit);
  config->force = true;  // past the plausibility checks: every stage sees the configuration
  Result<baker::BakeResult> baked = baker::Bake(body_path, config.value());
  if (!baked.ok()) return CheckError(baked.error());
  r.baked = true;
  if (const char* broken = CheckSegmentation(baked->mesh, baked->segmentation)) return broken;
  if (const char* broken = CheckSpheres(baked->fit.spheres, baked->segmentation.layout)) return broken;
  if (baked->asset.empty()) return "bake: no asset bytes";
  return nullptr;
}

// ---------------------------------------------------------------------------------------------------
// Each target's step on one input: what its LLVMFuzzerTestOneInput runs, and what the replay runs per file.

/// fuzz_import_gltf: `.glb` when the bytes start with the GLB magic "glTF", else `.gltf` JSON (buffers as data
/// URIs; a URI naming a file finds only the scratch folder).
inline const char* RunImportGltfInput(const uint8_t* data, size_t size, Reached* reached = nullptr) {
  const bool glb = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
  const std::string path = WriteScratch(glb ? "input.glb" : "input.gltf", data, size);
  return path.empty() ? nullptr : RunImportSequence(path, HarnessImportOptions(), reached);
}

/// fuzz_import_obj: the bytes as a Wavefront `.obj`.
inline const char* RunImportObjInput(const uint8_t* data, size_t size, Reached* reached = nullptr) {
  const std::string path = WriteScratch("input.obj", data, size);
  return path.empty() ? nullptr : RunImportSequence(path, HarnessImportOptions(), reached);
}

/// fuzz_import_makehuman: a MakeHuman rig beside the fixed body (FixedBodyPath): the bytes up to the first NUL
/// are the `.mhskel`, the rest the `.mhw`; with no NUL no weights file is given, so the skeleton's own
/// `weights_file` is looked up beside it.
inline const char* RunImportMakeHumanInput(const uint8_t* data, size_t size, Reached* reached = nullptr) {
  namespace fs = std::filesystem;
  static const std::string body = [] {
    const fs::path to = ScratchDir() / "body.obj";
    fs::copy_file(FixedBodyPath(), to, fs::copy_options::overwrite_existing);
    return to.string();
  }();
  const auto* nul = static_cast<const uint8_t*>(std::memchr(data, 0, size));
  const size_t skel_size = nul ? static_cast<size_t>(nul - data) : size;
  ImportOptions options = HarnessImportOptions();
  options.rig_path = WriteScratch("input.mhskel", data, skel_size);
  std::error_code ec;
  fs::remove(ScratchDir() / "input.mhw", ec);
  if (nul) options.weights_path = WriteScratch("input.mhw", nul + 1, size - skel_size - 1);
  if (options.rig_path.empty() || (nul && options.weights_path.empty())) return nullptr;
  return RunImportSequence(body, options, reached);
}

/// fuzz_import_assimp: the formats the baker reads through assimp; the first byte picks one
/// (kAssimpFormats[data[0] % 12]), the rest is the file.
inline constexpr const char* kAssimpFormats[] = {"fbx", "dae", "x",   "blend",   "3ds",  "ply",
                                                 "stl", "iqm", "smd", "md5mesh", "ms3d", "b3d"};
inline const char* RunImportAssimpInput(const uint8_t* data, size_t size, Reached* reached = nullptr) {
  if (size == 0) return nullptr;
  const char* ext = kAssimpFormats[data[0] % std::size(kAssimpFormats)];
  const std::string path = WriteScratch(std::string("input.") + ext, data + 1, size - 1);
  return path.empty() ? nullptr : RunImportSequence(path, HarnessImportOptions(), reached);
}

/// fuzz_bake_config: up to the first NUL the JSON configuration, after it (when there is a NUL) its region map.
inline const char* RunBakeConfigInput(const uint8_t* data, size_t size, Reached* reached = nullptr) {
  const auto* nul = static_cast<const uint8_t*>(std::memchr(data, 0, size));
  const char* text = reinterpret_cast<const char*>(data);
  const std::string config(text, nul ? static_cast<size_t>(nul - data) : size);
  const std::string map = nul ? std::string(reinterpret_cast<const char*>(nul + 1), text + size) : std::string();
  return RunBakeConfigSequence(config, map, FixedBodyPath(), reached);
}

}  // namespace spherechain::fuzz
