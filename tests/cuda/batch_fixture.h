// doctest fixtures of the spherechain::cuda suites: the device check (visible SKIP), assets on host and
// device, device instance buffers, recorded animation frames, and the CPU == GPU comparison of one frame.
#pragma once

#include <doctest/doctest.h>

#include <cuda_runtime_api.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>

#include "cuda/cuda_test_util.h"
#include "test_data.h"

#define CUDA_REQUIRE(expr) REQUIRE_MESSAGE((expr) == cudaSuccess, #expr)

namespace spherechain::test {

namespace sc = spherechain::cuda;

/// True when a CUDA device is usable; otherwise a visible SKIPPED message (the test returns early).
inline bool RequireDevice() {
  if (sc::DeviceAvailable() == sc::Status::kOk) return true;
  Skip("no CUDA device (cudaGetDeviceCount: " + std::string(sc::LastCudaErrorString()) +
       ") — spherechain::cuda tests need a GPU");
  return false;
}

/// One asset on host (bytes, view, CPU model and workspace, rest positions) and device.
struct AssetSet {
  Mesh mesh;
  AlignedBytes bytes;
  runtime::AssetView view;
  runtime::Model model;   // the CPU model the device copy is uploaded from
  runtime::Workspace ws;  // a CPU character of it (the reference runs)
  sc::DeviceAsset device;
  std::vector<std::vector<float>> joint_frames;  // recorded clips: per frame #J×12 (frame_NNNN.joints), or none
};

/// Loads `set->bytes` into the view, the CPU model and workspace, and the device copy (from the model).
inline void LoadBytes(AssetSet* s) {
  REQUIRE(runtime::LoadAsset(s->bytes.data(), s->bytes.size, &s->view) == runtime::Status::kOk);
  REQUIRE(s->model.Init(s->view) == runtime::Status::kOk);
  REQUIRE(s->ws.Init(s->model) == runtime::Status::kOk);
  REQUIRE(s->device.Upload(s->model) == sc::Status::kOk);
  CHECK(s->device.contact_margin() == s->model.contact_margin());
  CHECK(s->device.fold_margin() == s->model.fold_margin());
  CHECK(s->device.joint_count() == s->model.joint_count());
}

inline void LoadSet(AssetSet* s, AssetData d) {
  s->bytes = Serialize(d);
  LoadBytes(s);
}

/// The baked MakeHuman asset the CUDA cases compare on: $SPHERECHAIN_MH_ASSET (scripts/gpu-check.sh, which
/// builds without the baker), else the test fixture's bake (tests/makehuman.sphc in the build folder: the
/// cli_bake_makehuman fixture, which the cuda cases require).
inline std::string MakeHumanAssetPath() {
  const char* env = std::getenv("SPHERECHAIN_MH_ASSET");
  return env && *env ? std::string(env) : std::string(SPHERECHAIN_BINARY_DIR) + "/tests/makehuman.sphc";
}

/// A baked .sphc file (e.g. MakeHumanAssetPath()).
inline void LoadFile(AssetSet* s, const std::string& path) {
  REQUIRE_MESSAGE(ReadAlignedFile(path, &s->bytes), path);
  LoadBytes(s);
}

/// A "star" of tubes crossing near the origin (many crossing pairs), chains mixing tubes; its
/// Asset.contact_margin is `contact_margin` (0: the field absent, as asset_builder.h writes it).
/// With `fold_margin` >= 0 it also has Asset.fold_margin and Asset.sphere_regions: tube i is region i % 3.
/// With `joints` > 0 it has joint weights (schema v3) over that many joints: sphere k follows 1 + k % 4
/// influences (fewer when `joints` < 4), distinct joints, random weights descending and summing to 1.
inline void MakeStar(AssetSet* s, uint32_t tubes, uint32_t rings, float contact_margin = 0.0f,
                     float fold_margin = -1.0f, uint32_t joints = 0) {
  std::vector<Tube> ts;
  for (uint32_t i = 0; i < tubes; ++i) {
    Tube t;
    const float ang = 3.14159265f * float(i) / float(tubes);
    t.direction[0] = std::cos(ang);
    t.direction[1] = std::sin(ang);
    t.direction[2] = 0.1f * float(i % 3);
    const float l = std::sqrt(1.0f + t.direction[2] * t.direction[2]);
    for (float& v : t.direction) v /= l;
    for (int k = 0; k < 3; ++k) t.origin[k] = -0.5f * t.spacing * float(rings - 1) * t.direction[k];
    t.origin[2] += 0.3f * float(i);
    t.rings = rings;
    t.sphere_scale = 1.0f + 0.05f * float(i);
    ts.push_back(t);
  }
  std::vector<std::vector<uint32_t>> chains;
  for (uint32_t i = 0; i < tubes; ++i) chains.push_back({i, (i + 1) % tubes});
  chains.push_back({0});
  AssetData d = MakeTubes(ts, chains, &s->mesh);
  d.contact_margin = contact_margin;
  if (fold_margin >= 0.0f) {
    d.fold_margin = fold_margin;
    const uint32_t S = static_cast<uint32_t>(d.spheres.size());
    d.sphere_regions.assign(S, 0);
    for (uint32_t t = 0; t < tubes; ++t)
      for (uint32_t k = d.tube_first_sphere[t], e = t + 1 < tubes ? d.tube_first_sphere[t + 1] : S; k < e; ++k)
        d.sphere_regions[k] = static_cast<uint8_t>(t % 3);
  }
  if (joints > 0) {
    std::mt19937 rng(1234u + joints);
    std::uniform_real_distribution<float> u(0.05f, 1.0f);
    const uint32_t S = static_cast<uint32_t>(d.spheres.size());
    d.joint_count = joints;
    d.sphere_joints.assign(size_t{4} * S, 0);
    d.sphere_joint_weights.assign(size_t{4} * S, 0.0f);
    for (uint32_t k = 0; k < S; ++k) {
      const uint32_t n = std::min(1 + k % 4, joints);
      float w[4] = {};
      float sum = 0.0f;
      for (uint32_t i = 0; i < n; ++i) sum += w[i] = u(rng);
      std::sort(w, w + n, std::greater<float>());
      for (uint32_t i = 0; i < n; ++i) {  // n <= joints: distinct joints
        d.sphere_joints[4 * k + i] = static_cast<uint16_t>((k + i) % joints);
        d.sphere_joint_weights[4 * k + i] = w[i] / sum;
      }
    }
  }
  s->bytes = Serialize(d);
  LoadBytes(s);
}

/// Instances on the device: one allocation, instance i at its own offset with its own stride.
struct DeviceInstances {
  std::vector<std::vector<float>> host;  // packed xyz per instance (CPU input)
  std::vector<sc::Instance> table;
  std::vector<uint32_t> strides;
  void* buffer = nullptr;
  std::vector<size_t> offsets;
  std::vector<std::vector<float>> joints;  // per instance #J×12 (RefitSource::kJoints input), or none
  float* joint_buffer = nullptr;
  ~DeviceInstances() {
    if (buffer) (void)cudaFree(buffer);
    if (joint_buffer) (void)cudaFree(joint_buffer);
  }
  // Copies `joints` (one #J×12 set per instance, #J of the instance's asset) to the device and points the
  // table's joint_matrices / joint_count at them (allocated on the first call; later calls reuse it).
  void UploadJoints() {
    REQUIRE(joints.size() == table.size());
    size_t total = 0;
    for (const auto& j : joints) total += j.size();
    if (!joint_buffer) CUDA_REQUIRE(cudaMalloc(reinterpret_cast<void**>(&joint_buffer), std::max<size_t>(total, 1) * 4));
    size_t off = 0;
    for (size_t i = 0; i < joints.size(); ++i) {
      CUDA_REQUIRE(cudaMemcpy(joint_buffer + off, joints[i].data(), joints[i].size() * 4, cudaMemcpyHostToDevice));
      table[i].joint_matrices = joint_buffer + off;
      table[i].joint_count = static_cast<uint32_t>(joints[i].size() / 12);
      off += joints[i].size();
    }
  }
  void Build(const std::vector<AssetSet*>& assets, uint32_t n, uint32_t seed, bool rest = false) {
    std::mt19937 rng(seed);
    size_t total = 0;
    for (uint32_t i = 0; i < n; ++i) {
      AssetSet& a = *assets[i % assets.size()];
      host.push_back(rest ? a.mesh.positions : RandomMotion(a.mesh.positions, rng, 20.0f, 0.05f));
      strides.push_back(i % 3 == 2 ? 16u : 12u);
      offsets.push_back(total);
      total += size_t{a.view.vertex_count} * strides.back();
      total = (total + 15) & ~size_t{15};
    }
    CUDA_REQUIRE(cudaMalloc(&buffer, total));
    Upload();
    for (uint32_t i = 0; i < n; ++i)
      table.push_back({static_cast<char*>(buffer) + offsets[i], assets[i % assets.size()]->view.vertex_count, strides[i],
                       static_cast<uint32_t>(i % assets.size())});
  }
  // Writes host[i] into the device buffer with instance i's stride (padding lanes = NaN).
  void Upload() {
    for (size_t i = 0; i < host.size(); ++i) {
      const uint32_t fl = strides[i] / 4, nv = static_cast<uint32_t>(host[i].size() / 3);
      std::vector<float> s(size_t{nv} * fl, std::nanf(""));
      for (uint32_t v = 0; v < nv; ++v) std::memcpy(&s[size_t{v} * fl], &host[i][3 * size_t{v}], 12);
      CUDA_REQUIRE(cudaMemcpy(static_cast<char*>(buffer) + offsets[i], s.data(), s.size() * 4, cudaMemcpyHostToDevice));
    }
  }
};

inline bool NearRel(float a, float b, float tol = 1e-5f) {
  return std::fabs(a - b) <= tol * std::max(1.0f, std::max(std::fabs(a), std::fabs(b)));
}

/// The margin instance spheres of `a` are tested with under `fp` (as DetectJob's: < 0 the asset's).
inline float FrameMargin(const AssetSet& a, const sc::FrameParams& fp) {
  return fp.margin < 0.0f ? a.model.contact_margin() : fp.margin;
}

/// The fold margin of `a` under `fp` (as DetectJob's: < 0 the asset's; < 0 result: none).
inline float FrameFoldMargin(const AssetSet& a, const sc::FrameParams& fp) {
  return a.model.fold_margin() < 0.0f ? -1.0f : fp.fold_margin < 0.0f ? a.model.fold_margin() : fp.fold_margin;
}

/// Checks the GPU frame against the CPU runtime (RefitJob, or JointRefitJob for fp.source == kJoints, then
/// DetectJob with fp.margin and fp.fold_margin) for every instance, bit for bit: the spheres (when
/// written) equal as floats, the pairs the same set with the same chains mask and the same depth. A pair
/// that differs is reported as borderline when it is within rounding of the test on the CPU spheres
/// (|d² − (ra+rb+2m)²| ≤ 1e-5 (ra+rb+2m)², m the pair's margin) — still a failure, but the message says so.
inline void CompareWithCpu(const std::vector<AssetSet*>& assets, const DeviceInstances& inst, const sc::HostResults& gpu,
                           const sc::Batch& batch, const sc::FrameParams& fp) {
  std::vector<std::map<std::pair<int, int>, runtime::Collision>> by_inst(inst.host.size());
  for (const sc::BatchCollision& c : gpu.pairs) {
    REQUIRE(c.instance < inst.host.size());
    CHECK(by_inst[c.instance].emplace(std::make_pair(int(c.pair.a), int(c.pair.b)), c.pair).second);  // no duplicates
  }
  size_t borderline = 0, cpu_total = 0;
  for (size_t i = 0; i < inst.host.size(); ++i) {
    AssetSet& a = *assets[inst.table[i].asset];
    const float m = FrameMargin(a, fp), fold = FrameFoldMargin(a, fp);
    const bool from_joints = fp.source == runtime::RefitSource::kJoints;
    REQUIRE((!from_joints || i < inst.joints.size()));
    const CpuFrame cpu = CpuReference(a.model, a.ws, a.view, inst.host[i].data(), 12, fp.mode, fp.method, fp.margin,
                                      a.model.fold_margin() < 0.0f ? -1.0f : fp.fold_margin,
                                      from_joints ? inst.joints[i].data() : nullptr);
    REQUIRE(cpu.x.size() == a.view.sphere_count);
    cpu_total += cpu.pairs.size();
    if (fp.write_spheres) {
      const uint32_t off = batch.sphere_offset(static_cast<uint32_t>(i));
      for (uint32_t s = 0; s < a.view.sphere_count; ++s) {
        const float4 g = gpu.spheres[off + s];
        const bool ok = g.x == cpu.x[s] && g.y == cpu.y[s] && g.z == cpu.z[s] && g.w == cpu.r[s];
        if (!ok) {
          FAIL_CHECK("instance " << i << " sphere " << s << ": gpu (" << g.x << ", " << g.y << ", " << g.z << ", " << g.w
                                 << ") cpu (" << cpu.x[s] << ", " << cpu.y[s] << ", " << cpu.z[s] << ", " << cpu.r[s] << ")");
          break;
        }
      }
    }
    CHECK(gpu.instance_counts[i] == by_inst[i].size());
    auto borderline_pair = [&](int pa, int pb) {
      const float dx = cpu.x[pb] - cpu.x[pa], dy = cpu.y[pb] - cpu.y[pa], dz = cpu.z[pb] - cpu.z[pa];
      const float mp = fold >= 0.0f && a.model.fold_region(pa) == a.model.fold_region(pb) ? fold : m;
      const float rr = (cpu.r[pa] + mp) + (cpu.r[pb] + mp);
      return std::fabs(dx * dx + dy * dy + dz * dz - rr * rr) <= 1e-5f * rr * rr;
    };
    std::set<std::pair<int, int>> cpu_set;
    for (const runtime::Collision& c : cpu.pairs) {
      cpu_set.insert({c.a, c.b});
      auto it = by_inst[i].find({c.a, c.b});
      if (it == by_inst[i].end()) {
        if (borderline_pair(c.a, c.b)) { ++borderline; continue; }
        FAIL_CHECK("instance " << i << ": CPU pair (" << c.a << ", " << c.b << ") missing on the GPU");
        continue;
      }
      CHECK(it->second.chains == c.chains);
      CHECK(it->second.depth == c.depth);
    }
    for (const auto& [key, c] : by_inst[i])
      if (!cpu_set.count(key)) {
        if (borderline_pair(key.first, key.second)) { ++borderline; continue; }
        FAIL_CHECK("instance " << i << ": GPU pair (" << key.first << ", " << key.second << ") not on the CPU");
      }
  }
  CHECK(gpu.total == gpu.pairs.size());
  CHECK_FALSE(gpu.overflow);
  CHECK_MESSAGE(borderline == 0, borderline << " pairs differ from the CPU's (within rounding of the test)");
  MESSAGE("compared " << inst.host.size() << " instances, " << cpu_total << " CPU pairs, " << borderline
                      << " borderline differences (margin " << fp.margin << ", fold margin " << fp.fold_margin << ")");
}

/// Mean bind radius of an asset (a scale for margins of synthetic assets, whose own margin is 0).
inline float MeanBindRadius(const AssetSet& a) {
  double sum = 0.0;
  for (uint32_t s = 0; s < a.view.sphere_count; ++s) sum += a.view.asset->spheres()->Get(s)->radius();
  return static_cast<float>(sum / a.view.sphere_count);
}

/// The smallest batch over the many-instance threshold of this device (Batch::Run: fewer than 4 instances
/// an SM run the few-instance kernels, several blocks an instance): 4 · SMs + 1.
inline uint32_t ManyInstanceCrowd() {
  int dev_id = 0, sms = 0;
  CUDA_REQUIRE(cudaGetDevice(&dev_id));
  CUDA_REQUIRE(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, dev_id));
  return 4u * static_cast<uint32_t>(sms) + 1u;
}

/// Every (method, strategy) a batch runs: M1 with each strategy, M2 with all but kBlockPerChain (M1 only).
inline std::vector<std::pair<runtime::DetectMethod, sc::Strategy>> MethodStrategies() {
  std::vector<std::pair<runtime::DetectMethod, sc::Strategy>> out;
  for (runtime::DetectMethod method : {runtime::DetectMethod::kM1, runtime::DetectMethod::kM2})
    for (sc::Strategy strategy : {sc::Strategy::kThreadPerSphere, sc::Strategy::kBlockPerChain, sc::Strategy::kWarpPerInstance,
                                  sc::Strategy::kBlockBoxes})
      if (strategy != sc::Strategy::kBlockPerChain || method == runtime::DetectMethod::kM1) out.push_back({method, strategy});
  return out;
}

/// Runs one frame of `batch` with `fp` (spheres written), downloads it and checks it against the CPU
/// (CompareWithCpu: DetectJob with fp's margins for each instance). Returns the frame.
inline sc::HostResults RunCompared(const std::vector<AssetSet*>& assets, const DeviceInstances& inst,
                                   const sc::Batch& batch, sc::FrameParams fp) {
  fp.write_spheres = true;
  const sc::Status st = batch.Run(fp, 0);
  REQUIRE_MESSAGE(st == sc::Status::kOk, std::string(sc::ToString(st)) << " / " << std::string(sc::LastCudaErrorString()));
  sc::HostResults res;
  REQUIRE(batch.Download(0, &res, true) == sc::Status::kOk);
  CompareWithCpu(assets, inst, res, batch, fp);
  return res;
}

/// Recorded animation frames (`spherechain play ... --dump-frames DIR`: frame_NNNN.f32, #V×3 float32, and
/// for a rigged asset frame_NNNN.joints, #J×12 float32, loaded into set.joint_frames)
/// named by SPHERECHAIN_GPU_FRAMES="a.sphc=framesdir;b.sphc=framesdir2" (scripts/gpu-carry.sh prepares
/// the MakeHuman morph, the CesiumMan walk and the BCN_Epileptic clip): calls `fn(set, frames)` per readable item, the asset
/// loaded and set.mesh.positions = frames[0]. Returns the number of items; 0 after a visible SKIPPED
/// message when the variable is unset.
inline size_t ForEachRecordedClip(const std::function<void(AssetSet&, const std::vector<std::vector<float>>&)>& fn) {
  const char* env = std::getenv("SPHERECHAIN_GPU_FRAMES");
  if (!env || !*env) {
    MESSAGE("SKIPPED: set SPHERECHAIN_GPU_FRAMES=asset.sphc=frames_dir[;...] (see scripts/gpu-carry.sh)");
    return 0;
  }
  const std::string spec = env;
  size_t start = 0, clips = 0;
  spherechain::test::SomeInputs inputs;
  while (start < spec.size()) {
    const size_t end = std::min(spec.find(';', start), spec.size());
    const std::string item = spec.substr(start, end - start);
    start = end + 1;
    const size_t eq = item.find('=');
    REQUIRE(eq != std::string::npos);
    const std::string asset_path = item.substr(0, eq), dir = item.substr(eq + 1);
    if (!inputs.Found(asset_path) || !inputs.Found(dir)) continue;
    AssetSet set;
    LoadFile(&set, asset_path);
    std::vector<std::string> files;
    for (const auto& e : std::filesystem::directory_iterator(dir))
      if (e.path().extension() == ".f32") files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
    REQUIRE(!files.empty());
    std::vector<std::vector<float>> frames;
    for (const std::string& f : files) {
      std::ifstream in(f, std::ios::binary);
      std::vector<float> p(size_t{set.view.vertex_count} * 3);
      in.read(reinterpret_cast<char*>(p.data()), std::streamsize(p.size() * sizeof(float)));
      REQUIRE_MESSAGE(in.gcount() == std::streamsize(p.size() * sizeof(float)), f << " is not #V×3 float32");
      frames.push_back(std::move(p));
    }
    set.mesh.positions = frames[0];
    const uint32_t J = set.model.joint_count();
    bool all_joints = J > 0;
    for (const std::string& f : files)
      all_joints = all_joints && std::filesystem::exists(std::filesystem::path(f).replace_extension(".joints"));
    for (const std::string& f : files) {
      if (!all_joints) break;
      const std::string jf = std::filesystem::path(f).replace_extension(".joints").string();
      std::ifstream in(jf, std::ios::binary);
      std::vector<float> m(size_t{J} * 12);
      in.read(reinterpret_cast<char*>(m.data()), std::streamsize(m.size() * sizeof(float)));
      REQUIRE_MESSAGE(in.gcount() == std::streamsize(m.size() * sizeof(float)), jf << " is not #J×12 float32");
      set.joint_frames.push_back(std::move(m));
    }
    fn(set, frames);
    MESSAGE(asset_path << ": " << frames.size() << " recorded frames, CPU == GPU");
    ++clips;
  }
  return clips;
}

/// Device instances holding `frames`, one instance per frame (all of asset slot 0).
inline void BuildFrameInstances(AssetSet& set, const std::vector<std::vector<float>>& frames, DeviceInstances* inst) {
  inst->Build({&set}, static_cast<uint32_t>(frames.size()), 1u, /*rest=*/true);
  for (size_t i = 0; i < frames.size(); ++i) inst->host[i] = frames[i];
  inst->Upload();
}

}  // namespace spherechain::test
