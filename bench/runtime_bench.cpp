// runtime_bench — per-frame cost of spherechain refit + detect against peers doing the same work.
//
//   runtime_bench --synthetic [--frames N] [--reps R] [--runs K]
//   runtime_bench ASSET.sphc FRAMES [--reps R] [--runs K]
//   runtime_bench ASSET.sphc FRAMES --profile R   (refit + M1 over all frames R times, nothing else:
//                                                   for valgrind --tool=callgrind instruction counts)
//     FRAMES: a .f32 file of #F×#V×3 little-endian float32 positions, or a folder of .f32 files (one
//     frame each, #V×3, sorted by name).
//
// Rows (median µs per frame over 5 rounds × frames of batches of R calls, one core; with --runs K the
// whole table is measured K times and each row keeps its best median — for a loaded machine):
//   sc refit            RefitJob (kPivotFrame), §5.1
//   sc M1 detect        DetectJob M1 (chains, §5.2) on stored spheres — the paper's method
//   sc refit+M1         RefitJob + DetectJob M1
//   sc M2 detect        DetectJob M2 (all spheres) on stored spheres
//   sc refit+M2         RefitJob + DetectJob M2
//   naive M2            AoS double loop + exclusion matrix over the refitted spheres
//   FCL DynAABBTree M2  fcl::DynamicAABBTreeCollisionManager, spheres updated, collide + sphere test
//   Bullet btDbvt M2    btDbvtBroadphase, AABBs updated, overlapping pairs then the sphere test
// Peers get the refitted spheres (refit not included) and apply the same excluded pairs; their pair
// counts are checked against DetectJob M2 every frame, and M1's against a naive loop over the pairs
// sharing a chain. Ratios: peer / sc M2 detect (the same all-pairs work) and peer / sc refit+M1 (the
// per-frame cost of the paper's pipeline against the peer's broad phase alone).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "runtime/asset_builder.h"
#include "spherechain/runtime/runtime.h"

#if SPHERECHAIN_BENCH_FCL
#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision_object.h>
#endif
#if SPHERECHAIN_BENCH_BULLET
#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>
#include <BulletCollision/BroadphaseCollision/btOverlappingPairCache.h>
#endif

namespace sc = spherechain::runtime;
namespace test = spherechain::test;

namespace {

struct Workload {
  test::AlignedBytes bytes;
  uint32_t vertex_count = 0;
  std::vector<std::vector<float>> frames;  // #F × (#V×3)
};

// ~ the paper's workload: 80 spheres, 6 chains of 22–23 (Table 1 pairs the four limbs), limbs swinging.
Workload Synthetic(uint32_t frame_count) {
  Workload w;
  test::Mesh mesh;
  std::vector<test::Tube> tubes;
  const float dirs[4][3] = {{0.8f, 0.6f, 0}, {-0.8f, 0.6f, 0}, {0.3f, -0.954f, 0}, {-0.3f, -0.954f, 0}};
  for (int l = 0; l < 4; ++l) {  // limbs, 11 spheres
    test::Tube t;
    t.rings = 11;
    for (int k = 0; k < 3; ++k) t.direction[k] = dirs[l][k];
    t.origin[0] = 0.6f * dirs[l][0];
    t.origin[1] = 0.6f * dirs[l][1];
    tubes.push_back(t);
  }
  for (int g = 0; g < 4; ++g) {  // torso: 4 columns of 9 (L, R, T, D groups)
    test::Tube t;
    t.rings = 9;
    t.direction[0] = 0;
    t.direction[1] = 1;
    t.origin[0] = -3.3f + 2.2f * float(g);
    t.origin[1] = -5.0f;
    t.origin[2] = -2.5f;
    tubes.push_back(t);
  }
  // Table 1 shape: each chain joins two limbs and a torso group (sizes 22 + a share of the torso).
  test::AssetData d = test::MakeTubes(tubes, {{0, 2}, {1, 3}, {0, 1, 6}, {2, 3, 7}, {0, 3}, {1, 2}}, &mesh);
  w.bytes = test::Serialize(d);
  w.vertex_count = mesh.vertex_count();
  // Animation: each limb swings about the z axis through its root, a different phase per limb.
  uint32_t first_vertex[9] = {0};
  for (size_t t = 0; t < tubes.size(); ++t) first_vertex[t + 1] = first_vertex[t] + tubes[t].rings * tubes[t].sides;
  for (uint32_t f = 0; f < frame_count; ++f) {
    std::vector<float> p = mesh.positions;
    for (int l = 0; l < 4; ++l) {
      const float a = 1.2f * std::sin(6.2831853f * float(f) / float(frame_count) + float(l));
      const float c = std::cos(a), s = std::sin(a);
      for (uint32_t v = first_vertex[l]; v < first_vertex[l + 1]; ++v) {
        const float x = p[3 * v] - tubes[l].origin[0], y = p[3 * v + 1] - tubes[l].origin[1];
        p[3 * v] = tubes[l].origin[0] + c * x - s * y;
        p[3 * v + 1] = tubes[l].origin[1] + s * x + c * y;
      }
    }
    w.frames.push_back(std::move(p));
  }
  return w;
}

bool ReadFile(const std::string& path, std::vector<char>* out) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return false;
  out->assign(std::istreambuf_iterator<char>(f), {});
  return true;
}

bool FromFiles(const std::string& asset, const std::string& frames, Workload* w) {
  std::vector<char> raw;
  if (!ReadFile(asset, &raw)) return std::fprintf(stderr, "cannot read %s\n", asset.c_str()), false;
  w->bytes.assign(reinterpret_cast<const uint8_t*>(raw.data()), raw.size());
  sc::AssetView view;
  if (sc::Status s = sc::LoadAsset(w->bytes.data(), w->bytes.size, &view); s != sc::Status::kOk)
    return std::fprintf(stderr, "%s: %s\n", asset.c_str(), sc::ToString(s)), false;
  w->vertex_count = view.vertex_count;
  const size_t per_frame = size_t{view.vertex_count} * 3;
  std::vector<std::string> files;
  if (std::filesystem::is_directory(frames)) {
    for (const auto& e : std::filesystem::directory_iterator(frames))
      if (e.path().extension() == ".f32") files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
  } else {
    files.push_back(frames);
  }
  for (const std::string& file : files) {
    if (!ReadFile(file, &raw) || raw.size() % (per_frame * 4) != 0 || raw.empty())
      return std::fprintf(stderr, "%s: not a multiple of #V×3 float32 (#V = %u)\n", file.c_str(), view.vertex_count), false;
    for (size_t off = 0; off < raw.size(); off += per_frame * 4) {
      std::vector<float> p(per_frame);
      std::memcpy(p.data(), raw.data() + off, per_frame * 4);
      w->frames.push_back(std::move(p));
    }
  }
  return !w->frames.empty();
}

// Median over batches of `reps` calls of fn(frame), per call, in µs.
double MedianMicros(size_t frames, int reps, const std::function<void(size_t)>& fn) {
  std::vector<double> samples;
  for (int round = 0; round < 5; ++round)
    for (size_t f = 0; f < frames; ++f) {
      const auto t0 = std::chrono::steady_clock::now();
      for (int r = 0; r < reps; ++r) fn(f);
      const auto t1 = std::chrono::steady_clock::now();
      samples.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count() / reps);
    }
  std::nth_element(samples.begin(), samples.begin() + samples.size() / 2, samples.end());
  return samples[samples.size() / 2];
}

volatile uint32_t g_sink = 0;

}  // namespace

int main(int argc, char** argv) {
  bool synthetic = false;
  int reps = 200, runs = 1, profile = 0;
  uint32_t frame_count = 40;
  std::vector<std::string> positional;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--synthetic") synthetic = true;
    else if (a == "--reps" && i + 1 < argc) reps = std::max(1, std::atoi(argv[++i]));
    else if (a == "--frames" && i + 1 < argc) frame_count = std::max(1, std::atoi(argv[++i]));
    else if (a == "--runs" && i + 1 < argc) runs = std::max(1, std::atoi(argv[++i]));
    else if (a == "--profile" && i + 1 < argc) profile = std::max(1, std::atoi(argv[++i]));
    else positional.push_back(a);
  }
  Workload w;
  if (synthetic) {
    w = Synthetic(frame_count);
  } else if (positional.size() == 2) {
    if (!FromFiles(positional[0], positional[1], &w)) return 1;
  } else {
    std::fprintf(stderr, "usage: runtime_bench --synthetic [--frames N] [--reps R] [--runs K]\n"
                         "       runtime_bench ASSET.sphc FRAMES(.f32 file | folder) [--reps R] [--runs K]\n"
                         "       runtime_bench ASSET.sphc FRAMES --profile R\n");
    return 2;
  }

  sc::AssetView view;
  if (sc::Status s = sc::LoadAsset(w.bytes.data(), w.bytes.size, &view); s != sc::Status::kOk)
    return std::fprintf(stderr, "load: %s\n", sc::ToString(s)), 1;
  sc::Context ctx;
  if (sc::Status s = ctx.Init(view); s != sc::Status::kOk) return std::fprintf(stderr, "init: %s\n", sc::ToString(s)), 1;
  const uint32_t S = view.sphere_count;
  uint32_t chain_total = 0;
  for (const auto* c : *view.asset->chains()) chain_total += c->spheres()->size();
  std::printf("asset: %u spheres, %u chains (avg %.1f spheres), %u vertices, %zu frames, %d reps\n", S,
              view.chain_count, view.chain_count ? double(chain_total) / view.chain_count : 0.0, view.vertex_count,
              w.frames.size(), reps);

  std::vector<sc::Collision> out(std::max(sc::DetectBound(view, sc::DetectMethod::kM1),
                                          sc::DetectBound(view, sc::DetectMethod::kM2)));
  uint32_t count = 0;
  sc::RefitJob refit;
  refit.context = &ctx;
  sc::DetectJob m1;
  m1.context = &ctx;
  m1.method = sc::DetectMethod::kM1;
  m1.output = out.data();
  m1.capacity = static_cast<uint32_t>(out.size());
  m1.count = &count;
  sc::DetectJob m2 = m1;
  m2.method = sc::DetectMethod::kM2;
  auto set_frame = [&](size_t f) { refit.positions = {w.frames[f].data(), w.vertex_count, 12}; };
  if (profile) {  // callgrind: Ir(RefitJob::Run + DetectJob::Run) / (profile × #F) = instructions per frame
    for (int r = 0; r < profile; ++r)
      for (size_t f = 0; f < w.frames.size(); ++f) {
        set_frame(f);
        (void)refit.Run();
        (void)m1.Run();
        g_sink = g_sink + count;
      }
    std::printf("profile: %d × %zu frames of refit + M1\n", profile, w.frames.size());
    return 0;
  }

  // Refitted spheres per frame (inputs of the peers) and the reference M2 counts.
  std::vector<std::vector<float>> sx(w.frames.size()), sy = sx, sz = sx, sr = sx;
  std::vector<uint32_t> m2_count(w.frames.size()), m1_count(w.frames.size());
  for (size_t f = 0; f < w.frames.size(); ++f) {
    set_frame(f);
    if (refit.Run() != sc::Status::kOk) return 1;
    const sc::SphereArrays s = ctx.spheres();
    sx[f].assign(s.x, s.x + S), sy[f].assign(s.y, s.y + S), sz[f].assign(s.z, s.z + S), sr[f].assign(s.r, s.r + S);
    if (m2.Run() != sc::Status::kOk) return 1;
    m2_count[f] = count;
    if (m1.Run() != sc::Status::kOk) return 1;
    m1_count[f] = count;
  }
  std::vector<uint8_t> excluded(size_t{S} * S, 0);
  for (uint32_t a = 0; a < S; ++a)
    for (uint32_t b = 0; b < S; ++b) excluded[size_t{a} * S + b] = ctx.IsExcluded(a, b);
  // M1 cross-check: naive loop over the distinct pairs sharing a chain.
  uint32_t m1_distinct_tests = 0, excluded_pairs = 0;
  for (uint32_t a = 0; a < S; ++a)
    for (uint32_t b = a + 1; b < S; ++b) {
      m1_distinct_tests += (ctx.chain_mask(a) & ctx.chain_mask(b)) != 0;
      excluded_pairs += excluded[size_t{a} * S + b];
    }
  bool mismatch = false;
  for (size_t f = 0; f < w.frames.size(); ++f) {
    uint32_t n = 0;
    for (uint32_t a = 0; a < S; ++a)
      for (uint32_t b = a + 1; b < S; ++b) {
        const float dx = sx[f][b] - sx[f][a], dy = sy[f][b] - sy[f][a], dz = sz[f][b] - sz[f][a], rr = sr[f][b] + sr[f][a];
        n += (ctx.chain_mask(a) & ctx.chain_mask(b)) && dx * dx + dy * dy + dz * dz < rr * rr && !excluded[size_t{a} * S + b];
      }
    if (n != m1_count[f]) mismatch = true;
  }
  if (mismatch) std::fprintf(stderr, "MISMATCH: DetectJob M1 differs from a naive loop over the chain pairs\n");
  auto load_spheres = [&](size_t f) {
    std::copy(sx[f].begin(), sx[f].end(), ctx.mutable_x());
    std::copy(sy[f].begin(), sy[f].end(), ctx.mutable_y());
    std::copy(sz[f].begin(), sz[f].end(), ctx.mutable_z());
    std::copy(sr[f].begin(), sr[f].end(), ctx.mutable_r());
  };
  auto overlap = [&](size_t f, uint32_t a, uint32_t b) {
    const float dx = sx[f][a] - sx[f][b], dy = sy[f][a] - sy[f][b], dz = sz[f][a] - sz[f][b], rr = sr[f][a] + sr[f][b];
    return dx * dx + dy * dy + dz * dz < rr * rr && !excluded[size_t{a} * S + b];
  };
  const size_t F = w.frames.size();
  uint64_t fcl_tests = 0, bullet_tests = 0;  // sphere tests the peers ran after their AABB culling

  struct Row {
    const char* name;
    double us;
  };
  std::vector<Row> rows;
  // Best median of `runs` measurements (a loaded machine only ever makes a median slower).
  auto measure = [&](const char* name, const std::function<void(size_t)>& fn) {
    double best = 1e300;
    for (int k = 0; k < runs; ++k) best = std::min(best, MedianMicros(F, reps, fn));
    rows.push_back({name, best});
    return best;
  };
  const double refit_us = measure("sc refit", [&](size_t f) { set_frame(f); (void)refit.Run(); });
  // Detect-only rows reuse the stored spheres (copying 4·#S floats costs ~20 ns, included for all).
  measure("sc M1 detect", [&](size_t f) {
    load_spheres(f);
    (void)m1.Run();
    g_sink = g_sink + count;
  });
  const double m1_us = measure("sc refit+M1", [&](size_t f) {
    set_frame(f);
    (void)refit.Run();
    (void)m1.Run();
    g_sink = g_sink + count;
  });
  const double m2_us = measure("sc M2 detect", [&](size_t f) {
    load_spheres(f);
    (void)m2.Run();
    g_sink = g_sink + count;
  });
  measure("sc refit+M2", [&](size_t f) {
    set_frame(f);
    (void)refit.Run();
    (void)m2.Run();
    g_sink = g_sink + count;
  });
  (void)refit_us;

  struct Aos {
    float x, y, z, r;
  };
  std::vector<Aos> aos(S);
  struct Peer {
    const char* name;
    double us;
  };
  std::vector<Peer> peers;
  peers.push_back({"naive M2", measure("naive M2", [&](size_t f) {
                     for (uint32_t i = 0; i < S; ++i) aos[i] = {sx[f][i], sy[f][i], sz[f][i], sr[f][i]};
                     uint32_t n = 0;
                     for (uint32_t a = 0; a < S; ++a)
                       for (uint32_t b = a + 1; b < S; ++b) {
                         const float dx = aos[a].x - aos[b].x, dy = aos[a].y - aos[b].y, dz = aos[a].z - aos[b].z;
                         const float rr = aos[a].r + aos[b].r;
                         if (dx * dx + dy * dy + dz * dz < rr * rr && !excluded[size_t{a} * S + b]) ++n;
                       }
                     if (n != m2_count[f]) mismatch = true;
                     g_sink = g_sink + n;
                   })});

#if SPHERECHAIN_BENCH_FCL
  {
    fcl::DynamicAABBTreeCollisionManager<float> manager;
    std::vector<std::shared_ptr<fcl::Sphere<float>>> shapes;
    std::vector<std::unique_ptr<fcl::CollisionObject<float>>> objects;
    for (uint32_t i = 0; i < S; ++i) {
      shapes.push_back(std::make_shared<fcl::Sphere<float>>(sr[0][i]));
      objects.push_back(std::make_unique<fcl::CollisionObject<float>>(shapes.back()));
      objects.back()->setUserData(reinterpret_cast<void*>(uintptr_t{i}));
      objects.back()->setTranslation(fcl::Vector3<float>(sx[0][i], sy[0][i], sz[0][i]));
      objects.back()->computeAABB();
      manager.registerObject(objects.back().get());
    }
    manager.setup();
    struct Data {
      std::function<bool(size_t, uint32_t, uint32_t)>* test;
      size_t frame;
      uint32_t n, tests;
    };
    std::function<bool(size_t, uint32_t, uint32_t)> test_fn = overlap;
    auto frame = [&](size_t f) {
      for (uint32_t i = 0; i < S; ++i) {
        shapes[i]->radius = sr[f][i];
        shapes[i]->computeLocalAABB();
        objects[i]->setTranslation(fcl::Vector3<float>(sx[f][i], sy[f][i], sz[f][i]));
        objects[i]->computeAABB();
      }
      manager.update();
      Data data{&test_fn, f, 0, 0};
      manager.collide(&data, [](fcl::CollisionObject<float>* o1, fcl::CollisionObject<float>* o2, void* p) {
        auto* d = static_cast<Data*>(p);
        uint32_t a = uint32_t(reinterpret_cast<uintptr_t>(o1->getUserData()));
        uint32_t b = uint32_t(reinterpret_cast<uintptr_t>(o2->getUserData()));
        if (a > b) std::swap(a, b);
        ++d->tests;
        if ((*d->test)(d->frame, a, b)) ++d->n;
        return false;
      });
      if (data.n != m2_count[f]) mismatch = true;
      g_sink = g_sink + data.n;
      return data.tests;
    };
    for (size_t f = 0; f < F; ++f) fcl_tests += frame(f);
    peers.push_back({"FCL DynAABBTree M2", measure("FCL DynAABBTree M2", [&](size_t f) { (void)frame(f); })});
  }
#endif
#if SPHERECHAIN_BENCH_BULLET
  {
    btDbvtBroadphase broadphase;
    std::vector<btBroadphaseProxy*> proxies;
    for (uint32_t i = 0; i < S; ++i) {
      const btVector3 c(sx[0][i], sy[0][i], sz[0][i]), e(sr[0][i], sr[0][i], sr[0][i]);
      proxies.push_back(broadphase.createProxy(c - e, c + e, 0, reinterpret_cast<void*>(uintptr_t{i}), 1, 1, nullptr));
    }
    auto frame = [&](size_t f) {
      for (uint32_t i = 0; i < S; ++i) {
        const btVector3 c(sx[f][i], sy[f][i], sz[f][i]), e(sr[f][i], sr[f][i], sr[f][i]);
        broadphase.setAabb(proxies[i], c - e, c + e, nullptr);
      }
      broadphase.calculateOverlappingPairs(nullptr);
      btOverlappingPairCache* cache = broadphase.getOverlappingPairCache();
      const int np = cache->getNumOverlappingPairs();
      btBroadphasePair* pairs = cache->getOverlappingPairArrayPtr();
      uint32_t n = 0;
      for (int k = 0; k < np; ++k) {
        uint32_t a = uint32_t(reinterpret_cast<uintptr_t>(pairs[k].m_pProxy0->m_clientObject));
        uint32_t b = uint32_t(reinterpret_cast<uintptr_t>(pairs[k].m_pProxy1->m_clientObject));
        if (a > b) std::swap(a, b);
        if (overlap(f, a, b)) ++n;
      }
      if (n != m2_count[f]) mismatch = true;
      g_sink = g_sink + n;
      return static_cast<uint32_t>(np);
    };
    for (size_t f = 0; f < F; ++f) bullet_tests += frame(f);
    peers.push_back({"Bullet btDbvt M2", measure("Bullet btDbvt M2", [&](size_t f) { (void)frame(f); })});
  }
#endif

  uint64_t m1_total = 0, m2_total = 0;
  for (size_t f = 0; f < F; ++f) m1_total += m1_count[f], m2_total += m2_count[f];
  sc::DetectStats st1, st2;
  m1.stats = &st1, m2.stats = &st2;
  (void)m1.Run(), (void)m2.Run();
  std::printf("pairs per frame (mean): M1 %.2f distinct, M2 %.2f; excluded pairs %u\n", double(m1_total) / F,
              double(m2_total) / F, excluded_pairs);
  std::printf("tests per frame: M1 %u (paper count, per chain; %u distinct pairs sharing a chain, each tested once), "
              "M2 %u, naive %u",
              st1.tests, m1_distinct_tests, st2.tests, st2.tests);
#if SPHERECHAIN_BENCH_FCL
  std::printf(", FCL %.1f sphere tests after AABB culling", double(fcl_tests) / F);
#endif
#if SPHERECHAIN_BENCH_BULLET
  std::printf(", Bullet %.1f", double(bullet_tests) / F);
#endif
  std::printf("\n%s\n", runs > 1 ? "(each row: best of the medians of several runs)" : "");
  std::printf("%-22s %12s %10s\n", "", "median us", "vs M2");
  for (const Row& r : rows) std::printf("%-22s %12.3f %10.2f\n", r.name, r.us, r.us / m2_us);
  std::printf("\n%-22s %14s %14s\n", "ratio (peer / sc)", "/ sc M2 det.", "/ sc refit+M1");
  for (const Peer& p : peers) std::printf("%-22s %13.1fx %13.1fx\n", p.name, p.us / m2_us, p.us / m1_us);
  if (mismatch) {
    std::fprintf(stderr, "MISMATCH: a pair count differs (see above)\n");
    return 1;
  }
  return 0;
}
