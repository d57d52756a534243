// Hand-made assets (tests/runtime/asset_builder.h tubes) through playback. The pictures of an asset that
// LoadAsset accepts without its optional region arrays (Asset.sphere_regions, triangle_regions: absent in a
// hand-made or older asset): the debug glTF and the SVG views are written, the character drawn grey, instead
// of reading through a null array. A session on an asset whose narrow phase the runtime refuses.
#include <doctest/doctest.h>

#include <filesystem>
#include <string>
#include <unistd.h>

#include "runtime/asset_builder.h"
#include "spherechain/playback/debug_export.h"
#include "spherechain/playback/session.h"

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
  const std::filesystem::path out = std::filesystem::temp_directory_path() / ("spherechain_optional_regions." + std::to_string(::getpid()) + ".gltf");
  const sc::playback::Status s = sc::playback::ExportDebugGltf(mesh, view, out.string());
  CHECK(s.ok());
  CHECK(std::filesystem::file_size(out) > 0);
  std::filesystem::remove(out);
}

TEST_CASE("a session's narrow phase on an asset whose crease reaches the whole bind surface: a format error") {
  // st::CreaseTube collapsed 1,000 times: every node of its 2,400 reaches all of them, past
  // NarrowPhaseModel::kReachPerNode. The runtime refuses the model (kErrorCreaseTooWide); a
  // Session with the narrow phase reports it as the asset's fault (kFormat), with what to do about it, and the
  // same asset without the narrow phase still plays.
  st::Mesh tube_mesh;
  const st::AssetData d = st::CreaseTube(1e-3f, &tube_mesh);
  const st::AlignedBytes bytes = st::Serialize(d);
  sc::runtime::AssetView view;
  REQUIRE(sc::runtime::LoadAsset(bytes.data(), bytes.size, &view) == sc::runtime::Status::kOk);
  sc::import::Mesh mesh;
  mesh.positions = tube_mesh.positions;
  mesh.indices = tube_mesh.triangles;
  sc::playback::SessionOptions options;
  options.narrow = sc::playback::SessionNarrow::kEvery;
  sc::playback::Session session;
  const auto e = session.Init(view, mesh, options);
  REQUIRE(!e.ok());
  CHECK(e.error().code == sc::import::Error::Code::kFormat);
  CHECK(e.error().message.find("kErrorCreaseTooWide") != std::string::npos);
  CHECK(e.error().message.find("smaller crease_rel") != std::string::npos);
  CHECK(session.runtime_status() == sc::runtime::Status::kErrorCreaseTooWide);
  options.narrow = sc::playback::SessionNarrow::kNone;
  CHECK(session.Init(view, mesh, options).ok());
}
