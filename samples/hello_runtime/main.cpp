// hello_runtime — the smallest complete integration of the spherechain runtime:
// load a .sphc asset, refit its spheres from a deformed vertex buffer, detect self-collisions, print.
//
//   hello_runtime ASSET.sphc MESH     (MESH: the character the asset was baked from)
//
// A game has its own vertex buffer; here the baker's importer stands in for it, and the "animation" is
// the left arm pushed into the chest.
#include <cstdio>
#include <cstring>
#include <fstream>
#include <vector>

#include "spherechain/import/import.h"
#include "spherechain/import/vertex_contract.h"
#include "spherechain/runtime/runtime.h"

using namespace spherechain;

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: hello_runtime ASSET.sphc MESH\n");
    return 2;
  }
  // 1. Load: the bytes must stay alive and 8-byte aligned while the view is used.
  std::ifstream file(argv[1], std::ios::binary | std::ios::ate);
  const std::streamoff end = file ? std::streamoff(file.tellg()) : -1;
  if (end < 0) {
    std::fprintf(stderr, "error: cannot open '%s'\n", argv[1]);
    return 1;
  }
  const size_t size = size_t(end);
  std::vector<uint64_t> bytes((size + 7) / 8);
  if (!file.seekg(0) || !file.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size))) {
    std::fprintf(stderr, "error: cannot read '%s'\n", argv[1]);
    return 1;
  }
  runtime::AssetView asset;
  if (runtime::Status s = runtime::LoadAsset(bytes.data(), size, &asset); runtime::Failed(s)) {
    std::fprintf(stderr, "error: '%s': %s\n", argv[1], runtime::ToString(s));
    return 1;
  }
  runtime::Model model;  // once per asset (shared by every character of it): one allocation
  runtime::Workspace ws;  // once per character: its spheres and scratch, one allocation
  if (runtime::Status s = model.Init(asset); runtime::Failed(s) || runtime::Failed(s = ws.Init(model))) {
    std::fprintf(stderr, "error: %s\n", runtime::ToString(s));
    return 1;
  }

  // 2. The game's vertex buffer (bind pose here), then the left arm pushed towards the chest.
  import::ImportOptions import;
  import.vertices = import::ContractForReimport(asset, argv[2]);  // the vertex buffer the asset was baked from
  auto mesh = import::ImportMesh(argv[2], import);
  if (!mesh.ok()) {
    std::fprintf(stderr, "error: %s\n", mesh.error().message.c_str());
    return 1;
  }
  // The mesh must be the one the asset was baked from: its triangles are indexed by the asset's (the refit
  // checks the vertex count too, but the loop below reads the mesh's triangles first).
  if (mesh->vertex_count() != asset.vertex_count || mesh->triangle_count() != asset.triangle_count) {
    std::fprintf(stderr, "error: '%s' has %u vertices and %u triangles, the asset was baked from %u and %u\n", argv[2],
                 mesh->vertex_count(), mesh->triangle_count(), asset.vertex_count, asset.triangle_count);
    return 1;
  }
  std::vector<float> positions = mesh->positions;
  // Regions are optional in the schema (the baker always writes them): without them nothing is moved.
  const auto* tri_regions = asset.asset->triangle_regions();
  std::vector<uint8_t> is_left_arm(positions.size() / 3, 0);
  for (uint32_t t = 0; tri_regions && t < asset.triangle_count; ++t)
    if (tri_regions->Get(t) == 0)
      for (int k = 0; k < 3; ++k) is_left_arm[mesh->indices[3 * t + k]] = 1;
  float arm[3] = {0, 0, 0}, body[3] = {0, 0, 0};
  uint32_t n_arm = 0, n_body = 0;
  for (size_t v = 0; v < is_left_arm.size(); ++v)
    for (int j = 0; j < 3; ++j) {
      (is_left_arm[v] ? arm : body)[j] += positions[3 * v + j];
      if (j == 0) ++(is_left_arm[v] ? n_arm : n_body);
    }
  for (size_t v = 0; n_arm > 0 && n_body > 0 && v < is_left_arm.size(); ++v)
    if (is_left_arm[v])
      for (int j : {0, 2}) positions[3 * v + j] -= 0.8f * (arm[j] / n_arm - body[j] / n_body);

  // 3. Every frame: refit, then detect (M2: all spheres) into a caller-owned buffer.
  std::vector<runtime::Collision> pairs(runtime::DetectBound(asset, runtime::DetectMethod::kM2));
  uint32_t count = 0;
  runtime::RefitJob refit;
  refit.model = &model;
  refit.workspace = &ws;
  refit.positions = {positions.data(), uint32_t(positions.size() / 3), 12};
  runtime::DetectJob detect;
  detect.model = &model;
  detect.workspace = &ws;
  detect.method = runtime::DetectMethod::kM2;
  detect.output = pairs.data();
  detect.capacity = uint32_t(pairs.size());
  detect.count = &count;
  if (runtime::Status s = refit.Run(); runtime::Failed(s)) {
    std::fprintf(stderr, "refit: %s\n", runtime::ToString(s));
    return 1;
  }
  if (runtime::Status s = detect.Run(); runtime::Failed(s)) {
    std::fprintf(stderr, "detect: %s\n", runtime::ToString(s));
    return 1;
  }

  // 4. Print the pairs and how many mesh triangles stand behind each sphere (its surrounding region, what a
  // narrow phase tests). Region names from the asset: the paper's five, or a creature's limbs and trunk.
  const auto* sphere_regions = asset.asset->sphere_regions();
  auto region = [&](uint32_t sphere) { return sphere_regions ? runtime::RegionName(asset, sphere_regions->Get(sphere)) : "?"; };
  std::printf("%s: %u spheres, %u colliding pairs with the left arm pushed into the chest\n", argv[1],
              asset.sphere_count, count);
  for (uint32_t i = 0; i < count; ++i) {
    const runtime::Collision& c = pairs[i];
    std::printf("  sphere %3u (%-9s) x sphere %3u (%-9s) depth %.3f  triangles %u + %u\n", c.a, region(c.a), c.b,
                region(c.b), c.depth,
                runtime::SurroundingTriangles(asset, c.a).count, runtime::SurroundingTriangles(asset, c.b).count);
  }
  return 0;
}
