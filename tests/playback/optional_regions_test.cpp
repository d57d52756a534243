// The pictures of an asset that LoadAsset accepts without its optional region arrays (Asset.sphere_regions,
// triangle_regions: absent in a hand-made or older asset): the debug glTF and the SVG views are written, the
// character drawn grey, instead of reading through a null array.
#include <doctest/doctest.h>

#include <filesystem>
#include <string>

#include "runtime/asset_builder.h"
#include "spherechain/playback/debug_export.h"

namespace sc = spherechain;
namespace st = spherechain::test;

TEST_CASE("debug pictures of an asset without sphere_regions and triangle_regions") {
  st::Mesh tube_mesh;
  st::Tube tube;
  const st::AssetData d = st::MakeTubes({tube}, {}, &tube_mesh);
  REQUIRE(d.sphere_regions.empty());
  REQUIRE(d.triangle_regions.empty());
  const st::AlignedBytes bytes = st::Serialize(d);
  sc::runtime::AssetView view;
  REQUIRE(sc::runtime::LoadAsset(bytes.data(), bytes.size, &view) == sc::runtime::Status::kOk);
  REQUIRE(view.asset->sphere_regions() == nullptr);
  sc::playback::Mesh mesh;
  mesh.positions = tube_mesh.positions;
  mesh.indices = tube_mesh.triangles;
  const std::string svg = sc::playback::RenderDebugSvg(mesh, view, 400);
  CHECK(svg.find("<svg") != std::string::npos);
  const std::filesystem::path out = std::filesystem::temp_directory_path() / "spherechain_optional_regions.gltf";
  const sc::playback::Status s = sc::playback::ExportDebugGltf(mesh, view, out.string());
  CHECK(s.ok());
  CHECK(std::filesystem::file_size(out) > 0);
  std::filesystem::remove(out);
}
