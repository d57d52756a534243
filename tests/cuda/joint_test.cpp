// spherechain::cuda refit from joint matrices (FrameParams::source = RefitSource::kJoints): CPU
// (JointRefitJob + DetectJob) == GPU bit for bit on synthetic rigged assets and on the recorded clips'
// joint matrices, every method and strategy, also as a crowd of two assets over the many-instance
// threshold; graph replay; the documented statuses.
#include "cuda/batch_fixture.h"

using namespace spherechain;
using namespace spherechain::test;
using runtime::DetectMethod;
using runtime::RefitMode;
using runtime::RefitSource;

namespace {

// Every (method, strategy) with kAuto too.
std::vector<std::pair<DetectMethod, sc::Strategy>> AllStrategies() {
  auto out = MethodStrategies();
  out.push_back({DetectMethod::kM1, sc::Strategy::kAuto});
  out.push_back({DetectMethod::kM2, sc::Strategy::kAuto});
  return out;
}

sc::FrameParams JointParams(DetectMethod method, sc::Strategy strategy) {
  sc::FrameParams fp{RefitMode::kPivotFrame, method, strategy, true};
  fp.source = RefitSource::kJoints;
  return fp;
}

// Two synthetic rigged assets: `a` with 9 joints (spheres of 1, 2, 3 and 4 influences), `b` with 3 (at most 3
// influences), a contact margin and a fold margin; `n` instances alternating a, b, moved at random
// (`seed`), each with random joint matrices (`joint_seed`), uploaded.
void BuildRiggedPair(AssetSet* a, AssetSet* b, uint32_t n, uint32_t seed, uint32_t joint_seed, DeviceInstances* inst) {
  MakeStar(a, 6, 12, 0.0f, -1.0f, 9);
  MakeStar(b, 4, 14, 0.05f, 0.02f, 3);
  REQUIRE(a->device.joint_count() == 9);
  REQUIRE(b->device.joint_count() == 3);
  inst->Build({a, b}, n, seed);
  std::mt19937 rng(joint_seed);
  for (size_t i = 0; i < inst->table.size(); ++i)
    inst->joints.push_back(RandomJointMatrices(i % 2 == 0 ? 9 : 3, rng, 3.0f, 0.25f));
  inst->UploadJoints();
}

}  // namespace

TEST_CASE("cuda: joint refit on synthetic rigged assets, 1-4 influences, CPU == GPU bit for bit (all strategies)") {
  if (!RequireDevice()) return;
  AssetSet a, b;
  DeviceInstances inst;
  BuildRiggedPair(&a, &b, 96, 31u, 5u, &inst);
  const sc::DeviceAsset* dev[] = {&a.device, &b.device};
  sc::Batch batch;
  REQUIRE(batch.Init(dev, 2, inst.table.data(), 96) == sc::Status::kOk);
  CHECK(batch.frame_joint_bytes() == 48u * 48u * (9u + 3u));
  size_t pairs = 0;
  for (const auto& [method, strategy] : AllStrategies()) {
    CAPTURE(int(method));
    CAPTURE(int(strategy));
    pairs += RunCompared({&a, &b}, inst, batch, JointParams(method, strategy)).total;
  }
  CHECK(pairs > 0);  // the motions make spheres of different joints meet
  // The same batch still refits from its positions.
  (void)RunCompared({&a, &b}, inst, batch, sc::FrameParams{RefitMode::kPivotFrame, DetectMethod::kM2, sc::Strategy::kAuto, true});
}

// The same two assets as a crowd over the many-instance threshold (4 instances an SM): a batch of several
// assets runs the many-instance kernels that read each instance's asset from the asset table (a batch of
// one asset reads it from the kernel's parameters; the recorded-frame crowd covers that one).
TEST_CASE("cuda: a crowd of two synthetic rigged assets over the many-instance threshold, both refit sources, CPU == GPU") {
  if (!RequireDevice()) return;
  const uint32_t n = ManyInstanceCrowd();
  AssetSet a, b;
  DeviceInstances inst;
  BuildRiggedPair(&a, &b, n, 37u, 11u, &inst);
  const sc::DeviceAsset* dev[] = {&a.device, &b.device};
  sc::Batch batch;
  REQUIRE(batch.Init(dev, 2, inst.table.data(), n) == sc::Status::kOk);
  size_t pairs = 0;
  for (const auto& [method, strategy] : AllStrategies()) {
    CAPTURE(int(method));
    CAPTURE(int(strategy));
    pairs += RunCompared({&a, &b}, inst, batch, JointParams(method, strategy)).total;
    pairs += RunCompared({&a, &b}, inst, batch, sc::FrameParams{RefitMode::kPivotFrame, method, strategy, true}).total;
  }
  CHECK(pairs > 0);
}

TEST_CASE("cuda: joint refit at the bind pose (identity matrices) gives the bind spheres exactly") {
  if (!RequireDevice()) return;
  AssetSet a;
  MakeStar(&a, 5, 10, 0.0f, -1.0f, 7);
  DeviceInstances inst;
  inst.Build({&a}, 3, 1u, /*rest=*/true);
  std::vector<float> identity(7 * 12, 0.0f);
  for (uint32_t j = 0; j < 7; ++j) identity[12 * j] = identity[12 * j + 5] = identity[12 * j + 10] = 1.0f;
  inst.joints.assign(3, identity);
  inst.UploadJoints();
  const sc::DeviceAsset* dev[] = {&a.device};
  sc::Batch batch;
  REQUIRE(batch.Init(dev, 1, inst.table.data(), 3) == sc::Status::kOk);
  const sc::HostResults res = RunCompared({&a}, inst, batch, JointParams(DetectMethod::kM2, sc::Strategy::kAuto));
  // Weights summing to 1 in float need not give exactly 1·c: compare with the bind centre to rounding,
  // and the radius exactly (the joint refit keeps the bind radius).
  for (uint32_t i = 0; i < 3; ++i)
    for (uint32_t s = 0; s < a.view.sphere_count; ++s) {
      const schema::Sphere* b = a.view.asset->spheres()->Get(s);
      const float4 g = res.spheres[batch.sphere_offset(i) + s];
      CHECK(g.w == b->radius());
      CHECK(NearRel(g.x, b->center().x(), 1e-5f));
      CHECK(NearRel(g.y, b->center().y(), 1e-5f));
      CHECK(NearRel(g.z, b->center().z(), 1e-5f));
    }
}

TEST_CASE("cuda: joint refit on recorded animation frames (MakeHuman, CesiumMan, BCN_Epileptic), CPU == GPU bit for bit") {
  if (!RequireDevice()) return;
  size_t clips_with_joints = 0;
  const size_t clips = ForEachRecordedClip([&](AssetSet& set, const std::vector<std::vector<float>>& frames) {
    if (set.joint_frames.empty()) {
      MESSAGE("no frame_NNNN.joints beside the frames (re-record with `spherechain play --dump-frames`)");
      return;
    }
    ++clips_with_joints;
    DeviceInstances inst;
    BuildFrameInstances(set, frames, &inst);
    inst.joints = set.joint_frames;
    inst.UploadJoints();
    const sc::DeviceAsset* dev[] = {&set.device};
    sc::Batch batch;
    const uint32_t n = static_cast<uint32_t>(frames.size());
    REQUIRE(batch.Init(dev, 1, inst.table.data(), n) == sc::Status::kOk);
    for (const auto& [method, strategy] : AllStrategies()) {
      CAPTURE(int(method));
      CAPTURE(int(strategy));
      (void)RunCompared({&set}, inst, batch, JointParams(method, strategy));
    }
    // The clip moved rigidly as a whole (a character walking across a level): every frame again.
    std::mt19937 rng(11u);
    for (auto& m : inst.joints) {
      const std::vector<float> T = RandomJointMatrices(1, rng, 50.0f, 0.0f);
      for (size_t j = 0; j < m.size(); j += 12) {
        float r[12];
        for (int row = 0; row < 3; ++row)
          for (int c = 0; c < 4; ++c)
            r[4 * row + c] = T[4 * row] * m[j + c] + T[4 * row + 1] * m[j + 4 + c] + T[4 * row + 2] * m[j + 8 + c] +
                             (c == 3 ? T[4 * row + 3] : 0.0f);
        std::copy(r, r + 12, m.begin() + std::ptrdiff_t(j));
      }
    }
    inst.UploadJoints();
    for (DetectMethod method : {DetectMethod::kM1, DetectMethod::kM2})
      (void)RunCompared({&set}, inst, batch, JointParams(method, sc::Strategy::kAuto));
  });
  if (clips > 0 && clips_with_joints == 0) Skip("the recorded clips hold no joint matrices");
}

TEST_CASE("cuda: a joint-refit frame captured into a CUDA graph replays to the CPU result for new matrices") {
  if (!RequireDevice()) return;
  AssetSet a;
  MakeStar(&a, 5, 12, 0.0f, -1.0f, 6);
  DeviceInstances inst;
  inst.Build({&a}, 32, 3u);
  std::mt19937 rng(9u);
  for (size_t i = 0; i < 32; ++i) inst.joints.push_back(RandomJointMatrices(6, rng, 2.0f, 0.3f));
  inst.UploadJoints();
  const sc::DeviceAsset* dev[] = {&a.device};
  sc::Batch batch;
  REQUIRE(batch.Init(dev, 1, inst.table.data(), 32) == sc::Status::kOk);
  cudaStream_t stream;
  CUDA_REQUIRE(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking));
  const sc::FrameParams fp = JointParams(DetectMethod::kM2, sc::Strategy::kAuto);
  cudaGraph_t graph;
  CUDA_REQUIRE(cudaStreamBeginCapture(stream, cudaStreamCaptureModeGlobal));
  const sc::Status st = batch.Run(fp, stream);
  CUDA_REQUIRE(cudaStreamEndCapture(stream, &graph));
  REQUIRE(st == sc::Status::kOk);
  cudaGraphExec_t exec;
  CUDA_REQUIRE(cudaGraphInstantiate(&exec, graph, 0));
  for (int round = 0; round < 2; ++round) {
    for (auto& m : inst.joints) m = RandomJointMatrices(6, rng, 2.0f, 0.3f);
    inst.UploadJoints();  // same device addresses: the graph reads the new matrices
    CUDA_REQUIRE(cudaGraphLaunch(exec, stream));
    sc::HostResults res;
    REQUIRE(batch.Download(stream, &res, true) == sc::Status::kOk);
    CompareWithCpu({&a}, inst, res, batch, fp);
  }
  CUDA_REQUIRE(cudaGraphExecDestroy(exec));
  CUDA_REQUIRE(cudaGraphDestroy(graph));
  CUDA_REQUIRE(cudaStreamDestroy(stream));
}

TEST_CASE("cuda: joint refit statuses: no joint weights, joint count, alignment, missing input, unknown source") {
  if (!RequireDevice()) return;
  AssetSet rigged, plain;
  MakeStar(&rigged, 4, 8, 0.0f, -1.0f, 5);
  MakeStar(&plain, 4, 8);
  REQUIRE(plain.device.joint_count() == 0);
  DeviceInstances inst;
  inst.Build({&rigged}, 2, 2u);
  std::mt19937 rng(4u);
  inst.joints = {RandomJointMatrices(5, rng, 1.0f, 0.1f), RandomJointMatrices(5, rng, 1.0f, 0.1f)};
  inst.UploadJoints();
  const sc::DeviceAsset* dev[] = {&rigged.device, &plain.device};
  sc::Batch batch;

  std::vector<sc::Instance> t = inst.table;
  t[1].asset = 1;  // joint matrices on an asset without joint weights
  t[1].vertex_count = plain.view.vertex_count;
  CHECK(batch.Init(dev, 2, t.data(), 2) == sc::Status::kErrorMissingField);
  CHECK_FALSE(batch.initialized());
  t = inst.table;
  t[0].joint_count = 4;
  CHECK(batch.Init(dev, 1, t.data(), 2) == sc::Status::kErrorJointCount);
  t = inst.table;
  t[1].joint_matrices = reinterpret_cast<const float*>(reinterpret_cast<const char*>(t[1].joint_matrices) + 2);
  CHECK(batch.Init(dev, 1, t.data(), 2) == sc::Status::kErrorAlignment);
  t = inst.table;
  t[0].positions = nullptr;
  t[0].joint_matrices = nullptr;
  CHECK(batch.Init(dev, 1, t.data(), 2) == sc::Status::kErrorNullArgument);

  // Joints only: a frame from vertices has no input (and writes nothing); from joints it runs.
  t = inst.table;
  for (sc::Instance& i : t) i.positions = nullptr;
  REQUIRE(batch.Init(dev, 1, t.data(), 2) == sc::Status::kOk);
  CHECK(batch.frame_position_bytes() == 0u);
  sc::FrameParams fp = JointParams(DetectMethod::kM2, sc::Strategy::kAuto);
  fp.source = RefitSource::kVertices;
  CHECK(batch.Run(fp, 0) == sc::Status::kErrorNullArgument);
  fp.source = static_cast<RefitSource>(7);
  CHECK(batch.Run(fp, 0) == sc::Status::kErrorInvalidJob);
  fp.source = RefitSource::kJoints;
  CHECK(batch.Run(fp, 0) == sc::Status::kOk);
  sc::HostResults res;
  CHECK(batch.Download(0, &res, true) == sc::Status::kOk);

  // Positions only: a frame from joints has no input.
  REQUIRE(batch.Init(dev, 2, std::vector<sc::Instance>{{inst.table[0].positions, rigged.view.vertex_count, inst.table[0].stride_bytes, 0}}.data(), 1) ==
          sc::Status::kOk);
  CHECK(batch.frame_joint_bytes() == 0u);
  CHECK(batch.Run(JointParams(DetectMethod::kM1, sc::Strategy::kAuto), 0) == sc::Status::kErrorNullArgument);
  CHECK(std::string(sc::ToString(sc::Status::kErrorJointCount)).find("kErrorJointCount") == 0);
}
