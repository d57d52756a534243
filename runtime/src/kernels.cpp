// SIMD kernels of RefitJob, DetectJob and JointRefitJob (see internal.h): kernels.inl and kernels_x86.inl
// compiled for SSE2 (baseline x86-64) and AVX, kernels_avx512.inl for AVX-512 (function-level targets,
// one set chosen at Model::Init), or scalar on other targets.
#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "avx512_target.h"
#include "internal.h"

#if defined(__GNUC__) && defined(__x86_64__)
#define SPHERECHAIN_X86_KERNELS 1
#include <immintrin.h>
#endif

namespace spherechain::runtime::kernels {

#if SPHERECHAIN_X86_KERNELS

namespace sse {
using V = __m128;
using M = __m128;
constexpr uint32_t kW = 4;
inline V Set1(float v) { return _mm_set1_ps(v); }
inline V Load(const float* p) { return _mm_loadu_ps(p); }
inline void Store(float* p, V v) { _mm_storeu_ps(p, v); }
inline V Sqrt(V v) { return _mm_sqrt_ps(v); }
inline M Gt(V a, V b) { return _mm_cmpgt_ps(a, b); }
inline M And(M a, M b) { return _mm_and_ps(a, b); }
inline V Blend(M m, V a, V b) { return _mm_or_ps(_mm_and_ps(m, a), _mm_andnot_ps(m, b)); }
inline V Min(V a, V b) { return _mm_min_ps(a, b); }
inline V Max(V a, V b) { return _mm_max_ps(a, b); }
inline V Abs(V a) { return _mm_andnot_ps(_mm_set1_ps(-0.0f), a); }
inline uint32_t LtMask(V a, V b) { return static_cast<uint32_t>(_mm_movemask_ps(_mm_cmplt_ps(a, b))); }
struct Ops {  // formulas.inl's lane interface
  using V = __m128;
  using M = __m128;
  static V Set1(float v) { return _mm_set1_ps(v); }
  static V Sqrt(V v) { return _mm_sqrt_ps(v); }
  static M Gt(V a, V b) { return _mm_cmpgt_ps(a, b); }
  static M Lt(V a, V b) { return _mm_cmplt_ps(a, b); }
  static M And(M a, M b) { return _mm_and_ps(a, b); }
  static V Blend(M m, V a, V b) { return _mm_or_ps(_mm_and_ps(m, a), _mm_andnot_ps(m, b)); }
};
#include "spherechain/runtime/formulas.inl"
#include "kernels_x86.inl"
inline void PivotCentroids(const RefitArgs& a, uint32_t s0, uint32_t n, V px[4], V py[4], V pz[4]) {
  PivotCentroids4(a, s0, n, s0, px, py, pz);  // pad lanes: lane 0's sphere
}
inline uint32_t Overlap4(V xi, V yi, V zi, V ri, const float* x, const float* y, const float* z, const float* r) {
  return static_cast<uint32_t>(_mm_movemask_ps(OverlapLanes<Ops>(xi, yi, zi, ri, Load(x), Load(y), Load(z), Load(r))));
}
inline uint32_t Overlap8(V xi, V yi, V zi, V ri, const float* x, const float* y, const float* z, const float* r) {
  return Overlap4(xi, yi, zi, ri, x, y, z, r) | Overlap4(xi, yi, zi, ri, x + 4, y + 4, z + 4, r + 4) << 4;
}
#include "kernels.inl"
}  // namespace sse

namespace avx {  // every AVX CPU has POPCNT (HasAvx checks both)
#ifdef __clang__
#pragma clang attribute push(__attribute__((target("avx,popcnt"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx,popcnt")
#endif
using V = __m256;
using M = __m256;
constexpr uint32_t kW = 8;
inline V Set1(float v) { return _mm256_set1_ps(v); }
inline V Load(const float* p) { return _mm256_loadu_ps(p); }
inline void Store(float* p, V v) { _mm256_storeu_ps(p, v); }
inline V Sqrt(V v) { return _mm256_sqrt_ps(v); }
inline M Gt(V a, V b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }
inline M And(M a, M b) { return _mm256_and_ps(a, b); }
inline V Blend(M m, V a, V b) { return _mm256_blendv_ps(b, a, m); }
inline V Min(V a, V b) { return _mm256_min_ps(a, b); }
inline V Max(V a, V b) { return _mm256_max_ps(a, b); }
inline V Abs(V a) { return _mm256_andnot_ps(_mm256_set1_ps(-0.0f), a); }
inline uint32_t LtMask(V a, V b) { return static_cast<uint32_t>(_mm256_movemask_ps(_mm256_cmp_ps(a, b, _CMP_LT_OQ))); }
struct Ops {  // formulas.inl's lane interface
  using V = __m256;
  using M = __m256;
  static V Set1(float v) { return _mm256_set1_ps(v); }
  static V Sqrt(V v) { return _mm256_sqrt_ps(v); }
  static M Gt(V a, V b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }
  static M Lt(V a, V b) { return _mm256_cmp_ps(a, b, _CMP_LT_OQ); }
  static M And(M a, M b) { return _mm256_and_ps(a, b); }
  static V Blend(M m, V a, V b) { return _mm256_blendv_ps(b, a, m); }
};
#include "spherechain/runtime/formulas.inl"
#include "kernels_x86.inl"
inline void PivotCentroids(const RefitArgs& a, uint32_t s0, uint32_t n, V px[4], V py[4], V pz[4]) {
  __m128 lx[4], ly[4], lz[4], hx[4], hy[4], hz[4];
  PivotCentroids4(a, s0, n, s0, lx, ly, lz);  // pad lanes: lane 0's sphere
  PivotCentroids4(a, s0 + 4, n > 4 ? n - 4 : 0, s0, hx, hy, hz);
  for (int k = 0; k < 4; ++k) {
    px[k] = _mm256_insertf128_ps(_mm256_castps128_ps256(lx[k]), hx[k], 1);
    py[k] = _mm256_insertf128_ps(_mm256_castps128_ps256(ly[k]), hy[k], 1);
    pz[k] = _mm256_insertf128_ps(_mm256_castps128_ps256(lz[k]), hz[k], 1);
  }
}
inline uint32_t Overlap8(V xi, V yi, V zi, V ri, const float* x, const float* y, const float* z, const float* r) {
  return static_cast<uint32_t>(_mm256_movemask_ps(OverlapLanes<Ops>(xi, yi, zi, ri, Load(x), Load(y), Load(z), Load(r))));
}
#include "kernels.inl"
#ifdef __clang__
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif
}  // namespace avx

namespace avx512 {
SPHERECHAIN_AVX512_BEGIN
struct Ops {  // formulas.inl's lane interface: 16 lanes, comparisons into mask registers
  using V = __m512;
  using M = __mmask16;
  static V Set1(float v) { return _mm512_set1_ps(v); }
  static V Sqrt(V v) { return _mm512_sqrt_ps(v); }
  static M Gt(V a, V b) { return _mm512_cmp_ps_mask(a, b, _CMP_GT_OQ); }
  static M Lt(V a, V b) { return _mm512_cmp_ps_mask(a, b, _CMP_LT_OQ); }
  static M And(M a, M b) { return static_cast<M>(a & b); }
  static V Blend(M m, V a, V b) { return _mm512_mask_blend_ps(m, b, a); }
};
#include "spherechain/runtime/formulas.inl"
#include "kernels_avx512.inl"
void RefitKernel(const RefitArgs& a, uint32_t begin, uint32_t end) { Refit(a, begin, end, &avx::Refit); }
SPHERECHAIN_AVX512_END
}  // namespace avx512

namespace {
bool NoGather(const GatherArgs&) { return false; }

constexpr Table kTables[kIsaCount] = {
    {&sse::Refit, &sse::BlockBoxes, &sse::BlockRows, &NoGather, &sse::JointRefit, &sse::Finite},
    {&avx::Refit, &avx::BlockBoxes, &avx::BlockRows, &NoGather, &avx::JointRefit, &avx::Finite},
    // AVX-512: the block boxes come with the gather (GatherBoxes); BlockBoxes (8 lanes) serves a model
    // over kMaxGatherSpheres.
    {&avx512::RefitKernel, &avx::BlockBoxes, &avx512::BlockRows, &avx512::GatherBoxes, &avx512::JointRefit,
     &avx512::Finite},
};
}  // namespace

bool Supported(Isa isa) {
  __builtin_cpu_init();
  switch (isa) {
    case Isa::kSse2: return true;
    case Isa::kAvx: return __builtin_cpu_supports("avx") && __builtin_cpu_supports("popcnt");
    case Isa::kAvx512:  // libgcc's checks include the OS's XCR0 (the ZMM and mask state saved)
      return Supported(Isa::kAvx) && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
             __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw");
  }
  return false;
}

#else  // scalar: one lane at a time, the same formulas

namespace scalar {
using V = float;
using M = bool;
constexpr uint32_t kW = 1;
inline V Set1(float v) { return v; }
inline V Load(const float* p) { return *p; }
inline void Store(float* p, V v) { *p = v; }
inline V Sqrt(V v) { return std::sqrt(v); }
inline M Gt(V a, V b) { return a > b; }
inline M And(M a, M b) { return a && b; }
inline V Blend(M m, V a, V b) { return m ? a : b; }
inline V Min(V a, V b) { return a < b ? a : b; }
inline V Max(V a, V b) { return a > b ? a : b; }
inline V Abs(V a) { return std::fabs(a); }
inline uint32_t LtMask(V a, V b) { return a < b ? 1u : 0u; }
using Ops = formulas::ScalarOps;
inline uint32_t Overlap8(V xi, V yi, V zi, V ri, const float* x, const float* y, const float* z, const float* r) {
  uint32_t bits = 0;
  for (uint32_t k = 0; k < 8; ++k)
    bits |= static_cast<uint32_t>(formulas::OverlapLanes<Ops>(xi, yi, zi, ri, x[k], y[k], z[k], r[k])) << k;
  return bits;
}
using formulas::RefitLanes;
inline void PivotCentroids(const RefitArgs& a, uint32_t s, uint32_t, V px[4], V py[4], V pz[4]) {
  const uint32_t* idx = a.pivot_vertices + size_t{12} * s;
  for (int k = 0; k < 4; ++k) {
    const float* va = reinterpret_cast<const float*>(a.base + idx[3 * k] * a.stride);
    const float* vb = reinterpret_cast<const float*>(a.base + idx[3 * k + 1] * a.stride);
    const float* vc = reinterpret_cast<const float*>(a.base + idx[3 * k + 2] * a.stride);
    px[k] = formulas::CentroidCoord(va[0], vb[0], vc[0]);
    py[k] = formulas::CentroidCoord(va[1], vb[1], vc[1]);
    pz[k] = formulas::CentroidCoord(va[2], vb[2], vc[2]);
  }
}
#include "kernels.inl"
}  // namespace scalar

namespace {
bool NoGather(const GatherArgs&) { return false; }

// JointRefitArgs, one float at a time: the same roundings as the x86 kernels.
void JointRefitScalar(const JointRefitArgs& a) {
  for (uint32_t n = 1; n <= 4; ++n)
    for (uint32_t k = n == 1 ? 0 : a.group_end[n - 2]; k < a.group_end[n - 1]; ++k) {
      float m[12];
      const float* M = a.matrices + a.offsets[4 * k];
      for (int e = 0; e < 12; ++e) m[e] = a.weights[4 * k] * M[e];
      for (uint32_t i = 1; i < n; ++i) {
        M = a.matrices + a.offsets[4 * k + i];
        for (int e = 0; e < 12; ++e) m[e] = m[e] + a.weights[4 * k + i] * M[e];
      }
      const float* b = a.bind + size_t{4} * k;
      float c[3];
      for (int row = 0; row < 3; ++row) {
        const float* p = m + 4 * row;
        c[row] = (p[0] * b[0] + p[1] * b[1]) + (p[2] * b[2] + p[3] * b[3]);
      }
      const uint32_t s = a.sphere[k];
      a.x[s] = c[0], a.y[s] = c[1], a.z[s] = c[2];
    }
}

bool FiniteScalar(const float* p, uint32_t n) {
  for (uint32_t i = 0; i < n; ++i)
    if (!std::isfinite(p[i])) return false;
  return true;
}

constexpr Table kScalar = {&scalar::Refit, &scalar::BlockBoxes, &scalar::BlockRows, &NoGather, &JointRefitScalar,
                           &FiniteScalar};
constexpr Table kTables[kIsaCount] = {kScalar, kScalar, kScalar};
}  // namespace

bool Supported(Isa isa) { return isa == Isa::kSse2; }

#endif

const char* ToString(Isa isa) {
  switch (isa) {
    case Isa::kSse2: return "sse2";
    case Isa::kAvx: return "avx";
    case Isa::kAvx512: return "avx512";
  }
  return "?";
}

Isa Best() {
  static const Isa best = [] {
    Isa cap = Isa::kAvx512;
    if (const char* env = std::getenv("SPHERECHAIN_ISA")) {
      for (int i = 0; i < kIsaCount; ++i)
        if (std::strcmp(env, ToString(static_cast<Isa>(i))) == 0) cap = static_cast<Isa>(i);
    }
    for (int i = static_cast<int>(cap); i > 0; --i)
      if (Supported(static_cast<Isa>(i))) return static_cast<Isa>(i);
    return Isa::kSse2;
  }();
  return best;
}

const Table& Kernels(Isa isa) { return kTables[static_cast<int>(isa)]; }

}  // namespace spherechain::runtime::kernels
