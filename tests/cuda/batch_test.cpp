// spherechain::cuda — CPU == GPU (refit + detect, every strategy/method/mode), CUDA graph replay,
// invalid inputs, overflow, and the MakeHuman asset. Every test SKIPs visibly without a CUDA device.
#include "cuda/batch_fixture.h"

using namespace spherechain;
using namespace spherechain::runtime;
using namespace spherechain::test;
namespace sc = spherechain::cuda;

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
                                    sc::Strategy::kWarpPerInstance, sc::Strategy::kBlockBoxes}) {
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
  CHECK(empty.Upload(runtime::Model{}) == sc::Status::kErrorNullArgument);
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
  CHECK(batch.Run({RefitMode::kPaper, DetectMethod::kM1, static_cast<sc::Strategy>(5), false}, 0) ==
        sc::Status::kErrorInvalidJob);
  CHECK(std::string(sc::ToString(sc::Status::kErrorVertexCount)).find("kErrorVertexCount") == 0);
  CHECK(std::string(sc::ToString(sc::Status::kErrorCuda)).find("kErrorCuda") == 0);
}

TEST_CASE("cuda: a too-small output sets the overflow flag and the counts stay complete") {
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
  const std::string asset_path = MakeHumanAssetPath();
  const std::string obj = test::SharedData("makehuman/base.obj");
  if (!test::Require(asset_path) || !test::Require(obj)) {
    MESSAGE("SKIPPED: bake it with `spherechain bake " << obj << " -o " << asset_path << "` (or set SPHERECHAIN_MH_ASSET)");
    return;
  }
  AssetSet mh;
  LoadFile(&mh, asset_path);
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
    for (const auto& [method, strategy] : MethodStrategies()) {
      (void)RunCompared({&mh}, inst, batch, sc::FrameParams{mode, method, strategy, true});
    }
}

// Recorded animation frames (`spherechain play ... --dump-frames DIR`), each frame one instance of one
// batch: the MakeHuman morph, the CesiumMan walk and the BCN_Epileptic clip, CPU == GPU (SPHERECHAIN_GPU_FRAMES, see
// ForEachRecordedClip).
TEST_CASE("cuda: recorded animation frames (MakeHuman morph, CesiumMan walk, BCN_Epileptic clip), CPU == GPU") {
  if (!RequireDevice()) return;
  ForEachRecordedClip([](AssetSet& set, const std::vector<std::vector<float>>& frames) {
    DeviceInstances inst;
    BuildFrameInstances(set, frames, &inst);
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
  });
}

// A crowd of the recorded frames over the many-instance threshold (4 instances an SM: one block an instance,
// the register-capped kernels; below it a batch runs the few-instance kernels, several blocks an
// instance, which the other cases cover), from vertices and from the skinning matrices: every strategy
// and method, CPU == GPU.
TEST_CASE("cuda: a crowd of recorded frames over the many-instance threshold, both refit sources, CPU == GPU") {
  if (!RequireDevice()) return;
  const uint32_t n = ManyInstanceCrowd();
  ForEachRecordedClip([&](AssetSet& set, const std::vector<std::vector<float>>& frames) {
    std::vector<std::vector<float>> crowd(n);
    for (uint32_t i = 0; i < n; ++i) crowd[i] = frames[i % frames.size()];
    DeviceInstances inst;
    BuildFrameInstances(set, crowd, &inst);
    if (!set.joint_frames.empty()) {
      for (uint32_t i = 0; i < n; ++i) inst.joints.push_back(set.joint_frames[i % set.joint_frames.size()]);
      inst.UploadJoints();
    }
    const sc::DeviceAsset* dev[] = {&set.device};
    sc::Batch batch;
    REQUIRE(batch.Init(dev, 1, inst.table.data(), n) == sc::Status::kOk);
    for (const auto& [method, strategy] : MethodStrategies()) {
      CAPTURE(int(method));
      CAPTURE(int(strategy));
      const sc::HostResults res = RunCompared({&set}, inst, batch, sc::FrameParams{RefitMode::kPivotFrame, method, strategy, true});
      CHECK(res.total > 0);  // the recorded clips collide somewhere: the crowd tests real pairs
      if (set.joint_frames.empty()) continue;
      sc::FrameParams fp{RefitMode::kPivotFrame, method, strategy, true};
      fp.source = RefitSource::kJoints;
      (void)RunCompared({&set}, inst, batch, fp);
    }
  });
}
