// import input policy (import.h, docs/guide.md "Bad input"): format allowlist, size cap, glTF confined
// to its folder, degenerate / non-manifold triangles kept and counted.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "spherechain/import/import.h"
#include "test_data.h"

namespace {

using spherechain::import::Error;
using spherechain::import::ImportMesh;
using spherechain::import::InspectMesh;
using spherechain::import::Mesh;
namespace fs = std::filesystem;

struct PolicyDir {
  fs::path dir;
  PolicyDir() {
    // One folder per process: ctest runs each test case of this file as its own process, in parallel.
    dir = fs::temp_directory_path() / ("spherechain_import_policy_test." + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir / "sub");
    fs::create_directories(dir / "secret");
  }
  ~PolicyDir() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
  std::string Write(const std::string& rel, const std::string& bytes) const {
    std::ofstream(dir / rel, std::ios::binary) << bytes;
    return (dir / rel).string();
  }
};

/// One-triangle glTF whose buffer is `uri` (36 bytes: 3 float3).
std::string TriangleGltf(const std::string& uri) {
  return R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"scene":0,"nodes":[{"mesh":0}],)"
         R"("meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],)"
         R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","max":[1,1,0],"min":[0,0,0]}],)"
         R"("bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"uri":")" +
         uri + R"(","byteLength":36}]})";
}

std::string TriangleBytes() {
  const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  return std::string(reinterpret_cast<const char*>(v), sizeof v);
}

}  // namespace

TEST_CASE("Import policy: formats outside the allowlist are kFormat, naming the supported ones") {
  PolicyDir d;
  for (const char* name : {"notes.txt", "model.off", "scene.lwo", "noextension", "model.ifc"}) {
    CAPTURE(name);
    auto r = ImportMesh(d.Write(name, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
    REQUIRE(!r.ok());
    CHECK(r.error().code == Error::Code::kFormat);
    CHECK(r.error().message.find("unsupported format") != std::string::npos);
    CHECK(r.error().message.find("FBX") != std::string::npos);
  }
}

TEST_CASE("Import policy: content in a disguise is read only by the importer of its extension") {
  // An OFF file renamed .stl: assimp's OFF importer is unregistered, so sniffing cannot reach it.
  PolicyDir d;
  auto r = ImportMesh(d.Write("cube.stl", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
  REQUIRE(!r.ok());
  CHECK(r.error().code == Error::Code::kFormat);
}

TEST_CASE("Import policy: a file over kMaxInputBytes is refused before parsing") {
  PolicyDir d;
  const std::string big = d.Write("big.obj", "");
  fs::resize_file(big, spherechain::import::kMaxInputBytes + 1);  // sparse: no disk used
  auto r = ImportMesh(big);
  REQUIRE(!r.ok());
  CHECK(r.error().code == Error::Code::kFormat);
  CHECK(r.error().message.find("input limit") != std::string::npos);
}

TEST_CASE("Import policy: glTF reads buffers only inside its own folder") {
  PolicyDir d;
  d.Write("secret/data.bin", TriangleBytes());
  d.Write("sub/data.bin", TriangleBytes());
  {
    auto ok = ImportMesh(d.Write("sub/inside.gltf", TriangleGltf("data.bin")));
    REQUIRE_MESSAGE(ok.ok(), (ok.ok() ? "" : ok.error().message));
    CHECK(ok->triangle_count() == 1);
  }
  for (const std::string& uri : std::vector<std::string>{"../secret/data.bin", "%2E%2E/secret/data.bin", "sub/../../secret/data.bin",
                                (d.dir / "secret/data.bin").string(), "file://" + (d.dir / "secret/data.bin").string()}) {
    CAPTURE(uri);
    auto r = ImportMesh(d.Write("sub/escape.gltf", TriangleGltf(uri)));
    REQUIRE(!r.ok());
    CHECK(r.error().code == Error::Code::kFormat);
  }
}

TEST_CASE("InspectMesh counts degenerate triangles and non-manifold edges, and ImportMesh keeps them") {
  Mesh m;
  m.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 2, 0, 0};
  m.indices = {0, 1, 2,   // fine
               0, 1, 3,   // fine: edge 0-1 now in 2 triangles
               0, 1, 4,   // zero area (collinear), edge 0-1 in 3 triangles: non-manifold
               2, 2, 3};  // repeated index
  const auto issues = InspectMesh(m);
  CHECK(issues.degenerate_triangles == 2);
  CHECK(issues.non_manifold_edges == 1);

  PolicyDir d;
  auto r = ImportMesh(d.Write("degenerate.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 3 3 1\n"));
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  CHECK(r->triangle_count() == 3);  // kept, source order
  CHECK(InspectMesh(r.value()).degenerate_triangles == 2);
}
