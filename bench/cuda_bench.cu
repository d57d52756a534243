// cuda_bench — spherechain::cuda refit + detect throughput for 1 … 100,000 character instances, side
// by side with the CPU runtime in the same run.
//
//   cuda_bench [ASSET.sphc [BASE.obj]] [--max-instances N] [--synthetic]
//     defaults: /tmp/mh.sphc and ${SPHERECHAIN_SHARED_DATA_DIR}/makehuman/base.obj (MakeHuman); when
//     either is missing (or --synthetic) a synthetic ~80-sphere, 6-chain tube character is used and
//     the header says so.
//
// Instances: the bind pose, each with its own rotation about the vertical axis, translation and
// per-vertex noise (generated on the device, one packed xyz buffer per instance, so N instances read
// N distinct buffers). Per row (one frame = refit + detect for all N instances, one kernel launch):
//   GPU µs/frame   mean over graph replays timed with cudaEvents (throughput; launch cost amortised)
//   GPU latency    median wall-clock of one frame: cudaGraphLaunch + cudaStreamSynchronize
//   chars/s        N / (µs/frame)
//   GB/s           useful position bytes (12 vertices × 12 B per sphere) / frame time, and % of the
//                  device peak (2 × memory clock × bus width); the hardware moves 32 B sectors,
//                  so the DRAM traffic is higher than this figure
//   CPU µs/frame   the runtime's RefitJob + DetectJob, one core, measured on min(N, 1000) instances
//                  and scaled to N (marked '*' when scaled)
// Targets (H100): 10,000 characters ≤ 200 µs/frame; 1 character ≤ 10 µs.
#include <cuda_runtime.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
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
__global__ void PerturbKernel(const float* rest, float* out, uint32_t V, uint32_t N, float extent, float noise) {
  const uint64_t idx = uint64_t{blockIdx.x} * blockDim.x + threadIdx.x;
  if (idx >= uint64_t{V} * N) return;
  const uint32_t i = static_cast<uint32_t>(idx / V), v = static_cast<uint32_t>(idx % V);
  const float ang = 3.14159265f * Unit(Hash(2 * i + 1));
  const float c = cosf(ang), s = sinf(ang);
  const float tx = extent * Unit(Hash(3 * i + 7)), tz = extent * Unit(Hash(5 * i + 11));
  const float x = rest[3 * v], y = rest[3 * v + 1], z = rest[3 * v + 2];
  const uint32_t h = Hash(static_cast<uint32_t>(idx) * 3u + 0x9e3779b9u);
  float* o = out + idx * 3;
  o[0] = c * x + s * z + tx + noise * Unit(h);
  o[1] = y + noise * Unit(Hash(h));
  o[2] = -s * x + c * z + tz + noise * Unit(Hash(h + 1));
}

double NowUs() {
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

int main(int argc, char** argv) {
  std::string asset_path = "/tmp/mh.sphc", obj_path = std::string(SPHERECHAIN_SHARED_DATA_DIR) + "/makehuman/base.obj";
  uint32_t max_instances = 100000;
  bool synthetic = false;
  int positional = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--max-instances" && i + 1 < argc) max_instances = static_cast<uint32_t>(std::stoul(argv[++i]));
    else if (a == "--synthetic") synthetic = true;
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
  float* d_rest = nullptr;
  CK(cudaMalloc(&d_rest, mesh.positions.size() * 4));
  CK(cudaMemcpy(d_rest, mesh.positions.data(), mesh.positions.size() * 4, cudaMemcpyHostToDevice));
  float ymin = 1e30f, ymax = -1e30f;
  for (size_t i = 1; i < mesh.positions.size(); i += 3) ymin = std::min(ymin, mesh.positions[i]), ymax = std::max(ymax, mesh.positions[i]);
  const float height = std::max(ymax - ymin, 1.0f);

  cudaStream_t stream;
  CK(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking));
  cudaEvent_t e0, e1;
  CK(cudaEventCreate(&e0));
  CK(cudaEventCreate(&e1));

  std::printf("\n%8s %-4s %-16s %12s %12s %14s %9s %7s %14s %8s %10s\n", "N", "meth", "strategy", "GPU us/frame",
              "GPU latency", "chars/s", "GB/s", "%peak", "CPU us/frame", "speedup", "pairs/inst");
  const char* strategy_names[] = {"auto", "thread/sphere", "block/chain", "warp/instance"};
  for (uint32_t N : {1u, 100u, 1000u, 10000u, 100000u}) {
    if (N > max_instances) break;
    size_t free_b = 0, total_b = 0;
    CK(cudaMemGetInfo(&free_b, &total_b));
    const size_t pos_bytes = size_t{N} * V * 12;
    const uint32_t capacity = static_cast<uint32_t>(std::min<uint64_t>(uint64_t{N} * 128, 1u << 30));
    if (pos_bytes + size_t{capacity} * 16 + size_t{N} * S * 16 > free_b * 0.9) {
      std::printf("%8u  SKIPPED: needs %.1f GB of device memory, %.1f GB free\n", N, pos_bytes / 1e9, free_b / 1e9);
      continue;
    }
    float* d_pos = nullptr;
    CK(cudaMalloc(&d_pos, pos_bytes));
    const uint64_t threads = uint64_t{N} * V;
    PerturbKernel<<<static_cast<uint32_t>((threads + 255) / 256), 256>>>(d_rest, d_pos, V, N, 2.0f * height, 0.002f * height);
    CK(cudaGetLastError());
    CK(cudaDeviceSynchronize());
    std::vector<sc::Instance> inst(N);
    for (uint32_t i = 0; i < N; ++i) inst[i] = {d_pos + size_t{i} * V * 3, V, 12, 0};
    const sc::DeviceAsset* assets[] = {&asset};
    sc::Batch batch;
    if (sc::Status s = batch.Init(assets, 1, inst.data(), N, capacity); s != sc::Status::kOk) {
      std::printf("%8u  Batch::Init failed: %s (%s)\n", N, sc::ToString(s), sc::LastCudaErrorString());
      CK(cudaFree(d_pos));
      continue;
    }
    // CPU: the runtime on min(N, 1000) of the same instances.
    const uint32_t cpu_n = std::min(N, 1000u);
    std::vector<float> host(size_t{cpu_n} * V * 3);
    CK(cudaMemcpy(host.data(), d_pos, host.size() * 4, cudaMemcpyDeviceToHost));
    for (runtime::DetectMethod method : {runtime::DetectMethod::kM1, runtime::DetectMethod::kM2}) {
      std::vector<runtime::Collision> out(runtime::DetectBound(view, method));
      double best = 1e30;
      for (int rep = 0; rep < 3; ++rep) {
        const double t0 = NowUs();
        for (uint32_t i = 0; i < cpu_n; ++i) {
          runtime::RefitJob refit;
          refit.model = &model;
          refit.workspace = &ws;
          refit.positions = {host.data() + size_t{i} * V * 3, V, 12};
          uint32_t n = 0;
          runtime::DetectJob det;
          det.model = &model;
          det.workspace = &ws;
          det.method = method;
          det.output = out.data();
          det.capacity = static_cast<uint32_t>(out.size());
          det.count = &n;
          if (refit.Run() != runtime::Status::kOk || runtime::Failed(det.Run())) return 1;
        }
        best = std::min(best, (NowUs() - t0) / cpu_n);
      }
      const double cpu_frame = best * N;
      const bool m1 = method == runtime::DetectMethod::kM1;
      for (sc::Strategy strategy : {sc::Strategy::kAuto, sc::Strategy::kThreadPerSphere, sc::Strategy::kBlockPerChain,
                                    sc::Strategy::kWarpPerInstance}) {
        if (!m1 && strategy == sc::Strategy::kBlockPerChain) continue;
        const sc::FrameParams fp{runtime::RefitMode::kPivotFrame, method, strategy, false};
        if (batch.Run(fp, stream) != sc::Status::kOk) return 1;  // warm-up
        CK(cudaStreamSynchronize(stream));
        cudaGraph_t graph;
        cudaGraphExec_t exec;
        CK(cudaStreamBeginCapture(stream, cudaStreamCaptureModeGlobal));
        const sc::Status st = batch.Run(fp, stream);
        CK(cudaStreamEndCapture(stream, &graph));
        if (st != sc::Status::kOk) return 1;
        CK(cudaGraphInstantiate(&exec, graph, 0));
        // Latency: one frame, launch to completion, median of 51.
        std::vector<double> lat;
        for (int r = 0; r < 51; ++r) {
          const double t0 = NowUs();
          CK(cudaGraphLaunch(exec, stream));
          CK(cudaStreamSynchronize(stream));
          lat.push_back(NowUs() - t0);
        }
        std::nth_element(lat.begin(), lat.begin() + 25, lat.end());
        // Throughput: back-to-back replays for ~0.2 s.
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
        const double us = 1e3 * ms / reps;
        sc::HostResults res;
        const sc::Status ds = batch.Download(stream, &res);
        const double gbs = batch.frame_position_bytes() / (us * 1e-6) / 1e9;
        std::printf("%8u %-4s %-16s %12.2f %12.2f %14.3g %9.1f %6.1f%% %13.1f%s %8.1fx %10.2f%s\n", N, m1 ? "M1" : "M2",
                    strategy_names[static_cast<int>(strategy)], us, lat[25], N / (us * 1e-6), gbs, 100.0 * gbs / peak_gbs,
                    cpu_frame, cpu_n < N ? "*" : " ", cpu_frame / us, double(res.total) / N,
                    ds == sc::Status::kOkTruncated ? " (overflow)" : "");
        CK(cudaGraphExecDestroy(exec));
        CK(cudaGraphDestroy(graph));
      }
    }
    batch.Release();
    CK(cudaFree(d_pos));
  }
  std::printf("\n* CPU time measured on 1000 instances and scaled to N (one core, RefitJob kPivotFrame + DetectJob).\n");
  CK(cudaFree(d_rest));
  return 0;
}
