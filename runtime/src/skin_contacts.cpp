// spherechain runtime — the narrow phase under the skin's own definition (Exclusions::kCrease).
//
// The crease rule (crease.h) is a property of the bind surface, so the model decides it once, for every
// pair of triangles that could ever be near, and no frame searches the surface:
//   - Init groups the triangles into patches of up to 16, grown over the welded bind surface from seeds
//     in Morton order (each patch the nearest unassigned triangles around its seed that touch it), and
//     records, for every pair of patches holding a near pair, 16×16 near bits (one bounded Dijkstra per
//     distinct corner of each patch at the asset's crease; a patch pair where every pair is near — most of a patch with
//     itself and its neighbours — is marked to skip whole).
//   - Each frame: each patch's distinct vertices read once, giving its box and its 16 triangle boxes; the
//     groups of 4 patches (consecutive in Morton order) swept against each other along the longest axis of
//     the mesh (sort and sweep; the order kept from the last frame and re-sorted by insertion), each with
//     itself too, and per overlapping pair of groups their patch boxes 4 at a time; per overlapping pair of
//     patches whose near block (from window masks when the two are fewer than 64 apart in Morton order,
//     else from the lower one's sorted row of partners) is not all near: each side kept to its triangles
//     that meet the other patch's box and have a partner not near in it, then each kept triangle's box
//     against the other side's kept boxes (16 lanes at a time) with the near bits cleared, and the rest tested exactly
//     (TrianglesIntersect on prepared triangles). A job wider than the asset's crease also asks the graph
//     (CreaseScratch::Near) about each intersecting pair the bits let through.
// So every pair of triangles whose boxes overlap is either near by the bits (skipped: a fold, or
// neighbours sharing a corner — the two-ring floor covers them) or tested: the same contacts as testing
// every pair of triangles, each once.
// The code is skin_contacts_sweep.inl, compiled twice below: CreaseSweep (baseline x86-64, or scalar) and,
// on x86-64, CreaseSweepAvx512 (AVX-512 function target: the 16-lane box tests in one compare per bound).
// RunCrease picks per job as the other kernels do (kernels::Best(), capped by SPHERECHAIN_ISA); the two give
// the same contacts, depths and order (comparisons and min/max only; no FMA: -ffp-contract=off). The AVX-512
// copy also runs the exact tests' float filter a row at a time: a patch's 16 triangles prepared by lane once a
// frame (PrepareFilter16, the values PrepareTriangle writes), and each kept triangle against the other patch's
// 16 in one pass (FilterRejects16); the pairs it rejects are counted as tests, the others are tested as in the
// baseline copy (a certified lane is copied out as its PreparedTriangle), so the decisions are the same.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <new>

#include "alloc_guard.h"
#include "avx512_target.h"
#include "internal.h"
#include "spherechain/runtime/narrow_phase.h"

#if defined(__GNUC__) && defined(__x86_64__)
#define SPHERECHAIN_SKIN_SSE2 1
#include <immintrin.h>
#endif
#if defined(__GNUC__)
#define SPHERECHAIN_SKIN_INLINE inline __attribute__((always_inline))
#else
#define SPHERECHAIN_SKIN_INLINE inline
#endif

namespace spherechain::runtime {

namespace {
constexpr float kInfinity = std::numeric_limits<float>::infinity();
constexpr uint32_t kPatch = 16;     // triangles per patch (one uint16_t of near bits per row)
constexpr uint32_t kFilterFloats = 16 * kPatch;  // a patch in the float filter's lanes: 16 rows of 16 (PrepareFilter16)
constexpr uint32_t kGroup = 4;      // patches per group (consecutive in Morton order): what the sweep sorts
constexpr uint32_t kGroupWindow = 16;  // pairs of groups fewer than this apart: skip masks in group_near_
constexpr uint32_t kNone = ~0u;
constexpr uint32_t kAllNear = ~0u;      // a near block: every pair of the two patches is near
constexpr uint32_t kFarPair = ~0u - 1;  // no near block: no pair of the two patches is near

// Maps a float to a uint32 of the same order (negative floats flipped).
uint32_t OrderedBits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

// Bit j (< 16) set when box j of `b` (6 rows of 16: min x, y, z, max x, y, z) overlaps the box (lo, hi)
// (closed intervals). SSE2 on x86-64 (its baseline), scalar elsewhere; the same answer.
SPHERECHAIN_SKIN_INLINE uint32_t OverlapMask16(const float* b, const float lo[3], const float hi[3]) {
#if SPHERECHAIN_SKIN_SSE2
  const __m128 lx = _mm_set1_ps(lo[0]), ly = _mm_set1_ps(lo[1]), lz = _mm_set1_ps(lo[2]);
  const __m128 hx = _mm_set1_ps(hi[0]), hy = _mm_set1_ps(hi[1]), hz = _mm_set1_ps(hi[2]);
  uint32_t mask = 0;
  for (int q = 0; q < 4; ++q) {
    const float* c = b + 4 * q;
    __m128 m = _mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(c), hx), _mm_cmpge_ps(_mm_loadu_ps(c + 48), lx));
    m = _mm_and_ps(m, _mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(c + 16), hy), _mm_cmpge_ps(_mm_loadu_ps(c + 64), ly)));
    m = _mm_and_ps(m, _mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(c + 32), hz), _mm_cmpge_ps(_mm_loadu_ps(c + 80), lz)));
    mask |= static_cast<uint32_t>(_mm_movemask_ps(m)) << (4 * q);
  }
  return mask;
#else
  uint32_t mask = 0;
  for (uint32_t j = 0; j < 16; ++j)
    mask |= static_cast<uint32_t>((b[j] <= hi[0]) & (b[48 + j] >= lo[0]) & (b[16 + j] <= hi[1]) & (b[64 + j] >= lo[1]) &
                                  (b[32 + j] <= hi[2]) & (b[80 + j] >= lo[2]))
            << j;
  return mask;
#endif
}

// Bit i (< 4) set when box i of `b` (6 rows of 4: min x, y, z, max x, y, z) overlaps the box (lo, hi)
// (closed intervals). SSE2 on x86-64, scalar elsewhere; the same answer.
SPHERECHAIN_SKIN_INLINE uint32_t OverlapMask4(const float* b, const float lo[3], const float hi[3]) {
#if SPHERECHAIN_SKIN_SSE2
  __m128 in = _mm_cmple_ps(_mm_loadu_ps(b), _mm_set1_ps(hi[0]));
  in = _mm_and_ps(in, _mm_cmple_ps(_mm_loadu_ps(b + 4), _mm_set1_ps(hi[1])));
  in = _mm_and_ps(in, _mm_cmple_ps(_mm_loadu_ps(b + 8), _mm_set1_ps(hi[2])));
  in = _mm_and_ps(in, _mm_cmpge_ps(_mm_loadu_ps(b + 12), _mm_set1_ps(lo[0])));
  in = _mm_and_ps(in, _mm_cmpge_ps(_mm_loadu_ps(b + 16), _mm_set1_ps(lo[1])));
  in = _mm_and_ps(in, _mm_cmpge_ps(_mm_loadu_ps(b + 20), _mm_set1_ps(lo[2])));
  return static_cast<uint32_t>(_mm_movemask_ps(in));
#else
  uint32_t mask = 0;
  for (uint32_t i = 0; i < 4; ++i) {
    bool in = true;
    for (int k = 0; k < 3; ++k) in &= b[4 * k + i] <= hi[k] && b[4 * (3 + k) + i] >= lo[k];
    mask |= uint32_t{in} << i;
  }
  return mask;
#endif
}

// Interleaves the low 10 bits of x, y, z (a 30-bit Morton code).
uint32_t Morton(uint32_t x, uint32_t y, uint32_t z) {
  auto spread = [](uint32_t v) {
    v &= 0x3ffu;
    v = (v | v << 16) & 0x030000ffu;
    v = (v | v << 8) & 0x0300f00fu;
    v = (v | v << 4) & 0x030c30c3u;
    v = (v | v << 2) & 0x09249249u;
    return v;
  };
  return spread(x) | spread(y) << 1 | spread(z) << 2;
}

}  // namespace

void ContactDepthOf(const float* const a[3], const float* const b[3], ContactDepth* out) {
  double n[2][3];
  const float* const* tri[2] = {a, b};
  for (int s = 0; s < 2; ++s) {
    const float* const* p = tri[s];
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k) e1[k] = double(p[1][k]) - p[0][k], e2[k] = double(p[2][k]) - p[0][k];
    n[s][0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[s][1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[s][2] = e1[0] * e2[1] - e1[1] * e2[0];
    const double len = std::sqrt(n[s][0] * n[s][0] + n[s][1] * n[s][1] + n[s][2] * n[s][2]);
    if (!(len > 0.0)) {
      *out = ContactDepth{0.0f, {0.0f, 0.0f, 0.0f}};
      return;
    }
    for (double& c : n[s]) c /= len;
  }
  // behind[s]: how far the deepest corner of triangle s lies behind the other's plane.
  double behind[2] = {0.0, 0.0};
  for (int s = 0; s < 2; ++s) {
    const float* const* p = tri[s];
    const float* const* q = tri[1 - s];
    const double* m = n[1 - s];
    for (int j = 0; j < 3; ++j) {
      double d = 0;
      for (int k = 0; k < 3; ++k) d += m[k] * (double(p[j][k]) - q[0][k]);
      behind[s] = std::max(behind[s], -d);
    }
  }
  const bool along_b = behind[0] <= behind[1];
  out->depth = static_cast<float>(along_b ? behind[0] : behind[1]);
  for (int k = 0; k < 3; ++k) out->direction[k] = static_cast<float>(along_b ? n[1][k] : -n[0][k]);
}

struct CreaseSweep {
#define SPHERECHAIN_SKIN_AVX512 0
#include "skin_contacts_sweep.inl"
#undef SPHERECHAIN_SKIN_AVX512
};

#if SPHERECHAIN_SKIN_SSE2
SPHERECHAIN_AVX512_BEGIN
struct CreaseSweepAvx512 {
#define SPHERECHAIN_SKIN_AVX512 1
#include "skin_contacts_sweep.inl"
#undef SPHERECHAIN_SKIN_AVX512
};
SPHERECHAIN_AVX512_END
#endif

bool NarrowPhaseModel::IntersectsAtBind(uint32_t t, uint32_t u) const {
  const uint64_t key = uint64_t{std::min(t, u)} << 32 | std::max(t, u);
  return std::binary_search(bind_contacts_.begin(), bind_contacts_.end(), key);
}

Status InitCreaseModel(NarrowPhaseModel& m, const AssetView& view) { return CreaseSweep::InitModel(m, view); }
Status InitCreaseWorkspace(NarrowPhaseWorkspace& w, const NarrowPhaseModel& m, BlockArena* arena) {
  return CreaseSweep::InitWorkspace(w, m, arena);
}
Status RunCrease(const NarrowPhaseJob& job) {
#if SPHERECHAIN_SKIN_SSE2
  if (kernels::Best() == kernels::Isa::kAvx512) return CreaseSweepAvx512::Run(job);
#endif
  return CreaseSweep::Run(job);
}

}  // namespace spherechain::runtime
