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

/// \#J skinning matrices (3×4 row-major, JointRefitJob's layout): one random rigid motion of the whole
/// body (uniform rotation, translation in [-t, t]^3) composed with a small random rotation per joint
/// (each quaternion component perturbed by up to `wobble`) about the origin, so spheres of different
/// joints move apart or into each other.
inline std::vector<float> RandomJointMatrices(uint32_t joint_count, std::mt19937& rng, float t, float wobble) {
  std::normal_distribution<float> n01(0.0f, 1.0f);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  auto rotation = [](float w, float x, float y, float z, float* R) {
    const float l = std::sqrt(w * w + x * x + y * y + z * z);
    w /= l, x /= l, y /= l, z /= l;
    const float r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
                        2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
                        2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)};
    std::copy(r, r + 9, R);
  };
  float G[9];
  rotation(n01(rng), n01(rng), n01(rng), n01(rng), G);
  const float tr[3] = {t * u(rng), t * u(rng), t * u(rng)};
  std::vector<float> out(size_t{joint_count} * 12);
  for (uint32_t j = 0; j < joint_count; ++j) {
    float L[9];
    rotation(1.0f, wobble * u(rng), wobble * u(rng), wobble * u(rng), L);
    float* m = out.data() + size_t{j} * 12;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) m[4 * r + c] = G[3 * r] * L[c] + G[3 * r + 1] * L[3 + c] + G[3 * r + 2] * L[6 + c];
      m[4 * r + 3] = tr[r];
    }
  }
  return out;
}

/// CPU reference for one instance: refit + detect with the runtime (all pairs, never truncated),
/// detect with DetectJob::margin = `margin` (< 0: the asset's). With `joint_matrices` (\#J × 12 floats) the
/// refit is JointRefitJob's from them instead of RefitJob's from `positions`.
struct CpuFrame {
  std::vector<runtime::Collision> pairs;
  std::vector<float> x, y, z, r;
};

inline CpuFrame CpuReference(const runtime::Model& model, runtime::Workspace& ws, const runtime::AssetView& view, const float* positions,
                             uint32_t stride_bytes, runtime::RefitMode mode, runtime::DetectMethod method,
                             float margin = -1.0f, float fold_margin = -1.0f, const float* joint_matrices = nullptr) {
  CpuFrame f;
  runtime::RefitJob refit;
  refit.model = &model;
  refit.workspace = &ws;
  refit.mode = mode;
  refit.positions = {positions, view.vertex_count, stride_bytes};
  runtime::JointRefitJob joint_refit;
  joint_refit.model = &model;
  joint_refit.workspace = &ws;
  joint_refit.joint_matrices = joint_matrices;
  joint_refit.joint_count = model.joint_count();
  if ((joint_matrices ? joint_refit.Run() : refit.Run()) != runtime::Status::kOk) return f;
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
