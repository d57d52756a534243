// Private: job kernels with access to Model's and Workspace's arrays (one definition, used by
// refit.cpp / detect.cpp / batch.cpp), and the SIMD kernels (kernels.cpp) they dispatch to.
#pragma once

#include <cstddef>
#include <cstdint>

#include "spherechain/runtime/detect.h"
#include "spherechain/runtime/refit.h"

namespace spherechain::runtime {

struct Model::Internal {
  static void Refit(const RefitJob& job, uint32_t begin, uint32_t end);
  static Status Detect(const DetectJob& job);
  /// Shared argument checks of the jobs: kErrorNullArgument (either null), kErrorInvalidJob (either not
  /// initialised), kErrorWorkspaceModel (the workspace was made for another model), else kOk.
  static Status CheckPair(const Model* model, const Workspace* ws) {
    if (!model || !ws) return Status::kErrorNullArgument;
    if (!model->initialized() || !ws->initialized()) return Status::kErrorInvalidJob;
    if (!ws->made_for(*model)) return Status::kErrorWorkspaceModel;
    return Status::kOk;
  }
};

/// Kernels over plain arrays, compiled twice (kernels.cpp): SSE2 (any x86-64) and AVX, picked per
/// model at Init (`__builtin_cpu_supports`); a scalar build elsewhere. Same operations in the same
/// order — the formulas themselves are spherechain/runtime/formulas.inl, included once per instruction
/// set — no FMA: every variant gives bit-identical results (tests/runtime/formulas_test.cpp).
namespace kernels {

/// Refit of spheres [begin, end) (see RefitJob, refit.h). Per-sphere arrays are readable up to a
/// multiple of 8 past `end` (padded); outputs are written for [begin, end) only. The x86 kernels read
/// each pivot vertex as four floats (x, y, z and the next float of the buffer, unused) except the
/// buffer's last vertex (`last_vertex`), which may end the buffer.
struct RefitArgs {
  const char* base;               // positions (strided)
  size_t stride;                  // bytes
  uint32_t last_vertex;           // #V − 1
  const uint32_t* pivot_vertices; // #S×12
  const float *local_x, *local_y, *local_z, *offset_x, *offset_y, *offset_z, *radius_scale;
  float *x, *y, *z, *r;
  bool frame_mode;                // kPivotFrame
};

/// Broad phase of DetectJob (M1 and M2 share it), one row block per call: spheres sit in blocks of 8
/// (Model::Init's layout: per chain-membership class, bind-pose kd split), gathered per frame in
/// block order (x, y, z, r grown by the margin; padding lanes NaN). Row block I is tested against
/// every block J >= I that the method's static table keeps (`live`: some allowed lane); a block pair
/// survives when the distance between the boxes of the two blocks' centres is below the sum of their
/// largest |radius| — computed with the sphere test's own float operations, so that it never drops a
/// pair the sphere test would report (see kernels.inl) — then each row sphere of I is tested the same
/// way against J's box, and the surviving rows run their 8 sphere tests, masked by
/// `allowed` (row r's lanes in byte r: not padding, j > i on the diagonal block, not excluded, and for
/// M1 sharing a chain). Each hit writes (first common chain, M1 only) << 32 | min(a,b) << 16 | max(a,b)
/// at keys[key_begin[I] ...]. Returns the number of keys; counters go to *box_tests / *sphere_tests.
struct BroadPhaseArgs {
  const float *x, *y, *z, *r;             // G = 8·B gathered spheres, block order
  const float *lx, *hx, *ly, *hy, *lz, *hz, *br;  // per block (B + 8, padding blocks empty): box of
                                          // the centres, largest |grown radius| (NaN lanes ignored)
  const uint32_t* order;                  // G: sphere id per slot (padding: #S)
  const uint32_t* chain_mask;             // #S + 1
  const uint64_t* allowed;                // B×B, [I·B + J] for J >= I: lanes of the pair, byte r = row r
  const uint8_t* live;                    // B × live_stride: bit k of byte c ⇔ allowed[I][I+8c+k] != 0
  uint32_t blocks, live_stride;
  bool m1;                                // keys carry the first common chain
  uint64_t* keys;
  const uint32_t* key_begin;              // B: first key slot of each row block
};

/// Block boxes of the transposed gathered spheres: t* hold lane l of block I at [l · pitch + I]
/// (pitch a multiple of 8 >= B; padding NaN). Writes lx..br for I < pitch.
struct BlockBoxArgs {
  const float *tx, *ty, *tz, *tr;
  uint32_t pitch;
  float *lx, *hx, *ly, *hy, *lz, *hz, *br;
};

void RefitSse(const RefitArgs& a, uint32_t begin, uint32_t end);
void RefitAvx(const RefitArgs& a, uint32_t begin, uint32_t end);
void BlockBoxesSse(const BlockBoxArgs& a);
void BlockBoxesAvx(const BlockBoxArgs& a);
uint32_t BlockRowSse(const BroadPhaseArgs& a, uint32_t I, uint32_t* box_tests, uint32_t* sphere_tests);
uint32_t BlockRowAvx(const BroadPhaseArgs& a, uint32_t I, uint32_t* box_tests, uint32_t* sphere_tests);
bool HasAvx();  // the CPU and OS support AVX and POPCNT (false on a non-x86 build)

}  // namespace kernels
}  // namespace spherechain::runtime
