// Device mirror of runtime/refit.h (BuildPivotFrame, PivotFrameToModel, PivotMeanDistance,
// TriangleCentroid) and of Context::Internal::Refit / the DetectJob overlap test (with its margin).
//
// refit.h's inline helpers are host-only (not __host__ __device__) and this backend may not edit
// them, so the formulas are transcribed here operation for operation, in the same order. The CUDA
// target is compiled with --fmad=false (no FMA contraction, IEEE division and square root by
// default), like the host build (-std=c++20 → -ffp-contract=off, no FMA on baseline x86-64), so the
// GPU spheres are expected to match the CPU ones bit for bit; the tests allow 1e-5 relative.
// KEEP IN SYNC with runtime/include/spherechain/runtime/refit.h, runtime/src/detect.cpp (the margin:
// JobMargin, the grown radii of DetectM1 / DetectM2, their depths) and runtime/src/kernels.inl (the CPU
// refit/detect kernels: the same formulas evaluated several spheres per instruction, bit-identical to
// refit.h's scalar helpers; its sqrt(max d²) for the frame scale equals max sqrt(d²) used here).
#pragma once

#include <cstdint>

#include "spherechain/cuda/asset.h"

namespace spherechain::cuda::detail {

/// TriangleCentroid: (a + b + c) · (1/3).
__device__ __forceinline__ void DevTriangleCentroid(const float a[3], const float b[3], const float c[3], float out[3]) {
#pragma unroll
  for (int k = 0; k < 3; ++k) out[k] = (a[k] + b[k] + c[k]) * (1.0f / 3.0f);
}

/// BuildPivotFrame (refit.h): origin = mean, x = normalize(p1 − p0), y = Gram–Schmidt of
/// (p2 + p3)/2 − (p0 + p1)/2, z = x × y; false when degenerate (eps = 1e-6 · (1 + max |p_k − o|)).
__device__ __forceinline__ bool DevBuildPivotFrame(const float p[4][3], float origin[3], float axes[3][3]) {
  float scale = 0.0f;
#pragma unroll
  for (int k = 0; k < 3; ++k) origin[k] = 0.25f * (p[0][k] + p[1][k] + p[2][k] + p[3][k]);
#pragma unroll
  for (int i = 0; i < 4; ++i) {
    const float dx = p[i][0] - origin[0], dy = p[i][1] - origin[1], dz = p[i][2] - origin[2];
    const float d = sqrtf(dx * dx + dy * dy + dz * dz);
    scale = d > scale ? d : scale;
  }
  const float eps = 1e-6f * (1.0f + scale);
  float x[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
  const float xl = sqrtf(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
  if (!(xl > eps)) return false;
#pragma unroll
  for (int k = 0; k < 3; ++k) x[k] /= xl;
  float w[3];
#pragma unroll
  for (int k = 0; k < 3; ++k) w[k] = 0.5f * (p[2][k] + p[3][k]) - 0.5f * (p[0][k] + p[1][k]);
  const float wx = w[0] * x[0] + w[1] * x[1] + w[2] * x[2];
#pragma unroll
  for (int k = 0; k < 3; ++k) w[k] -= wx * x[k];
  const float yl = sqrtf(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
  if (!(yl > eps)) return false;
#pragma unroll
  for (int k = 0; k < 3; ++k) w[k] /= yl;
#pragma unroll
  for (int k = 0; k < 3; ++k) {
    axes[0][k] = x[k];
    axes[1][k] = w[k];
  }
  axes[2][0] = x[1] * w[2] - x[2] * w[1];
  axes[2][1] = x[2] * w[0] - x[0] * w[2];
  axes[2][2] = x[0] * w[1] - x[1] * w[0];
  return true;
}

/// PivotMeanDistance: 0.25 · Σ_k ‖c − p_k‖ (summed in order k = 0..3).
__device__ __forceinline__ float DevPivotMeanDistance(const float p[4][3], const float c[3]) {
  float s = 0.0f;
#pragma unroll
  for (int i = 0; i < 4; ++i) {
    const float dx = c[0] - p[i][0], dy = c[1] - p[i][1], dz = c[2] - p[i][2];
    s += sqrtf(dx * dx + dy * dy + dz * dz);
  }
  return 0.25f * s;
}

/// Context::Internal::Refit for one sphere `s`: 12 vertex reads (strided, read-only path), the four
/// pivot centroids, then kPivotFrame (c = o + R·local, falling back to kPaper when degenerate) or
/// kPaper (c = mean(p) + centroid_offset); r = radius_scale · PivotMeanDistance(p, c).
/// Returns (x, y, z, r).
__device__ __forceinline__ float4 DevRefitSphere(const DeviceAssetDesc& a, const char* base, uint32_t stride,
                                                 uint32_t s, bool frame_mode) {
  float p[4][3];
  const uint32_t* idx = a.pivot_vertices + size_t{12} * s;
#pragma unroll
  for (int k = 0; k < 4; ++k) {
    float v[3][3];
#pragma unroll
    for (int t = 0; t < 3; ++t) {
      const float* q = reinterpret_cast<const float*>(base + size_t{__ldg(idx + 3 * k + t)} * stride);
      v[t][0] = __ldg(q);
      v[t][1] = __ldg(q + 1);
      v[t][2] = __ldg(q + 2);
    }
    DevTriangleCentroid(v[0], v[1], v[2], p[k]);
  }
  const float4 local = __ldg(a.frame_local + s);  // (local_center, radius_scale)
  float c[3];
  float origin[3], axes[3][3];
  if (frame_mode && DevBuildPivotFrame(p, origin, axes)) {
    const float l[3] = {local.x, local.y, local.z};
#pragma unroll
    for (int k = 0; k < 3; ++k) c[k] = origin[k] + l[0] * axes[0][k] + l[1] * axes[1][k] + l[2] * axes[2][k];
  } else {
    const float4 off = __ldg(a.frame_offset + s);
#pragma unroll
    for (int k = 0; k < 3; ++k) c[k] = 0.25f * (p[0][k] + p[1][k] + p[2][k] + p[3][k]);
    c[0] += off.x;
    c[1] += off.y;
    c[2] += off.z;
  }
  return make_float4(c[0], c[1], c[2], local.w * DevPivotMeanDistance(p, c));
}

/// The DetectJob overlap test for a < b with the contact margin m (DetectJob::margin resolved):
/// ‖c_b − c_a‖² < ((r_b + m) + (r_a + m))² (§5.2), the same operations in the same order as Overlap8 in
/// runtime/src/kernels.cpp on the radii DetectM1 / DetectM2 grow by m beforehand (r + m, one float add
/// each; with m == 0 that is r itself, as DetectM2's ungrown radii), so the pair set is the CPU's.
__device__ __forceinline__ bool DevOverlap(const float4& A, const float4& B, float m) {
  const float dx = B.x - A.x, dy = B.y - A.y, dz = B.z - A.z;
  const float rr = (B.w + m) + (A.w + m);
  return (dx * dx + dy * dy + dz * dz) < rr * rr;
}

/// Penetration depth of the spheres themselves, r_a + r_b − ‖c_b − c_a‖ (may be negative inside the
/// margin), rounded as the CPU method that reports it: `grow` = 0 as DetectM1 (own radii, the
/// expression MakeCollision uses); `grow` = m for DetectM2 with m ≠ 0, which subtracts the margins
/// again from the grown radii' depth: ((r_a + m) + (r_b + m) − ‖·‖) − 2m.
__device__ __forceinline__ float DevDepth(const float4& A, const float4& B, float grow) {
  const float dx = B.x - A.x, dy = B.y - A.y, dz = B.z - A.z;
  const float d = sqrtf(dx * dx + dy * dy + dz * dz);
  if (grow != 0.0f) return (A.w + grow) + (B.w + grow) - d - 2.0f * grow;
  return A.w + B.w - d;
}

/// True when (a, b), a < b, is an excluded (adjacent) pair: scan of a's sorted partner list.
__device__ __forceinline__ bool DevIsExcluded(const DeviceAssetDesc& d, uint32_t a, uint32_t b) {
  for (uint32_t i = __ldg(d.excl_offsets + a), e = __ldg(d.excl_offsets + a + 1); i < e; ++i) {
    const uint32_t n = d.excl_neighbors[i];
    if (n >= b) return n == b;
  }
  return false;
}

}  // namespace spherechain::cuda::detail
