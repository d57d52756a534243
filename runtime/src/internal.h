// Private: job kernels with access to Context's arrays (one definition, used by refit.cpp/detect.cpp),
// and the SIMD kernels (kernels.cpp) they dispatch to.
#pragma once

#include <cstddef>
#include <cstdint>

#include "spherechain/runtime/detect.h"
#include "spherechain/runtime/refit.h"

namespace spherechain::runtime {

struct Context::Internal {
  static void Refit(const RefitJob& job, uint32_t begin, uint32_t end);
  static void DetectSpan(const Context& ctx, uint32_t span);
  static Status DetectM1(const DetectJob& job);
  static Status DetectM2(const DetectJob& job);
};

/// Kernels over plain arrays, compiled twice (kernels.cpp): SSE2 (any x86-64) and AVX, picked per
/// context at Init (`__builtin_cpu_supports`); a scalar build elsewhere. Same operations in the same
/// order as the scalar formulas of refit.h / §5.2, no FMA: every variant gives bit-identical results.
namespace kernels {

/// Refit of spheres [begin, end) (see RefitJob, refit.h). Per-sphere arrays are readable up to a
/// multiple of 8 past `end` (padded); outputs are written for [begin, end) only.
struct RefitArgs {
  const char* base;               // positions (strided)
  size_t stride;                  // bytes
  const uint32_t* pivot_vertices; // #S×12
  const float *local_x, *local_y, *local_z, *offset_x, *offset_y, *offset_z, *radius_scale;
  float *x, *y, *z, *r;
  bool frame_mode;                // kPivotFrame
};

/// Overlap tests of every pair (row i < rows, column j > i < columns) of a span of gathered SoA
/// spheres, in 8-lane chunks aligned to 8 (spans padded to multiples of 8) numbered from `chunk`;
/// lanes to ignore (excluded pairs, j <= i, padding) come from the sorted skip stream `excl`
/// ((chunk << 32) | lane bits, UINT64_MAX-terminated, positioned at this span's first entry).
/// Each remaining overlapping pair writes first_chain << 32 | min(a, b) << 16 | max(a, b) to `keys`
/// (a, b = order[...], first_chain = the lowest chain holding both). Returns the number of keys.
struct SpanArgs {
  const float *x, *y, *z, *r;
  const uint16_t* order;
  const uint32_t* chain_mask;  // #S
  uint32_t begin, rows, columns;
  uint32_t chunk;
  const uint64_t* excl;
  uint64_t* keys;
};

/// M2: every pair a < b of the #S spheres (rows a, chunks of b aligned to 8 from a+1, arrays padded
/// to a multiple of 8), skip stream as above; writes the first `capacity` overlapping pairs to `out`
/// in (a, b) order and returns how many there are.
struct AllPairsArgs {
  const float *x, *y, *z, *r;
  uint32_t count;
  const uint64_t* excl;
  const uint32_t* chain_mask;
  Collision* out;
  uint32_t capacity;
};

void RefitSse(const RefitArgs& a, uint32_t begin, uint32_t end);
void RefitAvx(const RefitArgs& a, uint32_t begin, uint32_t end);
uint32_t SpanSse(const SpanArgs& a);
uint32_t SpanAvx(const SpanArgs& a);
uint32_t AllPairsSse(const AllPairsArgs& a);
uint32_t AllPairsAvx(const AllPairsArgs& a);
bool HasAvx();  // the CPU and OS support AVX (false on a non-x86 build)

}  // namespace kernels
}  // namespace spherechain::runtime
