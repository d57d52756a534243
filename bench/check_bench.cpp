// check_bench — `spherechain check`'s throughput (evaluate::CheckClips: skinning + the skin-contact narrow
// phase per frame, events, policy), one core, the bake excluded; the peer in the same run is the exact truth
// on the same frames (CGAL box intersection + exact triangle test over the whole mesh, then the same crease
// rule: what `evaluate` computes), on a sample of the frames.
//
// check_bench ASSET MESH [--clip NAME | --poses DIR] [--frames N (1000)] [--peer-frames N (20)] [--rig MHSKEL]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "spherechain/baker/contacts.h"
#include "spherechain/evaluate/check.h"
#include "spherechain/import/file_io.h"
#include "spherechain/playback/character.h"
#include "spherechain/runtime/crease.h"

using namespace spherechain;
using Clock = std::chrono::steady_clock;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: check_bench ASSET MESH [--clip NAME | --poses DIR] [--frames N] [--peer-frames N] [--rig R]\n");
    return 2;
  }
  std::string asset_path = argv[1], mesh_path = argv[2], clip, poses, rig;
  uint32_t frames = 1000, peer_frames = 20;
  for (int i = 3; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--clip")) clip = argv[i + 1];
    else if (!std::strcmp(argv[i], "--poses")) poses = argv[i + 1];
    else if (!std::strcmp(argv[i], "--frames")) frames = uint32_t(std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--peer-frames")) peer_frames = uint32_t(std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--rig")) rig = argv[i + 1];
    else return std::fprintf(stderr, "unknown option %s\n", argv[i]), 2;
  }
  import::LoadedAsset asset;
  import::Mesh mesh;
  if (auto s = playback::OpenCharacter(asset_path, mesh_path, rig, &asset, &mesh); !s.ok())
    return std::fprintf(stderr, "%s\n", s.error().message.c_str()), 1;

  evaluate::CheckOptions o;
  o.mesh_name = mesh_path;
  o.asset_name = asset_path;
  o.max_frames = frames;
  if (!poses.empty()) {
    o.poses = {poses};
    o.morph_frames = frames;
    if (!mesh.clips.empty()) return std::fprintf(stderr, "--poses: for a mesh without clips (MakeHuman)\n"), 2;
  } else {
    const import::Clip* c = nullptr;
    for (const auto& k : mesh.clips)
      if (clip.empty() || k.name == clip) c = c ? c : &k;
    if (!c) return std::fprintf(stderr, "no clip '%s'\n", clip.c_str()), 1;
    o.clips = {c->name};
    o.fps = (frames - 0.5) / c->duration_s;  // ceil(duration · fps) = frames
  }
  const auto t0 = Clock::now();
  auto r = evaluate::CheckClips(asset.view, mesh, o);
  const double total = std::chrono::duration<double>(Clock::now() - t0).count();
  if (!r.ok()) return std::fprintf(stderr, "%s\n", r.error().message.c_str()), 1;
  const evaluate::CheckClip& c = r->clips.back();
  std::printf("check_bench %s: %u triangles, clip '%s', %u frames\n", mesh_path.c_str(), mesh.triangle_count(),
              c.name.c_str(), c.frames);
  std::printf("  check:  %.3f s for the frames (%.3f ms a frame), %.3f s with the model's init; "
              "%zu events, %llu contacts\n",
              c.seconds, 1e3 * c.seconds / c.frames, total, c.events.size(),
              static_cast<unsigned long long>(c.contacts));

  // The peer: the exact truth on a sample of the same frames.
  const std::vector<uint32_t> weld = import::ComputeWeldIds(mesh.positions);
  runtime::CreaseGraph graph;
  runtime::CreaseScratch scratch;
  if (runtime::Failed(graph.Init(mesh.positions.data(), mesh.vertex_count(), mesh.indices.data(), mesh.triangle_count(),
                                 weld.data(), asset.view.asset->crease())) ||
      runtime::Failed(scratch.Init(graph)))
    return std::fprintf(stderr, "crease graph\n"), 1;
  double peer = 0;
  uint32_t sampled = 0;
  std::vector<float> pos;
  for (uint32_t f = 0; f < c.frames && sampled < peer_frames; f += std::max(1u, c.frames / peer_frames), ++sampled) {
    if (!evaluate::CheckFrame(mesh, o, c, f, &pos).ok()) return std::fprintf(stderr, "frame %u\n", f), 1;
    const auto t = Clock::now();
    auto pairs = baker::ExactSelfIntersections(pos.data(), mesh.vertex_count(), mesh.indices, weld);
    if (!pairs.ok()) return std::fprintf(stderr, "%s\n", pairs.error().message.c_str()), 1;
    uint32_t n = 0;
    for (const auto& p : pairs.value())
      n += !scratch.Near(graph, &mesh.indices[3 * size_t{p.a}], &mesh.indices[3 * size_t{p.b}], graph.crease());
    peer += std::chrono::duration<double>(Clock::now() - t).count();
    (void)n;
  }
  const double peer_ms = 1e3 * peer / std::max(1u, sampled);
  std::printf("  peer (CGAL box_intersection + exact test + the crease rule, the narrow phase only, %u frames): "
              "%.2f ms a frame; check (skinning included) is %.1fx faster\n",
              sampled, peer_ms, peer_ms / (1e3 * c.seconds / c.frames));
  return 0;
}
