// spherechain::cuda — CPU == GPU (refit + detect, every strategy/method/mode), CUDA graph replay,
// invalid inputs, overflow, and the MakeHuman asset. Every test SKIPs visibly without a CUDA device.
#include <doctest/doctest.h>

#include <cuda_runtime_api.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

#include "cuda/cuda_test_util.h"
#include "test_data.h"

using namespace spherechain;
using namespace spherechain::runtime;
namespace sc = spherechain::cuda;

namespace {

bool RequireDevice() {
  if (sc::DeviceAvailable() == sc::Status::kOk) return true;
  MESSAGE("SKIPPED: no CUDA device (cudaGetDeviceCount: " << std::string(sc::LastCudaErrorString())
          << ") — spherechain::cuda tests need a GPU");
  return false;
}

#define CUDA_REQUIRE(expr) REQUIRE_MESSAGE((expr) == cudaSuccess, #expr)

/// One asset on host (bytes, view, CPU context, rest positions) and device.
struct AssetSet {
  test::Mesh mesh;
  test::AlignedBytes bytes;
  AssetView view;
  Context ctx;
  sc::DeviceAsset device;
};

void LoadSet(AssetSet* s, test::AssetData d) {
  s->bytes = test::Serialize(d);
  REQUIRE(LoadAsset(s->bytes.data(), s->bytes.size, &s->view) == runtime::Status::kOk);
  REQUIRE(s->ctx.Init(s->view) == runtime::Status::kOk);
  REQUIRE(s->device.Upload(s->view) == sc::Status::kOk);
}

/// A "star" of tubes crossing near the origin (many crossing pairs), chains mixing tubes.
void MakeStar(AssetSet* s, uint32_t tubes, uint32_t rings) {
  std::vector<test::Tube> ts;
  for (uint32_t i = 0; i < tubes; ++i) {
    test::Tube t;
    const float ang = 3.14159265f * float(i) / float(tubes);
    t.direction[0] = std::cos(ang);
    t.direction[1] = std::sin(ang);
    t.direction[2] = 0.1f * float(i % 3);
    const float l = std::sqrt(1.0f + t.direction[2] * t.direction[2]);
    for (float& v : t.direction) v /= l;
    for (int k = 0; k < 3; ++k) t.origin[k] = -0.5f * t.spacing * float(rings - 1) * t.direction[k];
    t.origin[2] += 0.3f * float(i);
    t.rings = rings;
    t.sphere_scale = 1.0f + 0.05f * float(i);
    ts.push_back(t);
  }
  std::vector<std::vector<uint32_t>> chains;
  for (uint32_t i = 0; i < tubes; ++i) chains.push_back({i, (i + 1) % tubes});
  chains.push_back({0});
  LoadSet(s, test::MakeTubes(ts, chains, &s->mesh));
}

/// Instances on the device: one allocation, instance i at its own offset with its own stride.
struct DeviceInstances {
  std::vector<std::vector<float>> host;  // packed xyz per instance (CPU input)
  std::vector<sc::Instance> table;
  std::vector<uint32_t> strides;
  void* buffer = nullptr;
  std::vector<size_t> offsets;
  ~DeviceInstances() {
    if (buffer) (void)cudaFree(buffer);
  }
  void Build(const std::vector<AssetSet*>& assets, uint32_t n, uint32_t seed, bool rest = false) {
    std::mt19937 rng(seed);
    size_t total = 0;
    for (uint32_t i = 0; i < n; ++i) {
      AssetSet& a = *assets[i % assets.size()];
      host.push_back(rest ? a.mesh.positions : test::RandomMotion(a.mesh.positions, rng, 20.0f, 0.05f));
      strides.push_back(i % 3 == 2 ? 16u : 12u);
      offsets.push_back(total);
      total += size_t{a.view.vertex_count} * strides.back();
      total = (total + 15) & ~size_t{15};
    }
    CUDA_REQUIRE(cudaMalloc(&buffer, total));
    Upload();
    for (uint32_t i = 0; i < n; ++i)
      table.push_back({static_cast<char*>(buffer) + offsets[i], assets[i % assets.size()]->view.vertex_count, strides[i],
                       static_cast<uint32_t>(i % assets.size())});
  }
  // Writes host[i] into the device buffer with instance i's stride (padding lanes = NaN).
  void Upload() {
    for (size_t i = 0; i < host.size(); ++i) {
      const uint32_t fl = strides[i] / 4, nv = static_cast<uint32_t>(host[i].size() / 3);
      std::vector<float> s(size_t{nv} * fl, std::nanf(""));
      for (uint32_t v = 0; v < nv; ++v) std::memcpy(&s[size_t{v} * fl], &host[i][3 * size_t{v}], 12);
      CUDA_REQUIRE(cudaMemcpy(static_cast<char*>(buffer) + offsets[i], s.data(), s.size() * 4, cudaMemcpyHostToDevice));
    }
  }
};

bool NearRel(float a, float b, float tol = 1e-5f) {
  return std::fabs(a - b) <= tol * std::max(1.0f, std::max(std::fabs(a), std::fabs(b)));
}

/// Checks the GPU frame against the CPU runtime for every instance. Pairs must be the same set with
/// the same chains mask and depth (1e-5 rel); a pair may differ only when it is borderline on the CPU
/// spheres (|d² − (ra+rb)²| ≤ 1e-5 (ra+rb)²). Spheres (when written) equal within 1e-5 relative.
void CompareWithCpu(const std::vector<AssetSet*>& assets, const DeviceInstances& inst, const sc::HostResults& gpu,
                    const sc::Batch& batch, const sc::FrameParams& fp) {
  std::vector<std::map<std::pair<int, int>, runtime::Collision>> by_inst(inst.host.size());
  for (const sc::BatchCollision& c : gpu.pairs) {
    REQUIRE(c.instance < inst.host.size());
    CHECK(by_inst[c.instance].emplace(std::make_pair(int(c.pair.a), int(c.pair.b)), c.pair).second);  // no duplicates
  }
  size_t borderline = 0, cpu_total = 0;
  for (size_t i = 0; i < inst.host.size(); ++i) {
    AssetSet& a = *assets[inst.table[i].asset];
    const test::CpuFrame cpu = test::CpuReference(a.ctx, a.view, inst.host[i].data(), 12, fp.mode, fp.method);
    cpu_total += cpu.pairs.size();
    if (fp.write_spheres) {
      const uint32_t off = batch.sphere_offset(static_cast<uint32_t>(i));
      for (uint32_t s = 0; s < a.view.sphere_count; ++s) {
        const float4 g = gpu.spheres[off + s];
        const bool ok = NearRel(g.x, cpu.x[s]) && NearRel(g.y, cpu.y[s]) && NearRel(g.z, cpu.z[s]) && NearRel(g.w, cpu.r[s]);
        if (!ok) {
          FAIL_CHECK("instance " << i << " sphere " << s << ": gpu (" << g.x << ", " << g.y << ", " << g.z << ", " << g.w
                                 << ") cpu (" << cpu.x[s] << ", " << cpu.y[s] << ", " << cpu.z[s] << ", " << cpu.r[s] << ")");
          break;
        }
      }
    }
    CHECK(gpu.instance_counts[i] == by_inst[i].size());
    auto borderline_pair = [&](int pa, int pb) {
      const float dx = cpu.x[pb] - cpu.x[pa], dy = cpu.y[pb] - cpu.y[pa], dz = cpu.z[pb] - cpu.z[pa];
      const float rr = cpu.r[pa] + cpu.r[pb];
      return std::fabs(dx * dx + dy * dy + dz * dz - rr * rr) <= 1e-5f * rr * rr;
    };
    std::set<std::pair<int, int>> cpu_set;
    for (const runtime::Collision& c : cpu.pairs) {
      cpu_set.insert({c.a, c.b});
      auto it = by_inst[i].find({c.a, c.b});
      if (it == by_inst[i].end()) {
        if (borderline_pair(c.a, c.b)) { ++borderline; continue; }
        FAIL_CHECK("instance " << i << ": CPU pair (" << c.a << ", " << c.b << ") missing on the GPU");
        continue;
      }
      CHECK(it->second.chains == c.chains);
      CHECK(NearRel(it->second.depth, c.depth, 1e-4f));
    }
    for (const auto& [key, c] : by_inst[i])
      if (!cpu_set.count(key)) {
        if (borderline_pair(key.first, key.second)) { ++borderline; continue; }
        FAIL_CHECK("instance " << i << ": GPU pair (" << key.first << ", " << key.second << ") not on the CPU");
      }
  }
  CHECK(gpu.total == gpu.pairs.size());
  CHECK_FALSE(gpu.overflow);
  MESSAGE("compared " << inst.host.size() << " instances, " << cpu_total << " CPU pairs, " << borderline
                      << " borderline differences");
}

}  // namespace

TEST_CASE("cuda: CPU == GPU on synthetic assets and randomised instances (all strategies, methods, modes)") {
  if (!RequireDevice()) return;
  AssetSet star, two;
  MakeStar(&star, 6, 12);
  {
    test::Mesh m;
    test::AssetData d = test::TwoTubes(true, &m);
    two.mesh = std::move(m);
    LoadSet(&two, std::move(d));
  }
  const std::vector<AssetSet*> assets = {&star, &two};
  DeviceInstances inst;
  inst.Build(assets, 257, 1234u);
  const sc::DeviceAsset* dev[] = {&star.device, &two.device};
  sc::Batch batch;
  REQUIRE(batch.Init(dev, 2, inst.table.data(), static_cast<uint32_t>(inst.table.size())) == sc::Status::kOk);

  for (RefitMode mode : {RefitMode::kPaper, RefitMode::kPivotFrame})
    for (DetectMethod method : {DetectMethod::kM1, DetectMethod::kM2})
      for (sc::Strategy strategy : {sc::Strategy::kAuto, sc::Strategy::kThreadPerSphere, sc::Strategy::kBlockPerChain,
                                    sc::Strategy::kWarpPerInstance}) {
        CAPTURE(int(mode));
        CAPTURE(int(method));
        CAPTURE(int(strategy));
        sc::FrameParams fp{mode, method, strategy, true};
        const sc::Status st = batch.Run(fp, 0);
        if (strategy == sc::Strategy::kBlockPerChain && method == DetectMethod::kM2) {
          CHECK(st == sc::Status::kErrorInvalidJob);
          continue;
        }
        REQUIRE_MESSAGE(st == sc::Status::kOk, std::string(sc::ToString(st)) << " / " << std::string(sc::LastCudaErrorString()));
        sc::HostResults res;
        REQUIRE(batch.Download(0, &res, true) == sc::Status::kOk);
        CompareWithCpu(assets, inst, res, batch, fp);
      }
}

TEST_CASE("cuda: rest pose reproduces the bind spheres and a single instance works") {
  if (!RequireDevice()) return;
  AssetSet star;
  MakeStar(&star, 4, 10);
  DeviceInstances inst;
  inst.Build({&star}, 1, 1u, /*rest=*/true);
  const sc::DeviceAsset* dev[] = {&star.device};
  sc::Batch batch;
  REQUIRE(batch.Init(dev, 1, inst.table.data(), 1) == sc::Status::kOk);
  for (DetectMethod method : {DetectMethod::kM1, DetectMethod::kM2}) {
    sc::FrameParams fp{RefitMode::kPivotFrame, method, sc::Strategy::kAuto, true};
    REQUIRE(batch.Run(fp, 0) == sc::Status::kOk);
    sc::HostResults res;
    REQUIRE(batch.Download(0, &res, true) == sc::Status::kOk);
    for (uint32_t s = 0; s < star.view.sphere_count; ++s) {
      const schema::Sphere* b = star.view.asset->spheres()->Get(s);
      CHECK(NearRel(res.spheres[s].w, b->radius(), 1e-4f));
      CHECK(NearRel(res.spheres[s].x, b->center().x(), 1e-4f));
    }
    CompareWithCpu({&star}, inst, res, batch, fp);
  }
}

TEST_CASE("cuda: a frame captured into a CUDA graph replays to the CPU result for new positions") {
  if (!RequireDevice()) return;
  AssetSet star;
  MakeStar(&star, 5, 12);
  DeviceInstances inst;
  inst.Build({&star}, 64, 99u);
  const sc::DeviceAsset* dev[] = {&star.device};
  sc::Batch batch;
  REQUIRE(batch.Init(dev, 1, inst.table.data(), 64) == sc::Status::kOk);
  cudaStream_t stream;
  CUDA_REQUIRE(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking));
  for (DetectMethod method : {DetectMethod::kM1, DetectMethod::kM2}) {
    const sc::FrameParams fp{RefitMode::kPivotFrame, method, sc::Strategy::kAuto, true};
    cudaGraph_t graph;
    CUDA_REQUIRE(cudaStreamBeginCapture(stream, cudaStreamCaptureModeGlobal));
    const sc::Status st = batch.Run(fp, stream);
    CUDA_REQUIRE(cudaStreamEndCapture(stream, &graph));
    REQUIRE(st == sc::Status::kOk);
    cudaGraphExec_t exec;
    CUDA_REQUIRE(cudaGraphInstantiate(&exec, graph, 0));
    // Replay twice (counters must be re-zeroed by the graph), then with new positions.
    sc::HostResults direct, replay;
    REQUIRE(batch.Run(fp, stream) == sc::Status::kOk);
    REQUIRE(batch.Download(stream, &direct, true) == sc::Status::kOk);
    CUDA_REQUIRE(cudaGraphLaunch(exec, stream));
    CUDA_REQUIRE(cudaGraphLaunch(exec, stream));
    REQUIRE(batch.Download(stream, &replay, true) == sc::Status::kOk);
    CHECK(replay.total == direct.total);
    CHECK(replay.instance_counts == direct.instance_counts);
    CompareWithCpu({&star}, inst, replay, batch, fp);

    std::mt19937 rng(7u + static_cast<uint32_t>(method));
    for (auto& h : inst.host) h = test::RandomMotion(star.mesh.positions, rng, 5.0f, 0.1f);
    inst.Upload();
    CUDA_REQUIRE(cudaGraphLaunch(exec, stream));
    REQUIRE(batch.Download(stream, &replay, true) == sc::Status::kOk);
    CompareWithCpu({&star}, inst, replay, batch, fp);
    CUDA_REQUIRE(cudaGraphExecDestroy(exec));
    CUDA_REQUIRE(cudaGraphDestroy(graph));
  }
  CUDA_REQUIRE(cudaStreamDestroy(stream));
}

TEST_CASE("cuda: invalid instances give the documented status") {
  if (!RequireDevice()) return;
  AssetSet star;
  MakeStar(&star, 3, 6);
  DeviceInstances inst;
  inst.Build({&star}, 2, 5u);
  const sc::DeviceAsset* dev[] = {&star.device};
  sc::Batch batch;
  std::vector<sc::Instance> bad = inst.table;
  bad[1].vertex_count += 1;
  CHECK(batch.Init(dev, 1, bad.data(), 2) == sc::Status::kErrorVertexCount);
  CHECK_FALSE(batch.initialized());
  bad = inst.table;
  bad[0].stride_bytes = 10;
  CHECK(batch.Init(dev, 1, bad.data(), 2) == sc::Status::kErrorStride);
  bad = inst.table;
  bad[0].positions = static_cast<const char*>(bad[0].positions) + 2;
  CHECK(batch.Init(dev, 1, bad.data(), 2) == sc::Status::kErrorAlignment);
  bad = inst.table;
  bad[0].positions = nullptr;
  CHECK(batch.Init(dev, 1, bad.data(), 2) == sc::Status::kErrorNullArgument);
  bad = inst.table;
  bad[1].asset = 1;
  CHECK(batch.Init(dev, 1, bad.data(), 2) == sc::Status::kErrorInvalidJob);
  CHECK(batch.Init(nullptr, 1, inst.table.data(), 2) == sc::Status::kErrorNullArgument);
  sc::DeviceAsset empty;
  CHECK(empty.Upload(AssetView{}) == sc::Status::kErrorNullArgument);
  const sc::DeviceAsset* dev_empty[] = {&empty};
  CHECK(batch.Init(dev_empty, 1, inst.table.data(), 2) == sc::Status::kErrorInvalidJob);
  CHECK(batch.Run({}, 0) == sc::Status::kErrorInvalidJob);  // not initialised

  REQUIRE(batch.Init(dev, 1, inst.table.data(), 2) == sc::Status::kOk);
  bad = inst.table;
  bad[0].vertex_count = 3;
  CHECK(batch.SetInstances(bad.data(), 2) == sc::Status::kErrorVertexCount);
  CHECK(batch.SetInstances(inst.table.data(), 1) == sc::Status::kErrorInvalidJob);
  CHECK(batch.SetInstances(inst.table.data(), 2) == sc::Status::kOk);
  CHECK(batch.Run({RefitMode::kPivotFrame, DetectMethod::kM2, sc::Strategy::kBlockPerChain, false}, 0) ==
        sc::Status::kErrorInvalidJob);
  CHECK(batch.Run({static_cast<RefitMode>(7), DetectMethod::kM1, sc::Strategy::kAuto, false}, 0) ==
        sc::Status::kErrorInvalidJob);
  CHECK(batch.Run({RefitMode::kPaper, static_cast<DetectMethod>(9), sc::Strategy::kAuto, false}, 0) ==
        sc::Status::kErrorInvalidJob);
  CHECK(std::string(sc::ToString(sc::Status::kErrorVertexCount)).find("kErrorVertexCount") == 0);
  CHECK(std::string(sc::ToString(sc::Status::kErrorCuda)).find("kErrorCuda") == 0);
}

TEST_CASE("cuda: a too-small output sets the overflow flag; counts stay complete") {
  if (!RequireDevice()) return;
  AssetSet star;
  MakeStar(&star, 6, 12);
  DeviceInstances inst;
  inst.Build({&star}, 16, 3u, /*rest=*/true);
  const sc::DeviceAsset* dev[] = {&star.device};
  sc::Batch full, small;
  REQUIRE(full.Init(dev, 1, inst.table.data(), 16) == sc::Status::kOk);
  REQUIRE(small.Init(dev, 1, inst.table.data(), 16, 5) == sc::Status::kOk);
  const sc::FrameParams fp{RefitMode::kPivotFrame, DetectMethod::kM2, sc::Strategy::kAuto, false};
  sc::HostResults a, b;
  REQUIRE(full.Run(fp, 0) == sc::Status::kOk);
  REQUIRE(full.Download(0, &a) == sc::Status::kOk);
  REQUIRE(a.total > 5);
  REQUIRE(small.Run(fp, 0) == sc::Status::kOk);
  CHECK(small.Download(0, &b) == sc::Status::kOkTruncated);
  CHECK(b.overflow);
  CHECK(b.pairs.size() == 5);
  CHECK(b.total == a.total);
  CHECK(b.instance_counts == a.instance_counts);
}

TEST_CASE("cuda: MakeHuman asset, CPU == GPU over randomised instances") {
  if (!RequireDevice()) return;
  const char* env = std::getenv("SPHERECHAIN_MH_ASSET");
  const std::string asset_path = env ? env : "/tmp/mh.sphc";
  const std::string obj = test::SharedData("makehuman/base.obj");
  if (!test::Require(asset_path) || !test::Require(obj)) {
    MESSAGE("SKIPPED: bake it with `spherechain bake " << obj << " -o /tmp/mh.sphc` (or set SPHERECHAIN_MH_ASSET)");
    return;
  }
  AssetSet mh;
  REQUIRE(test::ReadAligned(asset_path, &mh.bytes));
  REQUIRE(LoadAsset(mh.bytes.data(), mh.bytes.size, &mh.view) == runtime::Status::kOk);
  REQUIRE(mh.ctx.Init(mh.view) == runtime::Status::kOk);
  REQUIRE(mh.device.Upload(mh.view) == sc::Status::kOk);
  mh.mesh.positions = test::ObjPositions(obj, mh.view.vertex_count);
  if (mh.mesh.positions.empty()) {
    MESSAGE("SKIPPED: base.obj vertices do not match the asset's vertex_count " << mh.view.vertex_count);
    return;
  }
  DeviceInstances inst;
  inst.Build({&mh}, 200, 2024u);
  inst.host[0] = mh.mesh.positions;  // instance 0 at rest
  inst.Upload();
  const sc::DeviceAsset* dev[] = {&mh.device};
  sc::Batch batch;
  REQUIRE(batch.Init(dev, 1, inst.table.data(), 200) == sc::Status::kOk);
  for (RefitMode mode : {RefitMode::kPaper, RefitMode::kPivotFrame})
    for (DetectMethod method : {DetectMethod::kM1, DetectMethod::kM2})
      for (sc::Strategy strategy : {sc::Strategy::kThreadPerSphere, sc::Strategy::kBlockPerChain, sc::Strategy::kWarpPerInstance}) {
        if (strategy == sc::Strategy::kBlockPerChain && method == DetectMethod::kM2) continue;
        const sc::FrameParams fp{mode, method, strategy, true};
        REQUIRE(batch.Run(fp, 0) == sc::Status::kOk);
        sc::HostResults res;
        REQUIRE(batch.Download(0, &res, true) == sc::Status::kOk);
        CompareWithCpu({&mh}, inst, res, batch, fp);
      }
}

// Recorded animation frames (`spherechain play ... --dump-frames DIR`: frame_NNNN.f32, #V×3 float32),
// each frame one instance of one batch: the MakeHuman morph and the CesiumMan walk, CPU == GPU.
// SPHERECHAIN_GPU_FRAMES="a.sphc=framesdir;b.sphc=framesdir2" (scripts/gpu-carry.sh prepares both).
TEST_CASE("cuda: recorded animation frames (MakeHuman morph, CesiumMan walk), CPU == GPU") {
  if (!RequireDevice()) return;
  const char* env = std::getenv("SPHERECHAIN_GPU_FRAMES");
  if (!env || !*env) {
    MESSAGE("SKIPPED: set SPHERECHAIN_GPU_FRAMES=asset.sphc=frames_dir[;...] (see scripts/gpu-carry.sh)");
    return;
  }
  std::string spec = env;
  size_t start = 0;
  while (start < spec.size()) {
    const size_t end = std::min(spec.find(';', start), spec.size());
    const std::string item = spec.substr(start, end - start);
    start = end + 1;
    const size_t eq = item.find('=');
    REQUIRE(eq != std::string::npos);
    const std::string asset_path = item.substr(0, eq), dir = item.substr(eq + 1);
    if (!test::Require(asset_path) || !test::Require(dir)) continue;
    AssetSet set;
    REQUIRE(test::ReadAligned(asset_path, &set.bytes));
    REQUIRE(LoadAsset(set.bytes.data(), set.bytes.size, &set.view) == runtime::Status::kOk);
    REQUIRE(set.ctx.Init(set.view) == runtime::Status::kOk);
    REQUIRE(set.device.Upload(set.view) == sc::Status::kOk);
    std::vector<std::string> files;
    for (const auto& e : std::filesystem::directory_iterator(dir))
      if (e.path().extension() == ".f32") files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
    REQUIRE(!files.empty());
    std::vector<std::vector<float>> frames;
    for (const std::string& f : files) {
      std::ifstream in(f, std::ios::binary);
      std::vector<float> p(size_t{set.view.vertex_count} * 3);
      in.read(reinterpret_cast<char*>(p.data()), std::streamsize(p.size() * sizeof(float)));
      REQUIRE_MESSAGE(in.gcount() == std::streamsize(p.size() * sizeof(float)), f << " is not #V×3 float32");
      frames.push_back(std::move(p));
    }
    set.mesh.positions = frames[0];
    DeviceInstances inst;
    inst.Build({&set}, static_cast<uint32_t>(frames.size()), 1u, /*rest=*/true);
    for (size_t i = 0; i < frames.size(); ++i) inst.host[i] = frames[i];
    inst.Upload();
    const sc::DeviceAsset* dev[] = {&set.device};
    sc::Batch batch;
    REQUIRE(batch.Init(dev, 1, inst.table.data(), static_cast<uint32_t>(frames.size())) == sc::Status::kOk);
    for (RefitMode mode : {RefitMode::kPaper, RefitMode::kPivotFrame})
      for (DetectMethod method : {DetectMethod::kM1, DetectMethod::kM2}) {
        const sc::FrameParams fp{mode, method, sc::Strategy::kAuto, true};
        REQUIRE(batch.Run(fp, 0) == sc::Status::kOk);
        sc::HostResults res;
        REQUIRE(batch.Download(0, &res, true) == sc::Status::kOk);
        CompareWithCpu({&set}, inst, res, batch, fp);
      }
    MESSAGE(asset_path << ": " << frames.size() << " recorded frames, CPU == GPU");
  }
}
