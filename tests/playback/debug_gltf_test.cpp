// playback::ExportAnimatedGltf on the two real characters (heavy: real bakes; skipped visibly without
// ../shared/data): the file loads with tinygltf, holds one animation whose channels cover every skeleton
// node (3) and every sphere (2), sampler times strictly increase, every value is finite, the spheres'
// first keys equal Play()'s refit spheres of frame 0, and glTF skinning of the written skeleton keys
// reproduces the frames the library skins (what a viewer shows is what play measures).
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <algorithm>
#include <filesystem>
#include <set>
#include <map>

#include <tiny_gltf.h>

#include "playback/rig.h"
#include "spherechain/baker/bake.h"
#include "spherechain/import/import.h"
#include "spherechain/playback/debug_gltf.h"
#include "spherechain/playback/play.h"
#include "spherechain/runtime/runtime.h"
#include "test_data.h"

namespace sc = spherechain;

namespace {

/// Float `i` of accessor `a` (tightly packed or strided float data).
struct FloatReader {
  const tinygltf::Model& m;
  const float* At(int accessor, size_t element) const {
    const tinygltf::Accessor& a = m.accessors[accessor];
    const tinygltf::BufferView& v = m.bufferViews[a.bufferView];
    const size_t comps = size_t(tinygltf::GetNumComponentsInType(a.type));
    const size_t stride = v.byteStride ? v.byteStride : comps * 4;
    return reinterpret_cast<const float*>(m.buffers[v.buffer].data.data() + v.byteOffset + a.byteOffset + element * stride);
  }
  uint32_t U16(int accessor, size_t element, int k) const {
    const tinygltf::Accessor& a = m.accessors[accessor];
    const tinygltf::BufferView& v = m.bufferViews[a.bufferView];
    uint16_t x;
    std::memcpy(&x, m.buffers[v.buffer].data.data() + v.byteOffset + a.byteOffset + element * 8 + 2 * k, 2);
    return x;
  }
};

using M4 = std::array<double, 16>;  // column-major
M4 Mul(const M4& a, const M4& b) {
  M4 r{};
  for (int c = 0; c < 4; ++c)
    for (int row = 0; row < 4; ++row)
      for (int k = 0; k < 4; ++k) r[c * 4 + row] += a[k * 4 + row] * b[c * 4 + k];
  return r;
}
M4 Trs(const float* t, const float* q, const float* s) {
  const double x = q[0], y = q[1], z = q[2], w = q[3];
  const double R[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),
                       2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                       2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)};  // columns
  M4 m{};
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) m[c * 4 + r] = R[c * 3 + r] * s[c];
  m[12] = t[0], m[13] = t[1], m[14] = t[2], m[15] = 1;
  return m;
}

/// Bakes `input`, opens `request`'s animation, plays it (spheres kept), exports it and checks the file.
void CheckAnimatedExport(const std::string& input, sc::playback::AnimationRequest request, const std::string& name) {
  auto baked = sc::baker::Bake(input, sc::baker::BakeConfig{});
  REQUIRE_MESSAGE(baked.ok(), (baked.ok() ? "" : baked.error().message));
  std::vector<uint64_t> storage((baked->asset.size() + 7) / 8);
  std::memcpy(storage.data(), baked->asset.data(), baked->asset.size());
  sc::runtime::AssetView view;
  REQUIRE(sc::runtime::LoadAsset(reinterpret_cast<const uint8_t*>(storage.data()), baked->asset.size(), &view) ==
          sc::runtime::Status::kOk);
  auto mesh = sc::import::ImportMesh(input);  // with its clips
  REQUIRE(mesh.ok());
  request.mesh_name = input;
  auto anim = sc::playback::OpenAnimation(mesh.value(), request);
  REQUIRE_MESSAGE(anim.ok(), (anim.ok() ? "" : anim.error().message));

  sc::playback::PlayOptions opts;
  opts.repeat = 1;
  opts.keep_spheres = true;
  auto played = sc::playback::Play(mesh.value(), view, anim.value(), opts);
  REQUIRE_MESSAGE(played.ok(), (played.ok() ? "" : played.error().message));

  const std::string out = std::string(SPHERECHAIN_BINARY_DIR) + "/tests/" + name + ".gltf";
  sc::playback::AnimatedGltfStats stats;
  auto s = sc::playback::ExportAnimatedGltf(mesh.value(), view, anim.value(), out, sc::runtime::RefitMode::kPivotFrame, &stats);
  REQUIRE_MESSAGE(s.ok(), (s.ok() ? "" : s.error().message));
  const uint32_t S = view.sphere_count, F = anim->frames, N = uint32_t(mesh->skin->nodes.size());
  CHECK(stats.frames == F);
  CHECK(stats.spheres == S);
  CHECK(stats.first_frame_spheres == played->frames[0].spheres);

  tinygltf::Model m;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  REQUIRE_MESSAGE(loader.LoadASCIIFromFile(&m, &err, &warn, out), err);
  MESSAGE(name << ": " << stats.bytes / 1e6 << " MB, " << F << " frames, " << N << " skeleton nodes, " << S
               << " spheres, " << stats.max_influences << " influences at most");
  REQUIRE(m.animations.size() == 1);
  REQUIRE(m.skins.size() == 1);
  const tinygltf::Animation& a = m.animations[0];
  CHECK(a.channels.size() == 3 * N + 2 * S);

  // Which nodes are spheres: the children of "spheres", named sphere_<s>.
  std::map<int, int> sphere_of_node;
  for (size_t n = 0; n < m.nodes.size(); ++n)
    if (m.nodes[n].name == "spheres")
      for (int c : m.nodes[n].children) sphere_of_node[c] = std::stoi(m.nodes[c].name.substr(7));
  REQUIRE(sphere_of_node.size() == S);

  FloatReader rd{m};
  uint32_t sphere_channels = 0, sphere_translations = 0, sphere_scales = 0;
  const auto& first = played->frames[0].spheres;
  std::vector<const float*> key_t(N), key_r(N), key_s(N);  // skeleton keys of the frame checked below
  const uint32_t check_frame = F / 2 + 1 < F ? F / 2 + 1 : 0;
  for (const tinygltf::AnimationChannel& c : a.channels) {
    const tinygltf::AnimationSampler& smp = a.samplers[c.sampler];
    CHECK(smp.interpolation == "LINEAR");
    const tinygltf::Accessor& in = m.accessors[smp.input];
    const tinygltf::Accessor& outp = m.accessors[smp.output];
    REQUIRE(in.count == F);
    REQUIRE(outp.count == F);
    for (size_t k = 1; k < F; ++k) CHECK(*rd.At(smp.input, k) > *rd.At(smp.input, k - 1));
    const int comps = tinygltf::GetNumComponentsInType(outp.type);
    bool finite = true;
    for (size_t k = 0; k < F; ++k)
      for (int j = 0; j < comps; ++j) finite = finite && std::isfinite(rd.At(smp.output, k)[j]);
    CHECK(finite);
    auto it = sphere_of_node.find(c.target_node);
    if (it != sphere_of_node.end()) {
      ++sphere_channels;
      const int sph = it->second;
      const float* v0 = rd.At(smp.output, 0);
      if (c.target_path == "translation") {
        ++sphere_translations;
        for (int j = 0; j < 3; ++j) CHECK(v0[j] == first[4 * size_t(sph) + j]);
      } else {
        REQUIRE(c.target_path == "scale");
        ++sphere_scales;
        for (int j = 0; j < 3; ++j) CHECK(v0[j] == first[4 * size_t(sph) + 3]);
      }
    } else {
      REQUIRE(c.target_node < int(N));
      const float* v = rd.At(smp.output, check_frame);
      (c.target_path == "translation" ? key_t : c.target_path == "rotation" ? key_r : key_s)[c.target_node] = v;
    }
  }
  CHECK(sphere_channels == 2 * S);
  CHECK(sphere_translations == S);
  CHECK(sphere_scales == S);

  // glTF skinning of frame `check_frame` from the file alone == the library's skinning of that frame.
  std::vector<int> parent(m.nodes.size(), -1);
  for (size_t n = 0; n < m.nodes.size(); ++n)
    for (int c : m.nodes[n].children) parent[c] = int(n);
  std::vector<M4> global(N);
  for (uint32_t n = 0; n < N; ++n) {  // parents first (Skin::nodes order)
    REQUIRE((key_t[n] && key_r[n] && key_s[n]));
    const M4 local = Trs(key_t[n], key_r[n], key_s[n]);
    if (parent[n] >= int(N)) {  // a bone tree's root: under the file's one "skeleton" root, the identity
      const tinygltf::Node& root = m.nodes[size_t(parent[n])];
      CHECK(root.name == "skeleton");
      CHECK((root.translation.empty() && root.rotation.empty() && root.scale.empty() && root.matrix.empty()));
      CHECK(parent[size_t(parent[n])] == -1);
      global[n] = local;
    } else {
      global[n] = parent[n] >= 0 ? Mul(global[size_t(parent[n])], local) : local;
    }
  }
  const tinygltf::Skin& skin = m.skins[0];
  std::vector<M4> joint(skin.joints.size());
  for (size_t j = 0; j < skin.joints.size(); ++j) {
    M4 ibm;
    for (int k = 0; k < 16; ++k) ibm[k] = rd.At(skin.inverseBindMatrices, j)[k];
    const M4 g = skin.joints[j] < int(N) ? global[skin.joints[j]] : M4{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    joint[j] = Mul(g, ibm);
  }
  const tinygltf::Primitive& prim = m.meshes[m.nodes[m.nodes.size() - S - 2].mesh].primitives[0];
  sc::playback::SkinningScratch scratch;
  std::vector<float> expected;
  REQUIRE(anim->Frame(mesh.value(), check_frame, &scratch, &expected).ok());
  double max_err = 0, extent = 0;
  for (uint32_t v = 0; v < mesh->vertex_count(); ++v) {
    const float* p = rd.At(prim.attributes.at("POSITION"), v);
    double o[3] = {0, 0, 0};
    for (int set = 0; set < 4; ++set) {
      const std::string js = "JOINTS_" + std::to_string(set), ws = "WEIGHTS_" + std::to_string(set);
      if (!prim.attributes.count(js)) continue;
      const float* w = rd.At(prim.attributes.at(ws), v);
      for (int k = 0; k < 4; ++k) {
        if (w[k] == 0) continue;
        const M4& M = joint[rd.U16(prim.attributes.at(js), v, k)];
        for (int r = 0; r < 3; ++r) o[r] += w[k] * (M[r] * p[0] + M[4 + r] * p[1] + M[8 + r] * p[2] + M[12 + r]);
      }
    }
    for (int r = 0; r < 3; ++r) {
      max_err = std::max(max_err, std::abs(o[r] - expected[3 * size_t(v) + r]));
      extent = std::max(extent, std::abs(double(expected[3 * size_t(v) + r])));
    }
  }
  MESSAGE(name << ": glTF skinning of frame " << check_frame << " vs the library's: max |d| " << max_err
               << " (extent " << extent << ")");
  CHECK(max_err < 1e-4 * extent);
  std::filesystem::remove(out);
}

}  // namespace

TEST_CASE("animated debug glTF of the MakeHuman morph (heavy)") {
  const std::string input = sc::test::SharedData("makehuman/base.obj");
  if (!sc::test::Require(input)) return;
  sc::playback::AnimationRequest r;
  r.poses_dir = sc::test::SourceFile("data/poses/makehuman");
  CheckAnimatedExport(input, r, "animated_makehuman_morph");
}

TEST_CASE("animated debug glTF of CesiumMan's walk (heavy)") {
  const std::string input = sc::test::SharedData("gltf/CesiumMan.gltf");
  if (!sc::test::Require(input)) return;
  sc::playback::AnimationRequest r;
  r.frames = 24;
  CheckAnimatedExport(input, r, "animated_cesium_man_walk");
}

TEST_CASE("animated debug glTF of a synthetic rig: one animation, 3 channels a node, 2 a sphere, B's spheres lowered") {
  sc::test::Rig r;
  sc::test::MakeRig(&r);
  sc::playback::AnimationRequest req;
  req.mesh_name = "tubes";
  req.frames = 4;
  auto anim = sc::playback::OpenAnimation(r.mesh, req);
  REQUIRE(anim.ok());
  const std::string out = std::string(SPHERECHAIN_BINARY_DIR) + "/tests/animated_tubes.gltf";
  sc::playback::AnimatedGltfStats stats;
  auto s = sc::playback::ExportAnimatedGltf(r.mesh, r.view, anim.value(), out, sc::runtime::RefitMode::kPivotFrame, &stats);
  REQUIRE_MESSAGE(s.ok(), (s.ok() ? "" : s.error().message));
  CHECK(stats.channels == 3 * 3 + 2 * 16);
  CHECK(stats.max_influences == 1);
  tinygltf::Model m;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  REQUIRE_MESSAGE(loader.LoadASCIIFromFile(&m, &err, &warn, out), err);
  REQUIRE(m.animations.size() == 1);
  CHECK(m.animations[0].name == "lower");
  // The skin's joints share one root (glTF 2.0: a skin's joints must have a common root).
  std::vector<int> parent(m.nodes.size(), -1);
  for (size_t n = 0; n < m.nodes.size(); ++n)
    for (int c : m.nodes[n].children) parent[size_t(c)] = int(n);
  std::set<int> joint_roots;
  for (int j : m.skins.at(0).joints) {
    while (parent[size_t(j)] >= 0) j = parent[size_t(j)];
    joint_roots.insert(j);
  }
  CHECK(joint_roots.size() == 1);
  CHECK(m.animations[0].channels.size() == 3 * 3 + 2 * 16);
  FloatReader rd{m};
  // The last key of sphere 12's translation (tube B): 9 units below its bind centre at t = 0.75 s.
  for (const auto& c : m.animations[0].channels) {
    if (m.nodes[c.target_node].name != "sphere_12" || c.target_path != "translation") continue;
    const auto& smp = m.animations[0].samplers[c.sampler];
    CHECK(*rd.At(smp.input, 3) == doctest::Approx(0.75f));
    CHECK(rd.At(smp.output, 3)[2] == doctest::Approx(r.data.spheres[12].center().z() - 9.0f).epsilon(1e-4));
  }
  // Errors: a mesh that does not match, a missing folder (nothing written).
  sc::import::Mesh shorter = r.mesh;
  shorter.positions.resize(shorter.positions.size() - 3);
  CHECK(!sc::playback::ExportAnimatedGltf(shorter, r.view, anim.value(), out).ok());
  auto missing = sc::playback::ExportAnimatedGltf(r.mesh, r.view, anim.value(), "/nonexistent/dir/x.gltf");
  REQUIRE(!missing.ok());
  CHECK(missing.error().code == sc::import::Error::Code::kIo);
  std::filesystem::remove(out);
}

TEST_CASE("animated debug glTF: joint and clip names in another encoding are written as U+FFFD, not refused") {
  // FBX, X and DAE files from Latin-1 tools carry names that are not UTF-8; glTF's JSON must be. The writer
  // threw (nlohmann type_error.316) on them; each invalid byte is now U+FFFD and the rest of the name kept.
  sc::test::Rig r;
  sc::test::MakeRig(&r);
  REQUIRE(r.mesh.skin);
  REQUIRE(!r.mesh.clips.empty());
  r.mesh.skin->nodes[0].name = "Tail\xE9" "06";
  r.mesh.clips[0].name = "Lauf\xFC" "bung";
  sc::playback::AnimationRequest req;
  req.mesh_name = "tubes";
  req.clip = r.mesh.clips[0].name;
  req.frames = 4;
  auto anim = sc::playback::OpenAnimation(r.mesh, req);
  REQUIRE(anim.ok());
  const std::string out = std::string(SPHERECHAIN_BINARY_DIR) + "/tests/animated_latin1.gltf";
  auto s = sc::playback::ExportAnimatedGltf(r.mesh, r.view, anim.value(), out);
  REQUIRE_MESSAGE(s.ok(), (s.ok() ? "" : s.error().message));
  tinygltf::Model m;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  REQUIRE_MESSAGE(loader.LoadASCIIFromFile(&m, &err, &warn, out), err);
  CHECK(m.animations[0].name == "Lauf\xEF\xBF\xBD" "bung");
  CHECK(std::any_of(m.nodes.begin(), m.nodes.end(), [](const tinygltf::Node& n) { return n.name == "Tail\xEF\xBF\xBD" "06"; }));
  std::filesystem::remove(out);
}
