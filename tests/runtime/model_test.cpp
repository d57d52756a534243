// Model (shared per asset) and Workspace (per character): sharing gives the same results as separate
// models, a workspace used with another model is refused with nothing written, caller-memory models
// and workspaces check their buffer, and BatchJob equals the per-character jobs bit for bit.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <thread>
#include <vector>

#include "runtime/asset_builder.h"

using namespace spherechain;
using namespace spherechain::runtime;

namespace {

// Two crossing tubes with centre joint weights (3 joints), loaded.
struct Asset {
  test::Mesh mesh;
  test::AssetData data;
  test::AlignedBytes bytes;
  AssetView view;
  Asset() {
    data = test::TwoTubes(true, &mesh);
    data.joint_count = 3;
    for (size_t s = 0; s < data.spheres.size(); ++s) {
      data.sphere_joints.insert(data.sphere_joints.end(), {uint16_t(s % 2), 2, 0, 0});
      data.sphere_joint_weights.insert(data.sphere_joint_weights.end(), {0.7f, 0.3f, 0.0f, 0.0f});
    }
    bytes = test::Serialize(data);
    REQUIRE(LoadAsset(bytes.data(), bytes.size, &view) == Status::kOk);
  }
};

// A pose of the tubes: every vertex bent about the origin by an angle growing with its distance, plus
// a seeded jitter, so that each character has its own spheres and pairs.
std::vector<float> Pose(const test::Mesh& mesh, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const float bend = 0.15f * u(rng), lift = 0.5f * u(rng);
  std::vector<float> p = mesh.positions;
  for (size_t i = 0; i < p.size(); i += 3) {
    const float d = std::sqrt(p[i] * p[i] + p[i + 1] * p[i + 1]);
    const float a = bend * d, c = std::cos(a), s = std::sin(a);
    const float x = p[i], y = p[i + 1];
    p[i] = c * x - s * y + 0.02f * u(rng);
    p[i + 1] = s * x + c * y + 0.02f * u(rng);
    p[i + 2] += lift * d * 0.1f + 0.02f * u(rng);
  }
  return p;
}

std::vector<float> Joints(uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> m(3 * kJointMatrixFloats, 0.0f);
  for (uint32_t j = 0; j < 3; ++j) {
    const float a = u(rng), c = std::cos(a), s = std::sin(a);
    const float rows[12] = {c, -s, 0, u(rng), s, c, 0, u(rng), 0, 0, 1, u(rng)};
    std::memcpy(&m[12 * j], rows, sizeof rows);
  }
  return m;
}

// What one character gives: its spheres (bits) and its M1 or M2 records (bits) and counters.
struct Result {
  std::vector<float> spheres;
  std::vector<Collision> pairs;
  DetectStats stats;
  Status status = Status::kOk;
};

std::vector<float> SphereBits(const Workspace& ws) {
  const SphereArrays s = ws.spheres();
  std::vector<float> out;
  for (const float* a : {s.x, s.y, s.z, s.r}) out.insert(out.end(), a, a + s.count);
  return out;
}

Result RunAlone(const Model& model, Workspace& ws, const std::vector<float>& pos, DetectMethod method) {
  Result r;
  RefitJob refit;
  refit.model = &model;
  refit.workspace = &ws;
  refit.positions = {pos.data(), static_cast<uint32_t>(pos.size() / 3), 12};
  REQUIRE(refit.Run() == Status::kOk);
  r.spheres = SphereBits(ws);
  r.pairs.resize(model.m2_candidate_pairs());
  uint32_t n = 0;
  DetectJob detect;
  detect.model = &model;
  detect.workspace = &ws;
  detect.method = method;
  detect.output = r.pairs.data();
  detect.capacity = static_cast<uint32_t>(r.pairs.size());
  detect.count = &n;
  detect.stats = &r.stats;
  r.status = detect.Run();
  r.pairs.resize(n);
  return r;
}

void CheckSame(const Result& a, const Result& b) {
  REQUIRE(a.spheres.size() == b.spheres.size());
  CHECK(std::memcmp(a.spheres.data(), b.spheres.data(), a.spheres.size() * sizeof(float)) == 0);
  REQUIRE(a.pairs.size() == b.pairs.size());
  CHECK(std::memcmp(a.pairs.data(), b.pairs.data(), a.pairs.size() * sizeof(Collision)) == 0);
  CHECK(a.stats.raw_pairs == b.stats.raw_pairs);
  CHECK(a.stats.distinct_pairs == b.stats.distinct_pairs);
  CHECK(a.stats.box_tests == b.stats.box_tests);
  CHECK(a.stats.sphere_tests == b.stats.sphere_tests);
  CHECK(a.status == b.status);
}

// A ParallelFor hook that runs the task indices on two threads, interleaved (odd / even), to shuffle
// the order in which characters and row blocks run.
void TwoThreads(void*, uint32_t count, ParallelFor::Task task, void* data) {
  std::thread t([&] {
    for (uint32_t i = 1; i < count; i += 2) task(data, i, i + 1);
  });
  for (uint32_t i = 0; i < count; i += 2) task(data, i, i + 1);
  t.join();
}

}  // namespace

TEST_CASE("Model shared by two workspaces gives what separate models give, bit for bit") {
  Asset asset;
  Model shared;
  REQUIRE(shared.Init(asset.view) == Status::kOk);
  CHECK(shared.id() != 0);
  CHECK(shared.bytes() == Model::RequiredBytes(asset.view));
  CHECK(shared.joint_count() == 3);
  Workspace w1, w2;
  REQUIRE(w1.Init(shared) == Status::kOk);
  REQUIRE(w2.Init(shared) == Status::kOk);
  CHECK(w1.made_for(shared));
  CHECK(w2.model_id() == shared.id());
  const std::vector<float> p1 = Pose(asset.mesh, 1), p2 = Pose(asset.mesh, 2);
  for (DetectMethod method : {DetectMethod::kM1, DetectMethod::kM2}) {
    // Interleaved on the shared model: refit 1, refit 2, detect 1, detect 2 (each workspace its own state).
    const Result s1 = RunAlone(shared, w1, p1, method);
    const Result s2 = RunAlone(shared, w2, p2, method);
    const Result again1 = RunAlone(shared, w1, p1, method);
    test::Character c1, c2;
    REQUIRE(c1.Init(asset.view) == Status::kOk);
    REQUIRE(c2.Init(asset.view) == Status::kOk);
    CHECK(c1.model.id() != c2.model.id());
    CheckSame(s1, RunAlone(c1.model, c1.ws, p1, method));
    CheckSame(s2, RunAlone(c2.model, c2.ws, p2, method));
    CheckSame(s1, again1);
    CHECK(s1.spheres != s2.spheres);  // the two characters differ (the test can tell them apart)
  }
  // A moved model keeps its id: its workspaces stay valid.
  Model moved = std::move(shared);
  CHECK_FALSE(shared.initialized());
  CHECK(w1.made_for(moved));
  CHECK(w1.ResetToBindPose(moved) == Status::kOk);
}

TEST_CASE("A workspace used with another model: kErrorWorkspaceModel, nothing written") {
  Asset asset;
  test::Character a, b;  // two models of the same asset: same sizes, different ids
  REQUIRE(a.Init(asset.view) == Status::kOk);
  REQUIRE(b.Init(asset.view) == Status::kOk);
  const std::vector<float> pos = Pose(asset.mesh, 3);
  (void)RunAlone(b.model, b.ws, pos, DetectMethod::kM2);
  const std::vector<float> before = SphereBits(b.ws);

  RefitJob refit;
  refit.model = &a.model;
  refit.workspace = &b.ws;
  refit.positions = {asset.mesh.positions.data(), asset.mesh.vertex_count(), 12};
  CHECK(refit.Check() == Status::kErrorWorkspaceModel);
  CHECK(refit.Run() == Status::kErrorWorkspaceModel);

  std::vector<Collision> out(8, Collision{7, 9, 1.5f, 3});
  uint32_t n = 1234;
  DetectStats stats;
  stats.tests = 77;
  DetectJob detect;
  detect.model = &a.model;
  detect.workspace = &b.ws;
  detect.output = out.data();
  detect.capacity = 8;
  detect.count = &n;
  detect.stats = &stats;
  CHECK(detect.Run() == Status::kErrorWorkspaceModel);
  CHECK(n == 1234);
  CHECK(stats.tests == 77);
  CHECK((out[0].a == 7 && out[0].b == 9));

  const std::vector<float> m = Joints(4);
  JointRefitJob joints;
  joints.model = &a.model;
  joints.workspace = &b.ws;
  joints.joint_matrices = m.data();
  joints.joint_count = 3;
  CHECK(joints.Run() == Status::kErrorWorkspaceModel);
  CHECK(b.ws.ResetToBindPose(a.model) == Status::kErrorWorkspaceModel);
  CHECK(SphereBits(b.ws) == before);

  // The same jobs with the workspace's own model run (the status is about the pairing, nothing else).
  refit.model = detect.model = joints.model = &b.model;
  CHECK(refit.Run() == Status::kOk);
  CHECK(Succeeded(detect.Run()));  // capacity 8: may be truncated
  CHECK(n <= 8);
  CHECK(joints.Run() == Status::kOk);
  // An empty workspace or model: kErrorInvalidJob; null ones: kErrorNullArgument.
  Workspace empty;
  refit.workspace = &empty;
  CHECK(refit.Check() == Status::kErrorInvalidJob);
  refit.workspace = nullptr;
  CHECK(refit.Check() == Status::kErrorNullArgument);
  CHECK(empty.Init(Model{}) == Status::kErrorInvalidJob);
}

TEST_CASE("Caller-memory model and workspace: RequiredBytes, too small, misaligned, and the same results") {
  Asset asset;
  const size_t need = Model::RequiredBytes(asset.view);
  REQUIRE(need > 0);
  CHECK(Model::RequiredBytes(AssetView{}) == 0);
  std::unique_ptr<uint64_t[]> mem(new uint64_t[need / 8 + 4]);
  std::memset(mem.get(), 0xAB, need + 32);
  Model in_place;
  CHECK(in_place.InitInPlace(asset.view, mem.get(), need - 1) == Status::kErrorBufferTooSmall);
  CHECK_FALSE(in_place.initialized());
  CHECK(in_place.InitInPlace(asset.view, mem.get(), 0) == Status::kErrorBufferTooSmall);
  CHECK(in_place.InitInPlace(asset.view, reinterpret_cast<unsigned char*>(mem.get()) + 8, need) ==
        Status::kErrorAlignment);
  CHECK(in_place.InitInPlace(asset.view, nullptr, need) == Status::kErrorNullArgument);
  CHECK(in_place.InitInPlace(AssetView{}, mem.get(), need) == Status::kErrorNullArgument);
  // The bytes past `need` are never written.
  REQUIRE(in_place.InitInPlace(asset.view, mem.get(), need) == Status::kOk);
  const unsigned char* tail = reinterpret_cast<const unsigned char*>(mem.get()) + need;
  for (int i = 0; i < 16; ++i) CHECK(tail[i] == 0xAB);
  CHECK(in_place.bytes() == need);

  const size_t ws_need = Workspace::RequiredBytes(in_place);
  REQUIRE(ws_need > 0);
  std::unique_ptr<uint64_t[]> ws_mem(new uint64_t[ws_need / 8 + 2]);
  Workspace ws;
  CHECK(ws.InitInPlace(in_place, ws_mem.get(), ws_need - 4) == Status::kErrorBufferTooSmall);
  CHECK(ws.InitInPlace(in_place, nullptr, ws_need) == Status::kErrorNullArgument);
  REQUIRE(ws.InitInPlace(in_place, ws_mem.get(), ws_need) == Status::kOk);

  test::Character owned;
  REQUIRE(owned.Init(asset.view) == Status::kOk);
  const std::vector<float> pos = Pose(asset.mesh, 5);
  for (DetectMethod method : {DetectMethod::kM1, DetectMethod::kM2})
    CheckSame(RunAlone(in_place, ws, pos, method), RunAlone(owned.model, owned.ws, pos, method));
  CHECK(owned.model.m1_candidate_pairs() == in_place.m1_candidate_pairs());
}

TEST_CASE("BatchJob equals each character's own refit + detect, serial and on two threads") {
  Asset asset;
  Model model;
  REQUIRE(model.Init(asset.view) == Status::kOk);
  constexpr uint32_t N = 9;
  std::vector<std::vector<float>> poses, joints;
  for (uint32_t i = 0; i < N; ++i) poses.push_back(Pose(asset.mesh, 100 + i)), joints.push_back(Joints(200 + i));
  for (RefitSource source : {RefitSource::kVertices, RefitSource::kJoints})
    for (DetectMethod method : {DetectMethod::kM1, DetectMethod::kM2})
      for (int hook = 0; hook < 3; ++hook) {  // serial; two threads; two threads, one task (the largest grain)
        CAPTURE(static_cast<int>(source));
        CAPTURE(static_cast<int>(method));
        CAPTURE(hook);
        std::vector<Workspace> ws(N);
        std::vector<std::vector<Collision>> out(N, std::vector<Collision>(model.m2_candidate_pairs()));
        std::vector<uint32_t> count(N, 0);
        std::vector<DetectStats> stats(N);
        std::vector<CharacterFrame> frames(N);
        for (uint32_t i = 0; i < N; ++i) {
          REQUIRE(ws[i].Init(model) == Status::kOk);
          frames[i].workspace = &ws[i];
          frames[i].positions = {poses[i].data(), asset.mesh.vertex_count(), 12};
          frames[i].joint_matrices = joints[i].data();
          frames[i].output = out[i].data();
          frames[i].capacity = static_cast<uint32_t>(out[i].size());
          frames[i].count = &count[i];
          frames[i].stats = &stats[i];
        }
        BatchJob batch;
        batch.model = &model;
        batch.characters = frames.data();
        batch.character_count = N;
        batch.source = source;
        batch.joint_count = 3;
        batch.method = method;
        batch.parallel_grain = hook == 2 ? 0xffffffffu : 2;  // 0xffffffff: the task count once wrapped to 0
        if (hook) batch.parallel_for.run = &TwoThreads;
        REQUIRE(batch.Run() == Status::kOk);
        for (uint32_t i = 0; i < N; ++i) {
          CAPTURE(i);
          // The same character alone, on its own model.
          test::Character alone;
          REQUIRE(alone.Init(asset.view) == Status::kOk);
          Result want;
          if (source == RefitSource::kVertices) {
            want = RunAlone(alone.model, alone.ws, poses[i], method);
          } else {
            JointRefitJob jr;
            jr.model = &alone.model;
            jr.workspace = &alone.ws;
            jr.joint_matrices = joints[i].data();
            jr.joint_count = 3;
            REQUIRE(jr.Run() == Status::kOk);
            want.spheres = SphereBits(alone.ws);
            want.pairs.resize(model.m2_candidate_pairs());
            uint32_t n = 0;
            DetectJob d = test::MakeDetectJob(alone, method, want.pairs, &n, &want.stats);
            want.status = d.Run();
            want.pairs.resize(n);
          }
          Result got{SphereBits(ws[i]), std::vector<Collision>(out[i].begin(), out[i].begin() + count[i]), stats[i],
                     frames[i].status};
          CheckSame(got, want);
        }
      }
}

TEST_CASE("BatchJob: bad batch arguments write nothing; a bad character gets its status, the others run") {
  Asset asset;
  Model model, other;
  REQUIRE(model.Init(asset.view) == Status::kOk);
  REQUIRE(other.Init(asset.view) == Status::kOk);
  const std::vector<float> pos = Pose(asset.mesh, 7);
  Workspace good, foreign;
  REQUIRE(good.Init(model) == Status::kOk);
  REQUIRE(foreign.Init(other) == Status::kOk);
  std::vector<Collision> out(model.m2_candidate_pairs());
  uint32_t n_good = 99, n_foreign = 99;
  CharacterFrame frames[2];
  frames[0].workspace = &foreign;
  frames[0].positions = {pos.data(), asset.mesh.vertex_count(), 12};
  frames[0].count = &n_foreign;
  frames[1].workspace = &good;
  frames[1].positions = frames[0].positions;
  frames[1].output = out.data();
  frames[1].capacity = static_cast<uint32_t>(out.size());
  frames[1].count = &n_good;
  BatchJob batch;
  batch.model = &model;
  batch.characters = frames;
  batch.character_count = 2;
  batch.margin = NAN;
  CHECK(batch.Run() == Status::kErrorInvalidJob);
  CHECK(n_good == 99);
  batch.margin = -1.0f;
  batch.source = RefitSource::kJoints;
  batch.joint_count = 2;
  CHECK(batch.Run() == Status::kErrorJointCount);
  batch.source = RefitSource::kVertices;
  batch.characters = nullptr;
  CHECK(batch.Run() == Status::kErrorNullArgument);
  batch.characters = frames;
  const std::vector<float> foreign_before = SphereBits(foreign);
  CHECK(batch.Run() == Status::kErrorWorkspaceModel);
  CHECK(frames[0].status == Status::kErrorWorkspaceModel);
  CHECK(n_foreign == 99);
  CHECK(SphereBits(foreign) == foreign_before);
  CHECK(frames[1].status == Status::kOk);
  CHECK(n_good > 0);  // the crossing tubes overlap
  // A short output: kOkTruncated from the batch.
  frames[0].workspace = nullptr;
  batch.character_count = 2;
  CHECK(batch.Run() == Status::kErrorNullArgument);
  frames[1].capacity = 1;
  batch.characters = frames + 1;
  batch.character_count = 1;
  CHECK(batch.Run() == Status::kOkTruncated);
  CHECK(n_good == 1);
  // Its own detect arguments bad (a null count): status set, and its workspace's spheres not refit either.
  Workspace fresh;
  REQUIRE(fresh.Init(model) == Status::kOk);
  const std::vector<float> fresh_before = SphereBits(fresh);
  frames[1].workspace = &fresh;
  frames[1].count = nullptr;
  CHECK(batch.Run() == Status::kErrorNullArgument);
  CHECK(frames[1].status == Status::kErrorNullArgument);
  CHECK(SphereBits(fresh) == fresh_before);
}
