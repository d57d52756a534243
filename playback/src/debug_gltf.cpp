// The animated debug glTF (debug_gltf.h): skeleton + skinned, region-coloured mesh + one node per
// sphere, one animation with the skeleton's sampled locals and the spheres' per-frame refit.
#include "spherechain/playback/debug_gltf.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include <tiny_gltf.h>

#include "spherechain/playback/debug_export.h"
#include "spherechain/playback/session.h"
#include "spherechain/import/file_io.h"
#include "spherechain/runtime/runtime.h"
#include "utf8.h"

namespace spherechain::playback {

namespace {

/// Builds a tinygltf::Model: one buffer, views and accessors appended as data comes.
class GltfBuilder {
 public:
  tinygltf::Model model;

  int View(const void* data, size_t bytes, int target = 0) {
    const size_t off = buffer_.size();
    const auto* p = static_cast<const unsigned char*>(data);
    buffer_.insert(buffer_.end(), p, p + bytes);
    while (buffer_.size() % 4) buffer_.push_back(0);
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = off;
    v.byteLength = bytes;
    v.target = target;
    model.bufferViews.push_back(v);
    return int(model.bufferViews.size() - 1);
  }
  int Accessor(int view, int component, size_t count, int type, std::vector<double> mn = {},
               std::vector<double> mx = {}) {
    tinygltf::Accessor a;
    a.bufferView = view;
    a.componentType = component;
    a.count = count;
    a.type = type;
    a.minValues = std::move(mn);
    a.maxValues = std::move(mx);
    model.accessors.push_back(a);
    return int(model.accessors.size() - 1);
  }
  /// Float accessor of `v` (#count × components), with min/max when `bounds`.
  int Floats(const std::vector<float>& v, int type, int components, bool bounds = false, int target = 0) {
    std::vector<double> mn, mx;
    if (bounds) {
      mn.assign(components, 1e300);
      mx.assign(components, -1e300);
      for (size_t i = 0; i < v.size(); ++i) {
        mn[i % components] = std::min(mn[i % components], double(v[i]));
        mx[i % components] = std::max(mx[i % components], double(v[i]));
      }
    }
    return Accessor(View(v.data(), v.size() * 4, target), TINYGLTF_COMPONENT_TYPE_FLOAT, v.size() / components, type,
                    std::move(mn), std::move(mx));
  }
  void Finish() {
    tinygltf::Buffer b;
    b.data = std::move(buffer_);
    model.buffers.push_back(std::move(b));
  }

 private:
  std::vector<unsigned char> buffer_;
};

/// Unit UV sphere (12 × 8): positions = normals, triangle indices.
void UnitSphere(std::vector<float>* pos, std::vector<uint16_t>* idx) {
  const int slices = 12, stacks = 8;
  for (int i = 0; i <= stacks; ++i)
    for (int j = 0; j <= slices; ++j) {
      const double th = M_PI * i / stacks, ph = 2 * M_PI * j / slices;
      pos->insert(pos->end(), {float(std::sin(th) * std::cos(ph)), float(std::cos(th)), float(std::sin(th) * std::sin(ph))});
    }
  for (int i = 0; i < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      const uint16_t a = uint16_t(i * (slices + 1) + j), b = uint16_t(a + slices + 1);
      idx->insert(idx->end(), {a, b, uint16_t(a + 1), uint16_t(a + 1), b, uint16_t(b + 1)});
    }
}

Error Fail(Error::Code code, std::string m) { return MakeError(code, "animated glTF: " + std::move(m)); }

}  // namespace

Status ExportAnimatedGltf(const Mesh& mesh, const runtime::AssetView& asset, const Animation& anim,
                          const std::string& out_path, runtime::RefitMode refit_mode, AnimatedGltfStats* stats) {
  if (!asset.valid()) return Fail(Error::Code::kConfig, "the asset is not loaded");
  if (mesh.vertex_count() != asset.vertex_count || mesh.triangle_count() != asset.triangle_count)
    return Fail(Error::Code::kConfig, "the mesh (" + std::to_string(mesh.vertex_count()) + " vertices, " +
                                          std::to_string(mesh.triangle_count()) + " triangles) does not match the asset (" +
                                          std::to_string(asset.vertex_count) + ", " + std::to_string(asset.triangle_count) + ")");
  if (!mesh.skin) return Fail(Error::Code::kConfig, "the mesh has no skin ('" + mesh.source_path + "')");
  if (anim.frames == 0) return Fail(Error::Code::kConfig, "the animation has no frames");
  const Skin& skin = *mesh.skin;
  const uint32_t N = uint32_t(skin.nodes.size()), V = mesh.vertex_count(), S = asset.sphere_count, F = anim.frames;
  const uint32_t J = uint32_t(skin.joints.size());
  if (skin.weight_offsets.size() != size_t(V) + 1)
    return Fail(Error::Code::kConfig, "the skin's weight rows do not match the mesh's vertices");
  for (const SkinJoint& j : skin.joints)
    if (j.node < 0 || uint32_t(j.node) >= N) return Fail(Error::Code::kConfig, "a skin joint's node is out of range");

  // ---- per frame: locals (skeleton channels) and the refit spheres (sphere channels) ----------------
  SessionOptions so;  // the frame pipeline: skin, refit; no broad or narrow phase
  so.refit = refit_mode == runtime::RefitMode::kPaper ? PlayRefit::kPaper : PlayRefit::kPivotFrame;
  so.m1 = so.m2 = false;
  Session session;
  if (auto s = session.Init(asset, mesh, so); !s.ok()) return Fail(s.error().code, s.error().message);
  std::vector<float> times(F), node_t(size_t(F) * N * 3), node_r(size_t(F) * N * 4), node_s(size_t(F) * N * 3);
  std::vector<float> sphere_t(size_t(F) * S * 3), sphere_s(size_t(F) * S * 3);
  const bool clip_timed = anim.clip && anim.clip->duration_s > 0.0f;
  for (uint32_t f = 0; f < F; ++f) {
    times[f] = clip_timed ? anim.FrameTime(f) : float(f) / Animation::kMorphFps;
    if (auto s = session.Step(anim, f); !s.ok()) {
      if (session.runtime_status() == runtime::Status::kOk) return s;  // the skinning's error, as it is
      return Fail(Error::Code::kInternal, "frame " + std::to_string(f) + ": runtime " + s.error().message);
    }
    // The skinning left the frame's locals in its scratch (SkinLocals' input).
    const std::vector<Transform>& locals = session.skinning().locals;
    if (locals.size() != N) return Fail(Error::Code::kInternal, "the frame's locals do not cover the skeleton");
    for (uint32_t n = 0; n < N; ++n) {
      const Transform& t = locals[n];
      std::copy(t.translation.begin(), t.translation.end(), node_t.begin() + (size_t(n) * F + f) * 3);
      std::copy(t.rotation.begin(), t.rotation.end(), node_r.begin() + (size_t(n) * F + f) * 4);
      std::copy(t.scale.begin(), t.scale.end(), node_s.begin() + (size_t(n) * F + f) * 3);
    }
    const runtime::SphereArrays& sp = session.frame().spheres;
    for (uint32_t s = 0; s < S; ++s) {
      const float c[4] = {sp.x[s], sp.y[s], sp.z[s], sp.r[s]};
      for (float v : c)
        if (!std::isfinite(v))
          return Fail(Error::Code::kInternal, "sphere " + std::to_string(s) + " is not finite at frame " + std::to_string(f));
      float* T = &sphere_t[(size_t(s) * F + f) * 3];
      float* R = &sphere_s[(size_t(s) * F + f) * 3];
      T[0] = c[0], T[1] = c[1], T[2] = c[2];
      R[0] = R[1] = R[2] = c[3];
    }
    if (f == 0 && stats) {
      stats->first_frame_spheres.resize(size_t(S) * 4);
      for (uint32_t s = 0; s < S; ++s) {
        float* o = &stats->first_frame_spheres[size_t(s) * 4];
        o[0] = sp.x[s], o[1] = sp.y[s], o[2] = sp.z[s], o[3] = sp.r[s];
      }
    }
  }

  GltfBuilder g;
  tinygltf::Model& m = g.model;
  m.asset.version = "2.0";
  m.asset.generator = "spherechain export-debug (animated)";

  // ---- skeleton nodes --------------------------------------------------------------------------------
  std::vector<int> roots;
  for (uint32_t n = 0; n < N; ++n) {
    const Node& src = skin.nodes[n];
    tinygltf::Node node;
    node.name = src.name.empty() ? "node_" + std::to_string(n) : detail::ValidUtf8(src.name);  // JSON is UTF-8
    node.translation = {src.translation[0], src.translation[1], src.translation[2]};
    node.rotation = {src.rotation[0], src.rotation[1], src.rotation[2], src.rotation[3]};
    node.scale = {src.scale[0], src.scale[1], src.scale[2]};
    m.nodes.push_back(node);
  }
  for (uint32_t n = 0; n < N; ++n) {
    const int32_t p = skin.nodes[n].parent;
    if (p >= 0 && uint32_t(p) < n) m.nodes[p].children.push_back(int(n));
    else roots.push_back(int(n));
  }
  const int static_node = int(m.nodes.size());
  {
    tinygltf::Node node;
    node.name = "static";
    m.nodes.push_back(node);
  }
  // One root above the bone trees and "static" (the identity): a skin's joints must share a common root
  // (glTF 2.0, skins; the Khronos validator's SKIN_NO_COMMON_ROOT), and no global transform changes.
  const int skeleton_node = int(m.nodes.size());
  {
    tinygltf::Node node;
    node.name = "skeleton";
    node.children = roots;
    node.children.push_back(static_node);
    m.nodes.push_back(node);
    roots.assign(1, skeleton_node);
  }

  // ---- materials: the character's regions, one translucent material per region for the spheres ------
  tinygltf::Material body;
  body.name = "regions";
  body.pbrMetallicRoughness.metallicFactor = 0.0;
  body.doubleSided = true;
  m.materials.push_back(body);
  const int region_count = int(runtime::RegionCount(asset));  // 5, or a creature's (schema v4)
  for (int r = 0; r < region_count; ++r) {
    const auto c = RegionColor(asset, uint32_t(r));
    tinygltf::Material glass;
    glass.name = std::string("spheres_") + import::RegionSymbol(static_cast<import::Region>(r));
    glass.alphaMode = "BLEND";
    glass.pbrMetallicRoughness.baseColorFactor = {c[0], c[1], c[2], 0.35};
    glass.pbrMetallicRoughness.metallicFactor = 0.0;
    m.materials.push_back(glass);
  }

  // ---- the skinned character ---------------------------------------------------------------------------
  std::vector<float> colors(size_t(V) * 3, 0.5f);
  if (const auto* tri_regions = asset.asset->triangle_regions())
    for (uint32_t t = 0; t < mesh.triangle_count() && t < tri_regions->size(); ++t) {
      const auto c = RegionColor(asset, tri_regions->Get(t));
      for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j) colors[3 * size_t(mesh.indices[3 * size_t(t) + k]) + j] = c[j];
    }
  uint32_t max_inf = 0;
  for (uint32_t v = 0; v < V; ++v) max_inf = std::max(max_inf, skin.weight_offsets[v + 1] - skin.weight_offsets[v]);
  // Every influence is written (exact glTF skinning); per vertex sorted by weight, largest first, so a
  // viewer that reads only JOINTS_0/WEIGHTS_0 (three.js) gets the four strongest.
  const uint32_t sets = std::max(1u, (max_inf + 3) / 4);
  std::vector<std::vector<uint16_t>> joints(sets, std::vector<uint16_t>(size_t(V) * 4, 0));
  std::vector<std::vector<float>> weights(sets, std::vector<float>(size_t(V) * 4, 0.0f));
  std::vector<uint32_t> order;
  for (uint32_t v = 0; v < V; ++v) {
    const uint32_t b = skin.weight_offsets[v], e = skin.weight_offsets[v + 1];
    double sum = 0;
    for (uint32_t k = b; k < e; ++k) sum += skin.weights[k];
    if (e == b || !(sum > 0)) {
      joints[0][4 * size_t(v)] = uint16_t(J);  // the static joint: stays at bind, as SkinPositions leaves it
      weights[0][4 * size_t(v)] = 1.0f;
      continue;
    }
    order.resize(e - b);
    for (uint32_t k = b; k < e; ++k) order[k - b] = k;
    std::stable_sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) { return skin.weights[x] > skin.weights[y]; });
    for (uint32_t i = 0; i < order.size(); ++i) {
      joints[i / 4][4 * size_t(v) + i % 4] = uint16_t(skin.weight_joints[order[i]]);
      weights[i / 4][4 * size_t(v) + i % 4] = float(skin.weights[order[i]] / sum);
    }
  }
  tinygltf::Primitive prim;
  prim.attributes["POSITION"] = g.Floats(mesh.positions, TINYGLTF_TYPE_VEC3, 3, true, TINYGLTF_TARGET_ARRAY_BUFFER);
  prim.attributes["COLOR_0"] = g.Floats(colors, TINYGLTF_TYPE_VEC3, 3, false, TINYGLTF_TARGET_ARRAY_BUFFER);
  for (uint32_t k = 0; k < sets; ++k) {
    prim.attributes["JOINTS_" + std::to_string(k)] =
        g.Accessor(g.View(joints[k].data(), joints[k].size() * 2, TINYGLTF_TARGET_ARRAY_BUFFER),
                   TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, V, TINYGLTF_TYPE_VEC4);
    prim.attributes["WEIGHTS_" + std::to_string(k)] = g.Floats(weights[k], TINYGLTF_TYPE_VEC4, 4, false, TINYGLTF_TARGET_ARRAY_BUFFER);
  }
  prim.indices = g.Accessor(g.View(mesh.indices.data(), mesh.indices.size() * 4, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER),
                            TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, mesh.indices.size(), TINYGLTF_TYPE_SCALAR);
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  prim.material = 0;
  tinygltf::Mesh body_mesh;
  body_mesh.name = "character";
  body_mesh.primitives.push_back(prim);
  m.meshes.push_back(body_mesh);

  std::vector<float> ibm;
  tinygltf::Skin gskin;
  gskin.name = "skin";
  for (const SkinJoint& j : skin.joints) {
    gskin.joints.push_back(j.node);
    ibm.insert(ibm.end(), j.inverse_bind.begin(), j.inverse_bind.end());
  }
  gskin.joints.push_back(static_node);
  const float identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  ibm.insert(ibm.end(), identity, identity + 16);
  gskin.inverseBindMatrices = g.Floats(ibm, TINYGLTF_TYPE_MAT4, 16);
  m.skins.push_back(gskin);
  const int mesh_node = int(m.nodes.size());
  {
    tinygltf::Node node;
    node.name = "mesh";
    node.mesh = 0;
    node.skin = 0;
    m.nodes.push_back(node);
    roots.push_back(mesh_node);
  }

  // ---- spheres: a unit sphere mesh per region, one node per sphere ----------------------------------
  std::vector<float> unit;
  std::vector<uint16_t> unit_idx;
  UnitSphere(&unit, &unit_idx);
  const int unit_pos = g.Floats(unit, TINYGLTF_TYPE_VEC3, 3, true, TINYGLTF_TARGET_ARRAY_BUFFER);
  const int unit_ind = g.Accessor(g.View(unit_idx.data(), unit_idx.size() * 2, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER),
                                  TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, unit_idx.size(), TINYGLTF_TYPE_SCALAR);
  const int first_sphere_mesh = int(m.meshes.size());
  for (int r = 0; r < region_count; ++r) {
    tinygltf::Primitive p;
    p.attributes["POSITION"] = unit_pos;
    p.attributes["NORMAL"] = unit_pos;
    p.indices = unit_ind;
    p.mode = TINYGLTF_MODE_TRIANGLES;
    p.material = 1 + r;
    tinygltf::Mesh sm;
    sm.name = std::string("sphere_") + import::RegionSymbol(static_cast<import::Region>(r));
    sm.primitives.push_back(p);
    m.meshes.push_back(sm);
  }
  const int spheres_node = int(m.nodes.size());
  {
    tinygltf::Node node;
    node.name = "spheres";
    m.nodes.push_back(node);
    roots.push_back(spheres_node);
  }
  const auto* sphere_regions = asset.asset->sphere_regions();
  const int first_sphere_node = int(m.nodes.size());
  for (uint32_t s = 0; s < S; ++s) {
    tinygltf::Node node;
    node.name = "sphere_" + std::to_string(s);
    const int region = sphere_regions && s < sphere_regions->size() ? std::min<int>(sphere_regions->Get(s), region_count - 1)
                                                                    : region_count - 1;
    node.mesh = first_sphere_mesh + region;
    const float* T = &sphere_t[size_t(s) * F * 3];
    const float* R = &sphere_s[size_t(s) * F * 3];
    node.translation = {T[0], T[1], T[2]};
    node.scale = {R[0], R[1], R[2]};
    m.nodes.push_back(node);
    m.nodes[spheres_node].children.push_back(first_sphere_node + int(s));
  }

  // ---- the animation -----------------------------------------------------------------------------------
  tinygltf::Animation a;
  a.name = anim.clip ? detail::ValidUtf8(anim.clip->name) : "morph";
  const int input = g.Floats(times, TINYGLTF_TYPE_SCALAR, 1, true);
  auto channel = [&](int node, const char* path, const float* values, size_t floats, int type, int comps) {
    std::vector<float> v(values, values + floats);
    tinygltf::AnimationSampler sampler;
    sampler.input = input;
    sampler.output = g.Floats(v, type, comps);
    sampler.interpolation = "LINEAR";
    a.samplers.push_back(sampler);
    tinygltf::AnimationChannel c;
    c.sampler = int(a.samplers.size() - 1);
    c.target_node = node;
    c.target_path = path;
    a.channels.push_back(c);
  };
  for (uint32_t n = 0; n < N; ++n) {
    channel(int(n), "translation", &node_t[size_t(n) * F * 3], size_t(F) * 3, TINYGLTF_TYPE_VEC3, 3);
    channel(int(n), "rotation", &node_r[size_t(n) * F * 4], size_t(F) * 4, TINYGLTF_TYPE_VEC4, 4);
    channel(int(n), "scale", &node_s[size_t(n) * F * 3], size_t(F) * 3, TINYGLTF_TYPE_VEC3, 3);
  }
  for (uint32_t s = 0; s < S; ++s) {
    channel(first_sphere_node + int(s), "translation", &sphere_t[size_t(s) * F * 3], size_t(F) * 3, TINYGLTF_TYPE_VEC3, 3);
    channel(first_sphere_node + int(s), "scale", &sphere_s[size_t(s) * F * 3], size_t(F) * 3, TINYGLTF_TYPE_VEC3, 3);
  }
  m.animations.push_back(a);
  g.Finish();

  tinygltf::Scene scene;
  scene.name = "spherechain debug (animated)";
  scene.nodes = roots;
  m.scenes.push_back(scene);
  m.defaultScene = 0;

  namespace fs = std::filesystem;
  const fs::path target(out_path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return MakeError(Error::Code::kIo, "folder '" + dir.string() + "' does not exist");
  std::ostringstream text;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToStream(&m, text, /*prettyPrint=*/false, GltfBinary(out_path)))
    return Fail(Error::Code::kIo, "tinygltf could not serialise the scene");
  const std::string bytes = text.str();
  if (auto s = import::WriteFileAtomic(out_path, bytes); !s.ok()) return s;
  if (stats) {
    stats->frames = F;
    stats->skeleton_nodes = N;
    stats->spheres = S;
    stats->channels = uint32_t(a.channels.size());
    stats->max_influences = max_inf;
    stats->bytes = bytes.size();
  }
  return Ok{};
}

}  // namespace spherechain::playback
