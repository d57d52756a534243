// spherechain::cuda — the fold margin (Asset.fold_margin, FrameParams::fold_margin): pairs of two spheres of
// one region tested with it, pairs of two regions with the contact margin, CPU == GPU against DetectJob with
// the same margins (every strategy and method) on synthetic assets whose fold margin lies below and above the
// contact margin, in a batch mixed with an asset without one; the frame's own fold margin; NaN / inf and a
// fold margin on a batch with an asset without one rejected. Every test SKIPs visibly without a CUDA device.
#include "cuda/batch_fixture.h"

#include <limits>

using namespace spherechain;
using namespace spherechain::runtime;
using namespace spherechain::test;
namespace sc = spherechain::cuda;

namespace {

/// CPU pairs of one instance, as a set, with the asset's margins or a fold margin of the job's own.
std::set<std::pair<int, int>> CpuPairs(AssetSet& a, const std::vector<float>& positions, DetectMethod method,
                                       float fold_margin) {
  const CpuFrame f = CpuReference(a.model, a.ws, a.view, positions.data(), 12, RefitMode::kPivotFrame, method, -1.0f,
                                  fold_margin);
  std::set<std::pair<int, int>> out;
  for (const runtime::Collision& c : f.pairs) out.insert({c.a, c.b});
  return out;
}

}  // namespace

// Three stars of the same tubes: contact margin 0.2 r̄, fold margin 0 (below), 0.6 r̄ (above), and none. With
// the asset's margins (FrameParams defaults) every instance must match DetectJob; the fold margin must
// change the pair set on the CPU (else the comparison would not see a kernel that ignored it).
TEST_CASE("cuda: Asset.fold_margin below and above the contact margin, mixed batch, CPU == GPU (all strategies)") {
  if (!RequireDevice()) return;
  AssetSet probe;
  MakeStar(&probe, 6, 12);
  const float r = MeanBindRadius(probe), contact = 0.2f * r;
  AssetSet below, above, none;
  MakeStar(&below, 6, 12, contact, 0.0f);
  MakeStar(&above, 6, 12, contact, 0.6f * r);
  MakeStar(&none, 6, 12, contact);
  REQUIRE(below.device.fold_margin() == 0.0f);
  REQUIRE(above.device.fold_margin() == 0.6f * r);
  REQUIRE(none.device.fold_margin() < 0.0f);
  const std::vector<AssetSet*> assets = {&below, &above, &none};
  DeviceInstances inst;
  inst.Build(assets, 96, 1357u);  // instance i of asset i % 3
  // The fold margin matters on these instances: summed over them, the pair sets differ from the contact
  // margin's (DetectJob with fold_margin = contact is the asset tested with one margin).
  size_t differ_below = 0, differ_above = 0;
  for (size_t i = 0; i < inst.host.size(); i += 3) {
    differ_below += CpuPairs(below, inst.host[i], DetectMethod::kM2, -1.0f) !=
                    CpuPairs(below, inst.host[i], DetectMethod::kM2, contact);
    differ_above += CpuPairs(above, inst.host[i + 1], DetectMethod::kM2, -1.0f) !=
                    CpuPairs(above, inst.host[i + 1], DetectMethod::kM2, contact);
  }
  MESSAGE("instances whose pairs the fold margin changes: below " << differ_below << ", above " << differ_above);
  REQUIRE(differ_below > 0);
  REQUIRE(differ_above > 0);

  const sc::DeviceAsset* dev[] = {&below.device, &above.device, &none.device};
  sc::Batch batch;
  REQUIRE(batch.Init(dev, 3, inst.table.data(), static_cast<uint32_t>(inst.table.size())) == sc::Status::kOk);
  for (const auto& [method, strategy] : MethodStrategies()) {
    CAPTURE(int(method));
    CAPTURE(int(strategy));
    const sc::FrameParams fp{RefitMode::kPivotFrame, method, strategy, true};
    REQUIRE(fp.fold_margin < 0.0f);
    (void)RunCompared(assets, inst, batch, fp);  // per instance: DetectJob with its asset's margins
  }
}

// FrameParams::fold_margin >= 0 replaces every asset's (as DetectJob::fold_margin), on a batch whose assets
// all have one; a larger fold margin never loses a pair.
TEST_CASE("cuda: FrameParams::fold_margin overrides the assets', CPU == GPU") {
  if (!RequireDevice()) return;
  AssetSet probe;
  MakeStar(&probe, 6, 12);
  const float r = MeanBindRadius(probe);
  AssetSet a, b;
  MakeStar(&a, 6, 12, 0.2f * r, 0.1f * r);
  MakeStar(&b, 5, 10, 0.1f * r, 0.0f);
  const std::vector<AssetSet*> assets = {&a, &b};
  DeviceInstances inst;
  inst.Build(assets, 64, 97531u);
  const sc::DeviceAsset* dev[] = {&a.device, &b.device};
  sc::Batch batch;
  REQUIRE(batch.Init(dev, 2, inst.table.data(), static_cast<uint32_t>(inst.table.size())) == sc::Status::kOk);
  for (const auto& [method, strategy] : MethodStrategies()) {
    uint32_t previous = 0;
    for (float fold : {0.0f, 0.3f * r, 0.9f * r}) {
      CAPTURE(int(method));
      CAPTURE(int(strategy));
      CAPTURE(fold);
      sc::FrameParams fp{RefitMode::kPivotFrame, method, strategy, true};
      fp.fold_margin = fold;
      const sc::HostResults res = RunCompared(assets, inst, batch, fp);
      CHECK(res.total >= previous);
      previous = res.total;
    }
  }
}

TEST_CASE("cuda: FrameParams::fold_margin NaN, infinite, or on an asset without one gives kErrorInvalidJob") {
  if (!RequireDevice()) return;
  AssetSet with, without;
  MakeStar(&with, 4, 8, 0.0f, 0.0f);
  MakeStar(&without, 4, 8);
  DeviceInstances inst;
  inst.Build({&with, &without}, 8, 5u, /*rest=*/true);
  const sc::DeviceAsset* dev[] = {&with.device, &without.device};
  sc::Batch mixed, alone;
  REQUIRE(mixed.Init(dev, 2, inst.table.data(), 8) == sc::Status::kOk);
  DeviceInstances only;
  only.Build({&with}, 4, 5u, /*rest=*/true);
  REQUIRE(alone.Init(dev, 1, only.table.data(), 4) == sc::Status::kOk);
  for (DetectMethod method : {DetectMethod::kM1, DetectMethod::kM2}) {
    sc::FrameParams fp{RefitMode::kPivotFrame, method, sc::Strategy::kAuto, false};
    CHECK(mixed.Run(fp, 0) == sc::Status::kOk);  // each asset's own (none for `without`)
    fp.fold_margin = 0.0f;
    CHECK(alone.Run(fp, 0) == sc::Status::kOk);
    CHECK(mixed.Run(fp, 0) == sc::Status::kErrorInvalidJob);  // `without` has no regions to tell pairs apart
    for (float bad : {std::nanf(""), std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()}) {
      fp.fold_margin = bad;
      CHECK(alone.Run(fp, 0) == sc::Status::kErrorInvalidJob);
    }
  }
  // The CPU job agrees.
  uint32_t n = 0;
  runtime::DetectJob det;
  det.model = &without.model;
  det.workspace = &without.ws;
  det.count = &n;
  det.fold_margin = 0.0f;
  CHECK(det.Run() == runtime::Status::kErrorInvalidJob);
}
