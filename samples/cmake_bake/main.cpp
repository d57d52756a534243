// cmake_bake — the game side of a character its own build baked (CMakeLists.txt: spherechain_bake). It links
// only spherechain::runtime: load the asset, build the model and a character's workspace, run one frame at the
// bind pose (the asset's own bind positions stand in for the game's skinned vertex buffer) and print what the
// runtime sees.
//
//   cmake_bake [ASSET.sphc]        (default: the asset this build baked)
#include <cstdio>
#include <fstream>
#include <vector>

#include "spherechain/runtime/runtime.h"

namespace runtime = spherechain::runtime;

int main(int argc, char** argv) {
  const char* path = argc > 1 ? argv[1] : CMAKE_BAKE_ASSET;
  // The file's bytes, 8-byte aligned (LoadAsset reads them in place; they outlive the model).
  std::ifstream file(path, std::ios::binary | std::ios::ate);
  const std::streamoff end = file ? std::streamoff(file.tellg()) : -1;
  if (end < 0) return std::fprintf(stderr, "error: cannot read '%s'\n", path), 1;
  const size_t size = size_t(end);
  std::vector<uint64_t> bytes((size + 7) / 8);
  if (!file.seekg(0) || !file.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size)))
    return std::fprintf(stderr, "error: cannot read '%s'\n", path), 1;
  runtime::AssetView asset;
  runtime::Status s = runtime::LoadAsset(bytes.data(), size, &asset);
  if (runtime::Failed(s)) return std::fprintf(stderr, "error: '%s': %s\n", path, runtime::ToString(s)), 1;
  runtime::Model model;
  runtime::Workspace ws;
  if (runtime::Failed(s = model.Init(asset)) || runtime::Failed(s = ws.Init(model)))
    return std::fprintf(stderr, "error: %s\n", runtime::ToString(s)), 1;

  // One frame: refit the spheres from a vertex buffer, find the colliding sphere pairs (M2: all spheres).
  const auto* bind = asset.asset->bind_positions();
  if (!bind) return std::fprintf(stderr, "error: '%s' has no bind positions (baked before the crease rule: re-bake it)\n", path), 1;
  std::vector<runtime::Collision> pairs(runtime::DetectBound(asset, runtime::DetectMethod::kM2));
  uint32_t n = 0;
  runtime::RefitJob refit;
  refit.model = &model;
  refit.workspace = &ws;
  refit.positions = {bind->data(), asset.vertex_count, 12};
  runtime::DetectJob detect;
  detect.model = &model;
  detect.workspace = &ws;
  detect.method = runtime::DetectMethod::kM2;
  detect.output = pairs.data();
  detect.capacity = uint32_t(pairs.size());
  detect.count = &n;
  if (runtime::Failed(s = refit.Run()) || runtime::Failed(s = detect.Run()))
    return std::fprintf(stderr, "error: %s\n", runtime::ToString(s)), 1;
  std::printf("%s: %u spheres, %u chains, %u vertices, %u triangles; bind pose: %u colliding sphere pairs\n", path,
              asset.sphere_count, asset.chain_count, asset.vertex_count, asset.triangle_count, n);
  return 0;
}
