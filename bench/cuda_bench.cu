// cuda_bench — spherechain::cuda refit + detect throughput for 1 … 100,000 character instances, side
// by side with the CPU runtime in the same run.
//
//   cuda_bench [ASSET.sphc [BASE.obj]] [--max-instances N] [--sizes N,N,...] [--source vertices|joints|both]
//              [--frames DIR] [--synthetic] [--strategies auto,sphere,chain,warp,boxes] [--no-cpu]
//     defaults: /tmp/mh.sphc and ${SPHERECHAIN_SHARED_DATA_DIR}/makehuman/base.obj (MakeHuman); when
//     either is missing (or --synthetic) a synthetic ~80-sphere, 6-chain tube character is used and
//     the header says so. --strategies: the rows to run (default all five); --no-cpu: no CPU columns
//     (a quicker run, e.g. to compare builds of the kernels on the same machine).
//
// Instances: the bind pose, each with its own rotation about the vertical axis, translation and
// per-vertex noise (generated on the device, one packed xyz buffer per instance, so N instances read
// N distinct buffers). From joints (RefitSource::kJoints, assets with joint weights): each instance's
// #J skinning matrices are that rotation and translation (the bind pose's skinning matrices are the
// identity) with a small per-joint translation noise, one packed buffer per instance.
// --frames DIR (`spherechain play --dump-frames DIR`: frame_NNNN.f32 and .joints): an animated crowd —
// instance i is recorded frame i mod F, moved by its rotation and translation, without noise.
// Per row (one frame = refit + detect for all N instances, one kernel launch):
//   GPU µs/frame   mean over graph replays timed with cudaEvents (throughput; launch cost amortised)
//   GPU latency    median wall-clock of one frame: cudaGraphLaunch + cudaStreamSynchronize
//   chars/s        N / (µs/frame)
//   GB/s           useful position bytes (12 vertices × 12 B per sphere) / frame time, and % of the
//                  device peak (2 × memory clock × bus width); the hardware moves 32 B sectors,
//                  so the DRAM traffic is higher than this figure. From joints: #J × 48 B per instance
//   CPU µs/frame   the runtime's RefitJob (JointRefitJob from joints) + DetectJob, one core, measured on min(N, 1000) instances
//                  and scaled to N (marked '*' when scaled)
//   CPU×T µs/frame the runtime's BatchJob over T = all hardware threads of this machine (std::thread,
//                  one task per 16 characters), measured on min(N, 10000) instances and scaled to N
//                  ('*'); "vs CPU×T" is that figure over the GPU's
// Targets (H100): 10,000 characters ≤ 200 µs/frame; 1 character ≤ 10 µs.
#include <cuda_runtime.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "cuda/cuda_test_util.h"

using namespace spherechain;
namespace sc = spherechain::cuda;

namespace {

#define CK(expr)                                                                                   \
  do {                                                                                             \
    const cudaError_t e_ = (expr);                                                                 \
    if (e_ != cudaSuccess) {                                                                       \
      std::fprintf(stderr, "%s:%d: %s: %s\n", __FILE__, __LINE__, #expr, cudaGetErrorString(e_)); \
      std::exit(1);                                                                                \
    }                                                                                              \
  } while (0)

__device__ uint32_t Hash(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}
__device__ float Unit(uint32_t h) { return float(h >> 8) * (1.0f / 16777216.0f) * 2.0f - 1.0f; }

// out[i] = R_y(angle_i) · rest + t_i + noise, instance i's buffer at out + i · V · 3.
// Instance i's #J matrices (3×4 row-major) at out + i · J · 12: [R_y(angle_i) | t_i + noise_j], the angle
// and translation of PerturbKernel's instance i.
// With `clip` (F frames of #J×12): [R_y | t] composed with frame i mod F's matrices.
double NowUs() {
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The launch floor: a kernel that does nothing, one block of one thread.
__global__ void EmptyKernel() {}

// A graph's timing: the median latency of 51 single frames (launch to the end of the stream's
// synchronisation, wall clock) and the mean of back-to-back replays over ~0.2 s timed with events.
struct GraphTiming {
  double latency_us, replay_us;
};
GraphTiming TimeGraph(cudaGraphExec_t exec, cudaStream_t stream, cudaEvent_t e0, cudaEvent_t e1) {
  std::vector<double> lat;
  for (int r = 0; r < 51; ++r) {
    const double t0 = NowUs();
    CK(cudaGraphLaunch(exec, stream));
    CK(cudaStreamSynchronize(stream));
    lat.push_back(NowUs() - t0);
  }
  std::nth_element(lat.begin(), lat.begin() + 25, lat.end());
  float probe_ms = 0;
  CK(cudaEventRecord(e0, stream));
  CK(cudaGraphLaunch(exec, stream));
  CK(cudaEventRecord(e1, stream));
  CK(cudaEventSynchronize(e1));
  CK(cudaEventElapsedTime(&probe_ms, e0, e1));
  const int reps = std::clamp(static_cast<int>(200.0 / std::max(probe_ms, 1e-3f)), 10, 20000);
  CK(cudaEventRecord(e0, stream));
  for (int r = 0; r < reps; ++r) CK(cudaGraphLaunch(exec, stream));
  CK(cudaEventRecord(e1, stream));
  CK(cudaEventSynchronize(e1));
  float ms = 0;
  CK(cudaEventElapsedTime(&ms, e0, e1));
  return {lat[25], 1e3 * ms / reps};
}

__global__ void JointsKernel(const float* clip, uint32_t F, float* out, uint32_t J, uint32_t N, float extent, float noise) {
  const uint64_t idx = uint64_t{blockIdx.x} * blockDim.x + threadIdx.x;
  if (idx >= uint64_t{J} * N) return;
  const uint32_t i = static_cast<uint32_t>(idx / J);
  const float ang = 3.14159265f * Unit(Hash(2 * i + 1));
  const float c = cosf(ang), s = sinf(ang);
  const float tx = extent * Unit(Hash(3 * i + 7)), tz = extent * Unit(Hash(5 * i + 11));
  const uint32_t h = Hash(static_cast<uint32_t>(idx) * 3u + 0x51ed270bu);
  const float m[12] = {c, 0, s, tx + noise * Unit(h), 0, 1, 0, noise * Unit(Hash(h)), -s, 0, c, tz + noise * Unit(Hash(h + 1))};
  if (!clip) {
    for (int e = 0; e < 12; ++e) out[idx * 12 + e] = m[e];
    return;
  }
  const float* q = clip + (uint64_t{i % F} * J + idx % J) * 12;
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 4; ++k)
      out[idx * 12 + 4 * r + k] = m[4 * r] * q[k] + m[4 * r + 1] * q[4 + k] + m[4 * r + 2] * q[8 + k] + (k == 3 ? m[4 * r + 3] : 0.0f);
}

// `rest`: F poses of #V×3 (instance i starts from pose i mod F).
__global__ void PerturbKernel(const float* rest, uint32_t F, float* out, uint32_t V, uint32_t N, float extent, float noise) {
  const uint64_t idx = uint64_t{blockIdx.x} * blockDim.x + threadIdx.x;
  if (idx >= uint64_t{V} * N) return;
  const uint32_t i = static_cast<uint32_t>(idx / V), v = static_cast<uint32_t>(idx % V);
  const float ang = 3.14159265f * Unit(Hash(2 * i + 1));
  const float c = cosf(ang), s = sinf(ang);
  const float tx = extent * Unit(Hash(3 * i + 7)), tz = extent * Unit(Hash(5 * i + 11));
  const float* pose = rest + uint64_t{i % F} * V * 3;
  const float x = pose[3 * v], y = pose[3 * v + 1], z = pose[3 * v + 2];
  const uint32_t h = Hash(static_cast<uint32_t>(idx) * 3u + 0x9e3779b9u);
  float* o = out + idx * 3;
  o[0] = c * x + s * z + tx + noise * Unit(h);
  o[1] = y + noise * Unit(Hash(h));
  o[2] = -s * x + c * z + tz + noise * Unit(Hash(h + 1));
}

// runtime::ParallelFor over std::thread (the GPU machine has no TBB): T threads pull task indices from an
// atomic counter. Threads are started per Run, a few tens of µs against the milliseconds of a 10,000-character
// batch; the N = 1 and 100 rows of the CPU×T column include that cost.
struct ThreadParallelFor {
  uint32_t threads = 1;
  static void Run(void* user, uint32_t count, runtime::ParallelFor::Task task, void* data) {
    const uint32_t t = std::min(static_cast<ThreadParallelFor*>(user)->threads, count);
    std::atomic<uint32_t> next{0};
    auto work = [&] {
      for (uint32_t i; (i = next.fetch_add(1, std::memory_order_relaxed)) < count;) task(data, i, i + 1);
    };
    std::vector<std::thread> pool;
    for (uint32_t k = 1; k < t; ++k) pool.emplace_back(work);
    work();
    for (auto& th : pool) th.join();
  }
};

}  // namespace

int main(int argc, char** argv) {
  std::string asset_path = "/tmp/mh.sphc", obj_path = std::string(SPHERECHAIN_SHARED_DATA_DIR) + "/makehuman/base.obj";
  uint32_t max_instances = 100000;
  std::vector<uint32_t> sizes = {1, 100, 1000, 10000, 100000};
  std::string source_arg = "both", frames_dir;
  bool synthetic = false, cpu = true;
  const char* strategy_names[] = {"auto", "thread/sphere", "block/chain", "warp/instance", "block/boxes"};
  const char* strategy_args[] = {"auto", "sphere", "chain", "warp", "boxes"};
  bool run_strategy[5] = {true, true, true, true, true};
  int positional = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--max-instances" && i + 1 < argc) max_instances = static_cast<uint32_t>(std::stoul(argv[++i]));
    else if (a == "--synthetic") synthetic = true;
    else if (a == "--source" && i + 1 < argc) source_arg = argv[++i];
    else if (a == "--frames" && i + 1 < argc) frames_dir = argv[++i];
    else if (a == "--no-cpu") cpu = false;
    else if (a == "--strategies" && i + 1 < argc) {
      const std::string list = "," + std::string(argv[++i]) + ",";
      for (int k = 0; k < 5; ++k) run_strategy[k] = list.find("," + std::string(strategy_args[k]) + ",") != std::string::npos;
    }
    else if (a == "--sizes" && i + 1 < argc) {
      sizes.clear();
      for (std::string list = argv[++i]; !list.empty();) {
        const size_t comma = list.find(',');
        sizes.push_back(static_cast<uint32_t>(std::stoul(list.substr(0, comma))));
        list = comma == std::string::npos ? "" : list.substr(comma + 1);
      }
    }
    else if (positional == 0) asset_path = a, ++positional;
    else obj_path = a, ++positional;
  }
  if (sc::DeviceAvailable() != sc::Status::kOk) {
    std::printf("SKIPPED: no CUDA device (%s)\n", sc::LastCudaErrorString());
    return 0;
  }
  int dev = 0, mem_khz = 0, bus_bits = 0, sms = 0;
  CK(cudaGetDevice(&dev));
  cudaDeviceProp prop{};
  CK(cudaGetDeviceProperties(&prop, dev));
  CK(cudaDeviceGetAttribute(&mem_khz, cudaDevAttrMemoryClockRate, dev));
  CK(cudaDeviceGetAttribute(&bus_bits, cudaDevAttrGlobalMemoryBusWidth, dev));
  CK(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, dev));
  const double peak_gbs = 2.0 * mem_khz * 1e3 * (bus_bits / 8.0) / 1e9;

  // ---- asset + rest positions --------------------------------------------------------------------
  test::AlignedBytes bytes;
  test::Mesh mesh;
  runtime::AssetView view;
  std::string source;
  if (!synthetic && test::ReadAlignedFile(asset_path, &bytes) &&
      runtime::LoadAsset(bytes.data(), bytes.size, &view) == runtime::Status::kOk) {
    mesh.positions = test::ObjPositions(obj_path, view.vertex_count);
    source = "MakeHuman " + asset_path;
    if (mesh.positions.empty()) view = {};
  }
  if (!view.valid()) {
    std::vector<test::Tube> tubes(6);
    for (uint32_t t = 0; t < 6; ++t) {
      const float ang = 3.14159265f * float(t) / 6.0f;
      tubes[t].direction[0] = std::cos(ang);
      tubes[t].direction[1] = std::sin(ang);
      tubes[t].rings = t < 2 ? 14 : 13;  // 80 spheres
      for (int k = 0; k < 2; ++k) tubes[t].origin[k] = -7.0f * tubes[t].direction[k];
      tubes[t].origin[2] = 0.4f * float(t);
    }
    mesh = {};
    const test::AssetData d = test::MakeTubes(tubes, {{0, 1}, {1, 2}, {2, 3}, {3, 4}, {4, 5}, {5, 0}}, &mesh);
    bytes = test::Serialize(d);
    if (runtime::LoadAsset(bytes.data(), bytes.size, &view) != runtime::Status::kOk) return 1;
    source = "SYNTHETIC 6-tube character (MakeHuman asset/obj not found: " + asset_path + ", " + obj_path + ")";
  }
  const uint32_t V = view.vertex_count, S = view.sphere_count;
  std::printf("cuda_bench: %s | #V %u  #S %u  chains %u\n", source.c_str(), V, S, view.chain_count);
  std::printf("device: %s, %d SMs, peak memory bandwidth %.0f GB/s (%d kHz x %d bit x 2)\n", prop.name, sms, peak_gbs,
              mem_khz, bus_bits);

  runtime::Model model;  // built once on the host; the device copy reads it
  runtime::Workspace ws;
  if (model.Init(view) != runtime::Status::kOk || ws.Init(model) != runtime::Status::kOk) return 1;
  sc::DeviceAsset asset;
  if (sc::Status s = asset.Upload(model); s != sc::Status::kOk) {
    std::printf("Upload failed: %s (%s)\n", sc::ToString(s), sc::LastCudaErrorString());
    return 1;
  }
  // Recorded frames (--frames): every frame_NNNN.f32 (#V×3) and, when all are there, frame_NNNN.joints (#J×12).
  std::vector<float> poses = mesh.positions, clip_joints;
  uint32_t F = 1;
  if (!frames_dir.empty()) {
    std::vector<std::string> files;
    for (const auto& e : std::filesystem::directory_iterator(frames_dir))
      if (e.path().extension() == ".f32") files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
    poses.clear();
    bool joints_ok = model.joint_count() > 0;
    for (const std::string& f : files) {
      std::vector<float> p(size_t{view.vertex_count} * 3), j(size_t{model.joint_count()} * 12);
      std::ifstream in(f, std::ios::binary), jin(std::filesystem::path(f).replace_extension(".joints"), std::ios::binary);
      in.read(reinterpret_cast<char*>(p.data()), std::streamsize(p.size() * 4));
      if (in.gcount() != std::streamsize(p.size() * 4)) return std::fprintf(stderr, "%s: not #V×3 float32\n", f.c_str()), 1;
      poses.insert(poses.end(), p.begin(), p.end());
      jin.read(reinterpret_cast<char*>(j.data()), std::streamsize(j.size() * 4));
      joints_ok = joints_ok && jin.gcount() == std::streamsize(j.size() * 4);
      clip_joints.insert(clip_joints.end(), j.begin(), j.end());
    }
    if (files.empty()) return std::fprintf(stderr, "%s: no frame_NNNN.f32\n", frames_dir.c_str()), 1;
    if (!joints_ok) clip_joints.clear();
    F = static_cast<uint32_t>(files.size());
    std::printf("instances: %u recorded frames of %s%s, each moved rigidly\n", F, frames_dir.c_str(),
                clip_joints.empty() ? " (no joint matrices: joint rows from the bind pose)" : "");
  }
  float* d_rest = nullptr;
  float* d_clip = nullptr;
  CK(cudaMalloc(&d_rest, poses.size() * 4));
  CK(cudaMemcpy(d_rest, poses.data(), poses.size() * 4, cudaMemcpyHostToDevice));
  if (!clip_joints.empty()) {
    CK(cudaMalloc(&d_clip, clip_joints.size() * 4));
    CK(cudaMemcpy(d_clip, clip_joints.data(), clip_joints.size() * 4, cudaMemcpyHostToDevice));
  }
  const float noise_scale = frames_dir.empty() ? 0.002f : 0.0f;
  float ymin = 1e30f, ymax = -1e30f;
  for (size_t i = 1; i < mesh.positions.size(); i += 3) ymin = std::min(ymin, mesh.positions[i]), ymax = std::max(ymax, mesh.positions[i]);
  const float height = std::max(ymax - ymin, 1.0f);

  cudaStream_t stream;
  CK(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking));
  cudaEvent_t e0, e1;
  CK(cudaEventCreate(&e0));
  CK(cudaEventCreate(&e1));

  const uint32_t hw_threads = std::max(1u, std::thread::hardware_concurrency());
  ThreadParallelFor pool{hw_threads};
  std::printf("CPU: %u hardware threads\n", hw_threads);
  {  // The launch floor: a graph of one empty kernel, timed as the rows' latency and µs/frame are.
    cudaGraph_t graph;
    cudaGraphExec_t exec;
    CK(cudaStreamBeginCapture(stream, cudaStreamCaptureModeGlobal));
    EmptyKernel<<<1, 1, 0, stream>>>();
    CK(cudaStreamEndCapture(stream, &graph));
    CK(cudaGraphInstantiate(&exec, graph, 0));
    const GraphTiming t = TimeGraph(exec, stream, e0, e1);
    std::printf("launch floor (a graph of one empty kernel): %.2f us a replay, latency %.2f us\n", t.replay_us, t.latency_us);
    CK(cudaGraphExecDestroy(exec));
    CK(cudaGraphDestroy(graph));
  }
  std::printf("\n%-6s %8s %-4s %-16s %12s %12s %14s %9s %7s %14s %8s %14s %9s %10s\n", "source", "N", "meth", "strategy", "GPU us/frame",
              "GPU latency", "chars/s", "GB/s", "%peak", "CPU us/frame", "speedup", "CPUxT us/frm", "vs CPUxT",
              "pairs/inst");
  const uint32_t J = model.joint_count();
  std::vector<runtime::RefitSource> sources;
  if (source_arg != "joints") sources.push_back(runtime::RefitSource::kVertices);
  if (source_arg != "vertices" && J > 0) sources.push_back(runtime::RefitSource::kJoints);
  if (source_arg == "joints" && J == 0) std::printf("no joint rows: the asset holds no joint weights\n");
  for (const runtime::RefitSource source : sources)
  for (uint32_t N : sizes) {
    if (N > max_instances) break;
    const bool from_joints = source == runtime::RefitSource::kJoints;
    size_t free_b = 0, total_b = 0;
    CK(cudaMemGetInfo(&free_b, &total_b));
    const size_t pos_bytes = from_joints ? size_t{N} * J * 48 : size_t{N} * V * 12;
    const uint32_t capacity = static_cast<uint32_t>(std::min<uint64_t>(uint64_t{N} * 128, 1u << 30));
    if (pos_bytes + size_t{capacity} * 16 + size_t{N} * S * 16 > free_b * 0.9) {
      std::printf("%8u  SKIPPED: needs %.1f GB of device memory, %.1f GB free\n", N, pos_bytes / 1e9, free_b / 1e9);
      continue;
    }
    float* d_pos = nullptr;
    CK(cudaMalloc(&d_pos, pos_bytes));
    const uint64_t threads = uint64_t{N} * (from_joints ? J : V);
    if (from_joints)
      JointsKernel<<<static_cast<uint32_t>((threads + 255) / 256), 256>>>(d_clip, F, d_pos, J, N, 2.0f * height,
                                                                          d_clip ? 0.0f : 0.002f * height);
    else
      PerturbKernel<<<static_cast<uint32_t>((threads + 255) / 256), 256>>>(d_rest, F, d_pos, V, N, 2.0f * height,
                                                                           noise_scale * height);
    CK(cudaGetLastError());
    CK(cudaDeviceSynchronize());
    std::vector<sc::Instance> inst(N);
    for (uint32_t i = 0; i < N; ++i)
      inst[i] = from_joints ? sc::Instance{nullptr, V, 12, 0, d_pos + size_t{i} * J * 12, J}
                            : sc::Instance{d_pos + size_t{i} * V * 3, V, 12, 0};
    const sc::DeviceAsset* assets[] = {&asset};
    sc::Batch batch;
    if (sc::Status s = batch.Init(assets, 1, inst.data(), N, capacity); s != sc::Status::kOk) {
      std::printf("%8u  Batch::Init failed: %s (%s)\n", N, sc::ToString(s), sc::LastCudaErrorString());
      CK(cudaFree(d_pos));
      continue;
    }
    // CPU: the runtime on min(N, 1000) of the same instances.
    const uint32_t cpu_n = std::min(N, 1000u), mt_n = std::min(N, 10000u);
    const size_t per_inst = from_joints ? size_t{J} * 12 : size_t{V} * 3;  // floats of one instance's input
    std::vector<float> host(size_t{mt_n} * per_inst);
    CK(cudaMemcpy(host.data(), d_pos, host.size() * 4, cudaMemcpyDeviceToHost));
    for (runtime::DetectMethod method : {runtime::DetectMethod::kM1, runtime::DetectMethod::kM2}) {
      std::vector<runtime::Collision> out(runtime::DetectBound(view, method));
      double best = 1e30;
      for (int rep = 0; rep < (cpu ? 3 : 0); ++rep) {
        const double t0 = NowUs();
        for (uint32_t i = 0; i < cpu_n; ++i) {
          runtime::RefitJob refit;
          refit.model = &model;
          refit.workspace = &ws;
          refit.positions = {host.data() + size_t{i} * per_inst, V, 12};
          runtime::JointRefitJob joint_refit;
          joint_refit.model = &model;
          joint_refit.workspace = &ws;
          joint_refit.joint_matrices = host.data() + size_t{i} * per_inst;
          joint_refit.joint_count = J;
          uint32_t n = 0;
          runtime::DetectJob det;
          det.model = &model;
          det.workspace = &ws;
          det.method = method;
          det.output = out.data();
          det.capacity = static_cast<uint32_t>(out.size());
          det.count = &n;
          if ((from_joints ? joint_refit.Run() : refit.Run()) != runtime::Status::kOk || runtime::Failed(det.Run())) return 1;
        }
        best = std::min(best, (NowUs() - t0) / cpu_n);
      }
      const double cpu_frame = cpu ? best * N : NAN;
      // All cores: one BatchJob over mt_n characters, each with its own workspace and output.
      std::vector<runtime::Workspace> mt_ws(cpu ? mt_n : 0);
      std::vector<runtime::CharacterFrame> frames(mt_n);
      std::vector<runtime::Collision> mt_out(size_t{mt_n} * out.size());
      std::vector<uint32_t> mt_count(mt_n);
      for (uint32_t i = 0; i < mt_ws.size(); ++i) {
        if (mt_ws[i].Init(model) != runtime::Status::kOk) return 1;
        frames[i].workspace = &mt_ws[i];
        if (from_joints)
          frames[i].joint_matrices = host.data() + size_t{i} * per_inst;
        else
          frames[i].positions = {host.data() + size_t{i} * per_inst, V, 12};
        frames[i].output = mt_out.data() + size_t{i} * out.size();
        frames[i].capacity = static_cast<uint32_t>(out.size());
        frames[i].count = &mt_count[i];
      }
      runtime::BatchJob bj;
      bj.model = &model;
      bj.characters = frames.data();
      bj.character_count = mt_n;
      bj.source = source;
      bj.joint_count = from_joints ? J : 0;
      bj.mode = runtime::RefitMode::kPivotFrame;
      bj.method = method;
      bj.parallel_for = {&ThreadParallelFor::Run, &pool};
      bj.parallel_grain = 16;
      double mt_best = 1e30;
      for (int rep = 0; rep < (cpu ? 3 : 0); ++rep) {
        const double t0 = NowUs();
        if (runtime::Failed(bj.Run())) return 1;
        mt_best = std::min(mt_best, NowUs() - t0);
      }
      const double mt_frame = cpu ? mt_best * N / mt_n : NAN;
      const bool m1 = method == runtime::DetectMethod::kM1;
      for (sc::Strategy strategy : {sc::Strategy::kAuto, sc::Strategy::kThreadPerSphere, sc::Strategy::kBlockPerChain,
                                    sc::Strategy::kWarpPerInstance, sc::Strategy::kBlockBoxes}) {
        if ((!m1 && strategy == sc::Strategy::kBlockPerChain) || !run_strategy[static_cast<int>(strategy)]) continue;
        sc::FrameParams fp{runtime::RefitMode::kPivotFrame, method, strategy, false};
        fp.source = source;
        if (batch.Run(fp, stream) != sc::Status::kOk) return 1;  // warm-up
        CK(cudaStreamSynchronize(stream));
        cudaGraph_t graph;
        cudaGraphExec_t exec;
        CK(cudaStreamBeginCapture(stream, cudaStreamCaptureModeGlobal));
        const sc::Status st = batch.Run(fp, stream);
        CK(cudaStreamEndCapture(stream, &graph));
        if (st != sc::Status::kOk) return 1;
        CK(cudaGraphInstantiate(&exec, graph, 0));
        const GraphTiming t = TimeGraph(exec, stream, e0, e1);
        const double us = t.replay_us;
        sc::HostResults res;
        const sc::Status ds = batch.Download(stream, &res);
        const double gbs = (from_joints ? batch.frame_joint_bytes() : batch.frame_position_bytes()) / (us * 1e-6) / 1e9;
        std::printf("%-6s %8u %-4s %-16s %12.2f %12.2f %14.3g %9.1f %6.1f%% %13.1f%s %8.1fx %13.1f%s %8.1fx %10.2f%s\n",
                    from_joints ? "joints" : "verts", N, m1 ? "M1" : "M2", strategy_names[static_cast<int>(strategy)], us, t.latency_us, N / (us * 1e-6), gbs,
                    100.0 * gbs / peak_gbs, cpu_frame, cpu_n < N ? "*" : " ", cpu_frame / us, mt_frame, mt_n < N ? "*" : " ",
                    mt_frame / us, double(res.total) / N,
                    ds == sc::Status::kOkTruncated ? " (overflow)" : "");
        CK(cudaGraphExecDestroy(exec));
        CK(cudaGraphDestroy(graph));
      }
    }
    batch.Release();
    CK(cudaFree(d_pos));
  }
  std::printf("\n* CPU time measured on 1000 instances (one core: RefitJob kPivotFrame, or JointRefitJob, + DetectJob) or\n"
              "  10000 (CPUxT: BatchJob of the same source, %u threads) and scaled to N.\n", hw_threads);
  CK(cudaFree(d_rest));
  if (d_clip) CK(cudaFree(d_clip));
  return 0;
}
