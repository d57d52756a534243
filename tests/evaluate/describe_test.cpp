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
