// LoadAsset: envelope, verification and semantic checks (runtime/include/spherechain/runtime/asset.h).
#include <doctest/doctest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include "runtime/asset_builder.h"
#include "test_data.h"

using namespace spherechain;
using namespace spherechain::runtime;
using spherechain::test::AlignedBytes;

namespace {

Status Load(const test::AssetData& d, AssetView* view) {
  static AlignedBytes keep;  // the view borrows the bytes
  keep = test::Serialize(d);
  return LoadAsset(keep.data(), keep.size, view);
}

test::AssetData Valid(test::Mesh* mesh) { return test::TwoTubes(true, mesh); }

}  // namespace

TEST_CASE("LoadAsset accepts a valid synthetic asset and exposes its counts") {
  test::Mesh mesh;
  const test::AssetData d = Valid(&mesh);
  AssetView view;
  REQUIRE(Load(d, &view) == Status::kOk);
  CHECK(view.valid());
  CHECK(view.sphere_count == 16);
  CHECK(view.vertex_count == mesh.vertex_count());
  CHECK(view.triangle_count == mesh.triangle_count());
  CHECK(view.chain_count == 3);
  const TriangleSpan region = SurroundingTriangles(view, 2);
  REQUIRE(region.count == 16);
  CHECK(region.data[0] == 2 * 16);
  CHECK(SurroundingTriangles(view, 7).count == 0);  // last ring of tube A owns no segment
  CHECK(PivotTriangles(view, 0).count == 4);
}

TEST_CASE("LoadAsset: every truncated prefix is an error, never a crash") {
  test::Mesh mesh;
  const AlignedBytes full = test::Serialize(Valid(&mesh));
  for (size_t n = 0; n < full.size; ++n) {
    AlignedBytes prefix;
    prefix.assign(full.data(), n);
    AssetView view;
    const Status s = LoadAsset(n ? prefix.data() : full.data(), n, &view);
    CAPTURE(n);
    REQUIRE(Failed(s));
    REQUIRE(!view.valid());
  }
}

TEST_CASE("LoadAsset: single bit flips never crash and a success is still semantically valid") {
  test::Mesh mesh;
  const AlignedBytes full = test::Serialize(Valid(&mesh));
  uint32_t rejected = 0;
  for (size_t i = 0; i < full.size; i += 3) {
    AlignedBytes copy = full;
    copy.data()[i] ^= uint8_t(1u << (i % 8));
    AssetView view;
    if (Failed(LoadAsset(copy.data(), copy.size, &view))) {
      ++rejected;
      continue;
    }
    test::Character ctx;  // a flipped-but-valid asset must still be usable safely
    REQUIRE(ctx.Init(view) == Status::kOk);
  }
  CHECK(rejected > 0);
}

TEST_CASE("LoadAsset: envelope errors") {
  test::Mesh mesh;
  test::AssetData d = Valid(&mesh);
  AssetView view;
  AlignedBytes ok = test::Serialize(d);
  CHECK(LoadAsset(nullptr, ok.size, &view) == Status::kErrorNullArgument);
  CHECK(LoadAsset(ok.data(), ok.size, nullptr) == Status::kErrorNullArgument);
  CHECK(LoadAsset(ok.data() + 4, ok.size - 8, &view) == Status::kErrorAlignment);
  CHECK(LoadAsset(ok.data(), 7, &view) == Status::kErrorAssetTooSmall);
  CHECK(LoadAsset(ok.data(), kMaxAssetBytes + 1, &view) == Status::kErrorAssetTooLarge);

  test::AssetData wrong_id = d;
  wrong_id.identifier = "GLTF";
  CHECK(Load(wrong_id, &view) == Status::kErrorIdentifier);

  test::AssetData old_v = d;
  old_v.schema_version = 0;
  CHECK(Load(old_v, &view) == Status::kErrorVersionTooOld);
  test::AssetData new_v = d;
  new_v.schema_version = kSchemaVersion + 1;
  CHECK(Load(new_v, &view) == Status::kErrorVersionTooNew);
  CHECK(std::string(ToString(Status::kErrorVersionTooNew)).find("newer") != std::string::npos);
}

TEST_CASE("LoadAsset: semantic errors each give their status") {
  test::Mesh mesh;
  const test::AssetData base = Valid(&mesh);
  AssetView view;
  auto expect = [&](auto mutate, Status want) {
    test::AssetData d = base;
    mutate(d);
    const Status got = Load(d, &view);
    CHECK_MESSAGE(got == want, ToString(got));
    CHECK(!view.valid());
  };
  expect([](test::AssetData& d) { d.pivot_vertices[5] = d.vertex_count; }, Status::kErrorIndexOutOfRange);
  expect([](test::AssetData& d) { d.pivot_triangles[1] = d.triangle_count; }, Status::kErrorIndexOutOfRange);
  expect([](test::AssetData& d) { d.surrounding_triangles[0] = d.triangle_count + 7; }, Status::kErrorIndexOutOfRange);
  expect([](test::AssetData& d) { d.chains[1].push_back(16); }, Status::kErrorIndexOutOfRange);
  expect([](test::AssetData& d) { d.triangle_spheres[0] = 99; }, Status::kErrorIndexOutOfRange);
  expect([](test::AssetData& d) { d.excluded.push_back(schema::SpherePair(15, 16)); }, Status::kErrorIndexOutOfRange);
  expect([](test::AssetData& d) {
    d.spheres[3] = schema::Sphere(d.spheres[3].center(), std::numeric_limits<float>::quiet_NaN());
  }, Status::kErrorNonFinite);
  expect([](test::AssetData& d) {
    d.spheres[3] = schema::Sphere(schema::Vec3(INFINITY, 0, 0), 1.0f);
  }, Status::kErrorNonFinite);
  expect([](test::AssetData& d) { d.spheres[3] = schema::Sphere(d.spheres[3].center(), 0.0f); }, Status::kErrorRadius);
  expect([](test::AssetData& d) { d.spheres[3] = schema::Sphere(d.spheres[3].center(), -1.0f); }, Status::kErrorRadius);
  expect([](test::AssetData& d) {
    d.frames[2] = schema::PivotFrame(d.frames[2].local_center(), d.frames[2].centroid_offset(), 0.0f);
  }, Status::kErrorPivotFrame);
  // So small that the refit's radius scale (radius / mean distance) is infinite.
  expect([](test::AssetData& d) {
    d.frames[2] = schema::PivotFrame(d.frames[2].local_center(), d.frames[2].centroid_offset(), 1e-39f);
  }, Status::kErrorPivotFrame);
  // A NaN margin would make every overlap test false (no pair ever reported): refused, as is < 0.
  expect([](test::AssetData& d) { d.contact_margin = std::numeric_limits<float>::quiet_NaN(); }, Status::kErrorNonFinite);
  expect([](test::AssetData& d) { d.contact_margin = INFINITY; }, Status::kErrorNonFinite);
  expect([](test::AssetData& d) { d.contact_margin = -0.01f; }, Status::kErrorContactMargin);
  // The fold margin (optional): finite, and tested per region pair, so only with the spheres' regions; a
  // negative one means none (what assets without the field hold).
  expect([](test::AssetData& d) { d.fold_margin = std::numeric_limits<float>::quiet_NaN(); }, Status::kErrorNonFinite);
  expect([](test::AssetData& d) { d.fold_margin = 0.01f; }, Status::kErrorMissingField);
  for (float fold : {0.01f, -2.0f}) {
    test::AssetData d = base;
    d.fold_margin = fold;
    if (fold >= 0.0f) d.sphere_regions.assign(d.spheres.size(), 1);
    CHECK(Load(d, &view) == Status::kOk);
    CHECK(view.valid());
  }
  // Joint weights (schema v3): four influences per sphere, indices < joint_count, weights a partition of 1.
  auto with_joints = [](test::AssetData& d) {
    d.joint_count = 3;
    for (size_t i = 0; i < d.spheres.size(); ++i) {
      d.sphere_joints.insert(d.sphere_joints.end(), {uint16_t(i % 3), uint16_t((i + 1) % 3), 0, 0});
      d.sphere_joint_weights.insert(d.sphere_joint_weights.end(), {0.75f, 0.25f, 0.0f, 0.0f});
    }
  };
  expect([&](test::AssetData& d) { with_joints(d); d.sphere_joints[5] = 3; }, Status::kErrorIndexOutOfRange);
  expect([&](test::AssetData& d) { with_joints(d); d.joint_count = 0; }, Status::kErrorIndexOutOfRange);
  expect([&](test::AssetData& d) { with_joints(d); d.sphere_joint_weights[4] = NAN; }, Status::kErrorSkinWeights);
  expect([&](test::AssetData& d) { with_joints(d); d.sphere_joint_weights[4] = INFINITY; }, Status::kErrorSkinWeights);
  expect([&](test::AssetData& d) {
    with_joints(d);
    d.sphere_joint_weights[4] = 1.25f;  // sums to 1 with the negative weight beside it
    d.sphere_joint_weights[5] = -0.25f;
  }, Status::kErrorSkinWeights);
  expect([&](test::AssetData& d) { with_joints(d); d.sphere_joint_weights[9] = 0.2f; }, Status::kErrorSkinWeights);
  // A weight after a 0: the refit's blend ends at the first 0, so (0.5, 0, 0.5, 0) would follow half a joint
  // and (0, 1, 0, 0) none. Out of order without a 0 between is blended whole: accepted.
  expect([&](test::AssetData& d) {
    with_joints(d);
    d.sphere_joint_weights[4] = 0.5f, d.sphere_joint_weights[5] = 0.0f, d.sphere_joint_weights[6] = 0.5f;
  }, Status::kErrorSkinWeights);
  expect([&](test::AssetData& d) { with_joints(d); d.sphere_joint_weights[4] = 0.0f, d.sphere_joint_weights[5] = 1.0f; },
         Status::kErrorSkinWeights);
  {
    test::AssetData d = base;
    with_joints(d);
    std::swap(d.sphere_joint_weights[4], d.sphere_joint_weights[5]);  // (0.25, 0.75, 0, 0)
    CHECK(Load(d, &view) == Status::kOk);
  }
  // Joint indices are uint16: a joint_count past 65,536 would only ask for memory and time.
  expect([&](test::AssetData& d) { with_joints(d); d.joint_count = kMaxJoints + 1; }, Status::kErrorIndexOutOfRange);
  {
    test::AssetData d = base;
    with_joints(d);
    d.joint_count = kMaxJoints;
    CHECK(Load(d, &view) == Status::kOk);
  }
  expect([&](test::AssetData& d) { with_joints(d); d.sphere_joints.resize(d.sphere_joints.size() - 4); },
         Status::kErrorCountMismatch);
  expect([&](test::AssetData& d) { with_joints(d); d.sphere_joint_weights.clear(); }, Status::kErrorMissingField);
  // Skin weights per vertex (schema v4, with the crease rule): one count a vertex, as many joints and weights as
  // they add up to, joints < joint_count, each vertex's rounded weights summing to 255 within half its count.
  auto with_skin = [&](test::AssetData& d) {
    with_joints(d);
    d.bind_positions = mesh.positions;
    d.crease = 0.5f;
    for (uint32_t v = 0; v < d.vertex_count; ++v) {
      d.skin_counts.push_back(2);
      d.skin_joints.insert(d.skin_joints.end(), {uint16_t(v % 3), uint16_t((v + 1) % 3)});
      d.skin_weights.insert(d.skin_weights.end(), {200, 55});
    }
  };
  {
    test::AssetData d = base;
    with_skin(d);
    CHECK(Load(d, &view) == Status::kOk);
    d.skin_weights[1] = 56;  // 256 for two influences: within one of 255
    CHECK(Load(d, &view) == Status::kOk);
  }
  expect([&](test::AssetData& d) { with_skin(d); d.skin_weights[1] = 57; }, Status::kErrorSkinWeights);
  expect([&](test::AssetData& d) { with_skin(d); d.skin_joints[3] = 3; }, Status::kErrorIndexOutOfRange);
  expect([&](test::AssetData& d) { with_skin(d); d.skin_counts[0] = 3; }, Status::kErrorCountMismatch);
  expect([&](test::AssetData& d) { with_skin(d); d.skin_counts.pop_back(); }, Status::kErrorCountMismatch);
  expect([&](test::AssetData& d) { with_skin(d); d.skin_weights.clear(); }, Status::kErrorMissingField);
  expect([&](test::AssetData& d) { with_skin(d); d.crease = -1.0f, d.bind_positions.clear(); }, Status::kErrorCountMismatch);
  {
    test::AssetData d = base;
    with_joints(d);
    REQUIRE(Load(d, &view) == Status::kOk);
    CHECK(view.asset->joint_count() == 3);
    CHECK(view.asset->sphere_joints()->size() == 4 * d.spheres.size());
  }
  expect([](test::AssetData& d) { d.frames.pop_back(); }, Status::kErrorCountMismatch);
  expect([](test::AssetData& d) { d.pivot_vertices.pop_back(); }, Status::kErrorCountMismatch);
  expect([](test::AssetData& d) { d.triangle_spheres.pop_back(); }, Status::kErrorCountMismatch);
  expect([](test::AssetData& d) { d.surrounding_offsets.pop_back(); }, Status::kErrorCountMismatch);
  expect([](test::AssetData& d) { std::swap(d.surrounding_offsets[2], d.surrounding_offsets[3]); }, Status::kErrorOffsets);
  expect([](test::AssetData& d) { d.surrounding_offsets.back() += 1; }, Status::kErrorOffsets);
  // Reach regions (optional, both arrays or neither): the surrounding regions plus sphere 0 reaching the
  // first triangle of sphere 1's region.
  auto with_reach = [](test::AssetData& d) {
    d.reach_offsets = {0};
    for (size_t s = 0; s + 1 < d.surrounding_offsets.size(); ++s) {
      std::vector<uint32_t> list(d.surrounding_triangles.begin() + d.surrounding_offsets[s],
                                 d.surrounding_triangles.begin() + d.surrounding_offsets[s + 1]);
      if (s == 0) list.push_back(d.surrounding_triangles[d.surrounding_offsets[1]]);
      std::sort(list.begin(), list.end());
      d.reach_triangles.insert(d.reach_triangles.end(), list.begin(), list.end());
      d.reach_offsets.push_back(uint32_t(d.reach_triangles.size()));
    }
  };
  {
    test::AssetData d = base;
    with_reach(d);
    REQUIRE(Load(d, &view) == Status::kOk);
    const TriangleSpan r0 = ReachTriangles(view, 0), s0 = SurroundingTriangles(view, 0);
    CHECK(r0.count == s0.count + 1);
    CHECK(ReachTriangles(view, 1).count == SurroundingTriangles(view, 1).count);
    test::AssetData plain = base;
    REQUIRE(Load(plain, &view) == Status::kOk);  // no reach regions: the surrounding regions stand in
    CHECK(ReachTriangles(view, 0).count == SurroundingTriangles(view, 0).count);
    CHECK(ReachTriangles(view, 0).data == SurroundingTriangles(view, 0).data);
  }
  expect([&](test::AssetData& d) { with_reach(d); d.reach_triangles.clear(); }, Status::kErrorMissingField);
  expect([&](test::AssetData& d) { with_reach(d); d.reach_offsets.pop_back(); }, Status::kErrorCountMismatch);
  expect([&](test::AssetData& d) { with_reach(d); d.reach_offsets.back() += 1; }, Status::kErrorOffsets);
  // An offset far past the end that a later one falls back from (fuzz_load_asset: each sphere's range was
  // walked before the next offset was checked, so sphere 0 read past reach_triangles).
  expect([&](test::AssetData& d) { with_reach(d); d.reach_offsets[1] = 1u << 30; }, Status::kErrorOffsets);
  expect([&](test::AssetData& d) { with_reach(d); std::swap(d.reach_triangles[0], d.reach_triangles[1]); },
         Status::kErrorOffsets);  // not ascending within sphere 0
  expect([&](test::AssetData& d) { with_reach(d); d.reach_triangles[0] = 1u << 30; }, Status::kErrorIndexOutOfRange);
  expect([](test::AssetData& d) { std::swap(d.chains[1][0], d.chains[1][1]); }, Status::kErrorChainOrder);
  expect([](test::AssetData& d) { d.chains[1][1] = d.chains[1][0]; }, Status::kErrorChainOrder);
  expect([](test::AssetData& d) { std::swap(d.excluded[0], d.excluded[1]); }, Status::kErrorExcludedPairs);
  expect([](test::AssetData& d) { d.excluded[0] = schema::SpherePair(1, 0); }, Status::kErrorExcludedPairs);
  expect([](test::AssetData& d) { d.chains.resize(kMaxChains + 1, d.chains[0]); }, Status::kErrorTooManyChains);
  // One chain of 2,100 spheres: 2.2 M candidate pairs > kMaxChainPairs (the M1 workspace would be huge).
  expect([](test::AssetData& d) {
    const uint32_t n = 2100;
    d.spheres.resize(n, d.spheres[0]);
    d.frames.resize(n, d.frames[0]);
    d.pivot_triangles.resize(4 * n, d.pivot_triangles[0]);
    d.pivot_vertices.resize(12 * n, d.pivot_vertices[0]);
    d.surrounding_offsets.resize(n + 1, d.surrounding_offsets.back());
    d.chains = {std::vector<uint16_t>(n)};
    for (uint32_t i = 0; i < n; ++i) d.chains[0][i] = static_cast<uint16_t>(i);
  }, Status::kErrorTooManyChains);
  expect([](test::AssetData& d) {
    d.spheres.clear();
  }, Status::kErrorNoSpheres);
  // Regions (schema v4): 2..kMaxRegions, one Trunk and it the last, every region value below their count.
  auto creature = [](test::AssetData& d) {
    d.regions = {{"Tail", false}, {"Leg_L", false}, {"trunk", true}};
    d.sphere_regions.assign(d.spheres.size(), 2);
    d.sphere_regions[0] = 0;
    d.triangle_regions.assign(d.triangle_spheres.size(), 1);
  };
  {
    test::AssetData d = base;
    creature(d);
    REQUIRE(Load(d, &view) == Status::kOk);
    CHECK(RegionCount(view) == 3);
    CHECK(std::string(RegionName(view, 0)) == "Tail");
    CHECK(std::string(RegionName(view, 2)) == "trunk");
    CHECK(std::string(RegionName(view, 3)).empty());
    CHECK(IsTrunkRegion(view, 2));
    CHECK_FALSE(IsTrunkRegion(view, 1));
  }
  {
    test::AssetData d = base;  // no regions: the paper's five
    REQUIRE(Load(d, &view) == Status::kOk);
    CHECK(RegionCount(view) == 5);
    CHECK(std::string(RegionName(view, 4)) == "torso");
    CHECK(IsTrunkRegion(view, 4));
    d.sphere_regions.assign(d.spheres.size(), 4);
    d.triangle_regions.assign(d.triangle_spheres.size(), 4);
    CHECK(Load(d, &view) == Status::kOk);
  }
  // Without the regions table a value is one of the paper's five (a C caller indexes a table of RegionCount).
  expect([&](test::AssetData& d) { d.sphere_regions.assign(d.spheres.size(), 4); d.sphere_regions[1] = 5; },
         Status::kErrorRegions);
  expect([&](test::AssetData& d) { d.triangle_regions.assign(d.triangle_spheres.size(), 0); d.triangle_regions[0] = 200; },
         Status::kErrorRegions);
  expect([&](test::AssetData& d) { creature(d); d.sphere_regions[1] = 3; }, Status::kErrorRegions);
  expect([&](test::AssetData& d) { creature(d); d.triangle_regions[0] = 7; }, Status::kErrorRegions);
  expect([&](test::AssetData& d) { creature(d); d.regions[2].second = false; }, Status::kErrorRegions);  // no trunk
  expect([&](test::AssetData& d) { creature(d); d.regions[0].second = true; }, Status::kErrorRegions);   // trunk first
  expect([&](test::AssetData& d) { creature(d); d.regions.resize(1); d.sphere_regions.assign(d.spheres.size(), 0);
                                   d.triangle_regions.assign(d.triangle_spheres.size(), 0); d.regions[0].second = true; },
         Status::kErrorRegions);  // one region only
  expect([&](test::AssetData& d) {
    creature(d);
    d.regions.assign(kMaxRegions + 1, {"limb", false});
    d.regions.back().second = true;
  }, Status::kErrorRegions);
}

TEST_CASE("ToString names every status and Succeeded/Failed split them") {
  CHECK(Succeeded(Status::kOk));
  CHECK(Succeeded(Status::kOkTruncated));
  CHECK(IsTruncated(Status::kOkTruncated));
  CHECK(Failed(Status::kErrorCorrupt));
  CHECK(std::string(ToString(static_cast<Status>(0x1234u))) == "unknown status");
  CHECK(std::string(ToString(Status::kErrorVertexCount)).rfind("kErrorVertexCount", 0) == 0);
  // Every status of status.h: its string starts with its own name, and the error bit decides Failed().
  const std::pair<Status, const char*> all[] = {
      {Status::kOk, "kOk"},
      {Status::kOkTruncated, "kOkTruncated"},
      {Status::kErrorNullArgument, "kErrorNullArgument"},
      {Status::kErrorAlignment, "kErrorAlignment"},
      {Status::kErrorInvalidJob, "kErrorInvalidJob"},
      {Status::kErrorVertexCount, "kErrorVertexCount"},
      {Status::kErrorStride, "kErrorStride"},
      {Status::kErrorOutOfMemory, "kErrorOutOfMemory"},
      {Status::kErrorNonFinitePositions, "kErrorNonFinitePositions"},
      {Status::kErrorJointCount, "kErrorJointCount"},
      {Status::kErrorNonFiniteJoints, "kErrorNonFiniteJoints"},
      {Status::kErrorWorkspaceModel, "kErrorWorkspaceModel"},
      {Status::kErrorBufferTooSmall, "kErrorBufferTooSmall"},
      {Status::kErrorFrameTangled, "kErrorFrameTangled"},
      {Status::kErrorAssetTooSmall, "kErrorAssetTooSmall"},
      {Status::kErrorAssetTooLarge, "kErrorAssetTooLarge"},
      {Status::kErrorIdentifier, "kErrorIdentifier"},
      {Status::kErrorVersionTooOld, "kErrorVersionTooOld"},
      {Status::kErrorVersionTooNew, "kErrorVersionTooNew"},
      {Status::kErrorCorrupt, "kErrorCorrupt"},
      {Status::kErrorMissingField, "kErrorMissingField"},
      {Status::kErrorNoSpheres, "kErrorNoSpheres"},
      {Status::kErrorTooManySpheres, "kErrorTooManySpheres"},
      {Status::kErrorTooManyChains, "kErrorTooManyChains"},
      {Status::kErrorCountMismatch, "kErrorCountMismatch"},
      {Status::kErrorIndexOutOfRange, "kErrorIndexOutOfRange"},
      {Status::kErrorOffsets, "kErrorOffsets"},
      {Status::kErrorNonFinite, "kErrorNonFinite"},
      {Status::kErrorRadius, "kErrorRadius"},
      {Status::kErrorPivotFrame, "kErrorPivotFrame"},
      {Status::kErrorChainOrder, "kErrorChainOrder"},
      {Status::kErrorExcludedPairs, "kErrorExcludedPairs"},
      {Status::kErrorContactMargin, "kErrorContactMargin"},
      {Status::kErrorSkinWeights, "kErrorSkinWeights"},
      {Status::kErrorRegions, "kErrorRegions"},
      {Status::kErrorBindPoseTangled, "kErrorBindPoseTangled"},
      {Status::kErrorCreaseTooWide, "kErrorCreaseTooWide"},
  };
  for (const auto& entry : all) {
    const Status status = entry.first;
    const char* const name = entry.second;  // not a structured binding: CAPTURE's lambda takes it (clang 14)
    CAPTURE(name);
    CHECK(std::string(ToString(status)).rfind(name, 0) == 0);
    CHECK(Failed(status) == (std::string(name).rfind("kError", 0) == 0));
  }
  // The list above is status.h's: as many entries as the header has enumerators (`kName = 0x...`), so a
  // status added without a ToString case and an entry here fails.
  std::ifstream header(spherechain::test::SourceFile("runtime/include/spherechain/runtime/status.h"));
  REQUIRE(header.good());
  size_t enumerators = 0;
  for (std::string line; std::getline(header, line);)
    if (line.find(" = 0x") != std::string::npos && line.find("  k") == 0) ++enumerators;
  CHECK(enumerators == std::size(all));
}
