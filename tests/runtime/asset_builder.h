// Test helper: synthetic .sphc assets built with flatbuffers::FlatBufferBuilder from tubes.
// Each tube: `rings` rings of `sides` vertices (radius R) along a direction; one sphere per ring
// (centre on the axis, radius `sphere_scale`·R); segment i's triangles form sphere i's surrounding
// region; sphere i's 4 pivot triangles are 4 triangles of segment min(i, rings−2) at 90° steps;
// consecutive spheres of a tube are excluded (adjacent) pairs. Bind data comes from the runtime's
// BuildPivotFrame / PivotMeanDistance exactly as the baker computes it.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "spherechain/runtime/runtime.h"

namespace spherechain::test {

struct Tube {
  float origin[3] = {0, 0, 0};
  float direction[3] = {1, 0, 0};  // unit
  uint32_t rings = 8;
  uint32_t sides = 8;
  float radius = 1.0f;
  float spacing = 1.2f;        // distance between rings
  float sphere_scale = 1.0f;   // sphere radius = sphere_scale · radius
};

/// One character of one asset, for the tests: the asset's Model and a Workspace made for it.
struct Character {
  runtime::Model model;
  runtime::Workspace ws;
  /// model.Init(view), then ws.Init(model); the first error.
  runtime::Status Init(const runtime::AssetView& view) {
    if (runtime::Status s = model.Init(view); s != runtime::Status::kOk) return s;
    return ws.Init(model);
  }
};

/// A DetectJob on `ch` writing into `out` (capacity out.size()), its count into *n, its stats into *stats.
inline runtime::DetectJob MakeDetectJob(Character& ch, runtime::DetectMethod method,
                                        std::vector<runtime::Collision>& out, uint32_t* n,
                                        runtime::DetectStats* stats) {
  runtime::DetectJob job;
  job.model = &ch.model;
  job.workspace = &ch.ws;
  job.method = method;
  job.output = out.data();
  job.capacity = static_cast<uint32_t>(out.size());
  job.count = n;
  job.stats = stats;
  return job;
}

/// Bytes with 8-byte alignment (LoadAsset's requirement).
struct AlignedBytes {
  std::vector<uint64_t> storage;
  size_t size = 0;
  const uint8_t* data() const { return reinterpret_cast<const uint8_t*>(storage.data()); }
  uint8_t* data() { return reinterpret_cast<uint8_t*>(storage.data()); }
  void assign(const uint8_t* p, size_t n) {
    storage.assign((n + 7) / 8, 0);
    size = n;
    if (n) std::memcpy(storage.data(), p, n);
  }
};

/// Reads the whole file at `path` into `out` (8-byte aligned, as LoadAsset requires). False when it cannot
/// be opened or read, or is empty (`out` then holds what was read, possibly nothing). The one asset-file
/// reader of the runtime-level tests, the C API tests, the CUDA tests and the benches: they link the runtime
/// alone, not spherechain::import, whose import::LoadAssetFile every offline tool uses.
inline bool ReadAlignedFile(const std::string& path, AlignedBytes* out) {
  out->storage.clear();
  out->size = 0;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  bool ok = std::fseek(f, 0, SEEK_END) == 0;
  const long end = ok ? std::ftell(f) : -1L;
  ok = ok && end > 0 && std::fseek(f, 0, SEEK_SET) == 0;
  if (ok) {
    out->storage.assign((size_t(end) + 7) / 8, 0);
    out->size = size_t(end);
    ok = std::fread(out->storage.data(), 1, out->size, f) == out->size;
  }
  std::fclose(f);
  return ok;
}

struct Mesh {
  std::vector<float> positions;     // #V×3
  std::vector<uint32_t> triangles;  // #T×3
  uint32_t vertex_count() const { return static_cast<uint32_t>(positions.size() / 3); }
  uint32_t triangle_count() const { return static_cast<uint32_t>(triangles.size() / 3); }
};

/// Raw arrays of the asset, editable before serialisation (to corrupt them in tests).
struct AssetData {
  uint32_t schema_version = runtime::kSchemaVersion;
  std::string identifier = "SPHC";
  float contact_margin = 0.0f;  ///< Asset.contact_margin (schema v2) [source units]; 0 = not written
  float fold_margin = -1.0f;    ///< Asset.fold_margin [source units]; -1 (the schema default) = not written
  uint32_t vertex_count = 0, triangle_count = 0;
  uint64_t positions_hash = 0, indices_hash = 0;  ///< Asset.fingerprint hashes (0 = not written)
  std::vector<schema::Sphere> spheres;
  std::vector<std::vector<uint16_t>> chains;
  std::vector<schema::SpherePair> excluded;
  std::vector<uint16_t> triangle_spheres;
  std::vector<uint32_t> surrounding_offsets, surrounding_triangles, pivot_triangles, pivot_vertices;
  std::vector<schema::PivotFrame> frames;
  std::vector<uint32_t> tube_first_sphere;  // per tube
  std::vector<uint32_t> triangles;  // [opt] Asset.triangles (#T×3): empty = field absent
  std::vector<uint32_t> weld_ids;   // [opt] Asset.weld_ids (#V): empty = field absent
  uint32_t joint_count = 0;                 // Asset.joint_count (schema v3)
  std::vector<uint16_t> sphere_joints;      // [opt] #S×4: empty = field absent
  std::vector<float> sphere_joint_weights;  // [opt] #S×4: empty = field absent
  std::vector<uint8_t> sphere_regions;      // [opt] #S: empty = field absent
  std::vector<uint8_t> triangle_regions;    // [opt] #T: empty = field absent
  std::vector<uint32_t> reach_offsets, reach_triangles;  // [opt] Asset.reach_*: each empty = field absent
  std::vector<float> bind_positions;  // [opt] Asset.bind_positions (#V×3): empty = field absent
  float crease = -1.0f;               ///< Asset.crease; -1 (the schema default) = not written
  std::vector<uint8_t> skin_counts;   // [opt] Asset.skin_counts (#V): empty = field absent
  std::vector<uint16_t> skin_joints;  // [opt] Asset.skin_joints: empty = field absent
  std::vector<uint8_t> skin_weights;  // [opt] Asset.skin_weights: empty = field absent
  /// [opt] Asset.regions (schema v4): names and kinds (true: Trunk); empty = field absent.
  std::vector<std::pair<std::string, bool>> regions;
};

inline void Orthonormal(const float d[3], float u[3], float v[3]) {
  const float a[3] = {std::fabs(d[0]) < 0.9f ? 1.0f : 0.0f, std::fabs(d[0]) < 0.9f ? 0.0f : 1.0f, 0.0f};
  u[0] = d[1] * a[2] - d[2] * a[1];
  u[1] = d[2] * a[0] - d[0] * a[2];
  u[2] = d[0] * a[1] - d[1] * a[0];
  const float l = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  for (int k = 0; k < 3; ++k) u[k] /= l;
  v[0] = d[1] * u[2] - d[2] * u[1];
  v[1] = d[2] * u[0] - d[0] * u[2];
  v[2] = d[0] * u[1] - d[1] * u[0];
}

/// Builds the mesh and the asset arrays. `chains` lists, per chain, the tubes it contains (all their
/// spheres); pass {} for one chain per tube.
inline AssetData MakeTubes(const std::vector<Tube>& tubes, const std::vector<std::vector<uint32_t>>& chains,
                           Mesh* mesh) {
  AssetData d;
  std::vector<std::pair<uint32_t, uint32_t>> ranges;  // per tube: first sphere, count
  for (const Tube& t : tubes) {
    const uint32_t v0 = mesh->vertex_count(), t0 = mesh->triangle_count();
    const uint32_t s0 = static_cast<uint32_t>(d.spheres.size());
    d.tube_first_sphere.push_back(s0);
    ranges.push_back({s0, t.rings});
    float u[3], v[3];
    Orthonormal(t.direction, u, v);
    for (uint32_t i = 0; i < t.rings; ++i)
      for (uint32_t k = 0; k < t.sides; ++k) {
        const float ang = 6.2831853f * (float(k) + 0.5f * float(i % 2)) / float(t.sides);
        for (int c = 0; c < 3; ++c)
          mesh->positions.push_back(t.origin[c] + t.direction[c] * t.spacing * float(i) +
                                    t.radius * (std::cos(ang) * u[c] + std::sin(ang) * v[c]));
      }
    for (uint32_t i = 0; i + 1 < t.rings; ++i)
      for (uint32_t k = 0; k < t.sides; ++k) {
        const uint32_t a = v0 + i * t.sides + k, b = v0 + i * t.sides + (k + 1) % t.sides;
        const uint32_t c = a + t.sides, e = b + t.sides;
        for (uint32_t x : {a, b, c, b, e, c}) mesh->triangles.push_back(x);
      }
    for (uint32_t i = 0; i < t.rings; ++i) {
      const uint32_t s = s0 + i;
      schema::Sphere sp(schema::Vec3(t.origin[0] + t.direction[0] * t.spacing * float(i),
                                     t.origin[1] + t.direction[1] * t.spacing * float(i),
                                     t.origin[2] + t.direction[2] * t.spacing * float(i)),
                        t.sphere_scale * t.radius);
      d.spheres.push_back(sp);
      const uint32_t seg = i + 1 < t.rings ? i : t.rings - 2;
      d.surrounding_offsets.push_back(static_cast<uint32_t>(d.surrounding_triangles.size()));
      if (i + 1 < t.rings)
        for (uint32_t q = 0; q < 2 * t.sides; ++q) d.surrounding_triangles.push_back(t0 + seg * 2 * t.sides + q);
      float p[4][3];
      for (uint32_t k = 0; k < 4; ++k) {
        const uint32_t tri = t0 + seg * 2 * t.sides + 2 * (k * t.sides / 4) + (k % 2);
        d.pivot_triangles.push_back(tri);
        float vtx[3][3];
        for (int c = 0; c < 3; ++c) {
          const uint32_t vi = mesh->triangles[3 * tri + c];
          d.pivot_vertices.push_back(vi);
          for (int x = 0; x < 3; ++x) vtx[c][x] = mesh->positions[3 * vi + x];
        }
        runtime::TriangleCentroid(vtx[0], vtx[1], vtx[2], p[k]);
      }
      const float c[3] = {sp.center().x(), sp.center().y(), sp.center().z()};
      runtime::PivotFrameBasis f;
      const bool ok = runtime::BuildPivotFrame(p, &f);
      (void)ok;
      float local[3];
      runtime::PivotFrameToLocal(f, c, local);
      d.frames.push_back(schema::PivotFrame(schema::Vec3(local[0], local[1], local[2]),
                                            schema::Vec3(c[0] - f.origin[0], c[1] - f.origin[1], c[2] - f.origin[2]),
                                            runtime::PivotMeanDistance(p, c)));
      if (i + 1 < t.rings) d.excluded.push_back(schema::SpherePair(uint16_t(s), uint16_t(s + 1)));
      (void)s;
    }
    for (uint32_t i = 0; i + 1 < t.rings; ++i)
      for (uint32_t q = 0; q < 2 * t.sides; ++q) d.triangle_spheres.push_back(uint16_t(s0 + i));
  }
  d.surrounding_offsets.push_back(static_cast<uint32_t>(d.surrounding_triangles.size()));
  if (chains.empty()) {
    for (const auto& r : ranges) {
      std::vector<uint16_t> c;
      for (uint32_t i = 0; i < r.second; ++i) c.push_back(uint16_t(r.first + i));
      d.chains.push_back(c);
    }
  } else {
    for (const auto& tl : chains) {
      std::vector<uint16_t> c;
      for (uint32_t t : tl)
        for (uint32_t i = 0; i < ranges[t].second; ++i) c.push_back(uint16_t(ranges[t].first + i));
      std::sort(c.begin(), c.end());
      d.chains.push_back(c);
    }
  }
  d.vertex_count = mesh->vertex_count();
  d.triangle_count = mesh->triangle_count();
  d.triangles = mesh->triangles;
  d.weld_ids.resize(d.vertex_count);
  for (uint32_t v = 0; v < d.vertex_count; ++v) d.weld_ids[v] = v;  // tubes share vertices: nothing to weld
  return d;
}

/// Serialises `d` into a finished FlatBuffer with identifier `d.identifier`.
inline AlignedBytes Serialize(const AssetData& d) {
  flatbuffers::FlatBufferBuilder b(1024);
  auto fp = schema::CreateFingerprint(b, d.vertex_count, d.triangle_count, d.positions_hash, d.indices_hash);
  auto params = schema::CreateBakeParams(b, 80, 2, 0.25f, 0.3f, 4, b.CreateString("geometry"), 0);
  auto spheres = b.CreateVectorOfStructs(d.spheres);
  std::vector<flatbuffers::Offset<schema::Chain>> chains;
  for (size_t i = 0; i < d.chains.size(); ++i)
    chains.push_back(schema::CreateChain(b, b.CreateString("chain" + std::to_string(i)), b.CreateVector(d.chains[i])));
  auto chains_v = b.CreateVector(chains);
  auto excl = b.CreateVectorOfStructs(d.excluded);
  auto ts = b.CreateVector(d.triangle_spheres);
  auto so = b.CreateVector(d.surrounding_offsets);
  auto st = b.CreateVector(d.surrounding_triangles);
  auto pt = b.CreateVector(d.pivot_triangles);
  auto pv = b.CreateVector(d.pivot_vertices);
  auto pf = b.CreateVectorOfStructs(d.frames);
  flatbuffers::Offset<flatbuffers::Vector<uint32_t>> tris, weld;
  if (!d.triangles.empty()) tris = b.CreateVector(d.triangles);
  if (!d.weld_ids.empty()) weld = b.CreateVector(d.weld_ids);
  flatbuffers::Offset<flatbuffers::Vector<uint16_t>> sj;
  flatbuffers::Offset<flatbuffers::Vector<float>> sw;
  if (!d.sphere_joints.empty()) sj = b.CreateVector(d.sphere_joints);
  if (!d.sphere_joint_weights.empty()) sw = b.CreateVector(d.sphere_joint_weights);
  flatbuffers::Offset<flatbuffers::Vector<uint8_t>> sr, tr;
  if (!d.sphere_regions.empty()) sr = b.CreateVector(d.sphere_regions);
  if (!d.triangle_regions.empty()) tr = b.CreateVector(d.triangle_regions);
  flatbuffers::Offset<flatbuffers::Vector<uint32_t>> ro, rt;
  if (!d.reach_offsets.empty()) ro = b.CreateVector(d.reach_offsets);
  if (!d.reach_triangles.empty()) rt = b.CreateVector(d.reach_triangles);
  flatbuffers::Offset<flatbuffers::Vector<float>> bind;
  if (!d.bind_positions.empty()) bind = b.CreateVector(d.bind_positions);
  flatbuffers::Offset<flatbuffers::Vector<uint8_t>> kc, kw;
  flatbuffers::Offset<flatbuffers::Vector<uint16_t>> kj;
  if (!d.skin_counts.empty()) kc = b.CreateVector(d.skin_counts);
  if (!d.skin_joints.empty()) kj = b.CreateVector(d.skin_joints);
  if (!d.skin_weights.empty()) kw = b.CreateVector(d.skin_weights);
  flatbuffers::Offset<flatbuffers::Vector<flatbuffers::Offset<schema::RegionInfo>>> regions;
  if (!d.regions.empty()) {
    std::vector<flatbuffers::Offset<schema::RegionInfo>> list;
    for (const auto& [name, trunk] : d.regions)
      list.push_back(schema::CreateRegionInfo(b, b.CreateString(name), trunk ? schema::RegionKind::Trunk : schema::RegionKind::Limb));
    regions = b.CreateVector(list);
  }
  auto gen = b.CreateString("asset_builder.h");
  auto units = b.CreateString("unknown");
  schema::AssetBuilder ab(b);
  ab.add_schema_version(d.schema_version);
  ab.add_generator(gen);
  ab.add_fingerprint(fp);
  ab.add_units(units);
  ab.add_params(params);
  ab.add_spheres(spheres);
  ab.add_chains(chains_v);
  ab.add_excluded_pairs(excl);
  ab.add_triangle_spheres(ts);
  ab.add_surrounding_offsets(so);
  ab.add_surrounding_triangles(st);
  ab.add_pivot_triangles(pt);
  ab.add_pivot_vertices(pv);
  ab.add_pivot_frames(pf);
  if (!d.triangles.empty()) ab.add_triangles(tris);
  if (!d.weld_ids.empty()) ab.add_weld_ids(weld);
  if (!d.bind_positions.empty()) ab.add_bind_positions(bind);
  if (!(d.crease == -1.0f)) ab.add_crease(d.crease);
  if (!d.skin_counts.empty()) ab.add_skin_counts(kc);
  if (!d.skin_joints.empty()) ab.add_skin_joints(kj);
  if (!d.skin_weights.empty()) ab.add_skin_weights(kw);
  if (d.contact_margin != 0.0f) ab.add_contact_margin(d.contact_margin);
  if (!(d.fold_margin == -1.0f)) ab.add_fold_margin(d.fold_margin);  // NaN written too (loader tests)
  if (d.joint_count != 0) ab.add_joint_count(d.joint_count);
  if (!d.sphere_joints.empty()) ab.add_sphere_joints(sj);
  if (!d.sphere_joint_weights.empty()) ab.add_sphere_joint_weights(sw);
  if (!d.sphere_regions.empty()) ab.add_sphere_regions(sr);
  if (!d.triangle_regions.empty()) ab.add_triangle_regions(tr);
  if (!d.regions.empty()) ab.add_regions(regions);
  if (!d.reach_offsets.empty()) ab.add_reach_offsets(ro);
  if (!d.reach_triangles.empty()) ab.add_reach_triangles(rt);
  b.Finish(ab.Finish(), d.identifier.c_str());
  AlignedBytes out;
  out.assign(b.GetBufferPointer(), b.GetSize());
  return out;
}

/// Two tubes of 8 rings along x and y; `crossing`: they cross at the origin region, else tube B is
/// lifted by 10 units in z. Chains: {A ∪ B}, {A}, {B}.
inline AssetData TwoTubes(bool crossing, Mesh* mesh) {
  Tube a, bt;
  a.origin[0] = -4.2f;
  bt.origin[1] = -4.2f;
  bt.direction[0] = 0;
  bt.direction[1] = 1;
  if (!crossing) bt.origin[2] = 10.0f;
  return MakeTubes({a, bt}, {{0, 1}, {0}, {1}}, mesh);
}

/// One tube of 150 rings of 16 sides (2,400 nodes, 4,768 triangles, rings 0.6 apart) with bind positions
/// (Asset.bind_positions) equal to its mesh scaled by `bind_scale` about the origin, under a crease of 3.
/// At 1 (straight) a node's search out to the crease reaches its ring and the rings within 3 along the tube;
/// at 1e-3 (collapsed within 0.09 of the middle) every node reaches all 2,400, 5.76 million in all: past
/// NarrowPhaseModel::kReachPerNode (2,048) × 2,400 + kSweepSlack, so the narrow phase is refused.
inline AssetData CreaseTube(float bind_scale, Mesh* mesh) {
  Tube tube;
  tube.rings = 150;
  tube.sides = 16;
  tube.spacing = 0.6f;
  AssetData d = MakeTubes({tube}, {}, mesh);
  d.bind_positions = mesh->positions;
  for (float& x : d.bind_positions) x *= bind_scale;
  d.crease = 3.0f;
  return d;
}

/// Vertex i of `positions` transformed by rotation matrix R (row-major) and translation t.
inline std::vector<float> Transform(const std::vector<float>& positions, const float R[9], const float t[3]) {
  std::vector<float> out(positions.size());
  for (size_t i = 0; i < positions.size(); i += 3)
    for (int r = 0; r < 3; ++r)
      out[i + r] = R[3 * r] * positions[i] + R[3 * r + 1] * positions[i + 1] + R[3 * r + 2] * positions[i + 2] + t[r];
  return out;
}

}  // namespace spherechain::test
