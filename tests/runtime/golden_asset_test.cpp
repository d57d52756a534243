// Golden assets, one per schema version (tests/data/golden/v<N>/): what an SDK once baked must keep
// loading — or be refused with the version status — when the schema or the loader changes.
#include <doctest/doctest.h>

#include <filesystem>

#include <cstring>
#include <vector>

#include "runtime/asset_builder.h"
#include "spherechain/runtime/runtime.h"
#include "test_data.h"

using namespace spherechain::runtime;

namespace {

/// The file's bytes, 8-byte aligned (test::ReadAlignedFile), and their size (0 when unreadable).
std::vector<uint64_t> ReadAligned(const std::string& path, size_t* size) {
  spherechain::test::AlignedBytes bytes;
  spherechain::test::ReadAlignedFile(path, &bytes);
  *size = bytes.size;
  return std::move(bytes.storage);
}

/// Pairs M2 reports on the context's current spheres with the given margin (−1: the asset's).
uint32_t CountM2(const AssetView& view, spherechain::test::Character& ctx, float margin = -1.0f) {
  std::vector<Collision> out(DetectBound(view, DetectMethod::kM2));
  uint32_t count = 99;
  DetectJob job;
  job.model = &ctx.model;
  job.workspace = &ctx.ws;
  job.method = DetectMethod::kM2;
  job.margin = margin;
  job.output = out.data();
  job.capacity = static_cast<uint32_t>(out.size());
  job.count = &count;
  REQUIRE(job.Run() == Status::kOk);
  return count;
}

}  // namespace

TEST_CASE("golden v1 asset (CesiumMan, baked by spherechain 0.1.0) loads with its counts and runs") {
  const std::string path = spherechain::test::SourceFile("tests/data/golden/v1/cesium_man.sphc");
  REQUIRE_MESSAGE(std::filesystem::exists(path), "the golden asset is part of the repository");
  size_t size = 0;
  std::vector<uint64_t> bytes = ReadAligned(path, &size);
  AssetView view;
  REQUIRE(LoadAsset(bytes.data(), size, &view) == Status::kOk);
  CHECK(view.asset->schema_version() == 1);
  CHECK(view.vertex_count == 3273);   // CesiumMan.gltf as imported
  CHECK(view.triangle_count == 4672);
  CHECK(view.sphere_count == 101);
  CHECK(view.chain_count == 6);
  spherechain::test::Character ctx;
  REQUIRE(ctx.Init(view) == Status::kOk);
  // v1 has no contact margin: read as 0. At the bind pose (spheres as baked) nothing collides.
  CHECK(ctx.model.contact_margin() == 0.0f);
  CHECK(CountM2(view, ctx) == 0);

  // The same bytes stamped with another schema version are refused with the version status.
  std::vector<uint64_t> other = bytes;
  const auto* root = view.asset;
  const uint8_t* base = reinterpret_cast<const uint8_t*>(bytes.data());
  const auto* field = reinterpret_cast<const flatbuffers::Table*>(root)->GetAddressOf(
      spherechain::schema::Asset::VT_SCHEMA_VERSION);
  REQUIRE(field != nullptr);
  const size_t offset = static_cast<size_t>(field - base);
  uint32_t v = kSchemaVersion + 1;
  std::memcpy(reinterpret_cast<uint8_t*>(other.data()) + offset, &v, 4);
  AssetView newer;
  CHECK(LoadAsset(other.data(), size, &newer) == Status::kErrorVersionTooNew);
  v = kMinSchemaVersion - 1;
  std::memcpy(reinterpret_cast<uint8_t*>(other.data()) + offset, &v, 4);
  CHECK(LoadAsset(other.data(), size, &newer) == Status::kErrorVersionTooOld);
}

TEST_CASE("golden v2 asset (CesiumMan, cover fit, baked by spherechain 0.2.0) loads with its margin and coverage") {
  const std::string path = spherechain::test::SourceFile("tests/data/golden/v2/cesium_man.sphc");
  REQUIRE_MESSAGE(std::filesystem::exists(path), "the golden asset is part of the repository");
  size_t size = 0;
  std::vector<uint64_t> bytes = ReadAligned(path, &size);
  AssetView view;
  REQUIRE(LoadAsset(bytes.data(), size, &view) == Status::kOk);
  CHECK(view.asset->schema_version() == 2);
  CHECK(view.vertex_count == 3273);
  CHECK(view.triangle_count == 4672);
  CHECK(view.sphere_count == 128);
  CHECK(view.chain_count == 6);
  // The v2 fields: the fit, the contact margin (0.4 % of CesiumMan's 1.507 m), the bind coverage.
  REQUIRE(view.asset->fit_method() != nullptr);
  CHECK(view.asset->fit_method()->str() == "cover");
  CHECK(view.asset->contact_margin() == doctest::Approx(0.004 * 1.507).epsilon(0.01));
  REQUIRE(view.asset->coverage() != nullptr);
  CHECK(view.asset->coverage()->coverage() > 0.85f);
  CHECK(view.asset->coverage()->protrusion() < 0.05f);
  spherechain::test::Character ctx;
  REQUIRE(ctx.Init(view) == Status::kOk);
  CHECK(ctx.model.contact_margin() == view.asset->contact_margin());
  // Bind pose, grown by the asset's margin: quiet (pairs within two margins are excluded at bake).
  CHECK(CountM2(view, ctx) == 0);
  // A margin of 5 % of the height makes non-excluded bind neighbours touch: the override is honoured.
  CHECK(CountM2(view, ctx, 0.05f * 1.507f) > 0);
}

TEST_CASE("golden v3 asset (CesiumMan, cover fit, joint weights, baked by spherechain 0.2.0) refits from joints") {
  const std::string path = spherechain::test::SourceFile("tests/data/golden/v3/cesium_man.sphc");
  REQUIRE_MESSAGE(std::filesystem::exists(path), "the golden asset is part of the repository");
  size_t size = 0;
  std::vector<uint64_t> bytes = ReadAligned(path, &size);
  AssetView view;
  REQUIRE(LoadAsset(bytes.data(), size, &view) == Status::kOk);
  CHECK(view.asset->schema_version() == 3);
  CHECK(view.vertex_count == 3273);
  CHECK(view.sphere_count == 128);
  // The v3 fields: CesiumMan's skin has 19 joints; four influences per sphere.
  CHECK(view.asset->joint_count() == 19);
  REQUIRE(view.asset->sphere_joints() != nullptr);
  CHECK(view.asset->sphere_joints()->size() == 4 * 128);
  spherechain::test::Character ctx;
  REQUIRE(ctx.Init(view) == Status::kOk);
  // Identity skinning matrices are the bind pose: the spheres come back as baked, and nothing collides.
  std::vector<float> identity(19 * kJointMatrixFloats, 0.0f);
  for (int j = 0; j < 19; ++j)
    for (int d = 0; d < 3; ++d) identity[12 * j + 5 * d] = 1.0f;
  JointRefitJob job;
  job.model = &ctx.model;
  job.workspace = &ctx.ws;
  job.joint_matrices = identity.data();
  job.joint_count = 19;
  REQUIRE(job.Run() == Status::kOk);
  const SphereArrays sp = ctx.ws.spheres();
  for (uint32_t s = 0; s < sp.count; ++s) {
    const auto* b = view.asset->spheres()->Get(s);
    CHECK(sp.x[s] == doctest::Approx(b->center().x()).epsilon(1e-5));
    CHECK(sp.z[s] == doctest::Approx(b->center().z()).epsilon(1e-5));
    CHECK(sp.r[s] == b->radius());
  }
  CHECK(CountM2(view, ctx) == 0);

  // The v2 golden asset has no joint weights: the joint refit says so (re-bake), the vertex refit works.
  const std::string v2 = spherechain::test::SourceFile("tests/data/golden/v2/cesium_man.sphc");
  size_t size2 = 0;
  std::vector<uint64_t> bytes2 = ReadAligned(v2, &size2);
  AssetView view2;
  REQUIRE(LoadAsset(bytes2.data(), size2, &view2) == Status::kOk);
  spherechain::test::Character ctx2;
  REQUIRE(ctx2.Init(view2) == Status::kOk);
  job.model = &ctx2.model;
  job.workspace = &ctx2.ws;
  CHECK(job.Run() == Status::kErrorMissingField);
}

TEST_CASE("golden v4 asset (the synthetic creature, any-skeleton path) names its regions, which v3 readers refuse") {
  // tests/data/creature/creature.gltf baked by `spherechain bake` (default configuration): five limbs and
  // a trunk in Asset.regions, 15 chains pairing them.
  const std::string path = spherechain::test::SourceFile("tests/data/golden/v4/creature.sphc");
  REQUIRE_MESSAGE(std::filesystem::exists(path), "the golden asset is part of the repository");
  size_t size = 0;
  std::vector<uint64_t> bytes = ReadAligned(path, &size);
  AssetView view;
  REQUIRE(LoadAsset(bytes.data(), size, &view) == Status::kOk);
  CHECK(view.asset->schema_version() == 4);
  CHECK(view.triangle_count == 1504);
  CHECK(view.chain_count == 15);
  REQUIRE(RegionCount(view) == 6);
  const char* names[6] = {"Tail", "HindLeg_L", "HindLeg_R", "ForeLeg_L", "ForeLeg_R", "trunk"};
  for (uint32_t r = 0; r < 6; ++r) CHECK(std::string(RegionName(view, r)) == names[r]);
  CHECK(IsTrunkRegion(view, 5));
  CHECK(view.asset->regions()->Get(3)->mirror() == 4);
  // Region values stay within the table (LoadAsset checked it): every region owns spheres.
  std::vector<int> spheres(6, 0);
  for (uint8_t r : *view.asset->sphere_regions()) ++spheres.at(r);
  for (int n : spheres) CHECK(n > 0);
  // The joint refit at bind pose (identity matrices; the creature's skin has 13 joints): nothing collides.
  spherechain::test::Character ctx;
  REQUIRE(ctx.Init(view) == Status::kOk);
  REQUIRE(view.asset->joint_count() == 13);
  std::vector<float> identity(13 * kJointMatrixFloats, 0.0f);
  for (int j = 0; j < 13; ++j)
    for (int d = 0; d < 3; ++d) identity[12 * j + 5 * d] = 1.0f;
  JointRefitJob job;
  job.model = &ctx.model;
  job.workspace = &ctx.ws;
  job.joint_matrices = identity.data();
  job.joint_count = 13;
  REQUIRE(job.Run() == Status::kOk);
  CHECK(CountM2(view, ctx) == 0);
  // This SDK reads v1..v4; a v3 SDK's kSchemaVersion was 3, so it answers kErrorVersionTooNew for this
  // asset (what LoadAsset answers here for a version past kSchemaVersion):
  CHECK(kSchemaVersion == 4);
  CHECK(kPaperSchemaVersion == 3);
}
