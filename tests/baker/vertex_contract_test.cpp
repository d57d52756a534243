// The vertex contract for assimp formats (import.h VertexContract, bake --vertices): what each contract
// reads, that "joined" is exactly the buffer a game gets from assimp with aiProcess_Triangulate |
// aiProcess_JoinIdenticalVertices, that glTF / OBJ are read as is, that the asset records the contract
// and that a buffer of the other contract is refused with a message naming it.
#include <doctest/doctest.h>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <unistd.h>

#include "spherechain/baker/bake.h"
#include "spherechain/import/import.h"
#include "spherechain/import/vertex_contract.h"
#include "spherechain/playback/validate.h"
#include "spherechain/runtime/asset.h"
#include "test_data.h"

using namespace spherechain;
using namespace spherechain::baker;
namespace fs = std::filesystem;

namespace {

// A folder of this process's own (ctest runs each test case as a process, in parallel), removed at its end.
const fs::path& TempDir() {
  static const struct Folder {
    fs::path dir = fs::temp_directory_path() / ("sc_vertex_contract_" + std::to_string(::getpid()));
    Folder() { fs::create_directories(dir); }
    ~Folder() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } folder;
  return folder.dir;
}

std::string TempFile(const std::string& name, const std::string& text) {
  const fs::path p = TempDir() / name;
  std::ofstream(p) << text;
  return p.string();
}

Mesh Import(const std::string& path, VertexContract c, std::vector<std::string>* warnings = nullptr) {
  ImportOptions o;
  o.vertices = c;
  Context ctx;
  ctx.sink = [&](Context::Level level, const std::string& m) {
    if (warnings && level == Context::Level::kWarn) warnings->push_back(m);
  };
  auto r = ImportMesh(path, o, &ctx);
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  return std::move(r).value();
}

/// Every triangle corner at the same position in both meshes (same triangle order, same corner order).
bool SameCornerPositions(const Mesh& a, const Mesh& b) {
  if (a.triangle_count() != b.triangle_count()) return false;
  for (size_t i = 0; i < a.indices.size(); ++i)
    for (int d = 0; d < 3; ++d)
      if (a.positions[3 * size_t(a.indices[i]) + d] != b.positions[3 * size_t(b.indices[i]) + d]) return false;
  return true;
}

size_t DistinctPositions(const Mesh& m) {
  std::set<std::array<float, 3>> s;
  for (uint32_t v = 0; v < m.vertex_count(); ++v)
    s.insert({m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]});
  return s.size();
}

// Two triangles of a quad whose shared edge is listed twice (4 distinct positions, 6 vertices): what an
// exporter writing one vertex per face corner produces.
const char* kPlyQuad =
    "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n1 1 0\n0 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 3 4 5\n";

}  // namespace

TEST_CASE("vertex contract: a PLY with one vertex per face corner, joined (default) and source") {
  const std::string ply = TempFile("quad.ply", kPlyQuad);
  const Mesh joined = Import(ply, VertexContract::kAuto);
  CHECK(joined.vertex_contract == "joined");
  CHECK(joined.vertex_count() == 4);
  CHECK(joined.source_vertex_count == 6);
  CHECK(joined.joined_vertex_count == 4);
  const Mesh source = Import(ply, VertexContract::kSource);
  CHECK(source.vertex_contract == "source");
  CHECK(source.vertex_count() == 6);
  CHECK(source.indices == std::vector<uint32_t>{0, 1, 2, 3, 4, 5});
  CHECK(source.source_vertex_count == 6);
  CHECK(source.joined_vertex_count == 4);  // counted by joining after the mesh was read
  CHECK(Import(ply, VertexContract::kJoined).positions == joined.positions);
  CHECK(SameCornerPositions(joined, source));  // the join only re-indexes: triangle and corner order kept
  CHECK(ReadThroughAssimp(ply));
  CHECK(!ReadThroughAssimp("a.gltf"));
  CHECK(!ReadThroughAssimp("a.OBJ"));
  CHECK(ReadThroughAssimp("a.X"));
}

TEST_CASE("vertex contract: OBJ is read as is — --vertices is a no-op with a warning") {
  const std::string obj = TempFile("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 4 5 6\n");
  std::vector<std::string> warnings;
  const Mesh plain = Import(obj, VertexContract::kAuto, &warnings);
  CHECK(warnings.empty());
  CHECK(plain.vertex_contract == "file");
  CHECK(plain.vertex_count() == 6);  // the file's own `v` order, nothing joined
  CHECK(plain.source_vertex_count == 0);
  for (VertexContract c : {VertexContract::kJoined, VertexContract::kSource}) {
    warnings.clear();
    const Mesh m = Import(obj, c, &warnings);
    CHECK(m.positions == plain.positions);
    CHECK(m.indices == plain.indices);
    CHECK(m.vertex_contract == "file");
    REQUIRE(warnings.size() == 1);
    CHECK(warnings[0].find("applies to assimp formats only") != std::string::npos);
  }
}

TEST_CASE("vertex contract: the bake configuration key 'vertices'") {
  auto ok = ParseBakeConfig(R"({"vertices": "source"})", "test");
  REQUIRE(ok.ok());
  CHECK(ok->import.vertices == VertexContract::kSource);
  CHECK(CanonicalConfig(ok.value()).find("\"vertices\":\"source\"") != std::string::npos);
  CHECK(CanonicalConfig(BakeConfig{}).find("\"vertices\"") == std::string::npos);  // default: hash unchanged
  auto bad = ParseBakeConfig(R"({"vertices": "welded"})", "test");
  REQUIRE(!bad.ok());
  CHECK(bad.error().code == Error::Code::kConfig);
  CHECK(bad.error().message.find("'vertices'") != std::string::npos);
}

TEST_CASE("vertex contract (heavy): BCN_Epileptic — joined is assimp's JoinIdenticalVertices buffer, source one vertex per corner") {
  const std::string path = test::AssimpModel("X/BCN_Epileptic.X");
  if (!test::Require(path)) return;
  const Mesh joined = Import(path, VertexContract::kAuto);
  const Mesh source = Import(path, VertexContract::kSource);
  MESSAGE("BCN_Epileptic: source " << source.vertex_count() << " vertices, joined " << joined.vertex_count()
                                   << ", distinct positions " << DistinctPositions(source) << ", triangles "
                                   << source.triangle_count());
  CHECK(source.vertex_count() == 15378);
  CHECK(DistinctPositions(source) == 2633);
  CHECK(DistinctPositions(joined) == 2633);
  CHECK(joined.vertex_count() >= 2633);
  CHECK(joined.vertex_count() < source.vertex_count());
  CHECK(joined.source_vertex_count == source.vertex_count());
  CHECK(source.joined_vertex_count == joined.vertex_count());
  CHECK(SameCornerPositions(joined, source));
  // Skin and clips survive the join: the same joints and clip.
  REQUIRE(joined.skin.has_value());
  REQUIRE(source.skin.has_value());
  CHECK(joined.skin->joints.size() == source.skin->joints.size());
  CHECK(joined.clips.size() == source.clips.size());

  // What a game gets from assimp with the usual real-time flags: the same counts, part by part.
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices);
  REQUIRE(scene);
  REQUIRE(scene->mNumMeshes == joined.parts.size());  // BCN: one instance per mesh
  uint32_t game_vertices = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) game_vertices += scene->mMeshes[m]->mNumVertices;
  CHECK(game_vertices == joined.vertex_count());
  std::multiset<uint32_t> game_parts, our_parts;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) game_parts.insert(scene->mMeshes[m]->mNumVertices);
  for (const MeshPart& p : joined.parts) our_parts.insert(p.vertex_count);
  CHECK(game_parts == our_parts);
}

TEST_CASE("vertex contract (heavy): the asset records it, and a buffer of the other contract is refused naming it") {
  const std::string path = test::AssimpModel("X/BCN_Epileptic.X");
  if (!test::Require(path)) return;
  BakeConfig config;
  config.import.vertices = VertexContract::kSource;
  auto baked = Bake(path, config);
  REQUIRE_MESSAGE(baked.ok(), (baked.ok() ? "" : baked.error().message));
  runtime::AssetView view;
  REQUIRE(runtime::Succeeded(runtime::LoadAsset(baked->asset.data(), baked->asset.size(), &view)));
  REQUIRE(view.asset->vertex_contract());
  CHECK(view.asset->vertex_contract()->str() == "source");
  CHECK(view.asset->source_vertex_count() == 15378);
  const uint32_t joined_count = view.asset->joined_vertex_count();
  CHECK(joined_count == Import(path, VertexContract::kJoined).vertex_count());
  CHECK(AssetVertexContractName(view) == "source");
  CHECK(ContractForReimport(view, path) == VertexContract::kSource);

  const std::string msg = DescribeVertexMismatch(view, joined_count);
  MESSAGE(msg);
  CHECK(msg.find("the buffer has " + GroupThousands(joined_count) + " vertices: it looks like the joined contract; "
                 "this asset was baked with --vertices source") == 0);
  CHECK(DescribeVertexMismatch(view, 15378).empty());
  CHECK(DescribeVertexMismatch(view, 7).find("neither contract") != std::string::npos);
  CHECK(GroupThousands(15378) == "15,378");
  CHECK(GroupThousands(999) == "999");
  CHECK(GroupThousands(1000000) == "1,000,000");

  // validate with the game's joined buffer: FP-COUNTS naming the contract; with the source buffer: valid.
  const Mesh game = Import(path, VertexContract::kJoined);
  auto findings = playback::ValidateAsset(view, &game);
  REQUIRE(!findings.empty());
  bool named = false;
  for (const auto& f : findings)
    named = named || (f.code == "FP-COUNTS" && f.message.find("it looks like the joined contract") != std::string::npos);
  CHECK_MESSAGE(named, findings.front().code << ": " << findings.front().message);
  const Mesh same = Import(path, VertexContract::kSource);
  CHECK(playback::CountErrors(playback::ValidateAsset(view, &same)) == 0);

  // The default bake is joined and the re-import follows the asset.
  auto def = Bake(path, BakeConfig{});
  REQUIRE(def.ok());
  runtime::AssetView dview;
  REQUIRE(runtime::Succeeded(runtime::LoadAsset(def->asset.data(), def->asset.size(), &dview)));
  CHECK(dview.asset->vertex_contract()->str() == "joined");
  CHECK(dview.vertex_count == joined_count);
  CHECK(ContractForReimport(dview, path) == VertexContract::kJoined);
  const std::string back = DescribeVertexMismatch(dview, 15378);
  CHECK(back.find("it looks like the source contract; this asset was baked with --vertices joined") != std::string::npos);
}

TEST_CASE("vertex contract (heavy): a glTF asset records 'file' and no per-contract counts") {
  const std::string path = test::SharedData("gltf/CesiumMan.gltf");
  if (!test::Require(path)) return;
  std::vector<std::string> warnings;
  const Mesh plain = Import(path, VertexContract::kAuto, &warnings);
  CHECK(plain.vertex_contract == "file");
  CHECK(plain.source_vertex_count == 0);
  CHECK(plain.joined_vertex_count == 0);
  const Mesh asked = Import(path, VertexContract::kJoined, &warnings);
  CHECK(asked.positions == plain.positions);
  CHECK(asked.indices == plain.indices);
  CHECK(!warnings.empty());
}

TEST_CASE("vertex contract: an asset baked before the field (golden v3) reads as unrecorded — assimp files re-import as source") {
  const std::string golden = test::SourceFile("tests/data/golden/v3/cesium_man.sphc");
  auto bytes = ReadFileBytes(golden);
  REQUIRE_MESSAGE(bytes.ok(), golden);
  runtime::AssetView view;
  REQUIRE(runtime::Succeeded(runtime::LoadAsset(bytes->data(), bytes->size(), &view)));
  CHECK(view.asset->vertex_contract() == nullptr);
  CHECK(view.asset->source_vertex_count() == 0);
  CHECK(AssetVertexContractName(view) == "unrecorded");
  CHECK(ContractForReimport(view, "CesiumMan.gltf") == VertexContract::kAuto);
  CHECK(ContractForReimport(view, "old_bake_of.X") == VertexContract::kSource);  // read as is back then
  const std::string msg = DescribeVertexMismatch(view, view.vertex_count + 1);
  CHECK(msg.find("vertex contract unrecorded") != std::string::npos);
  CHECK(DescribeVertexMismatch(view, view.vertex_count).empty());
}
