// Helpers shared by tests/cuda and bench/cuda_bench.cu: device check, CPU reference, random motions,
// the MakeHuman inputs (a baked .sphc + base.obj's `body` vertices in source order).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "runtime/asset_builder.h"
#include "spherechain/cuda/cuda.h"
#include "spherechain/runtime/runtime.h"

namespace spherechain::test {

/// Rest positions of an OBJ in the baker's vertex order for `vertex_count` vertices: every `v` when
/// the file has exactly that many, else the vertices referenced by faces of group `group`, in file
/// order (the MakeHuman importer's compaction). Empty when neither matches.
inline std::vector<float> ObjPositions(const std::string& path, uint32_t vertex_count, const std::string& group = "body") {
  std::ifstream in(path);
  if (!in) return {};
  std::vector<float> all;
  std::vector<uint8_t> used;
  std::string line;
  bool in_group = false;
  while (std::getline(in, line)) {
    if (line.size() > 2 && line[0] == 'v' && line[1] == ' ') {
      std::istringstream ss(line.substr(2));
      float x = 0, y = 0, z = 0;
      ss >> x >> y >> z;
      all.insert(all.end(), {x, y, z});
    } else if (line.size() > 1 && line[0] == 'g' && (line[1] == ' ' || line[1] == '\t')) {
      std::istringstream ss(line.substr(2));
      std::string t;
      in_group = false;
      while (ss >> t) in_group |= t == group;
    } else if (line.size() > 2 && line[0] == 'f' && line[1] == ' ' && in_group) {
      std::istringstream ss(line.substr(2));
      std::string t;
      while (ss >> t) {
        const long v = std::strtol(t.c_str(), nullptr, 10);
        const size_t idx = v > 0 ? size_t(v - 1) : all.size() / 3 + size_t(v);
        if (used.size() <= idx) used.resize(idx + 1, 0);
        used[idx] = 1;
      }
    }
  }
  if (all.size() == size_t{vertex_count} * 3) return all;
  std::vector<float> out;
  for (size_t v = 0; v < used.size() && 3 * v + 2 < all.size(); ++v)
    if (used[v]) out.insert(out.end(), {all[3 * v], all[3 * v + 1], all[3 * v + 2]});
  if (out.size() == size_t{vertex_count} * 3) return out;
  return {};
}

/// Random rotation (uniform quaternion) + translation in [-t, t]^3, then per-vertex noise in
/// [-noise, noise]^3. Row-major R.
inline std::vector<float> RandomMotion(const std::vector<float>& rest, std::mt19937& rng, float t, float noise) {
  std::normal_distribution<float> n01(0.0f, 1.0f);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  float q[4] = {n01(rng), n01(rng), n01(rng), n01(rng)};
  const float l = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (float& v : q) v /= l;
  const float w = q[0], x = q[1], y = q[2], z = q[3];
  const float R[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
                      2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
                      2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)};
  const float tr[3] = {t * u(rng), t * u(rng), t * u(rng)};
  std::vector<float> out = Transform(rest, R, tr);
  if (noise > 0)
    for (float& v : out) v += noise * u(rng);
  return out;
}

/// CPU reference for one instance: refit + detect with the runtime (all pairs, never truncated),
/// detect with DetectJob::margin = `margin` (< 0: the asset's).
struct CpuFrame {
  std::vector<runtime::Collision> pairs;
  std::vector<float> x, y, z, r;
};

inline CpuFrame CpuReference(const runtime::Model& model, runtime::Workspace& ws, const runtime::AssetView& view, const float* positions,
                             uint32_t stride_bytes, runtime::RefitMode mode, runtime::DetectMethod method,
                             float margin = -1.0f, float fold_margin = -1.0f) {
  CpuFrame f;
  runtime::RefitJob refit;
  refit.model = &model;
  refit.workspace = &ws;
  refit.mode = mode;
  refit.positions = {positions, view.vertex_count, stride_bytes};
  if (refit.Run() != runtime::Status::kOk) return f;
  const runtime::SphereArrays s = ws.spheres();
  f.x.assign(s.x, s.x + s.count);
  f.y.assign(s.y, s.y + s.count);
  f.z.assign(s.z, s.z + s.count);
  f.r.assign(s.r, s.r + s.count);
  f.pairs.resize(runtime::DetectBound(view, method));
  uint32_t n = 0;
  runtime::DetectJob det;
  det.model = &model;
  det.workspace = &ws;
  det.method = method;
  det.margin = margin;
  det.fold_margin = fold_margin;
  det.output = f.pairs.data();
  det.capacity = static_cast<uint32_t>(f.pairs.size());
  det.count = &n;
  if (det.Run() != runtime::Status::kOk) n = 0;
  f.pairs.resize(n);
  return f;
}

}  // namespace spherechain::test
