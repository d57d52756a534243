// import: real characters (MakeHuman base.obj + rig, CesiumMan glTF, BCN_Epileptic.X) and the
// documented error codes on broken inputs.
#include <doctest/doctest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
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
using spherechain::import::Mesh;
using spherechain::import::Skin;
using spherechain::import::UpAxis;
namespace fs = std::filesystem;

/// A fresh per-test temp directory (removed at scope exit).
struct TempDir {
  fs::path dir;
  explicit TempDir(const std::string& name) {
    dir = fs::temp_directory_path() / ("spherechain_import_test_" + name + "." + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
  std::string Write(const std::string& file, const std::string& bytes) const {
    const fs::path p = dir / file;
    std::ofstream(p, std::ios::binary) << bytes;
    return p.string();
  }
};

/// Axis-aligned extent of the positions: max − min per axis.
std::array<float, 3> Extent(const Mesh& m) {
  std::array<float, 3> lo{1e30f, 1e30f, 1e30f}, hi{-1e30f, -1e30f, -1e30f};
  for (size_t i = 0; i < m.positions.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], m.positions[i]);
    hi[i % 3] = std::max(hi[i % 3], m.positions[i]);
  }
  return {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
}

int AxisIndex(UpAxis a) { return a == UpAxis::kX ? 0 : a == UpAxis::kY ? 1 : 2; }

/// Rest-pose globals of Skin::nodes (parents-first).
std::vector<Eigen::Matrix4d> RestGlobals(const Skin& s) {
  std::vector<Eigen::Matrix4d> g(s.nodes.size());
  for (size_t n = 0; n < s.nodes.size(); ++n) {
    const auto& node = s.nodes[n];
    Eigen::Affine3d a = Eigen::Affine3d::Identity();
    a.translate(Eigen::Vector3d(node.translation[0], node.translation[1], node.translation[2]));
    a.rotate(Eigen::Quaterniond(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]).normalized());
    a.scale(Eigen::Vector3d(node.scale[0], node.scale[1], node.scale[2]));
    g[n] = node.parent < 0 ? a.matrix() : Eigen::Matrix4d(g[static_cast<size_t>(node.parent)] * a.matrix());
  }
  return g;
}

/// Largest ‖Σ w·Global(node_j)·inverse_bind_j·p − p‖ over the vertices that have influences;
/// `unweighted` counts vertices with none.
double MaxRestSkinningError(const Mesh& m, size_t* unweighted) {
  const Skin& s = *m.skin;
  const auto g = RestGlobals(s);
  std::vector<Eigen::Matrix4d> skinning(s.joints.size());
  for (size_t j = 0; j < s.joints.size(); ++j) {
    Eigen::Matrix4d ib;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) ib(r, c) = s.joints[j].inverse_bind[static_cast<size_t>(c * 4 + r)];
    skinning[j] = g[static_cast<size_t>(s.joints[j].node)] * ib;
  }
  double worst = 0.0;
  *unweighted = 0;
  for (uint32_t v = 0; v < m.vertex_count(); ++v) {
    const Eigen::Vector4d p(m.positions[v * 3], m.positions[v * 3 + 1], m.positions[v * 3 + 2], 1.0);
    Eigen::Vector4d q = Eigen::Vector4d::Zero();
    if (s.weight_offsets[v] == s.weight_offsets[v + 1]) {
      ++*unweighted;
      continue;
    }
    for (uint32_t k = s.weight_offsets[v]; k < s.weight_offsets[v + 1]; ++k)
      q += s.weights[k] * (skinning[s.weight_joints[k]] * p);
    worst = std::max(worst, (q - p).head<3>().norm());
  }
  return worst;
}

/// Largest |Σ weights − 1| over weighted vertices.
double MaxWeightSumError(const Skin& s) {
  double worst = 0.0;
  for (size_t v = 0; v + 1 < s.weight_offsets.size(); ++v) {
    if (s.weight_offsets[v] == s.weight_offsets[v + 1]) continue;
    double sum = 0.0;
    for (uint32_t k = s.weight_offsets[v]; k < s.weight_offsets[v + 1]; ++k) sum += s.weights[k];
    worst = std::max(worst, std::abs(sum - 1.0));
  }
  return worst;
}

}  // namespace

TEST_CASE("import: MakeHuman base.obj keeps group body in file order with the default rig") {
  const std::string path = spherechain::test::SharedData("makehuman/base.obj");
  if (!spherechain::test::Require(path)) return;
  auto r = ImportMesh(path);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  const Mesh& m = r.value();
  CHECK(m.vertex_count() == 13380);
  CHECK(m.triangle_count() == 26756);
  CHECK(m.units == "dm");
  CHECK(m.unit_scale_m == doctest::Approx(0.1f));
  CHECK(m.up_axis == UpAxis::kY);
  REQUIRE(m.parts.size() == 1);
  CHECK(m.parts[0].name == "body");
  // Source order: the first vertex of the file is the first vertex of the mesh.
  CHECK(m.positions[0] == doctest::Approx(-0.3492f));
  CHECK(m.positions[1] == doctest::Approx(7.3299f));
  CHECK(m.positions[2] == doctest::Approx(1.4076f));
  const auto e = Extent(m);
  CHECK(e[1] > e[0]);
  CHECK(e[1] > e[2]);
  CHECK(e[1] == doctest::Approx(16.7).epsilon(0.05));  // DESIGN.md: a 16.7-unit-tall body
  REQUIRE(m.skin.has_value());
  const Skin& s = *m.skin;
  CHECK(s.source == "mhskel");
  CHECK(s.nodes.size() == 163);
  CHECK(s.joints.size() == 163);
  for (size_t n = 0; n < s.nodes.size(); ++n) CHECK(s.nodes[n].parent < static_cast<int32_t>(n));
  CHECK(s.weight_offsets.size() == m.vertex_count() + 1);
  CHECK(MaxWeightSumError(s) < 1e-5);
  size_t unweighted = 0;
  CHECK(MaxRestSkinningError(m, &unweighted) < 1e-4);
  CHECK(unweighted == 0);
  CHECK(m.clips.empty());
}

TEST_CASE("import: CesiumMan glTF assembles a +Y standing walker with 19 joints and one clip") {
  const std::string path = spherechain::test::SharedData("gltf/CesiumMan.gltf");
  if (!spherechain::test::Require(path)) return;
  auto r = ImportMesh(path);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  const Mesh& m = r.value();
  CHECK(m.vertex_count() == 3273);
  CHECK(m.triangle_count() == 4672);
  CHECK(m.source_format == "gltf");
  CHECK(m.units == "m");
  CHECK(m.unit_scale_m == 1.0f);
  CHECK(m.up_axis == UpAxis::kY);
  // Stands along +Y: taller than its arm span (X) and much taller than deep (Z). Before assembly the
  // mesh data is Z-up, so an importer that skips the root node's matrix fails here.
  const auto e = Extent(m);
  CHECK(e[1] > e[0]);
  CHECK(e[1] > 2.0f * e[2]);
  CHECK(e[1] == doctest::Approx(1.5).epsilon(0.1));
  REQUIRE(m.skin.has_value());
  const Skin& s = *m.skin;
  CHECK(s.source == "gltf");
  CHECK(s.joints.size() == 19);
  CHECK(MaxWeightSumError(s) < 1e-5);
  size_t unweighted = 0;
  CHECK(MaxRestSkinningError(m, &unweighted) < 1e-3 * e[1]);
  CHECK(unweighted == 0);
  // Head above feet: the mean of the top tenth of vertices is narrower (a head) than the bottom tenth
  // would be, and +Y is up: the skeleton's highest joint lies above its lowest one and above the
  // centre of the body.
  const auto g = RestGlobals(s);
  double top = -1e30, bottom = 1e30;
  for (const auto& j : s.joints) {
    top = std::max(top, g[static_cast<size_t>(j.node)](1, 3));
    bottom = std::min(bottom, g[static_cast<size_t>(j.node)](1, 3));
  }
  CHECK(top - bottom > 0.6 * e[1]);
  REQUIRE(m.clips.size() == 1);
  // Keys run from 1/24 s to 1.9167 s: the walk spans 1.875 s; duration_s is the last key time.
  CHECK(m.clips[0].duration_s == doctest::Approx(1.9167f).epsilon(0.001));
  float first_key = 1e30f;
  for (const auto& ch : m.clips[0].channels) first_key = std::min(first_key, ch.times.front());
  CHECK(m.clips[0].duration_s - first_key == doctest::Approx(1.875f).epsilon(0.001));
  CHECK(m.clips[0].channels.size() >= 19);
  for (const auto& ch : m.clips[0].channels) {
    CHECK(ch.node >= 0);
    CHECK(ch.node < static_cast<int32_t>(s.nodes.size()));
  }
}

TEST_CASE("import: BCN_Epileptic.X joins three meshes into one standing body with one clip") {
  const std::string path = spherechain::test::AssimpModel("X/BCN_Epileptic.X");
  if (!spherechain::test::Require(path)) return;
  auto r = ImportMesh(path);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  const Mesh& m = r.value();
  CHECK(m.source_format == "x");
  REQUIRE(m.parts.size() == 3);
  uint32_t v = 0, t = 0;
  for (const auto& p : m.parts) {
    CHECK(p.first_vertex == v);
    CHECK(p.first_triangle == t);
    v += p.vertex_count;
    t += p.triangle_count;
  }
  CHECK(v == m.vertex_count());
  CHECK(t == m.triangle_count());
  const auto e = Extent(m);
  const int up = AxisIndex(m.up_axis);
  CHECK(m.up_axis == UpAxis::kY);
  CHECK(e[up] > 1.5f * e[(up + 1) % 3]);
  CHECK(e[up] > 1.5f * e[(up + 2) % 3]);
  // assimp's .x reader gives one vertex per face corner (--vertices source: 15,378); the default joined
  // contract reads what a game's aiProcess_JoinIdenticalVertices gives (vertex_contract_test.cpp).
  CHECK(m.vertex_contract == "joined");
  CHECK(m.source_vertex_count == 15378);
  CHECK(m.vertex_count() == m.joined_vertex_count);
  CHECK(m.vertex_count() < 15378);
  CHECK(m.triangle_count() == 5126);
  REQUIRE(m.skin.has_value());
  CHECK(m.skin->nodes.size() == 58);
  CHECK(m.skin->joints.size() == 54);
  // Joined: each part's range along the up axis touches the others' (the mesh frames' own transforms,
  // which skinning ignores, would push the head 0.5 units off the torso).
  for (size_t p = 0; p < m.parts.size(); ++p) {
    float lo = 1e30f, hi = -1e30f, olo = 1e30f, ohi = -1e30f;
    for (size_t q = 0; q < m.parts.size(); ++q) {
      const auto& part = m.parts[q];
      for (uint32_t i = part.first_vertex; i < part.first_vertex + part.vertex_count; ++i) {
        const float y = m.positions[i * 3 + static_cast<uint32_t>(up)];
        if (q == p) lo = std::min(lo, y), hi = std::max(hi, y);
        else olo = std::min(olo, y), ohi = std::max(ohi, y);
      }
    }
    CHECK_MESSAGE(hi >= olo - 0.02f * e[up], "part " << m.parts[p].name);
    CHECK_MESSAGE(lo <= ohi + 0.02f * e[up], "part " << m.parts[p].name);
  }
  REQUIRE(m.skin.has_value());
  CHECK(MaxWeightSumError(*m.skin) < 1e-5);
  size_t unweighted = 0;
  CHECK(MaxRestSkinningError(m, &unweighted) < 1e-3 * e[up]);
  REQUIRE(m.clips.size() == 1);
  CHECK(m.clips[0].name == "Epileptisch");
  CHECK(m.clips[0].duration_s == doctest::Approx(3.3f).epsilon(0.001));  // 15,840 ticks at 4,800/s
  MESSAGE("BCN_Epileptic: " << m.vertex_count() << " vertices, " << m.triangle_count() << " triangles, up axis "
                            << up << ", extent " << e[0] << " " << e[1] << " " << e[2] << ", "
                            << m.skin->nodes.size() << " nodes, " << m.skin->joints.size() << " joints, clip "
                            << m.clips[0].duration_s << " s, rest skinning error " << MaxRestSkinningError(m, &unweighted));
}

TEST_CASE("import: simple_skin glTF has a skin whose rest pose reproduces the positions") {
  const std::string path = spherechain::test::AssimpModel("glTF2/simple_skin/simple_skin.gltf");
  if (!spherechain::test::Require(path)) return;
  auto r = ImportMesh(path);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  const Mesh& m = r.value();
  CHECK(m.triangle_count() > 0);
  REQUIRE(m.skin.has_value());
  CHECK(m.skin->joints.size() == 2);
  size_t unweighted = 0;
  CHECK(MaxRestSkinningError(m, &unweighted) < 1e-4);
  CHECK(m.clips.size() == 1);
}

TEST_CASE("import: a missing file is kIo") {
  auto r = ImportMesh("/nonexistent/dir/character.gltf");
  REQUIRE(!r.ok());
  CHECK(r.error().code == Error::Code::kIo);
  CHECK(r.error().message.find("character.gltf") != std::string::npos);
}

TEST_CASE("import: an unsupported extension is kFormat") {
  TempDir tmp("ext");
  const std::string p = tmp.Write("character.notamesh", "hello");
  auto r = ImportMesh(p);
  REQUIRE(!r.ok());
  CHECK(r.error().code == Error::Code::kFormat);
  CHECK(r.error().message.find("character.notamesh") != std::string::npos);
}

TEST_CASE("import: truncated and garbage glTF/GLB files are kFormat, never a crash") {
  TempDir tmp("gltf");
  static const char kGarbage[] = "\x00\xff\x13garbage{{[[\x7f\x80";  // 16 bytes, a NUL first
  const std::string garbage(kGarbage, sizeof kGarbage - 1);
  for (const char* name : {"garbage.gltf", "garbage.glb"}) {
    auto r = ImportMesh(tmp.Write(name, garbage));
    REQUIRE(!r.ok());
    CHECK(r.error().code == Error::Code::kFormat);
    CHECK(r.error().message.find(name) != std::string::npos);
  }
  // Every 1/64 prefix of a real glTF file: an error (never a crash); the full file imports.
  const std::string cesium = spherechain::test::SharedData("gltf/CesiumMan.gltf");
  if (!spherechain::test::Require(cesium)) return;
  std::ifstream in(cesium, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  REQUIRE(bytes.size() > 1000);
  for (int k = 0; k < 64; ++k) {
    const size_t n = bytes.size() * static_cast<size_t>(k) / 64;
    auto r = ImportMesh(tmp.Write("truncated.gltf", bytes.substr(0, n)));
    CHECK_MESSAGE(!r.ok(), "prefix of " << n << " bytes imported");
    if (!r.ok()) CHECK(r.error().code == Error::Code::kFormat);
  }
}

TEST_CASE("import: OBJ with a NaN coordinate, no faces, or an out-of-range index is kInvalidMesh") {
  TempDir tmp("obj");
  SUBCASE("NaN coordinate names the vertex") {
    auto r = ImportMesh(tmp.Write("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n"));
    REQUIRE(!r.ok());
    CHECK(r.error().code == Error::Code::kInvalidMesh);
    CHECK(r.error().message.find("vertex 2") != std::string::npos);
    CHECK(r.error().message.find("nan.obj") != std::string::npos);
  }
  SUBCASE("Inf coordinate") {
    auto r = ImportMesh(tmp.Write("inf.obj", "v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n"));
    REQUIRE(!r.ok());
    CHECK(r.error().code == Error::Code::kInvalidMesh);
  }
  SUBCASE("coordinates beyond float's range: below it read as 0 or a denormal, above it non-finite (refused)") {
    auto r = ImportMesh(tmp.Write("tiny.obj", "v 1e-50 0 -1e-400\nv 1 0 1e-40\nv 0 1 0\nf 1 2 3\n"));
    REQUIRE_MESSAGE(r.ok(), r.error().message);
    CHECK(r->positions[0] == 0.0f);
    CHECK(r->positions[2] == 0.0f);
    CHECK(r->positions[5] == 1e-40f);
    for (const char* big : {"1e50", "-1e400"}) {
      auto b = ImportMesh(tmp.Write("big.obj", std::string("v 0 0 0\nv 1 ") + big + " 0\nv 0 1 0\nf 1 2 3\n"));
      REQUIRE(!b.ok());
      CHECK(b.error().code == Error::Code::kInvalidMesh);
      CHECK(b.error().message.find("vertex 1 has a non-finite coordinate") != std::string::npos);
    }
    CHECK(!ImportMesh(tmp.Write("word.obj", "v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n")).ok());
  }
  SUBCASE("no faces") {
    auto r = ImportMesh(tmp.Write("nofaces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"));
    REQUIRE(!r.ok());
    CHECK(r.error().code == Error::Code::kInvalidMesh);
    CHECK(r.error().message.find("no triangles") != std::string::npos);
  }
  SUBCASE("index past the end") {
    auto r = ImportMesh(tmp.Write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\nf 1 2 3\n"));
    REQUIRE(!r.ok());
    CHECK(r.error().code == Error::Code::kInvalidMesh);
    CHECK(r.error().message.find("line 5: face references vertex 4 (1-based) but the file has 3 vertices") !=
          std::string::npos);
  }
  SUBCASE("index 0 and a relative index before the first vertex") {
    auto r0 = ImportMesh(tmp.Write("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"));
    REQUIRE(!r0.ok());
    CHECK(r0.error().code == Error::Code::kInvalidMesh);
    auto r1 = ImportMesh(tmp.Write("neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n"));
    REQUIRE(!r1.ok());
    CHECK(r1.error().code == Error::Code::kInvalidMesh);
  }
  SUBCASE("unparsable number is kFormat") {
    auto r = ImportMesh(tmp.Write("bad.obj", "v 0 0 zero\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
    REQUIRE(!r.ok());
    CHECK(r.error().code == Error::Code::kFormat);
    CHECK(r.error().message.find("line 1") != std::string::npos);
  }
}

TEST_CASE("import: small OBJ keeps vertex order, fan-triangulates quads, and a MakeHuman base mesh keeps group body") {
  TempDir tmp("objok");
  const std::string p = tmp.Write("quad.obj",
                                  "v 9 9 9\n"
                                  "g helper\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 2 3 4\n"
                                  "g body\nf 2/1/1 3/2/2 4/3/3 5/4/4\n");
  // Not a MakeHuman base mesh (no "# basemesh" comment, no rig given): every group, every vertex.
  auto any = ImportMesh(p);
  REQUIRE_MESSAGE(any.ok(), any.error().message);
  CHECK(any->vertex_count() == 5);
  CHECK(any->triangle_count() == 3);
  // A MakeHuman base mesh: only group body.
  const std::string mh = tmp.Write("quad_mh.obj", "# basemesh hm08\n" + std::string(std::istreambuf_iterator<char>(
                                                                            std::ifstream(p, std::ios::binary).rdbuf()),
                                                                        std::istreambuf_iterator<char>()));
  auto r = ImportMesh(mh);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  // Only group body: its 4 referenced vertices (file vertices 2..5), in file order.
  CHECK(r->vertex_count() == 4);
  CHECK(r->triangle_count() == 2);
  CHECK(r->positions[0] == 0.0f);
  CHECK(r->positions[3] == 1.0f);
  CHECK(r->indices == std::vector<uint32_t>{0, 1, 2, 0, 2, 3});
  CHECK(!r->skin.has_value());

  spherechain::import::ImportOptions all;
  all.obj_group.clear();
  auto r2 = ImportMesh(mh, all);
  REQUIRE(r2.ok());
  CHECK(r2->vertex_count() == 5);
  CHECK(r2->triangle_count() == 3);
}

TEST_CASE("import: ValidateMesh names the first offending vertex and triangle") {
  Mesh m;
  m.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  m.indices = {0, 1, 2};
  CHECK(spherechain::import::ValidateMesh(m).ok());
  m.indices = {0, 1, 3};
  auto r = spherechain::import::ValidateMesh(m);
  REQUIRE(!r.ok());
  CHECK(r.error().code == Error::Code::kInvalidMesh);
  CHECK(r.error().message.find("triangle 0") != std::string::npos);
  m.indices = {0, 1, 2};
  m.positions[4] = std::numeric_limits<float>::quiet_NaN();
  r = spherechain::import::ValidateMesh(m);
  REQUIRE(!r.ok());
  CHECK(r.error().message.find("vertex 1") != std::string::npos);
  m.positions[4] = 0.0f;
  m.indices.clear();
  CHECK(!spherechain::import::ValidateMesh(m).ok());
}

namespace {

/// A skinned one-triangle glTF (data.bin beside it): the mesh node scaled by 2 (which skinning ignores),
/// joint 0 at the origin carrying every weight, joint 1 at y = 5 carrying none, both with identity inverse
/// binds (so joint 1's does not match its rest pose), and two animations both named "Walk".
std::string SkinnedTriangleGltf(const TempDir& tmp) {
  std::string bin;
  auto put = [&](const void* p, size_t n) { bin.append(static_cast<const char*>(p), n); };
  const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint32_t indices[3] = {0, 1, 2};
  const uint8_t joints[12] = {0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0};
  const float weights[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
  const float identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const float times[2] = {0, 1};
  const float rotations[8] = {0, 0, 0, 1, 0, 0, 0, 1};
  put(positions, 36);    // 0
  put(indices, 12);      // 36
  put(joints, 12);       // 48
  put(weights, 48);      // 60
  put(identity, 64);     // 108
  put(identity, 64);     // 172
  put(times, 8);         // 236
  put(rotations, 32);    // 244
  tmp.Write("data.bin", bin);
  const std::string walk = R"({"name":"Walk","channels":[{"sampler":0,"target":{"node":1,"path":"rotation"}}],)"
                           R"("samplers":[{"input":5,"output":6}]})";
  return tmp.Write("skinned.gltf",
                   R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0,1,2]}],)"
                   R"("nodes":[{"mesh":0,"skin":0,"scale":[2,2,2]},{"name":"j0"},{"name":"j1","translation":[0,5,0]}],)"
                   R"("skins":[{"joints":[1,2],"inverseBindMatrices":4}],)"
                   R"("meshes":[{"primitives":[{"attributes":{"POSITION":0,"JOINTS_0":2,"WEIGHTS_0":3},"indices":1}]}],)"
                   R"("animations":[)" + walk + "," + walk + R"(],)"
                   R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"},)"
                   R"({"bufferView":1,"componentType":5125,"count":3,"type":"SCALAR"},)"
                   R"({"bufferView":2,"componentType":5121,"count":3,"type":"VEC4"},)"
                   R"({"bufferView":3,"componentType":5126,"count":3,"type":"VEC4"},)"
                   R"({"bufferView":4,"componentType":5126,"count":2,"type":"MAT4"},)"
                   R"({"bufferView":5,"componentType":5126,"count":2,"type":"SCALAR","min":[0],"max":[1]},)"
                   R"({"bufferView":6,"componentType":5126,"count":2,"type":"VEC4"}],)"
                   R"("bufferViews":[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":12},)"
                   R"({"buffer":0,"byteOffset":48,"byteLength":12},{"buffer":0,"byteOffset":60,"byteLength":48},)"
                   R"({"buffer":0,"byteOffset":108,"byteLength":128},{"buffer":0,"byteOffset":236,"byteLength":8},)"
                   R"({"buffer":0,"byteOffset":244,"byteLength":32}],)"
                   R"("buffers":[{"uri":"data.bin","byteLength":276}]})");
}

}  // namespace

TEST_CASE("import: a skinned glTF is placed by its weighted joints only; repeated clip names are made unique") {
  TempDir tmp("skinned_gltf");
  const std::string path = SkinnedTriangleGltf(tmp);
  auto r = ImportMesh(path);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  // Joint 0 (all the weight) agrees with its inverse bind: the mesh sits where its joints put it, at scale 1
  // (the unweighted joint 1, whose inverse bind does not match, used to send it to its node's scale 2).
  CHECK(Extent(r.value())[0] == doctest::Approx(1.0));
  CHECK(Extent(r.value())[1] == doctest::Approx(1.0));
  REQUIRE(r->clips.size() == 2);
  CHECK(r->clips[0].name == "Walk");
  CHECK(r->clips[1].name == "Walk #2");
}

TEST_CASE("import: a MakeHuman rig given for a file that is not an OBJ is kConfig, not ignored") {
  TempDir tmp("rig_not_obj");
  const std::string path = SkinnedTriangleGltf(tmp);
  spherechain::import::ImportOptions o;
  o.rig_path = tmp.Write("rig.mhskel", "{}");
  auto r = ImportMesh(path, o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().code == Error::Code::kConfig);
  CHECK(r.error().message.find("applies to an OBJ mesh") != std::string::npos);
}

TEST_CASE("import: a glTF's morph targets are applied at their default weights (node's, else mesh's)") {
  TempDir tmp("morph_gltf");
  std::string bin;
  const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint32_t indices[3] = {0, 1, 2};
  const float delta[9] = {0, 0, 0, 0, 0, 0, 0, 1, 0};  // the target lifts vertex 2 by 1 in y
  bin.append(reinterpret_cast<const char*>(positions), 36);
  bin.append(reinterpret_cast<const char*>(indices), 12);
  bin.append(reinterpret_cast<const char*>(delta), 36);
  tmp.Write("data.bin", bin);
  auto gltf = [&](const std::string& mesh_weights, const std::string& node_weights) {
    return tmp.Write("morph.gltf",
                     R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0)" +
                         node_weights + R"(}],"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,)" +
                         R"("targets":[{"POSITION":2}]}])" + mesh_weights + R"(}],)" +
                         R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"},)" +
                         R"({"bufferView":1,"componentType":5125,"count":3,"type":"SCALAR"},)" +
                         R"({"bufferView":2,"componentType":5126,"count":3,"type":"VEC3"}],)" +
                         R"("bufferViews":[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":12},)" +
                         R"({"buffer":0,"byteOffset":48,"byteLength":36}],"buffers":[{"uri":"data.bin","byteLength":84}]})");
  };
  auto y2 = [&](const std::string& path) {
    auto r = ImportMesh(path);
    REQUIRE_MESSAGE(r.ok(), r.error().message);
    return r->positions[7];
  };
  CHECK(y2(gltf("", "")) == 1.0f);                                // no weights: the base shape
  CHECK(y2(gltf(R"(,"weights":[0.5])", "")) == 1.5f);            // the mesh's default weight
  CHECK(y2(gltf(R"(,"weights":[0.5])", R"(,"weights":[1])")) == 2.0f);  // the node's overrides it
  // A target of another length is refused, naming the unnamed mesh by its index.
  std::string json;
  {
    std::ifstream in(gltf(R"(,"weights":[0.5])", ""));
    json.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const std::string three = R"({"bufferView":2,"componentType":5126,"count":3,"type":"VEC3"})";
  REQUIRE(json.find(three) != std::string::npos);
  json.replace(json.find(three), three.size(), R"({"bufferView":2,"componentType":5126,"count":2,"type":"VEC3"})");
  auto bad = ImportMesh(tmp.Write("short_target.gltf", json));
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message.find("mesh 0 primitive 0 morph target 0 POSITION has 2 values, POSITION 3") !=
        std::string::npos);
}

