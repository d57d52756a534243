// DescribeAsset (`spherechain inspect`) on an asset LoadAsset accepts without its optional region arrays
// (Asset.sphere_regions, triangle_regions): every region counted 0, instead of reading through a null array.
#include <doctest/doctest.h>

#include "runtime/asset_builder.h"
#include "spherechain/evaluate/inspect.h"

namespace sc = spherechain;
namespace st = spherechain::test;

TEST_CASE("inspect: an asset without sphere_regions and triangle_regions") {
  st::Mesh mesh;
  st::Tube tube;
  st::AssetData d = st::MakeTubes({tube}, {}, &mesh);
  REQUIRE(d.sphere_regions.empty());
  const st::AlignedBytes bytes = st::Serialize(d);
  sc::runtime::AssetView view;
  REQUIRE(sc::runtime::LoadAsset(bytes.data(), bytes.size, &view) == sc::runtime::Status::kOk);
  const nlohmann::json j = sc::evaluate::DescribeAsset(view);
  CHECK(j["spheres"] == d.spheres.size());
  CHECK(j["regions"]["torso"]["spheres"] == 0);
  CHECK(j["regions"]["left_arm"]["triangles"] == 0);
  // With them, the counts are the arrays'.
  d.sphere_regions.assign(d.spheres.size(), 4);
  d.triangle_regions.assign(d.triangle_spheres.size(), 0);
  const st::AlignedBytes with = st::Serialize(d);
  REQUIRE(sc::runtime::LoadAsset(with.data(), with.size, &view) == sc::runtime::Status::kOk);
  const nlohmann::json k = sc::evaluate::DescribeAsset(view);
  CHECK(k["regions"]["torso"]["spheres"] == d.spheres.size());
  CHECK(k["regions"]["left_arm"]["triangles"] == d.triangle_spheres.size());
}

TEST_CASE("inspect: unassigned triangles are counted, not subtracted (a triangle listed twice in the surrounding regions)") {
  // LoadAsset does not require the surrounding regions to partition the triangles; T − (list length) once
  // wrapped round to 4,294,967,286 on such an asset.
  st::Mesh mesh;
  st::Tube tube;
  st::AssetData d = st::MakeTubes({tube}, {}, &mesh);
  const size_t T = mesh.triangle_count();
  REQUIRE(d.surrounding_triangles.size() == T);  // every triangle once
  const uint32_t first_of_second = d.surrounding_offsets[1];
  std::vector<uint32_t> twice(d.surrounding_triangles.begin(), d.surrounding_triangles.begin() + first_of_second);
  d.surrounding_triangles.insert(d.surrounding_triangles.begin() + first_of_second, twice.begin(), twice.end());
  for (size_t s = 1; s < d.surrounding_offsets.size(); ++s) d.surrounding_offsets[s] += first_of_second;
  const st::AlignedBytes bytes = st::Serialize(d);
  sc::runtime::AssetView view;
  REQUIRE(sc::runtime::LoadAsset(bytes.data(), bytes.size, &view) == sc::runtime::Status::kOk);
  const nlohmann::json j = sc::evaluate::DescribeAsset(view);
  CHECK(j["unassigned_triangles"] == 0);  // every triangle is in a region, the first segment's in two
}
