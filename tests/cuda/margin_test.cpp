// spherechain::cuda — the contact margin (FrameParams::margin, DeviceAsset::contact_margin): CPU == GPU
// against DetectJob with the same margin (every strategy and method) on synthetic assets, recorded
// animation frames and the MakeHuman asset; per-instance asset margins in a mixed batch; NaN / inf
// margins rejected. Every test SKIPs visibly without a CUDA device.
#include "cuda/batch_fixture.h"

#include <limits>

using namespace spherechain;
using namespace spherechain::runtime;
using namespace spherechain::test;
namespace sc = spherechain::cuda;

namespace {

/// Properties of one GPU frame `big` (margin `m_big` for every instance, spheres written) against the
/// same frame `small` with a smaller margin: every pair of `small` is in `big` (float rounding is
/// monotonic, so growing the radii never loses a pair), and every depth of `big` is > −2·m_big (up to
/// rounding, 1e-5 of rA + rB + 2·m_big). Returns the pairs of `big` with a negative depth (apart, but
/// within the margin).
size_t CheckGrowth(const sc::HostResults& small, const sc::HostResults& big, float m_big, const sc::Batch& batch) {
  std::set<std::tuple<uint32_t, int, int>> in_big;
  size_t negative = 0;
  for (const sc::BatchCollision& c : big.pairs) {
    in_big.insert({c.instance, c.pair.a, c.pair.b});
    const uint32_t off = batch.sphere_offset(c.instance);
    const float rr = big.spheres[off + c.pair.a].w + big.spheres[off + c.pair.b].w + 2.0f * m_big;
    CHECK(c.pair.depth > -2.0f * m_big - 1e-5f * rr);
    negative += c.pair.depth < 0.0f;
  }
  for (const sc::BatchCollision& c : small.pairs)
    if (!in_big.count({c.instance, c.pair.a, c.pair.b})) {
      FAIL_CHECK("instance " << c.instance << ": pair (" << c.pair.a << ", " << c.pair.b << ") lost when the margin grew");
      break;
    }
  for (size_t i = 0; i < small.instance_counts.size(); ++i) CHECK(small.instance_counts[i] <= big.instance_counts[i]);
  return negative;
}

/// Runs `batch` with every strategy valid for `method` and the given margins, compares each frame with
/// the CPU DetectJob of the same margin, and checks the growth properties margin by margin (margins
/// ascending, every one >= 0). Returns the pairs with a negative depth at the largest margin.
size_t CompareMargins(const std::vector<AssetSet*>& assets, const DeviceInstances& inst, const sc::Batch& batch,
                      RefitMode mode, const std::vector<float>& margins) {
  size_t negative = 0;
  for (const auto& [method, strategy] : MethodStrategies()) {
    sc::HostResults previous;
    for (size_t k = 0; k < margins.size(); ++k) {
      CAPTURE(int(method));
      CAPTURE(int(strategy));
      CAPTURE(margins[k]);
      sc::FrameParams fp{mode, method, strategy, true};
      fp.margin = margins[k];
      sc::HostResults res = RunCompared(assets, inst, batch, fp);
      if (k > 0) {
        const size_t n = CheckGrowth(previous, res, margins[k], batch);
        if (k + 1 == margins.size()) negative = std::max(negative, n);
      }
      previous = std::move(res);
    }
  }
  return negative;
}

}  // namespace

TEST_CASE("cuda: FrameParams::margin, CPU == GPU with the same DetectJob::margin on synthetic assets (all strategies)") {
  if (!RequireDevice()) return;
  AssetSet star;
  MakeStar(&star, 6, 12);
  REQUIRE(star.device.contact_margin() == 0.0f);  // the builder writes no Asset.contact_margin
  DeviceInstances inst;
  inst.Build({&star}, 129, 4321u);
  const sc::DeviceAsset* dev[] = {&star.device};
  sc::Batch batch;
  REQUIRE(batch.Init(dev, 1, inst.table.data(), static_cast<uint32_t>(inst.table.size())) == sc::Status::kOk);
  const float r = MeanBindRadius(star);
  for (RefitMode mode : {RefitMode::kPaper, RefitMode::kPivotFrame}) {
    CAPTURE(int(mode));
    const size_t negative = CompareMargins({&star}, inst, batch, mode, {0.0f, 0.05f * r, 0.25f * r, 1.0f * r});
    MESSAGE("pairs within the largest margin but apart: " << negative);
  }
  // The default (< 0) is the asset's margin, 0 here: the same frame as margin 0.
  sc::HostResults a, b;
  sc::FrameParams fp{RefitMode::kPivotFrame, DetectMethod::kM2, sc::Strategy::kAuto, false};
  REQUIRE(batch.Run(fp, 0) == sc::Status::kOk);
  REQUIRE(batch.Download(0, &a) == sc::Status::kOk);
  fp.margin = 0.0f;
  REQUIRE(batch.Run(fp, 0) == sc::Status::kOk);
  REQUIRE(batch.Download(0, &b) == sc::Status::kOk);
  CHECK(a.total == b.total);
  CHECK(a.instance_counts == b.instance_counts);
}

// Real characters on recorded frames (SPHERECHAIN_GPU_FRAMES, scripts/gpu-carry.sh): the asset's own
// margin (default), no margin, and larger ones, every strategy and method, against the CPU.
TEST_CASE("cuda: FrameParams::margin on recorded animation frames (asset's, 0, 2x, 4x), CPU == GPU") {
  if (!RequireDevice()) return;
  ForEachRecordedClip([](AssetSet& set, const std::vector<std::vector<float>>& frames) {
    DeviceInstances inst;
    BuildFrameInstances(set, frames, &inst);
    const sc::DeviceAsset* dev[] = {&set.device};
    sc::Batch batch;
    REQUIRE(batch.Init(dev, 1, inst.table.data(), static_cast<uint32_t>(frames.size())) == sc::Status::kOk);
    const float own = set.device.contact_margin();
    MESSAGE("asset contact margin " << own);
    const float unit = own > 0.0f ? own : 0.02f * MeanBindRadius(set);  // v1 assets: margin 0
    // The default (< 0): each instance uses the asset's margin, as DetectJob's default.
    for (DetectMethod method : {DetectMethod::kM1, DetectMethod::kM2}) {
      const sc::FrameParams fp{RefitMode::kPivotFrame, method, sc::Strategy::kAuto, true};
      REQUIRE(fp.margin < 0.0f);
      REQUIRE(batch.Run(fp, 0) == sc::Status::kOk);
      sc::HostResults res;
      REQUIRE(batch.Download(0, &res, true) == sc::Status::kOk);
      CompareWithCpu({&set}, inst, res, batch, fp);
    }
    const size_t negative = CompareMargins({&set}, inst, batch, RefitMode::kPivotFrame, {0.0f, unit, 2.0f * unit, 4.0f * unit});
    MESSAGE("pairs within 4x the margin but apart, over " << frames.size() << " frames: " << negative);
  });
}

// One batch, three synthetic assets whose Asset.contact_margin differ (0, 0.1 r̄, 0.5 r̄): with
// FrameParams::margin < 0 each instance is tested with its own asset's margin (== a run with that margin
// given explicitly, for that asset's instances); with a margin >= 0 every instance uses that one.
TEST_CASE("cuda: FrameParams::margin < 0 uses each instance's asset margin in a mixed batch") {
  if (!RequireDevice()) return;
  AssetSet probe;
  MakeStar(&probe, 6, 12);
  const float r = MeanBindRadius(probe);
  const float own[3] = {0.0f, 0.1f * r, 0.5f * r};
  AssetSet s0, s1, s2;
  MakeStar(&s0, 6, 12, own[0]);
  MakeStar(&s1, 6, 12, own[1]);
  MakeStar(&s2, 6, 12, own[2]);
  const std::vector<AssetSet*> assets = {&s0, &s1, &s2};
  for (int k = 0; k < 3; ++k) {
    CHECK(assets[k]->device.contact_margin() == own[k]);
    CHECK(assets[k]->model.contact_margin() == own[k]);
  }
  DeviceInstances inst;
  inst.Build(assets, 96, 2468u);  // instance i of asset i % 3
  const sc::DeviceAsset* dev[] = {&s0.device, &s1.device, &s2.device};
  sc::Batch batch;
  REQUIRE(batch.Init(dev, 3, inst.table.data(), static_cast<uint32_t>(inst.table.size())) == sc::Status::kOk);
  for (const auto& [method, strategy] : MethodStrategies()) {
    CAPTURE(int(method));
    CAPTURE(int(strategy));
    sc::FrameParams fp{RefitMode::kPivotFrame, method, strategy, true};
    REQUIRE(fp.margin < 0.0f);
    const sc::HostResults per_asset = RunCompared(assets, inst, batch, fp);  // per instance: DetectJob, margin -1
    for (int k = 0; k < 3; ++k) {
      CAPTURE(k);
      fp.margin = own[k];
      const sc::HostResults fixed = RunCompared(assets, inst, batch, fp);  // every instance with margin own[k]
      for (size_t i = static_cast<size_t>(k); i < inst.table.size(); i += 3)
        CHECK(per_asset.instance_counts[i] == fixed.instance_counts[i]);
    }
  }
}

// The MakeHuman asset (a fresh bake is schema v2 with a contact margin) on randomised instances, in
// one batch with a synthetic asset of another margin: the default, 0 and 2x the asset's, CPU == GPU.
TEST_CASE("cuda: FrameParams::margin on the MakeHuman asset mixed with a synthetic one, CPU == GPU") {
  if (!RequireDevice()) return;
  const std::string asset_path = MakeHumanAssetPath();
  const std::string obj = test::SharedData("makehuman/base.obj");
  if (!test::Require(asset_path) || !test::Require(obj)) {
    MESSAGE("SKIPPED: bake it with `spherechain bake " << obj << " -o " << asset_path << "` (or set SPHERECHAIN_MH_ASSET)");
    return;
  }
  AssetSet mh, star;
  LoadFile(&mh, asset_path);
  mh.mesh.positions = test::ObjPositions(obj, mh.view.vertex_count);
  if (mh.mesh.positions.empty()) {
    MESSAGE("SKIPPED: base.obj vertices do not match the asset's vertex_count " << mh.view.vertex_count);
    return;
  }
  const float own = mh.device.contact_margin();
  MESSAGE(asset_path << ": contact margin " << own << (own > 0.0f ? "" : " (schema v1 or margin 0: re-bake to test it)"));
  const float unit = own > 0.0f ? own : 0.02f * MeanBindRadius(mh);
  MakeStar(&star, 6, 12, 0.1f);
  const std::vector<AssetSet*> assets = {&mh, &star};
  DeviceInstances inst;
  inst.Build(assets, 64, 77u);  // even instances MakeHuman, odd ones the star
  inst.host[0] = mh.mesh.positions;  // instance 0 at rest
  inst.Upload();
  const sc::DeviceAsset* dev[] = {&mh.device, &star.device};
  sc::Batch batch;
  REQUIRE(batch.Init(dev, 2, inst.table.data(), static_cast<uint32_t>(inst.table.size())) == sc::Status::kOk);
  for (const auto& [method, strategy] : MethodStrategies()) {
    for (float margin : {-1.0f, 0.0f, 2.0f * unit}) {
      CAPTURE(int(method));
      CAPTURE(int(strategy));
      CAPTURE(margin);
      sc::FrameParams fp{RefitMode::kPivotFrame, method, strategy, true};
      fp.margin = margin;
      (void)RunCompared(assets, inst, batch, fp);  // per instance: DetectJob with the same fp.margin
    }
  }
}

TEST_CASE("cuda: FrameParams::margin NaN or infinite gives kErrorInvalidJob and enqueues nothing") {
  if (!RequireDevice()) return;
  AssetSet star;
  MakeStar(&star, 4, 8);
  DeviceInstances inst;
  inst.Build({&star}, 8, 11u, /*rest=*/true);
  const sc::DeviceAsset* dev[] = {&star.device};
  sc::Batch batch;
  REQUIRE(batch.Init(dev, 1, inst.table.data(), 8) == sc::Status::kOk);
  sc::FrameParams fp{RefitMode::kPivotFrame, DetectMethod::kM2, sc::Strategy::kAuto, false};
  fp.margin = 0.5f * MeanBindRadius(star);
  REQUIRE(batch.Run(fp, 0) == sc::Status::kOk);
  sc::HostResults before;
  REQUIRE(batch.Download(0, &before) == sc::Status::kOk);
  REQUIRE(before.total > 0);
  for (float bad : {std::nanf(""), std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()})
    for (DetectMethod method : {DetectMethod::kM1, DetectMethod::kM2})
      for (sc::Strategy strategy : {sc::Strategy::kAuto, sc::Strategy::kThreadPerSphere, sc::Strategy::kWarpPerInstance,
                                    sc::Strategy::kBlockBoxes}) {
        CAPTURE(bad);
        sc::FrameParams b{RefitMode::kPivotFrame, method, strategy, false};
        b.margin = bad;
        CHECK(batch.Run(b, 0) == sc::Status::kErrorInvalidJob);
      }
  // Nothing was enqueued: the counters still hold the valid frame's (Run zeroes them first otherwise).
  sc::HostResults after;
  REQUIRE(batch.Download(0, &after) == sc::Status::kOk);
  CHECK(after.total == before.total);
  CHECK(after.instance_counts == before.instance_counts);
  // The CPU job agrees on the same margins.
  uint32_t n = 0;
  runtime::DetectJob det;
  det.model = &star.model;
  det.workspace = &star.ws;
  det.count = &n;
  det.margin = std::nanf("");
  CHECK(det.Run() == runtime::Status::kErrorInvalidJob);
  // An uninitialised batch reports kErrorInvalidJob whatever the margin.
  sc::Batch empty;
  CHECK(empty.Run(fp, 0) == sc::Status::kErrorInvalidJob);
}
