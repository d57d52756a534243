// many_characters ASSET.sphc MESH [N] — N characters of one asset per frame on the CPU: one Model shared by
// all, one Workspace each, every character its own pose, BatchJob spread over the cores by TBB through the
// runtime's ParallelFor hook. Prints the characters per second and checks the batch against each
// character's own RefitJob + DetectJob.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <vector>

#include "spherechain/import/import.h"
#include "spherechain/import/vertex_contract.h"
#include "spherechain/runtime/runtime.h"

namespace runtime = spherechain::runtime;
namespace import = spherechain::import;

// The ParallelFor hook on TBB: the runtime hands over `count` task indices, TBB spreads them.
void TbbParallelFor(void*, uint32_t count, runtime::ParallelFor::Task task, void* data) {
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, count),
                    [&](const tbb::blocked_range<uint32_t>& r) { task(data, r.begin(), r.end()); });
}

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: many_characters ASSET.sphc MESH [N]\n");
    return 2;
  }
  const uint32_t N = argc > 3 ? uint32_t(std::max(1, std::atoi(argv[3]))) : 1000u;
  // 1. Load the asset once, build its Model once (shared, immutable), one Workspace per character.
  std::ifstream file(argv[1], std::ios::binary | std::ios::ate);
  const std::streamoff end = file ? std::streamoff(file.tellg()) : -1;
  if (end < 0) return std::fprintf(stderr, "error: cannot open '%s'\n", argv[1]), 1;
  const size_t size = size_t(end);
  std::vector<uint64_t> bytes((size + 7) / 8);
  if (!file.seekg(0) || !file.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size)))
    return std::fprintf(stderr, "error: cannot read '%s'\n", argv[1]), 1;
  runtime::AssetView asset;
  if (runtime::Status s = runtime::LoadAsset(bytes.data(), size, &asset); runtime::Failed(s))
    return std::fprintf(stderr, "error: '%s': %s\n", argv[1], runtime::ToString(s)), 1;
  runtime::Model model;
  if (runtime::Status s = model.Init(asset); runtime::Failed(s))
    return std::fprintf(stderr, "error: %s\n", runtime::ToString(s)), 1;
  std::vector<runtime::Workspace> workspaces(N);
  for (runtime::Workspace& ws : workspaces)
    if (runtime::Status s = ws.Init(model); runtime::Failed(s))
      return std::fprintf(stderr, "error: %s\n", runtime::ToString(s)), 1;

  // 2. Each character's vertex buffer: the bind pose with its left arm swung by its own angle (a game
  //    hands over what its skinning produced).
  import::ImportOptions options;
  options.vertices = import::ContractForReimport(asset, argv[2]);  // the vertex buffer the asset was baked from
  auto mesh = import::ImportMesh(argv[2], options);
  if (!mesh.ok()) return std::fprintf(stderr, "error: %s\n", mesh.error().message.c_str()), 1;
  const uint32_t V = asset.vertex_count;
  if (mesh->vertex_count() != V || mesh->triangle_count() != asset.triangle_count)  // the loop below indexes its triangles
    return std::fprintf(stderr, "error: the mesh has %u vertices and %u triangles, the asset %u and %u\n",
                        mesh->vertex_count(), mesh->triangle_count(), V, asset.triangle_count),
           1;
  const auto* tri_regions = asset.asset->triangle_regions();
  std::vector<uint8_t> arm(V, 0);
  for (uint32_t t = 0; t < asset.triangle_count; ++t)
    if (tri_regions && tri_regions->Get(t) == 0)
      for (int k = 0; k < 3; ++k) arm[mesh->indices[3 * t + k]] = 1;
  float centre[3] = {0, 0, 0};
  for (uint32_t v = 0; v < V; ++v)
    for (int k = 0; k < 3; ++k) centre[k] += mesh->positions[3 * v + k] / float(V);
  std::vector<std::vector<float>> poses(N, mesh->positions);
  for (uint32_t c = 0; c < N; ++c) {
    const float a = 1.2f * float(c) / float(N), co = std::cos(a), si = std::sin(a);  // about the body's up axis
    for (uint32_t v = 0; v < V; ++v)
      if (arm[v]) {
        float* p = &poses[c][3 * v];
        const float x = p[0] - centre[0], z = p[2] - centre[2];
        p[0] = centre[0] + co * x + si * z;
        p[2] = centre[2] - si * x + co * z;
      }
  }

  // 3. Every frame: one BatchJob over the N characters (refit from the vertex buffer + M1).
  const uint32_t capacity = runtime::DetectBound(asset, runtime::DetectMethod::kM1);
  std::vector<runtime::Collision> out(size_t{N} * capacity);
  std::vector<uint32_t> count(N, 0);
  std::vector<runtime::CharacterFrame> chars(N);
  for (uint32_t c = 0; c < N; ++c) {
    chars[c].workspace = &workspaces[c];
    chars[c].positions = {poses[c].data(), V, 12};
    chars[c].output = out.data() + size_t{c} * capacity;
    chars[c].capacity = capacity;
    chars[c].count = &count[c];
  }
  runtime::BatchJob batch;
  batch.model = &model;
  batch.characters = chars.data();
  batch.character_count = N;
  batch.method = runtime::DetectMethod::kM1;
  batch.parallel_for.run = &TbbParallelFor;
  double best_us = 1e300;
  for (int frame = 0; frame < 5; ++frame) {
    const auto t0 = std::chrono::steady_clock::now();
    if (runtime::Status s = batch.Run(); runtime::Failed(s))
      return std::fprintf(stderr, "batch: %s\n", runtime::ToString(s)), 1;
    best_us = std::min(best_us, std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }

  // 4. The batch gives every character what its own jobs give (checked on a few).
  uint64_t pairs = 0;
  for (uint32_t c = 0; c < N; ++c) pairs += count[c];
  runtime::Workspace alone;
  if (runtime::Failed(alone.Init(model))) return 1;
  std::vector<runtime::Collision> mine(capacity);
  for (uint32_t c = 0; c < N; c += std::max(1u, N / 7)) {
    runtime::RefitJob refit;
    refit.model = &model;
    refit.workspace = &alone;
    refit.positions = chars[c].positions;
    uint32_t n = 0;
    runtime::DetectJob detect;
    detect.model = &model;
    detect.workspace = &alone;
    detect.method = runtime::DetectMethod::kM1;
    detect.output = mine.data();
    detect.capacity = capacity;
    detect.count = &n;
    if (runtime::Failed(refit.Run()) || runtime::Failed(detect.Run()) || n != count[c] ||
        std::memcmp(mine.data(), chars[c].output, sizeof(runtime::Collision) * n) != 0)
      return std::fprintf(stderr, "character %u: the batch differs from its own jobs\n", c), 1;
  }
  std::printf("%u characters: %.0f characters/s (best of 5 frames, %.1f us a frame, TBB), %llu colliding pairs; "
              "batch equals per-character jobs\n",
              N, 1e6 * N / best_us, best_us, static_cast<unsigned long long>(pairs));
  return 0;
}
