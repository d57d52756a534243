// consumer ASSET.sphc — loads an asset through the installed runtime and prints what it holds.
// Exit 0 when LoadAsset, Model::Init and Workspace::Init succeed, 1 otherwise (the message names the status).
#include <cstdio>
#include <vector>

#include "spherechain/runtime/runtime.h"

int main(int argc, char** argv) {
  using namespace spherechain::runtime;
  if (argc != 2) return std::fprintf(stderr, "usage: consumer ASSET.sphc\n"), 2;
  std::FILE* f = std::fopen(argv[1], "rb");
  if (!f) return std::fprintf(stderr, "error: cannot open '%s'\n", argv[1]), 1;
  std::vector<unsigned long long> bytes;  // 8-byte aligned, as LoadAsset requires
  unsigned long long word = 0;
  size_t size = 0, n;
  while ((n = std::fread(&word, 1, sizeof word, f)) > 0) bytes.push_back(word), size += n, word = 0;
  std::fclose(f);
  AssetView asset;
  if (Status s = LoadAsset(bytes.data(), size, &asset); Failed(s))
    return std::fprintf(stderr, "error: '%s': %s\n", argv[1], ToString(s)), 1;
  Model model;
  Workspace ws;
  if (Status s = model.Init(asset); Failed(s) || Failed(s = ws.Init(model)))
    return std::fprintf(stderr, "error: %s\n", ToString(s)), 1;
  std::printf("spheres %u chains %u vertices %u triangles %u m2_bound %u\n", asset.sphere_count, asset.chain_count,
              asset.vertex_count, asset.triangle_count, DetectBound(asset, DetectMethod::kM2));
  return 0;
}
